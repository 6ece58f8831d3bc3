// Message <-> Eigen conversions of the nodelets (go_feap/ros/conversions.h), against rotations worked
// out by hand: the simulator publishes the odometry twist in the body frame, and the local planner needs
// it in the world frame.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "go_feap/ros/conversions.h"

namespace {

using go_feap::common::Vec3;
using go_feap::ros_conv::odometryPoseProblem;
using go_feap::ros_conv::worldVelocity;
using go_feap::ros_conv::yawOf;

geometry_msgs::Quaternion quat(double w, double x, double y, double z) {
  geometry_msgs::Quaternion q;
  q.w = w, q.x = x, q.y = y, q.z = z;
  return q;
}

geometry_msgs::Vector3 vec(double x, double y, double z) {
  geometry_msgs::Vector3 v;
  v.x = x, v.y = y, v.z = z;
  return v;
}

TEST(Conversions, WorldVelocityTurnsTheBodyTwistIntoTheWorld) {
  const double h = std::sqrt(0.5);
  // Level, heading +y (90 deg about z): flying forward in the body is +y in the world.
  const auto yaw90 = quat(h, 0, 0, h);
  EXPECT_NEAR(yawOf(yaw90), M_PI / 2, 1e-12);
  EXPECT_TRUE(worldVelocity(yaw90, vec(2, 0, 0)).isApprox(Vec3(0, 2, 0), 1e-12));
  EXPECT_TRUE(worldVelocity(yaw90, vec(0, 1, 0)).isApprox(Vec3(-1, 0, 0), 1e-12));
  // Heading back (180 deg): forward is -x; up stays up.
  EXPECT_TRUE(worldVelocity(quat(0, 0, 0, 1), vec(1, 0, 0.5)).isApprox(Vec3(-1, 0, 0.5), 1e-12));
  // Pitched nose down by 90 deg about y: body forward points down the world z.
  EXPECT_TRUE(worldVelocity(quat(h, 0, h, 0), vec(1, 0, 0)).isApprox(Vec3(0, 0, -1), 1e-12));
  // Identity, and a quaternion not of unit length (normalised first): the speed is kept.
  EXPECT_TRUE(worldVelocity(quat(1, 0, 0, 0), vec(0.3, -0.2, 0.1)).isApprox(Vec3(0.3, -0.2, 0.1), 1e-12));
  EXPECT_TRUE(worldVelocity(quat(2 * h, 0, 0, 2 * h), vec(2, 0, 0)).isApprox(Vec3(0, 2, 0), 1e-12));
  // The inverse of what the simulator publishes: body = q^-1 * world.
  const Eigen::Quaterniond q = Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized();
  const Vec3 world(1.2, -0.7, 0.4);
  const Vec3 body = q.inverse() * world;
  EXPECT_TRUE(worldVelocity(quat(q.w(), q.x(), q.y(), q.z()), vec(body.x(), body.y(), body.z()))
                  .isApprox(world, 1e-12));
}

TEST(Conversions, YawOfAnyScaledQuaternionIsItsRotationsHeading) {
  // Against the heading of the rotation matrix's x axis, for rotations about every axis and scales.
  const Eigen::Quaterniond rotations[] = {
      Eigen::Quaterniond(Eigen::AngleAxisd(2.5, Vec3::UnitZ())),
      Eigen::Quaterniond(Eigen::AngleAxisd(-1.2, Vec3::UnitZ()) * Eigen::AngleAxisd(0.3, Vec3::UnitY())),
      Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized()};
  for (const Eigen::Quaterniond& r : rotations) {
    const Vec3 x = r.toRotationMatrix().col(0);
    for (double scale : {1.0, 0.5, 3.0})
      EXPECT_NEAR(yawOf(quat(scale * r.w(), scale * r.x(), scale * r.y(), scale * r.z())), std::atan2(x.y(), x.x()),
                  1e-12)
          << "scale " << scale;
  }
}

TEST(Conversions, OdometryPosesThatAreNotFiniteOrNotARotationAreNamed) {
  geometry_msgs::Pose pose;
  pose.position.x = 1.0, pose.position.y = -2.0, pose.position.z = 1.5;
  pose.orientation = quat(std::sqrt(0.5), 0, 0, std::sqrt(0.5));
  EXPECT_EQ(odometryPoseProblem(pose), "");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  geometry_msgs::Pose bad = pose;
  bad.position.y = nan;
  EXPECT_NE(odometryPoseProblem(bad).find("position"), std::string::npos) << odometryPoseProblem(bad);
  bad = pose;
  bad.position.z = std::numeric_limits<double>::infinity();
  EXPECT_NE(odometryPoseProblem(bad).find("position"), std::string::npos);
  bad = pose;
  bad.orientation.z = nan;  // a finite position with an unusable heading: what the planners once took
  EXPECT_NE(odometryPoseProblem(bad).find("orientation"), std::string::npos) << odometryPoseProblem(bad);
  bad.orientation = quat(0, 0, 0, 0);  // left unset
  EXPECT_NE(odometryPoseProblem(bad).find("not a unit quaternion"), std::string::npos) << odometryPoseProblem(bad);
  bad.orientation = quat(2.0, 0, 0, 0);
  EXPECT_NE(odometryPoseProblem(bad).find("orientation"), std::string::npos);
  // Within 1e-3 of unit length (as tf2 accepts): used.
  bad.orientation = quat(1.0005, 0, 0, 0);
  EXPECT_EQ(odometryPoseProblem(bad), "");
}

}  // namespace
