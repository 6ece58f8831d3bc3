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
/// Why a trajectory would command more than max_speed (m/s), max_acceleration (m/s^2) or a heading rate
/// above max_yaw_rate (rad/s), or "" when it cannot: the control polygons' velocity and acceleration
/// points bound the curves' (convex hull). Catches finite control points that overflow (1e308 m) and knot
/// spans so short that the reference would leap to the end at once.
std::string motionProblem(const Trajectory& trajectory, double max_speed, double max_acceleration,
                          double max_yaw_rate);

}  // namespace go_feap::ros_traj
