// rostest: no frontier over the size limit in view (as for a start facing a wall; here the limit is
// out of reach). Through the ROS chain, the layer manager asks for a look round (LayerBounds
// look_around) and the local planner turns the vehicle in place, round every heading, before the run
// ends FINISHED(complete). Without the look round it ended after about 2 s without turning.
// A second local planner, fed only by this test, checks that its turn-in-place target is repeated while
// the look round is asked for (a first publication the trajectory planner missed left the vehicle still),
// and dropped when the trajectory planner reports it failed.
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <std_msgs/UInt32.h>

#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include "go_feap/ExplorationStatus.h"
#include "go_feap/LayerBounds.h"
#include "go_feap/ViewpointPath.h"
#include "go_feap/ros/conversions.h"
#include "ros_test_util.h"

namespace {

using go_feap::test::spinUntil;

TEST(LookRound, NoFrontierInViewTurnsRoundBeforeEndingComplete) {
  ros::NodeHandle nh;
  go_feap::ExplorationStatus::ConstPtr status;
  bool look_around = false;
  std::optional<double> last_yaw;
  double turned = 0.0;  // rad, summed heading change
  auto status_sub = nh.subscribe<go_feap::ExplorationStatus>(
      "status", 10, [&](const go_feap::ExplorationStatus::ConstPtr& m) { status = m; });
  auto layer_sub = nh.subscribe<go_feap::LayerBounds>(
      "layer", 10, [&](const go_feap::LayerBounds::ConstPtr& m) { look_around = look_around || m->look_around; });
  auto odom_sub = nh.subscribe<nav_msgs::Odometry>("odom", 100, [&](const nav_msgs::Odometry::ConstPtr& m) {
    const double yaw = go_feap::ros_conv::yawOf(m->pose.pose.orientation);
    if (last_yaw) turned += std::abs(std::remainder(yaw - *last_yaw, 2.0 * M_PI));
    last_yaw = yaw;
  });
  ASSERT_TRUE(spinUntil([&] { return status && status->state == go_feap::ExplorationStatus::FINISHED; }, 240.0))
      << "not finished: " << (status ? status->state_name : std::string("no status")) << "\n"
      << go_feap::test::threadStacks("/go_feap_manager");
  std::cout << status->finish_reason << " after " << status->elapsed << " s simulated, " << status->distance
            << " m, turned " << turned << " rad\n";
  // FINISHED: no target after it (the local planner used to turn the vehicle in place again after every
  // turn, for ever, on the empty tours that followed). One already on its way may arrive within 1 s.
  int targets = 0;
  auto target_sub = nh.subscribe<go_feap::ViewpointPath>("local_target", 10,
                                                         [&](const go_feap::ViewpointPath::ConstPtr&) { ++targets; });
  ASSERT_TRUE(spinUntil([&] { return target_sub.getNumPublishers() > 0; }, 10.0))
      << "local_target is not connected: the count below would show nothing";
  spinUntil([] { return false; }, 1.0);
  targets = 0;
  spinUntil([] { return false; }, 4.0);
  EXPECT_EQ(targets, 0) << "local targets sent after FINISHED";
  EXPECT_EQ(status->state, go_feap::ExplorationStatus::FINISHED);
  EXPECT_EQ(status->finish_reason, "complete");
  EXPECT_TRUE(look_around) << "no look round asked";
  // Every octant of heading: at least six whole octants turned (3/4 of a turn), in place.
  EXPECT_GT(turned, 1.5 * M_PI);
  EXPECT_LT(status->distance, 1.0);
}

// The probe sees a vehicle hovering at (0, 0, 1) facing yaw 0 and is asked for a look round at 5 Hz. Its
// target, a turn in place by scan_step, is never reached: it must come again, with the same number, at
// each request (once only before the repeat: a trajectory planner that subscribed late never turned).
// Reached, it is followed by the next turn, with a new number.
TEST(LookRound, AnUnreachedTurnInPlaceIsRepeatedWhileALookRoundIsAsked) {
  ros::NodeHandle nh;
  double scan_step = 0.0;
  ASSERT_TRUE(ros::param::get("/probe_local_planner/local/scan_step", scan_step));
  std::vector<go_feap::ViewpointPath::ConstPtr> targets;
  auto target_sub = nh.subscribe<go_feap::ViewpointPath>(
      "probe/local_target", 20, [&](const go_feap::ViewpointPath::ConstPtr& m) { targets.push_back(m); });
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("probe/odom", 5);
  auto layer_pub = nh.advertise<go_feap::LayerBounds>("probe/layer", 1);
  auto status_pub = nh.advertise<go_feap::ExplorationStatus>("probe/status", 1, /*latch=*/true);
  go_feap::ExplorationStatus exploring;  // the probe acts only while the exploration is under way
  exploring.state = go_feap::ExplorationStatus::EXPLORE;
  exploring.state_name = "EXPLORE";
  status_pub.publish(exploring);
  double yaw = 0.0;
  bool malformed = false;  // the requests' band NaN at its bottom
  ros::WallTime last_odom, last_layer;
  // Spins, publishing the hover odometry at 20 Hz and the look round request at 5 Hz, until pred().
  auto spinPublishing = [&](auto pred, double wall_timeout) {
    return spinUntil(
        [&] {
          const ros::WallTime now = ros::WallTime::now();
          if ((now - last_odom).toSec() >= 0.05) {
            nav_msgs::Odometry odom;
            odom.header.stamp = ros::Time::now();
            odom.header.frame_id = "world";
            odom.pose.pose.position.z = 1.0;
            odom.pose.pose.orientation.z = std::sin(0.5 * yaw);
            odom.pose.pose.orientation.w = std::cos(0.5 * yaw);
            odom_pub.publish(odom);
            // Each followed by odometry the local planner refuses (a VIO glitch at 1e155 m/s, and a pose in
            // another frame 4 m away): taken, the turn would never be reached, or be turned at x = 4.
            nav_msgs::Odometry glitch = odom;
            glitch.twist.twist.linear.x = 1e155;
            odom_pub.publish(glitch);
            nav_msgs::Odometry foreign = odom;
            foreign.header.frame_id = "odom";
            foreign.pose.pose.position.x = 4.0;
            odom_pub.publish(foreign);
            last_odom = now;
          }
          if ((now - last_layer).toSec() >= 0.2 && odom_pub.getNumSubscribers() > 0) {
            go_feap::LayerBounds layer;
            layer.header.stamp = ros::Time::now();
            layer.count = 1;
            layer.z_max = 3.0;
            if (malformed) layer.z_min = std::numeric_limits<double>::quiet_NaN();
            layer.look_around = true;
            layer_pub.publish(layer);
            last_layer = now;
          }
          return pred();
        },
        wall_timeout);
  };
  ASSERT_TRUE(spinPublishing([&] { return !targets.empty(); }, 60.0)) << "no probe/local_target";
  const go_feap::ViewpointPath first = *targets.front();
  ASSERT_EQ(first.positions.size(), 1u);
  EXPECT_NEAR(first.positions[0].x, 0.0, 1e-9);
  EXPECT_NEAR(first.positions[0].y, 0.0, 1e-9);
  EXPECT_NEAR(first.positions[0].z, 1.0, 1e-9);
  EXPECT_NEAR(first.yaws[0], scan_step, 1e-6);
  EXPECT_EQ(first.frontier_ids, std::vector<std::uint32_t>{0});
  // Unreached: repeated at each request, with its number.
  ASSERT_TRUE(spinPublishing([&] { return targets.size() >= 5; }, 10.0))
      << "the unreached turn was published " << targets.size() << " time(s) in 10 s of look round requests";
  for (const auto& t : targets) {
    EXPECT_EQ(t->target_seq, first.target_seq);
    EXPECT_DOUBLE_EQ(t->yaws.at(0), first.yaws[0]);
  }
  // Failed (the trajectory planner found no way to turn there, and reports frontier id 0): dropped, and
  // the next request turns anew from the same heading. Kept, it was repeated for ever and failed again
  // each time, while the tours that would blacklist their frontiers waited for it.
  auto failed_pub = nh.advertise<std_msgs::UInt32>("probe/frontier_failed", 10);
  ASSERT_TRUE(spinPublishing([&] { return failed_pub.getNumSubscribers() > 0; }, 10.0));
  std_msgs::UInt32 failed;
  failed.data = 0;
  failed_pub.publish(failed);
  ASSERT_TRUE(spinPublishing([&] { return targets.back()->target_seq != first.target_seq; }, 10.0))
      << "the failed turn was still repeated";
  const go_feap::ViewpointPath second = *targets.back();
  EXPECT_EQ(second.target_seq, first.target_seq + 1);
  EXPECT_NEAR(second.yaws.at(0), scan_step, 1e-6);
  // Reached: the next turn, numbered anew.
  yaw = second.yaws[0];
  ASSERT_TRUE(spinPublishing([&] { return targets.back()->target_seq != second.target_seq; }, 10.0))
      << "no next turn once the second was reached";
  EXPECT_EQ(targets.back()->target_seq, second.target_seq + 1);
  EXPECT_NEAR(std::remainder(targets.back()->yaws.at(0) - 2.0 * scan_step, 2.0 * M_PI), 0.0, 1e-6);
  // Requests in a malformed band (NaN at its bottom) are refused whole: the unreached turn is not repeated
  // for them (taken, the band would have sampled no viewpoint, and every tour frontier failed). Well formed
  // again, they are answered.
  malformed = true;
  spinPublishing([] { return false; }, 0.5);  // a well-formed request may still be on its way
  const std::size_t before = targets.size();
  spinPublishing([] { return false; }, 2.0);
  EXPECT_EQ(targets.size(), before) << "a target for a look round asked in a NaN band";
  malformed = false;
  EXPECT_TRUE(spinPublishing([&] { return targets.size() > before; }, 10.0)) << "no target once the band was well formed";
}

}  // namespace

GO_FEAP_ROSTEST_MAIN("test_look_round_ros")
