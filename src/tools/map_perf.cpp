// go_feap_map_perf: times the mapping and global-planning stages on depth rendered along a
// path through a procedural scene: occupancy integration, ESDF update, incremental frontier
// update and omission-aware global planning (A* distances, Held-Karp) per frame, and the
// map's memory.
#include <chrono>
#include <iostream>
#include <map>

#include "camera_path.h"
#include "cli_args.h"
#include "go_feap/frontier/frontier_finder.h"
#include "go_feap/map/voxel_map.h"
#include "go_feap/planning/astar.h"
#include "go_feap/planning/global_planner.h"
#include "go_feap/planning/local_planner.h"
#include "go_feap/planning/viewpoints.h"
#include "go_feap/trajectory/bspline_optimizer.h"
#include "go_feap/sim/depth_camera.h"
#include "go_feap/world/scene_files.h"

namespace {

int usage(const char* why) {
  if (why) std::cerr << "go_feap_map_perf: " << why << "\n";
  std::cerr << "usage: go_feap_map_perf --scene maze|powerplant [--frames N] [--skip-pixel K]\n"
               "Integrates N (default 300) rendered 640x480 depth frames taken along a path (steps of\n"
               "about 0.1 m, turning) and prints integration, ESDF, frontier and global planning times\n"
               "and map memory.\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace go_feap;
  std::map<std::string, std::string> args;
  bool help = false;
  const std::string error =
      tools::parseArgs(argc, argv, {{"--scene", true}, {"--frames", true}, {"--skip-pixel", true}}, args, help);
  if (help) return usage(nullptr), 0;
  if (!error.empty()) return usage(error.c_str());
  unsigned long long frames = 300, skip = 2;
  // Bounded: both are cast to int (2^31 pixels wrapped to a negative step, 2^32 to 0 and a loop for ever).
  if (args.count("--frames") && (!tools::parseCount(args["--frames"], frames) || frames == 0 || frames > 1000000))
    return usage("--frames must be an integer from 1 to 1000000");
  if (args.count("--skip-pixel") && (!tools::parseCount(args["--skip-pixel"], skip) || skip == 0 || skip > 640))
    return usage("--skip-pixel must be an integer from 1 to 640 (the image's width)");
  const std::string spec = args["--scene"];
  if (spec != "maze" && spec != "powerplant") return usage("--scene must be maze or powerplant");
  auto scene = world::makeScene(spec, 0);
  if (!scene) {
    std::cerr << "go_feap_map_perf: " << scene.message() << "\n";
    return 1;
  }
  const sim::DepthCameraConfig camera;
  const sim::DepthRenderer renderer(camera, *scene);
  // One loop of the path is ~10x the box diagonal long: ~0.1 m per step.
  const int samples = static_cast<int>(10.0 * scene->box.size().norm() / 0.1);
  const auto poses = tools::cameraPath(*scene, static_cast<int>(frames), samples);

  map::MapConfig config;
  config.occupancy.skip_pixel = static_cast<int>(skip);
  map::OccupancyMap occupancy(config.occupancy, scene->box);
  map::Esdf esdf(occupancy.geometry(), config.esdf);
  const auto K = camera.intrinsics();
  const map::DepthIntrinsics intrinsics{K.width, K.height, K.fx, K.fy, K.cx, K.cy};
  using Clock = std::chrono::steady_clock;
  frontier::FrontierFinder finder(frontier::FrontierConfig(), occupancy.geometry(), scene->box);
  const planning::GlobalPlannerConfig global;
  const planning::Astar astar(occupancy, esdf, planning::AstarConfig());
  double occ_total = 0, occ_max = 0, esdf_total = 0, esdf_max = 0, fr_total = 0, fr_max = 0, gl_total = 0, gl_max = 0,
         astar_total = 0, astar_max = 0;
  std::size_t tour_total = 0, frontier_total = 0;
  // Local planning and trajectory optimisation, replanned every 5th frame (3 Hz).
  planning::AstarConfig fly_config;
  fly_config.clearance = 0.3;
  fly_config.unknown_is_free = false;
  const planning::Astar fly(occupancy, esdf, fly_config);
  planning::ViewpointConfig vp_config;
  vp_config.max_evaluated_cells = 120;  // as config/exploration.yaml
  const planning::LocalPlannerConfig local_config;
  const trajectory::OptimizerConfig opt_config;
  double local_total = 0, local_max = 0, traj_total = 0, traj_max = 0;
  int replans = 0, local_ok = 0, traj_ok = 0, traj_tried = 0;
  int frame = 0;
  std::size_t rays = 0;
  cv::Mat depth;
  for (const auto& T : poses) {
    renderer.render(T, depth);
    const auto t0 = Clock::now();
    auto change = occupancy.integrate(depth, intrinsics, T);
    const auto t1 = Clock::now();
    if (!change) {
      std::cerr << "go_feap_map_perf: " << change.message() << "\n";
      return 1;
    }
    esdf.update(change->became_occupied, change->stopped_occupied);
    const auto t2 = Clock::now();
    const double a = std::chrono::duration<double, std::milli>(t1 - t0).count();
    const double b = std::chrono::duration<double, std::milli>(t2 - t1).count();
    occ_total += a, esdf_total += b;
    occ_max = std::max(occ_max, a), esdf_max = std::max(esdf_max, b);
    rays += change->rays;

    // Frontiers over the changed box, then a tour from the camera position.
    const double now = frame++ / 15.0;
    const auto t3 = Clock::now();
    if (change->any_change) finder.update(occupancy, change->changed, now);
    const auto t4 = Clock::now();
    std::vector<planning::FrontierSummary> summaries;
    for (const auto& f : finder.frontiers())
      summaries.push_back({f.id, f.average, static_cast<int>(f.cells.size()), f.duration(now), f.n_near, f.active});
    const common::Vec3 uav = T.translation();
    // Time spent in A* is booked separately from selection + cost matrix + solve.
    double astar_ms = 0.0;
    auto timed = [&](auto&& fn) {
      const auto s0 = Clock::now();
      const double r = fn();
      astar_ms += std::chrono::duration<double, std::milli>(Clock::now() - s0).count();
      return r;
    };
    planning::PathDistances d;
    d.from_uav = [&](std::size_t j) {
      const double e = (summaries[j].average - uav).norm();
      return e >= global.s_near ? e : timed([&] { return planning::pathDistance(astar, uav, summaries[j].average).metres; });
    };
    d.between = [&](std::size_t i, std::size_t j) {
      return timed([&] { return planning::pathDistance(astar, summaries[i].average, summaries[j].average).metres; });
    };
    auto tour = planning::planTour(summaries, d, global);
    const auto t5 = Clock::now();
    const double c = std::chrono::duration<double, std::milli>(t4 - t3).count();
    const double g = std::chrono::duration<double, std::milli>(t5 - t4).count() - astar_ms;
    fr_total += c, gl_total += g, astar_total += astar_ms;
    fr_max = std::max(fr_max, c), gl_max = std::max(gl_max, g), astar_max = std::max(astar_max, astar_ms);
    frontier_total += summaries.size();
    if (tour) tour_total += tour->frontier_ids.size();

    if (!tour || tour->frontier_ids.empty() || frame % 5 != 0) continue;
    ++replans;
    const auto t6 = Clock::now();
    std::vector<frontier::Frontier> ordered;
    std::vector<planning::FrontierType> types;
    for (unsigned id : tour->frontier_ids) {
      if (static_cast<int>(ordered.size()) >= local_config.k_frontiers) break;
      const frontier::Frontier* f = finder.find(id);
      if (!f) continue;
      frontier::Frontier copy = *f;
      copy.viewpoints = planning::sampleViewpoints(copy, occupancy, esdf, scene->box.min.z(), scene->box.max.z(),
                                                   vp_config);
      if (copy.viewpoints.empty()) continue;
      types.push_back(planning::classifyFrontier((copy.average - uav).norm(), planning::ObstacleWindow(local_config),
                                                 local_config));
      ordered.push_back(std::move(copy));
    }
    const double yaw = std::atan2(T.linear()(1, 2), T.linear()(0, 2));  // optical z axis
    auto local = ordered.empty() ? common::Result<planning::LocalPlan>::Error("no viewpoints")
                                 : planning::planLocal(uav, common::Vec3::Zero(), yaw, ordered, types, local_config);
    const auto t7 = Clock::now();
    const double lm = std::chrono::duration<double, std::milli>(t7 - t6).count();
    local_total += lm, local_max = std::max(local_max, lm);
    if (!local) continue;
    ++local_ok;
    // Trajectory: A* in known free space to the chosen viewpoint, fit, optimise.
    const planning::PathResult path = fly.search(uav, local->path.front().position);
    if (path.status != planning::PathStatus::kFound || path.length < 0.3) continue;
    ++traj_tried;
    const auto t8 = Clock::now();
    // At least 6 segments, as the trajectory planner takes: a hop under 0.9 m at 0.3 m gave 3 points, fewer
    // than fitPath's end conditions need, and its exception ended the tool.
    const auto samples = trajectory::UniformBspline::resamplePolyline(path.path, std::min(0.3, path.length / 6.0));
    const double total = std::max(path.length / (0.6 * opt_config.v_max), 2.5 * std::sqrt(path.length / opt_config.a_max));
    const auto init = trajectory::UniformBspline::fitPath(samples, total / std::max<std::size_t>(1, samples.size() - 1),
                                                          common::Vec3::Zero(), common::Vec3::Zero());
    const bool ok = trajectory::optimize(init, esdf, opt_config).ok();
    const double tm = std::chrono::duration<double, std::milli>(Clock::now() - t8).count();
    traj_total += tm, traj_max = std::max(traj_max, tm);
    traj_ok += ok;
  }
  const double n = static_cast<double>(poses.size());
  const std::size_t bytes = occupancy.memoryBytes() + esdf.memoryBytes();
  const auto& geo = occupancy.geometry();
  const double volume = geo.size() * std::pow(geo.resolution(), 3);
  std::cout << "scene " << spec << ", " << poses.size() << " frames 640x480, skip_pixel " << skip << ", "
            << rays / n << " rays per frame after merging\n"
            << "integration: mean " << occ_total / n << " ms, max " << occ_max << " ms per frame\n"
            << "ESDF update: mean " << esdf_total / n << " ms, max " << esdf_max << " ms per frame\n"
            << "frontier update: mean " << fr_total / n << " ms, max " << fr_max << " ms per frame ("
            << frontier_total / n << " frontiers on average)\n"
            << "global planning (NearCur_IDs, cost matrix, Held-Karp): mean " << gl_total / n << " ms, max " << gl_max
            << " ms per frame (" << tour_total / n << " frontiers per tour on average)\n"
            << "A* path lengths for it (no cache): mean " << astar_total / n << " ms, max " << astar_max
            << " ms per frame\n"
            << "local planning (viewpoints for <= 3 frontiers + DAG), " << replans << " replans: mean "
            << local_total / std::max(1, replans) << " ms, max " << local_max << " ms (" << local_ok << " plans)\n"
            << "trajectory optimisation: mean " << traj_total / std::max(1, traj_tried) << " ms, max " << traj_max
            << " ms, success " << traj_ok << " of " << traj_tried << "\n"
            << "map: " << geo.dims().transpose() << " voxels (" << volume << " m^3), " << bytes / (1024.0 * 1024.0)
            << " MiB incl. ESDF = " << bytes / volume / 1024.0 << " KiB per m^3; " << occupancy.knownCount()
            << " voxels known\n";
  return 0;
}
