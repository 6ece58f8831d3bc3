// rostest: no frontier over the size limit in view (as for a start facing a wall; here the limit is
// out of reach). Through the ROS chain, the layer manager asks for a look round (LayerBounds
// look_around) and the local planner turns the vehicle in place, round every heading, before the run
// ends FINISHED(complete). Without the look round it ended after about 2 s without turning.
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>

#include <cmath>
#include <optional>

#include "go_feap/ExplorationStatus.h"
#include "go_feap/LayerBounds.h"
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
      << "not finished: " << (status ? status->state_name : std::string("no status"));
  std::cout << status->finish_reason << " after " << status->elapsed << " s simulated, " << status->distance
            << " m, turned " << turned << " rad\n";
  EXPECT_EQ(status->finish_reason, "complete");
  EXPECT_TRUE(look_around) << "no look round asked";
  // Every octant of heading: at least six whole octants turned (3/4 of a turn), in place.
  EXPECT_GT(turned, 1.5 * M_PI);
  EXPECT_LT(status->distance, 1.0);
}

}  // namespace

GO_FEAP_ROSTEST_MAIN("test_look_round_ros")
