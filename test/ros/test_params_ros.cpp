// rostest: a nodelet given an invalid or missing parameter does not start, and says which. The test
// loads each nodelet into an empty manager through its load_nodelet service, under a name whose private
// parameters (params.test) are the shipped config with one value made invalid or left out: the load
// fails and the manager logs a fatal message naming the parameter in full. The same nodelet with the
// shipped config unchanged starts, so each failure is the one parameter's doing, and the manager lives
// on through every refusal.
#include <gtest/gtest.h>
#include <nodelet/NodeletLoad.h>
#include <nodelet/NodeletUnload.h>
#include <ros/ros.h>
#include <geometry_msgs/PoseStamped.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include "ros_test_util.h"

namespace {

using go_feap::test::spinUntil;

struct Case {
  const char* name;  // the nodelet's name: its private parameters are /name/...
  const char* type;
  const char* key;   // the parameter the message must name, in full: /name/key (after a quote, what it says)
};

TEST(Parameters, ANodeletWithAnInvalidOrMissingParameterDoesNotStartAndNamesIt) {
  ros::NodeHandle nh;
  std::vector<std::string> fatal;
  auto log_sub = nh.subscribe<rosgraph_msgs::Log>("/rosout", 200, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->level >= rosgraph_msgs::Log::FATAL) fatal.push_back(m->msg);
  });
  ASSERT_TRUE(ros::service::waitForService("go_feap_manager/load_nodelet", ros::Duration(30.0)));
  ASSERT_TRUE(spinUntil([&] { return log_sub.getNumPublishers() > 0; }, 10.0));
  auto load = [](const std::string& name, const std::string& type) {
    nodelet::NodeletLoad srv;
    srv.request.name = "/" + name;
    srv.request.type = type;
    return ros::service::call("go_feap_manager/load_nodelet", srv) && srv.response.success;
  };

  ASSERT_TRUE(load("good_layer_manager", "go_feap/LayerManager")) << "the shipped config does not start";
  const std::vector<Case> cases = {
      {"bad_world_frame", "go_feap/GlobalPlanner", "world_frame"},              // '/world': tf2 refuses it
      {"bad_layers_rate", "go_feap/LayerManager", "layers/rate"},                // 1e9 Hz: a timer that never sleeps
      {"bad_layer_height", "go_feap/LayerManager", "layers: layer_height"},     // infinite: NaN bands
      {"bad_max_odom_step", "go_feap/LayerManager", "metrics/max_odom_step"},   // -1 m
      {"bad_collision_distance", "go_feap/MetricsRecorder", "metrics/collision_distance"},  // 0: no collision ever counted
      {"missing_layers", "go_feap/LayerManager", "layers/"},                    // no exploration.yaml at all
      {"bad_box", "go_feap/LayerManager", "exploration_box/min"},              // an infinite top: NaN bands
      {"bad_box_min", "go_feap/LayerManager", "exploration_box/min"},          // an infinite bottom
      {"bad_box_inverted", "go_feap/LayerManager", "exploration_box/min"},     // min above max in x
      {"empty_world_frame", "go_feap/GlobalPlanner", "world_frame"},           // no frame at all
      {"bad_box_length", "go_feap/LayerManager", "exploration_box/min"},       // 4 numbers: the 4th was dropped
      {"bad_box_text", "go_feap/LayerManager", "exploration_box/min' must be a list of 3 numbers"},  // "-3", a string
      {"bad_auto_start_type", "go_feap/LayerManager", "layers/auto_start' has the wrong type"},  // "yes", a string
      {"bad_extrinsic_length", "go_feap/DepthCamera", "depth_camera/T_B_C"},   // 17 numbers
      {"bad_pose_tolerance", "go_feap/EsdfMapper", "mapper/pose_tolerance"},    // 5 s
      {"bad_map_size", "go_feap/EsdfMapper", "exploration_box"},                // 1e6 m long: 2.9e10 voxels
      {"bad_cluster_extent", "go_feap/LocalPlanner", "frontier/max_cluster_extent"},  // NaN
      {"bad_local_input_speed", "go_feap/LocalPlanner", "local/max_input_speed"},  // NaN: every odometry refused
      {"bad_local_odom_timeout", "go_feap/LocalPlanner", "local/odom_timeout"},  // 0: every odometry stale at once
      {"bad_global_rate", "go_feap/GlobalPlanner", "global/rate"},              // 0: no tour after the first, in silence
      {"bad_sample_rate", "go_feap/MetricsRecorder", "metrics/sample_rate"},    // 0 Hz: a timer of infinite period
      {"bad_progress_period", "go_feap/MetricsRecorder", "metrics/progress_period"},  // NaN
      {"bad_camera_extrinsic", "go_feap/DepthCamera", "depth_camera/T_B_C"},    // a NaN translation
      {"bad_camera_offset", "go_feap/DepthCamera", "depth_camera/T_B_C"},      // 100 mm written as 100 m
      {"bad_odometry_camera_offset", "go_feap/OdometryTf", "T_B_C"},            // likewise, on board
      {"bad_camera_range", "go_feap/DepthCamera", "depth_camera/max_range"},    // 70 m in 16-bit millimetres
      {"bad_camera_rate", "go_feap/DepthCamera", "depth_camera/rate"},          // 30 Hz on 20 Hz odometry: came at 20 in silence
      {"bad_command_limit", "go_feap/QuadrotorSim", "simulation/max_command_acceleration"},  // NaN
      {"bad_input_speed", "go_feap/TrajectoryPlanner", "planner/max_input_speed"},  // NaN: no speed refused
      {"bad_command_timeout", "go_feap/TrajectoryPlanner", "planner/command_timeout"},  // 0: no command recent
      {"bad_server_yaw_rate", "go_feap/TrajectoryServer", "server/max_yaw_rate"},  // below optimizer/yaw_rate_max
      {"bad_server_speed", "go_feap/TrajectoryServer", "server/max_speed"},     // 2.2 m/s: below 2.8 (v_max with the tolerance, times 4/3 for a braking polygon)
      {"bad_server_tolerance", "go_feap/TrajectoryServer", "optimizer: limit_tolerance"},  // NaN: read as 0 in silence
      {"bad_server_start_offset", "go_feap/TrajectoryServer", "server/max_start_offset"},  // 0.8 m, below the planner's 1 m tracking error
      {"bad_start", "go_feap/QuadrotorSim", "start"},                           // 100 m outside the maze
      {"bad_start_in_wall", "go_feap/QuadrotorSim", "start' must lie in the scene's box, in free space"},  // in the outer wall
      {"bad_rate_factor", "go_feap/QuadrotorSim", "simulation/rate_factor"},    // 1e-9: the first step would wait 1e7 s
      {"bad_command_speed", "go_feap/QuadrotorSim", "simulation/max_command_speed"},  // 1e308: a guard letting anything by
      {"bad_warn_period", "go_feap/EsdfMapper", "mapper/warn_period"},          // 1e9 s: every warning silenced
      {"bad_output_dir", "go_feap/MetricsRecorder", "metrics/output_dir"},      // not makeable: the results lost at the end
      {"bad_odometry_warn_period", "go_feap/OdometryTf", "warn_period"},         // 1e9 s: every warning silenced
      {"bad_odometry_tilt", "go_feap/OdometryTf", "max_body_tilt"},             // 3.2 rad: past pi, nothing ever said
      {"empty_planner_name", "go_feap/MetricsRecorder", "metrics/planner"},     // summary.json's rows unnamed
  };
  for (const Case& c : cases) {
    const std::string full = std::string("/") + c.name + "/" + c.key;
    const std::string core = std::string("/") + c.name + ": " + c.key;  // a core config's own message
    fatal.clear();
    EXPECT_FALSE(load(c.name, c.type)) << c.name << " started";
    // Loaded again every 2 s until its message comes: a message logged before this node's /rosout
    // connection to the manager was up would be lost, and every refused load logs it again.
    ros::WallTime loaded = ros::WallTime::now();
    EXPECT_TRUE(spinUntil(
        [&] {
          for (const std::string& m : fatal)
            if (m.find(full) != std::string::npos || m.find(core) != std::string::npos) return true;
          if ((ros::WallTime::now() - loaded).toSec() >= 2.0) {
            EXPECT_FALSE(load(c.name, c.type)) << c.name << " started";
            loaded = ros::WallTime::now();
          }
          return false;
        },
        10.0))
        << c.name << ": no fatal message naming " << full << "; fatal messages: " << ::testing::PrintToString(fatal);
  }
  // The manager is still there: the good nodelet unloads.
  nodelet::NodeletUnload unload;
  unload.request.name = "/good_layer_manager";
  EXPECT_TRUE(ros::service::call("go_feap_manager/unload_nodelet", unload) && unload.response.success);
}

