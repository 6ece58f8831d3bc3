// rostest: the small maze explored end to end through the ROS chain. Exploration must reach
// FINISHED(complete) within the simulated-time budget; the coverage of the observable set,
// computed here from the mapper's own OctoMap export (independently of the metrics recorder),
// must be at least 95 %; the flown path, sampled from odometry, must never come within 0.1 m of
// a ground-truth obstacle (brute-force lattice check); the recorder's summary.json must agree; and
// go_feap_bench's lock-step loop on the same scene and configuration must reach the same coverage
// within 3 %.
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <octomap/OcTree.h>
#include <ros/ros.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "go_feap/ExplorationStatus.h"
#include "go_feap/SaveMap.h"
#include "go_feap/bench/exploration_run.h"
#include "go_feap/world/scene_files.h"
#include "ros_test_util.h"

namespace {

using go_feap::common::Vec3;
using go_feap::test::latticeClearance;
using go_feap::test::spinUntil;

TEST(Exploration, SmallMazeFinishesCompleteWithFullCoverageAndNoCollision) {
  ros::NodeHandle nh, pnh("~");
  std::string output_dir;
  ASSERT_TRUE(pnh.getParam("output_dir", output_dir));
  auto scene = go_feap::test::sceneFromParams();
  ASSERT_TRUE(scene) << scene.message();

  std::vector<Vec3> path;
  go_feap::ExplorationStatus::ConstPtr status;
  auto odom_sub = nh.subscribe<nav_msgs::Odometry>("odom", 100, [&](const nav_msgs::Odometry::ConstPtr& m) {
    path.emplace_back(m->pose.pose.position.x, m->pose.pose.position.y, m->pose.pose.position.z);
  });
  auto status_sub = nh.subscribe<go_feap::ExplorationStatus>(
      "status", 10, [&](const go_feap::ExplorationStatus::ConstPtr& m) { status = m; });

  ASSERT_TRUE(spinUntil([&] { return status && status->state == go_feap::ExplorationStatus::FINISHED; }, 540.0))
      << "not finished: " << (status ? status->state_name : std::string("no status")) << " after "
      << (status ? status->elapsed : 0.0) << " s simulated\n"
      << go_feap::test::threadStacks("/go_feap_manager");
  EXPECT_EQ(status->finish_reason, "complete");
  std::cout << "finished (" << status->finish_reason << ") after " << status->elapsed << " s simulated, "
            << status->distance << " m\n";

  // Coverage from the mapper's map, through its own export.
  const std::string bt = (std::filesystem::temp_directory_path() / "go_feap_exploration_test.bt").string();
  go_feap::SaveMap save;
  save.request.path = bt;
  ASSERT_TRUE(ros::service::waitForService("save_map", ros::Duration(10.0)));
  ASSERT_TRUE(ros::service::call("save_map", save) && save.response.success) << save.response.message;
  octomap::OcTree tree(bt);
  const go_feap::world::ObservableSet observable = go_feap::world::computeObservableSet(*scene);
  const double coverage = go_feap::world::coverage(observable, [&](const Vec3& c) {
    return tree.search(c.x(), c.y(), c.z()) != nullptr;
  });
  std::cout << "coverage " << 100.0 * coverage << " % of " << observable.total() << " observable voxels\n";
  EXPECT_GE(coverage, 0.95);

  double min_clearance = 1.0;
  for (std::size_t i = 0; i < path.size(); i += 5)
    min_clearance = std::min(min_clearance, latticeClearance(*scene, path[i], 0.3));
  std::cout << path.size() << " odometry samples; closest approach to an obstacle " << min_clearance << " m\n";
  EXPECT_GT(min_clearance, 0.1) << "collision";

  // The recorder's files, written when the status said FINISHED.
  const std::string summary_path = output_dir + "/summary.json";
  ASSERT_TRUE(spinUntil([&] { return std::filesystem::exists(summary_path); }, 20.0)) << summary_path;
  for (const char* f : {"metrics.csv", "coverage.png"})
    EXPECT_TRUE(std::filesystem::exists(output_dir + "/" + f)) << f;
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(summary_path));
  EXPECT_EQ(summary["finish_reason"], "complete");
  EXPECT_EQ(summary["collisions"], 0);
  EXPECT_NEAR(summary["coverage"].get<double>(), coverage, 0.02);
  for (const char* key : {"scene", "seed", "planner", "exploration_time_s", "flight_distance_m", "compute_ms"})
    EXPECT_TRUE(summary.contains(key)) << key;

  // The bench runs the same core classes in lock-step simulated time: same outcome within tolerance.
  std::string config_dir;
  ASSERT_TRUE(pnh.getParam("config_dir", config_dir));
  auto config = go_feap::bench::loadExplorationConfig(config_dir, "go_feap");
  ASSERT_TRUE(config) << config.message();
  go_feap::bench::ExplorationRun bench(*scene, *config, "go_feap", 240.0);
  bench.run();
  const auto& b = bench.recorder().summary();
  std::cout << "bench: " << b.finish_reason << " after " << b.exploration_time_s << " s, coverage "
            << 100.0 * b.coverage << " %\n";
  EXPECT_EQ(b.finish_reason, "complete");
  EXPECT_NEAR(b.coverage, coverage, 0.03);
}

}  // namespace

GO_FEAP_ROSTEST_MAIN("test_exploration_ros")
