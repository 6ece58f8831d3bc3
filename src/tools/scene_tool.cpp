// go_feap_scene: builds a scene (procedural or from a scene YAML) and writes scene.pcd,
// scene.bt, scene.json and scene.png into --out.
#include <sys/resource.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "cli_args.h"
#include "go_feap/world/scene_files.h"
#include "go_feap/world/scene_image.h"

namespace {

int usage(const char* why) {
  if (why) std::cerr << "go_feap_scene: " << why << "\n";
  std::cerr << "usage: go_feap_scene --scene maze|powerplant|PATH.yaml [--seed S] --out DIR\n"
               "Writes DIR/scene.pcd, scene.bt, scene.json and scene.png.\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace go_feap;
  std::map<std::string, std::string> args;
  bool help = false;
  const std::string error = tools::parseArgs(argc, argv, {{"--scene", true}, {"--seed", true}, {"--out", true}}, args, help);
  if (help) return usage(nullptr), 0;
  if (!error.empty()) return usage(error.c_str());
  const std::string scene_spec = args["--scene"], out_dir = args["--out"];
  unsigned long long seed = 0;
  if (args.count("--seed") && !tools::parseCount(args["--seed"], seed))
    return usage("--seed must be a non-negative integer");
  if (scene_spec.empty()) return usage("--scene is required");
  if (out_dir.empty()) return usage("--out is required");

  const auto t0 = std::chrono::steady_clock::now();
  auto scene = world::makeScene(scene_spec, seed);
  const double load_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!scene) {
    std::cerr << "go_feap_scene: " << scene.message() << "\n";
    return 1;
  }
  const auto t1 = std::chrono::steady_clock::now();
  const world::ObservableSet observable = world::computeObservableSet(*scene);
  const double observable_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();

  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) {
    std::cerr << "go_feap_scene: cannot create " << out_dir << ": " << ec.message() << "\n";
    return 1;
  }
  const std::string dir = std::filesystem::path(out_dir).string() + "/";
  if (auto st = world::saveScenePcd(*scene, dir + "scene.pcd"); !st) {
    std::cerr << "go_feap_scene: " << st.message() << "\n";
    return 1;
  }
  if (auto st = world::saveSceneBt(*scene, dir + "scene.bt"); !st) {
    std::cerr << "go_feap_scene: " << st.message() << "\n";
    return 1;
  }
  bool pictured = false;
  try {
    pictured = cv::imwrite(dir + "scene.png", world::renderSceneImage(*scene));
  } catch (const cv::Exception& e) {  // OpenCV throws as well as returning false
    std::cerr << "go_feap_scene: " << e.what() << "\n";
  }
  if (!pictured) {
    std::cerr << "go_feap_scene: cannot write " << dir << "scene.png\n";
    return 1;
  }

  // Counts inside the exploration box.
  const auto& geo = scene->geometry();
  common::Index3 lo, hi;
  geo.centreRange(scene->box, lo, hi);
  std::size_t occ = 0, free = 0;
  for (int z = lo.z(); z < hi.z(); ++z)
    for (int y = lo.y(); y < hi.y(); ++y)
      for (int x = lo.x(); x < hi.x(); ++x) (scene->occupied.at({x, y, z}) ? occ : free)++;
  auto vec = [](const common::Vec3& v) { return nlohmann::json::array({v.x(), v.y(), v.z()}); };
  nlohmann::json j;
  j["name"] = scene->name;
  j["seed"] = scene->seed;
  j["source"] = scene_spec;
  j["resolution"] = scene->resolution();
  j["box"] = {{"min", vec(scene->box.min)}, {"max", vec(scene->box.max)}};
  j["grid"] = {{"origin", vec(geo.origin())}, {"dims", {geo.dims().x(), geo.dims().y(), geo.dims().z()}}};
  j["start"] = {{"position", vec(scene->start.position)}, {"yaw", scene->start.yaw}};
  j["voxels"] = {{"occupied_in_box", occ},
                 {"free_in_box", free},
                 {"occupied_in_grid", scene->occupiedCount()},
                 {"observable", observable.total()},
                 {"observable_free", observable.free_count},
                 {"observable_occupied", observable.occupied_count}};
  j["load_time_s"] = load_s;
  j["observable_time_s"] = observable_s;
  // The source path as given, with U+FFFD for bytes that are no UTF-8 (dump() threw on them).
  std::ofstream json(dir + "scene.json");
  json << j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) << "\n";
  if (!json.flush()) {
    std::cerr << "go_feap_scene: cannot write " << dir << "scene.json\n";
    return 1;
  }

  std::cout << "scene '" << scene->name << "' (seed " << scene->seed << "): " << occ << " occupied, " << free
            << " free voxels in the box, " << observable.total() << " observable; built in " << load_s
            << " s\nwrote " << dir << "scene.{pcd,bt,json,png}\n";
  return 0;
}