// A parameter that conflicts with the mapper's (viewpoints/clearance past esdf/max_distance: no viewpoint
// would pass) is found when the map comes, not at the start: the local planner starts, then names it in a
// fatal message and stops its manager, as a refused parameter ends a launch (it used to log an error every
// 10 s and plan nothing for good). params.test runs a mapper in a manager of its own, /NS/manager;
// the test feeds it frames, with each of which it sends its map's handle in the process.
// `ns` is the group of the manager, the mapper and the parameters of the nodelet `name` of `type`; `expected`
// begins the fatal message.
void expectTheConflictStopsTheManager(const std::string& ns, const std::string& name, const std::string& type,
                                      const std::string& expected) {
  ros::NodeHandle nh;
  std::vector<std::string> fatal;
  auto log_sub = nh.subscribe<rosgraph_msgs::Log>("/rosout", 200, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->level >= rosgraph_msgs::Log::FATAL) fatal.push_back(m->msg);
  });
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>(ns + "/camera_info", 1, /*latch=*/true);
  ros::Publisher depth_pub = nh.advertise<sensor_msgs::Image>(ns + "/depth", 5);
  ros::Publisher pose_pub = nh.advertise<geometry_msgs::PoseStamped>(ns + "/camera_pose", 5);
  ASSERT_TRUE(ros::service::waitForService(ns + "/manager/load_nodelet", ros::Duration(30.0)));
  // This test hears the manager's /rosout before the planner is loaded (a message would be lost before),
  // and the mapper hears the test.
  std::vector<std::string> publishers;
  ASSERT_TRUE(spinUntil(
      [&] {
        publishers = go_feap::test::publishersOf("/rosout");  // this node's own publisher among them
        return std::count(publishers.begin(), publishers.end(), "/" + ns + "/manager") == 1 &&
               log_sub.getNumPublishers() >= publishers.size() && info_pub.getNumSubscribers() > 0 &&
               depth_pub.getNumSubscribers() > 0 && pose_pub.getNumSubscribers() > 0;
      },
      20.0))
      << "/rosout: " << log_sub.getNumPublishers() << " connected of " << ::testing::PrintToString(publishers);
  nodelet::NodeletLoad srv;
  srv.request.name = "/" + ns + "/" + name;
  srv.request.type = type;
  ASSERT_TRUE(ros::service::call(ns + "/manager/load_nodelet", srv) && srv.response.success)
      << "its own parameters are valid: it starts";

  sensor_msgs::CameraInfo info;
  info.width = 64, info.height = 48;
  info.K = {32.0, 0.0, 32.0, 0.0, 32.0, 24.0, 0.0, 0.0, 1.0};
  info_pub.publish(info);
  sensor_msgs::Image depth;
  depth.header.frame_id = "camera";
  depth.width = info.width, depth.height = info.height;
  depth.encoding = "32FC1";
  depth.step = 4 * depth.width;
  const std::vector<float> metres(depth.width * depth.height, 2.0f);
  depth.data.resize(depth.step * depth.height);
  std::memcpy(depth.data.data(), metres.data(), depth.data.size());
  geometry_msgs::PoseStamped pose;
  pose.header.frame_id = "world";
  pose.pose.position.z = 1.0;
  pose.pose.orientation.w = 1.0;
  ros::WallTime sent;
  EXPECT_TRUE(spinUntil(
      [&] {
        if ((ros::WallTime::now() - sent).toSec() >= 0.2) {  // a frame every 0.2 s, until the message comes
          depth.header.stamp = pose.header.stamp = ros::Time::now();
          pose_pub.publish(pose);
          depth_pub.publish(depth);
          sent = ros::WallTime::now();
        }
        return std::any_of(fatal.begin(), fatal.end(), [&](const std::string& m) { return m.find(expected) != std::string::npos; });
      },
      20.0))
      << "no fatal message '" << expected << "'; fatal messages: " << ::testing::PrintToString(fatal);
  EXPECT_TRUE(spinUntil([&] { return !ros::service::exists(ns + "/manager/load_nodelet", false); }, 20.0))
      << "the manager still runs";
}

