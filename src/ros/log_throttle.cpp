#include "go_feap/ros/log_throttle.h"

namespace go_feap::ros_log {

bool Throttle::pass(const std::string& site, double period, double now) {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto [it, first] = last_.try_emplace(site, now);
  if (first) return true;
  if (!(now >= it->second + period || now < it->second)) return false;
  it->second = now;
  return true;
}

}  // namespace go_feap::ros_log
