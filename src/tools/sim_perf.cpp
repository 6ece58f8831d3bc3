// go_feap_sim_perf: times the simulator on a procedural scene: the depth camera (one thread)
// from poses along a fixed path through the free space of the box, then dynamics + controller.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "camera_path.h"
#include "cli_args.h"
#include "go_feap/sim/depth_camera.h"
#include "go_feap/sim/vehicle.h"
#include "go_feap/world/scene_files.h"

namespace {

using go_feap::common::Index3;
using go_feap::common::Vec3;

int usage(const char* why) {
  if (why) std::cerr << "go_feap_sim_perf: " << why << "\n";
  std::cerr << "usage: go_feap_sim_perf --scene maze|powerplant [--frames N]\n"
               "Renders N (default 200) 640x480 depth frames and prints frames per second and the\n"
               "mean / max time per frame, then the dynamics + controller speed.\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace go_feap;
  std::map<std::string, std::string> args;
  bool help = false;
  const std::string error = tools::parseArgs(argc, argv, {{"--scene", true}, {"--frames", true}}, args, help);
  if (help) return usage(nullptr), 0;
  if (!error.empty()) return usage(error.c_str());
  const std::string scene_spec = args["--scene"];
  unsigned long long frame_count = 200;
  if (args.count("--frames") && (!tools::parseCount(args["--frames"], frame_count) || frame_count == 0 ||
                                 frame_count > 1000000))
    return usage("--frames must be a positive integer");
  const int frames = static_cast<int>(frame_count);
  if (scene_spec != "maze" && scene_spec != "powerplant") return usage("--scene must be maze or powerplant");

  auto scene = world::makeScene(scene_spec, 0);
  if (!scene) {
    std::cerr << "go_feap_sim_perf: " << scene.message() << "\n";
    return 1;
  }
  using Clock = std::chrono::steady_clock;
  const sim::DepthCameraConfig config;
  const auto t_build = Clock::now();
  const sim::DepthRenderer renderer(config, *scene);
  const double build_ms = std::chrono::duration<double, std::milli>(Clock::now() - t_build).count();
  const std::vector<Eigen::Isometry3d> poses = tools::cameraPath(*scene, frames, 4 * frames);
  if (poses.empty()) {
    std::cerr << "go_feap_sim_perf: found no free camera pose in the box\n";
    return 1;
  }

  cv::Mat depth;
  double total_ms = 0.0, max_ms = 0.0, valid = 0.0;
  for (int f = 0; f < frames; ++f) {
    const auto t0 = Clock::now();
    renderer.render(poses[f % poses.size()], depth);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    total_ms += ms;
    max_ms = std::max(max_ms, ms);
    int returns = 0;
    for (int v = 0; v < depth.rows; ++v) {
      const float* row = depth.ptr<float>(v);
      for (int u = 0; u < depth.cols; ++u) returns += sim::isReturn(row[u]);
    }
    valid += static_cast<double>(returns) / static_cast<double>(depth.total());
  }
  const Index3 n = scene->geometry().dims();
  std::cout << "scene " << scene_spec << ": grid " << n.x() << " x " << n.y() << " x " << n.z() << " at "
            << scene->resolution() << " m, " << renderer.rectangleCount() << " surface rectangles (built in "
            << build_ms << " ms)\n"
            << frames << " frames " << config.width << "x" << config.height
            << ", 1 thread: " << 1000.0 * frames / total_ms << " fps, mean " << total_ms / frames
            << " ms, max " << max_ms << " ms per frame, " << 100.0 * valid / frames << " % valid pixels\n";

  // Dynamics + controller: fly 60 simulated seconds of a 2 m/s circle, 10 ms references.
  sim::SimulatedVehicle vehicle{sim::QuadrotorParams(), sim::So3ControllerConfig()};
  vehicle.reset(scene->start.position, 0.0);
  const double sim_seconds = 60.0, dt = 0.01;
  const auto t_dyn = Clock::now();
  for (double t = 0.0; t < sim_seconds; t += dt) {
    sim::PositionReference ref;
    ref.position = scene->start.position + Eigen::Vector3d(std::cos(t) - 1.0, std::sin(t), 0.0);
    ref.velocity = Eigen::Vector3d(-std::sin(t), std::cos(t), 0.0);
    ref.acceleration = Eigen::Vector3d(-std::cos(t), -std::sin(t), 0.0);
    vehicle.advance(dt, ref);
  }
  const double dyn_s = std::chrono::duration<double>(Clock::now() - t_dyn).count();
  std::cout << "dynamics + controller at " << sim::QuadrotorParams().dynamics_rate << " Hz: " << sim_seconds / dyn_s
            << " simulated seconds per wall second\n";
  return 0;
}