TEST(Parameters, AClearanceThatConflictsWithTheMappersStopsTheManagerAndNamesIt) {
  expectTheConflictStopsTheManager("conflict", "local_planner", "go_feap/LocalPlanner",
                                   "/conflict/local_planner: viewpoints: clearance must be <=");
}

// A sensor_range past the mapper's max_range likewise.
TEST(Parameters, ASensorRangePastTheMappersStopsTheManagerAndNamesIt) {
  expectTheConflictStopsTheManager("conflict_range", "local_planner", "go_feap/LocalPlanner",
                                   "/conflict_range/local_planner: viewpoints: sensor_range (4.500000 m) must not "
                                   "exceed occupancy: max_range (4.000000 m)");
}

// And a goal_tolerance under half the mapper's voxel diagonal, in the trajectory planner.
TEST(Parameters, AGoalToleranceUnderHalfTheMappersVoxelDiagonalStopsTheManagerAndNamesIt) {
  expectTheConflictStopsTheManager("conflict_goal", "trajectory_planner", "go_feap/TrajectoryPlanner",
                                   "/conflict_goal/trajectory_planner: planner: goal_tolerance must be at least half "
                                   "a voxel's diagonal (0.086603 m");
}

}  // namespace

GO_FEAP_ROSTEST_MAIN("test_params_ros")
