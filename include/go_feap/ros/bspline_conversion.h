// go_feap/Bspline <-> trajectory::UniformBspline.
#pragma once

#include <ros/time.h>

#include "go_feap/Bspline.h"
#include "go_feap/common/result.h"
#include "go_feap/trajectory/bspline.h"

namespace go_feap::ros_traj {

/// A position spline and a yaw spline that start together.
struct Trajectory {
  std::int64_t id = 0;
  ros::Time start_time;
  trajectory::UniformBspline position;  ///< 3-D
  trajectory::UniformBspline yaw;       ///< 1-D
  double duration() const { return position.duration(); }
};

/// knots = the uniform knot vector (u_i = (i - p) dt); yaw_dt = the yaw spline's knot span.
Bspline toMsg(const Trajectory& trajectory);
/// Checks sizes, spacing and finiteness; the message says what is wrong.
common::Result<Trajectory> fromMsg(const Bspline& msg);

}  // namespace go_feap::ros_traj
