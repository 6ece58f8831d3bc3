// Small message <-> Eigen conversions shared by the nodelets.
#pragma once

#include <geometry_msgs/Point.h>
#include <geometry_msgs/Quaternion.h>
#include <geometry_msgs/Vector3.h>

#include <Eigen/Geometry>

#include <cmath>

#include "go_feap/common/grid.h"

namespace go_feap::ros_conv {

inline geometry_msgs::Point toPoint(const common::Vec3& v) {
  geometry_msgs::Point p;
  p.x = v.x();
  p.y = v.y();
  p.z = v.z();
  return p;
}

inline common::Vec3 toVec3(const geometry_msgs::Point& p) { return common::Vec3(p.x, p.y, p.z); }

/// Heading (rad, about world z) of an orientation.
inline double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}

/// A velocity given in the body frame of `orientation` (nav_msgs/Odometry's twist, which is in the
/// child frame) turned into the world frame. The quaternion is normalised first.
inline common::Vec3 worldVelocity(const geometry_msgs::Quaternion& orientation, const geometry_msgs::Vector3& body) {
  const Eigen::Quaterniond q(orientation.w, orientation.x, orientation.y, orientation.z);
  return q.normalized() * common::Vec3(body.x, body.y, body.z);
}

}  // namespace go_feap::ros_conv
