// rostest: onboard.launch (D435i + VIO configuration) starts and runs on simulated inputs: the
// depth arrives as 16UC1 millimetres and is integrated through TF lookups (sync_mode tf); the
// OdometryTf nodelet turns odometry into world -> body_vio and adds the D435i extrinsic from
// config/d435i.yaml; exploration waits for the trigger (nothing is planned, targeted or flown before it,
// frontiers in view or not), then position commands flow and the metrics
// recorder publishes the flown path. The simulator's topics are under /vehicle, which onboard.test names
// in onboard.launch's arguments.
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <std_srvs/Trigger.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/transform_listener.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <vector>

#include "go_feap/Bspline.h"
#include "go_feap/ExplorationStatus.h"
#include "go_feap/FrontierArray.h"
#include "go_feap/GlobalTour.h"
#include "go_feap/MapUpdate.h"
#include "go_feap/PositionCommand.h"
#include "go_feap/ViewpointPath.h"
#include "ros_test_util.h"

namespace {

using go_feap::test::spinUntil;

TEST(Onboard, RunsTheChainOnD435iDepthAndVioOdometry) {
  ros::NodeHandle nh;
  sensor_msgs::Image::ConstPtr depth;
  nav_msgs::Odometry::ConstPtr odom;
  go_feap::ExplorationStatus::ConstPtr status;
  std::size_t changed = 0, commands = 0;
  auto depth_sub = nh.subscribe<sensor_msgs::Image>("vehicle/depth", 2, [&](const sensor_msgs::Image::ConstPtr& m) { depth = m; });
  std::vector<Eigen::Vector3d> odom_positions;  // every odometry position, for the flown path
  auto odom_sub = nh.subscribe<nav_msgs::Odometry>("vehicle/odom", 1000, [&](const nav_msgs::Odometry::ConstPtr& m) {
    odom = m;
    odom_positions.emplace_back(m->pose.pose.position.x, m->pose.pose.position.y, m->pose.pose.position.z);
  });
  std::size_t integrated = 0;  // frames (a still vehicle changes voxels only in the first frames, which
                              // may come before this subscription connects)
  auto update_sub = nh.subscribe<go_feap::MapUpdate>("map_update", 10, [&](const go_feap::MapUpdate::ConstPtr& m) {
    changed += m->changed_voxels;
    ++integrated;
  });
  auto status_sub = nh.subscribe<go_feap::ExplorationStatus>(
      "status", 5, [&](const go_feap::ExplorationStatus::ConstPtr& m) { status = m; });
  nav_msgs::Path::ConstPtr path;
  auto path_sub = nh.subscribe<nav_msgs::Path>("flown_path", 2, [&](const nav_msgs::Path::ConstPtr& m) { path = m; });
  std::size_t following = 0;  // commands that follow a trajectory (not a hold)
  auto cmd_sub = nh.subscribe<go_feap::PositionCommand>("vehicle/position_cmd", 10, [&](const go_feap::PositionCommand::ConstPtr& m) {
    ++commands;
    following += m->trajectory_flag != go_feap::PositionCommand::TRAJECTORY_STATUS_EMPTY;
  });
  // What the planners send: nothing of it before the trigger.
  std::size_t tours = 0, targets = 0, trajectories = 0, frontiers = 0;
  auto tour_sub = nh.subscribe<go_feap::GlobalTour>("global_tour", 10, [&](const go_feap::GlobalTour::ConstPtr&) { ++tours; });
  auto target_sub =
      nh.subscribe<go_feap::ViewpointPath>("local_target", 10, [&](const go_feap::ViewpointPath::ConstPtr&) { ++targets; });
  auto bspline_sub =
      nh.subscribe<go_feap::Bspline>("bspline", 10, [&](const go_feap::Bspline::ConstPtr&) { ++trajectories; });
  auto frontier_sub = nh.subscribe<go_feap::FrontierArray>(
      "frontiers", 10, [&](const go_feap::FrontierArray::ConstPtr& m) { frontiers = std::max(frontiers, m->frontiers.size()); });
  std::vector<std::string> warnings;  // from /rosout, heard from the start: its connections come one by one
  ros::Subscriber log_sub = nh.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->level == rosgraph_msgs::Log::WARN) warnings.push_back(m->msg);
  });
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);

  ASSERT_TRUE(spinUntil([&] { return depth && odom && status; }, 60.0)) << "no depth, odometry or status";
  EXPECT_EQ(depth->encoding, "16UC1");
  {  // Millimetres in the camera's range, or 0 for no measurement (the renderer's +-inf and NaN, REP 117:
     // converted unpatched, +inf saturated to 65535 mm, a wall 65 m away)
    double min_range = 0.0, max_range = 0.0;
    ASSERT_TRUE(ros::param::get("/vehicle/depth_camera/depth_camera/min_range", min_range));
    ASSERT_TRUE(ros::param::get("/vehicle/depth_camera/depth_camera/max_range", max_range));
    ASSERT_EQ(depth->step, depth->width * 2);
    std::size_t in_range = 0, none = 0;
    for (std::size_t i = 0; i + 1 < depth->data.size(); i += 2) {
      std::uint16_t mm;
      std::memcpy(&mm, &depth->data[i], 2);
      in_range += mm >= std::floor(1000.0 * min_range) && mm <= std::ceil(1000.0 * max_range);
      none += mm == 0;
    }
    EXPECT_EQ(in_range + none, std::size_t{depth->width} * depth->height) << "millimetres out of range";
    EXPECT_GT(in_range, 0u);
  }
  // Frames integrated, and frontiers found in them (the finder publishes after each frame).
  ASSERT_TRUE(spinUntil([&] { return integrated >= 5 && frontiers > 0; }, 60.0))
      << "the mapper integrated " << integrated << " 16UC1 frame(s) via TF (" << changed
      << " voxels changed seen), with " << frontiers << " frontiers";
  EXPECT_EQ(status->state, go_feap::ExplorationStatus::WAIT_TRIGGER) << "onboard waits for a trigger";
  // Frontiers in view, and 3 s more (30 global planner periods): still nothing planned, targeted or flown,
  // and the vehicle where it was (the planners used to act before the trigger: only the layer manager
  // waited for it).
  // Every planner's output and the command stream heard, so that the counts below cannot be zero for want of a
  // connection.
  ASSERT_TRUE(spinUntil([&] {
    return tour_sub.getNumPublishers() > 0 && target_sub.getNumPublishers() > 0 &&
           bspline_sub.getNumPublishers() > 0 && cmd_sub.getNumPublishers() > 0;
  }, 20.0)) << "global_tour, local_target, bspline or vehicle/position_cmd not connected";
  // A 2D Nav Goal from an rviz on the master meanwhile: no trigger on board (layers/goal_trigger false).
  ros::Publisher goal_pub = nh.advertise<geometry_msgs::PoseStamped>("/move_base_simple/goal", 1);
  spinUntil([] { return false; }, 1.0);
  EXPECT_EQ(goal_pub.getNumSubscribers(), 0u) << "the layer manager listens to move_base_simple/goal on board";
  geometry_msgs::PoseStamped goal;
  goal.header.frame_id = "world";
  goal.pose.orientation.w = 1.0;
  goal_pub.publish(goal);
  const nav_msgs::Odometry::ConstPtr waiting = odom;
  spinUntil([] { return false; }, 3.0);
  EXPECT_EQ(status->state, go_feap::ExplorationStatus::WAIT_TRIGGER);
  EXPECT_EQ(tours + targets + trajectories, 0u)
      << tours << " global_tour, " << targets << " local_target and " << trajectories << " bspline before the trigger";
  EXPECT_EQ(following, 0u) << "position commands following a trajectory before the trigger";
  EXPECT_EQ(commands, 0u) << "position commands before the first trajectory (a hold of the pose at launch, on the "
                             "ground on a real drone, would pull one taken off by hand back down)";
  const auto& a = waiting->pose.pose.position;
  const auto& b = odom->pose.pose.position;
  EXPECT_LT(std::hypot(a.x - b.x, a.y - b.y, a.z - b.z), 0.05) << "the vehicle moved before the trigger";

  // world -> body_vio follows odometry; body_vio -> camera_depth_optical_frame is the D435i extrinsic.
  // Looked up at the stamp of an odometry message (OdometryTf stamps the TF with it), so the
  // comparison does not depend on whether the vehicle moved in between.
  // One stamp is tried for 2 s before a newer one: the newest odometry is often a hop ahead of its TF.
  geometry_msgs::TransformStamped tf;
  nav_msgs::Odometry::ConstPtr at;
  ros::WallTime taken;
  ASSERT_TRUE(spinUntil(
      [&] {
        if (!at || (ros::WallTime::now() - taken).toSec() > 2.0) {
          at = odom;
          taken = ros::WallTime::now();
        }
        try {
          tf = buffer.lookupTransform("world", "camera_depth_optical_frame", at->header.stamp);
          return true;
        } catch (const tf2::TransformException&) {
          return false;
        }
      },
      20.0));
  Eigen::Isometry3d T_B_C = Eigen::Isometry3d::Identity();
  T_B_C.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T_B_C.translation() << 0.10, 0.0, 0.02;
  Eigen::Isometry3d T_W_B;
  tf2::fromMsg(at->pose.pose, T_W_B);
  const Eigen::Isometry3d expected = T_W_B * T_B_C, got = tf2::transformToEigen(tf);
  EXPECT_LT((expected.translation() - got.translation()).norm(), 1e-6);
  EXPECT_TRUE(expected.linear().isApprox(got.linear(), 1e-6));

  std_srvs::Trigger trigger;
  ASSERT_TRUE(ros::service::waitForService("trigger", ros::Duration(10.0)));
  ASSERT_TRUE(ros::service::call("trigger", trigger));
  EXPECT_TRUE(trigger.response.success) << trigger.response.message;
  ASSERT_TRUE(spinUntil([&] { return status->state == go_feap::ExplorationStatus::EXPLORE; }, 20.0));
  const std::size_t before = commands;
  EXPECT_TRUE(spinUntil([&] { return commands > before + 50 && following > 0; }, 20.0))
      << "no position commands following a trajectory";
  EXPECT_GT(tours, 0u);
  EXPECT_GT(targets, 0u);
  // The metrics recorder (sensor_view.launch) records the flight in the world frame: a path that goes
  // 0.3 m from where it began, each pose a position the odometry gave.
  auto reach = [&] {
    if (!path || path->poses.empty()) return 0.0;
    const auto& a = path->poses.front().pose.position;
    double most = 0.0;
    for (const auto& q : path->poses)
      most = std::max(most, std::hypot(q.pose.position.x - a.x, q.pose.position.y - a.y, q.pose.position.z - a.z));
    return most;
  };
  EXPECT_TRUE(spinUntil([&] { return reach() > 0.3; }, 30.0))
      << "no flown_path from the recorder that shows the flight (" << (path ? path->poses.size() : 0u)
      << " poses reaching " << reach() << " m from the first)";
  if (path) {
    // The path as it was when it showed the flight: a later one may hold poses of odometry that reaches this
    // test after the path (two publishers, two connections). Its poses are then matched against the
    // odometry received up to 5 s later; a pose that is no odometry position never matches.
    const nav_msgs::Path::ConstPtr shown = path;
    EXPECT_EQ(shown->header.frame_id, "world");
    auto unmatched = [&] {
      std::size_t n = 0;
      for (const auto& q : shown->poses) {
        const Eigen::Vector3d p(q.pose.position.x, q.pose.position.y, q.pose.position.z);
        n += std::none_of(odom_positions.begin(), odom_positions.end(),
                          [&](const Eigen::Vector3d& o) { return (o - p).norm() < 1e-9; });
      }
      return n;
    };
    spinUntil([&] { return unmatched() == 0; }, 5.0);
    EXPECT_EQ(unmatched(), 0u) << "flown_path poses that are no odometry position, of " << shown->poses.size();
    for (const auto& q : shown->poses) EXPECT_EQ(q.header.frame_id, "world");
  }
  // onboard.launch lays the D435i's sensor model (config/d435i_viewpoints.yaml, 1.34 x 0.98 rad) over
  // exploration.yaml's: nothing is said of the simulated camera's 80 x 60 degrees, nor of a D435i's
  // camera_info at any of its depth profiles (sent below, before the narrow one, on the same topic). A
  // narrower camera_info on the onboard topic (a driver restarted at another resolution) is named by the
  // local planner, which hears it there too: its viewpoints would be scored on cells the camera does not see.
  for (const std::string& w : warnings) EXPECT_EQ(w.find("must not exceed the depth camera's"), std::string::npos) << w;
  // The simulated odometry's body is FLU and flies level: OdometryTf says nothing of its tilt.
  for (const std::string& w : warnings) EXPECT_EQ(w.find("from the world's up"), std::string::npos) << w;
  ros::Publisher info_pub = nh.advertise<sensor_msgs::CameraInfo>("vehicle/camera_info", 1);
  // One connection: the mapper and the local planner share the manager's process.
  ASSERT_TRUE(spinUntil([&] { return info_pub.getNumSubscribers() >= 1; }, 20.0)) << "vehicle/camera_info unheard";
  sensor_msgs::CameraInfo narrow;
  narrow.header.frame_id = depth->header.frame_id;
  narrow.width = 640, narrow.height = 480;
  narrow.K = {500.0, 0.0, 319.5, 0.0, 500.0, 239.5, 0.0, 0.0, 1.0};  // 65 x 51 degrees
  // D435i depth profiles, with a focal length at the long end of the units' spread and the principal point
  // 3.5 px off the centre towards a corner: 848 x 480 (88.8 x 57.6 degrees), 640 x 480 (77.9 x 62.1 degrees,
  // the sides cropped), 1280 x 720 (88.8 x 57.5 degrees).
  std::vector<sensor_msgs::CameraInfo> d435i(3, narrow);
  d435i[0].width = 848, d435i[0].height = 480;
  d435i[0].K = {430.0, 0.0, 420.5, 0.0, 430.0, 236.0, 0.0, 0.0, 1.0};
  d435i[1].K = {392.0, 0.0, 316.5, 0.0, 392.0, 243.5, 0.0, 0.0, 1.0};
  d435i[2].width = 1280, d435i[2].height = 720;
  d435i[2].K = {650.0, 0.0, 636.5, 0.0, 650.0, 356.0, 0.0, 0.0, 1.0};
  // Sent every `every` s (of the simulated clock) until a warning holds `said`.
  auto sendUntilSaid = [&](const std::function<void()>& send, double every, const std::string& said, double timeout) {
    ros::Time sent;
    return spinUntil([&] {
      if (sent.isZero() || (ros::Time::now() - sent).toSec() > every) {
        send();
        sent = ros::Time::now();
      }
      return std::any_of(warnings.begin(), warnings.end(), [&](const std::string& w) { return w.find(said) != std::string::npos; });
    }, timeout);
  };
  // Each D435i profile 0.25 s (simulated) before the next, the narrow camera last: far enough apart for the
  // planner's queue of 2 among the simulator's own camera_info (15 Hz), so the D435i's have been checked once
  // the narrow one is named.
  std::size_t sends = 0;
  EXPECT_TRUE(sendUntilSaid([&] {
    sensor_msgs::CameraInfo& info = sends % 4 < 3 ? d435i[sends % 4] : narrow;
    ++sends;
    info.header.stamp = ros::Time::now();
    info_pub.publish(info);
  }, 0.25, "/local_planner: viewpoints: hfov (1.340000 rad) must not exceed the depth camera's (1.138626 rad)", 30.0))
      << "the local planner said nothing of a camera narrower than its viewpoints";
  for (const std::string& w : warnings)
    if (w.find("must not exceed the depth camera's") != std::string::npos)
      EXPECT_NE(w.find("(1.138626 rad)"), std::string::npos) << "a D435i's camera_info was judged too narrow: " << w;
  // The local planner hears the onboard depth topic too (its obstacle window judges the clutter): an rgb8
  // image sent there is refused by it, by name. Unconnected, nothing would be said and the window would stay
  // empty, silently.
  ros::Publisher rgb_pub = nh.advertise<sensor_msgs::Image>("vehicle/depth", 1);
  ASSERT_TRUE(spinUntil([&] { return rgb_pub.getNumSubscribers() >= 2; }, 20.0))
      << "vehicle/depth has " << rgb_pub.getNumSubscribers() << " subscribers (the manager's and this test's)";
  sensor_msgs::Image rgb = *depth;
  rgb.encoding = "rgb8";
  rgb.step = rgb.width * 3;
  rgb.data.assign(std::size_t{rgb.step} * rgb.height, 0);
  // Sent again past the warning's 5 s throttle (of the simulated clock) until heard.
  EXPECT_TRUE(sendUntilSaid([&] {
    rgb.header.stamp = ros::Time::now();
    rgb_pub.publish(rgb);
  }, 5.5, "/local_planner: depth image refused", 60.0))
      << "the local planner said nothing of an rgb8 image on the onboard depth topic";
}

}  // namespace

GO_FEAP_ROSTEST_MAIN("test_onboard_ros")
