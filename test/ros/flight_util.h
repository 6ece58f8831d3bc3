// Trajectories the rostests send to a trajectory server of their own.
#pragma once

#include <ros/time.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>

#include "go_feap/ros/bspline_conversion.h"

namespace go_feap::test {

// A straight flight from a to b over 4 knot spans of `span` s (7 control points: at rest at both ends),
// heading `yaw`, numbered `id`, starting at `start`.
inline ros_traj::Trajectory straightFlight(const Eigen::Vector3d& a, const Eigen::Vector3d& b, std::int64_t id,
                                           const ros::Time& start, double yaw = 0.0, double span = 0.75) {
  Eigen::MatrixXd q(3, 7), y = Eigen::MatrixXd::Constant(1, 4, yaw);
  for (int i = 0; i < 7; ++i) q.col(i) = a + (b - a) * std::clamp((i - 1) / 4.0, 0.0, 1.0);
  ros_traj::Trajectory t;
  t.position = trajectory::UniformBspline(q, 3, span);
  t.yaw = trajectory::UniformBspline(y, 3, span);
  t.id = id;
  t.start_time = start;
  return t;
}

}  // namespace go_feap::test
