// Reporting the wall time of a planning block on `compute_time` (go_feap/ComputeTime), for the
// metrics recorder's per-block figures (paper Table IV).
#pragma once

#include <ros/ros.h>

#include <chrono>
#include <string>

#include "go_feap/ComputeTime.h"

namespace go_feap::ros_conv {

using WallClock = std::chrono::steady_clock;

/// Publishes the milliseconds elapsed since t0 for `block`.
inline void publishComputeTime(const ros::Publisher& pub, const std::string& block, WallClock::time_point t0) {
  ComputeTime msg;
  msg.header.stamp = ros::Time::now();
  msg.block = block;
  msg.ms = std::chrono::duration<double, std::milli>(WallClock::now() - t0).count();
  pub.publish(msg);
}

}  // namespace go_feap::ros_conv
