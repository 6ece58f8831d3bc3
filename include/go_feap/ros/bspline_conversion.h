// go_feap/Bspline <-> trajectory::UniformBspline.
#pragma once

#include <ros/time.h>

#include "go_feap/Bspline.h"
#include "go_feap/common/result.h"
#include "go_feap/trajectory/trajectory_planner.h"

namespace go_feap::ros_traj {

/// A core trajectory with the id and start time the message carries.
struct Trajectory : trajectory::Trajectory {
  std::int64_t id = 0;
  ros::Time start_time;
};

/// knots = the uniform knot vector (u_i = (i - p) dt); yaw_dt = the yaw spline's knot span.
Bspline toMsg(const Trajectory& trajectory);
/// Checks sizes, spacing and finiteness; the message says what is wrong.
common::Result<Trajectory> fromMsg(const Bspline& msg);

}  // namespace go_feap::ros_traj
