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
#include <std_msgs/Float64.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <fstream>
#include <vector>
#include <nlohmann/json.hpp>

#include "go_feap/ExplorationStatus.h"
#include "go_feap/FrontierArray.h"
#include "go_feap/SaveMap.h"
#include "go_feap/bench/exploration_run.h"
#include "go_feap/planning/omission.h"
#include "go_feap/world/scene_files.h"
#include "../command_util.h"
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
  std::vector<ros::Time> path_stamps;
  go_feap::ExplorationStatus::ConstPtr status, finished;  // the latest status, the first FINISHED one
  auto odom_sub = nh.subscribe<nav_msgs::Odometry>("odom", 100, [&](const nav_msgs::Odometry::ConstPtr& m) {
    path.emplace_back(m->pose.pose.position.x, m->pose.pose.position.y, m->pose.pose.position.z);
    path_stamps.push_back(m->header.stamp);
  });
  auto status_sub = nh.subscribe<go_feap::ExplorationStatus>("status", 10, [&](const go_feap::ExplorationStatus::ConstPtr& m) {
    status = m;
    if (!finished && m->state == go_feap::ExplorationStatus::FINISHED) finished = m;
  });
  // The recorder's live coverage, a fraction as in summary.json (-1 while unknown).
  std::vector<double> live_coverage;
  auto coverage_sub = nh.subscribe<std_msgs::Float64>(
      "coverage", 100, [&](const std_msgs::Float64::ConstPtr& m) { live_coverage.push_back(m->data); });

  // The finder's published omission inputs, against an oracle on every frontier list of the run: N_near is
  // the count of the other frontiers (active or not) whose average lies within frontier/s_near of this one's,
  // a frontier's duration grows with the clock from one list to the next, and the omission likelihood is
  // xi of the three with the finder's omission/* parameters. (Published as 0, the planner's omission
  // ordering fell back to FUEL's, and the run still finished.)
  auto param = [](const std::string& key, auto& value) {
    EXPECT_TRUE(ros::param::get("/frontier_finder/" + key, value)) << key;
  };
  double s_near = 0.0;
  param("frontier/s_near", s_near);
  go_feap::planning::OmissionConfig omission;
  param("omission/alpha_max", omission.alpha_max);
  param("omission/c_small", omission.c_small);
  param("omission/w_t", omission.w_t);
  param("omission/t_max", omission.t_max);
  param("omission/n_t", omission.n_t);
  param("omission/n_max", omission.n_max);
  std::size_t lists = 0, neighbours = 0, wrong_n_near = 0, wrong_xi = 0, aged = 0, wrong_age = 0;
  std::map<std::uint32_t, std::pair<double, double>> first_heard;  // id -> list stamp, duration there
  auto frontier_sub = nh.subscribe<go_feap::FrontierArray>("frontiers", 50, [&](const go_feap::FrontierArray::ConstPtr& m) {
    ++lists;
    const double stamp = m->header.stamp.toSec();
    for (const auto& f : m->frontiers) {
      std::uint32_t n = 0;
      for (const auto& g : m->frontiers) {
        const double dx = g.average.x - f.average.x, dy = g.average.y - f.average.y, dz = g.average.z - f.average.z;
        n += g.id != f.id && dx * dx + dy * dy + dz * dz < s_near * s_near;
      }
      neighbours += n;
      wrong_n_near += f.n_near != n;
      const double xi = go_feap::planning::xi(omission, static_cast<int>(f.cells.size()), f.duration, static_cast<int>(n));
      wrong_xi += !(std::abs(f.omission_likelihood - xi) <= 1e-9);
      const auto [it, fresh] = first_heard.emplace(f.id, std::make_pair(stamp, f.duration));
      if (fresh || stamp == it->second.first) continue;
      ++aged;
      wrong_age += !(std::abs((f.duration - it->second.second) - (stamp - it->second.first)) <= 1e-6);
    }
  });

  ASSERT_TRUE(spinUntil([&] { return status && status->state == go_feap::ExplorationStatus::FINISHED; }, 540.0))
      << "not finished: " << (status ? status->state_name : std::string("no status")) << " after "
      << (status ? status->elapsed : 0.0) << " s simulated\n"
      << go_feap::test::threadStacks("/go_feap_manager");
  EXPECT_EQ(status->finish_reason, "complete");
  std::cout << lists << " frontier lists: " << neighbours << " neighbours counted, " << aged << " ages compared\n";
  EXPECT_GT(neighbours, 0u) << "no frontier had a neighbour: N_near untested";
  EXPECT_GT(aged, 0u) << "no frontier in two lists: durations untested";
  EXPECT_EQ(wrong_n_near, 0u) << "frontiers whose N_near is not the count within frontier/s_near";
  EXPECT_EQ(wrong_xi, 0u) << "frontiers whose omission likelihood is not xi of their cells, duration and N_near";
  EXPECT_EQ(wrong_age, 0u) << "frontiers whose duration did not grow with the clock";
  std::cout << "finished (" << status->finish_reason << ") after " << status->elapsed << " s simulated, "
            << status->distance << " m\n";

  // What rviz/exploration.rviz shows is what the chain publishes: each display's topic is advertised with
  // the type the display takes (a display on a topic nothing sends stays empty without a word), and its 2D
  // Nav Goal reaches a subscriber (the layer manager's trigger).
  {
    std::string rviz_config;
    ASSERT_TRUE(pnh.getParam("rviz_config", rviz_config));
    const std::map<std::string, std::string> type_of = {
        {"rviz/PointCloud2", "sensor_msgs/PointCloud2"}, {"rviz/Marker", "visualization_msgs/Marker"},
        {"rviz/MarkerArray", "visualization_msgs/MarkerArray"}, {"rviz/Odometry", "nav_msgs/Odometry"},
        {"rviz/Path", "nav_msgs/Path"}, {"rviz/Image", "sensor_msgs/Image"}};
    ros::master::V_TopicInfo advertised;
    ASSERT_TRUE(ros::master::getTopics(advertised));
    std::size_t shown = 0;
    const YAML::Node rviz = YAML::LoadFile(rviz_config);
    for (const YAML::Node& d : rviz["Visualization Manager"]["Displays"]) {
      const auto type = type_of.find(d["Class"].as<std::string>());
      if (type == type_of.end()) continue;
      const std::string topic =
          (d["Topic"] ? d["Topic"] : d["Marker Topic"] ? d["Marker Topic"] : d["Image Topic"]).as<std::string>("");
      ++shown;
      EXPECT_TRUE(std::any_of(advertised.begin(), advertised.end(), [&](const ros::master::TopicInfo& t) {
        return t.name == topic && t.datatype == type->second;
      })) << d["Name"].as<std::string>("") << ": nothing publishes " << topic << " as " << type->second;
    }
    EXPECT_GE(shown, 12u);
    std::string goal;
    for (const YAML::Node& t : rviz["Visualization Manager"]["Tools"])
      if (t["Class"].as<std::string>() == "rviz/SetGoal") goal = t["Topic"].as<std::string>("");
    XmlRpc::XmlRpcValue request, response, payload;
    request[0] = ros::this_node::getName();
    ASSERT_TRUE(ros::master::execute("getSystemState", request, response, payload, true));
    bool heard = false;
    for (int i = 0; i < payload[1].size(); ++i)  // [topic, [subscribers]]
      heard = heard || (static_cast<std::string>(payload[1][i][0]) == goal && payload[1][i][1].size() > 0);
    EXPECT_TRUE(heard) << "nothing subscribes to the 2D Nav Goal's " << goal;
  }

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
  ASSERT_FALSE(live_coverage.empty()) << "nothing on coverage";
  for (double c : live_coverage) EXPECT_TRUE(c == -1.0 || (c >= 0.0 && c <= 1.0)) << c;
  EXPECT_NEAR(live_coverage.back(), summary["coverage"].get<double>(), 0.02);
  for (const char* key : {"scene", "seed", "planner", "exploration_time_s", "flight_distance_m", "compute_ms"})
    EXPECT_TRUE(summary.contains(key)) << key;
  // metrics.csv: time, known volume and distance never go back; its last row is the run as it finished, its
  // known volume the map's known voxels (the saved map's, taken a little later, once the vehicle held).
  {
    const auto rows = go_feap::test::readCsv(output_dir + "/metrics.csv");
    ASSERT_GE(rows.size(), 10u);
    for (std::size_t i = 1; i < rows.size(); ++i)
      for (const char* column : {"t", "explored_m3", "distance"})
        EXPECT_GE(rows[i].at(column), rows[i - 1].at(column)) << column << ", row " << i;
    double known_m3 = 0.0;
    for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) known_m3 += std::pow(it.getSize(), 3);
    const auto& last = rows.back();
    std::cout << "metrics.csv: " << rows.size() << " rows, last " << last.at("explored_m3") << " m^3 known (the saved map "
              << known_m3 << " m^3), " << last.at("distance") << " m\n";
    EXPECT_LE(last.at("explored_m3"), known_m3 + 1e-3);
    EXPECT_GE(last.at("explored_m3"), 0.95 * known_m3);
    EXPECT_NEAR(last.at("t"), summary["exploration_time_s"].get<double>(), 1e-3);
    EXPECT_NEAR(last.at("distance"), summary["flight_distance_m"].get<double>(), 1e-3);
    EXPECT_NEAR(last.at("coverage"), summary["coverage"].get<double>(), 1e-5);
    // Where the vehicle was when the run finished: the odometry nearest the FINISHED status's stamp (it may
    // have braked on for most of a metre after it).
    std::size_t at_finish = 0;
    for (std::size_t i = 0; i < path.size(); ++i)
      if (std::abs((path_stamps[i] - finished->header.stamp).toSec()) <
          std::abs((path_stamps[at_finish] - finished->header.stamp).toSec()))
        at_finish = i;
    EXPECT_LT((Vec3(last.at("x"), last.at("y"), last.at("z")) - path[at_finish]).norm(), 0.3)
        << "the last row's position is not where the vehicle was when the run finished";
  }

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
