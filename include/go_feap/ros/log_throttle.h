// Throttled logging that belongs to one nodelet. rosconsole's *_THROTTLE macros keep one static per call
// site, shared by every nodelet of the process (one mapper's refusals silenced another's), and count the
// first period from time 0: under a simulated clock that starts near 0, a site's every message in its
// first period was dropped (a lone bad message in the first seconds of a simulation went unsaid). Here the
// first message of a site always passes, and each nodelet keeps its own record.
#pragma once

#include <ros/ros.h>

#include <mutex>
#include <string>
#include <unordered_map>

namespace go_feap::ros_log {

/// When each message site last logged, by the site's key. Thread-safe (the simulator's own thread logs
/// beside its callbacks, and onInit runs beside them).
class Throttle {
 public:
  /// True when the message of `site` is to be logged at ROS time `now` (s): the site's first message, one
  /// at least `period` s after the last logged, or one from before it (the clock went back: a bag looped,
  /// a simulation restarted). A message that passes is recorded as logged.
  bool pass(const std::string& site, double period, double now);

 private:
  std::mutex mutex_;
  std::unordered_map<std::string, double> last_;
};

}  // namespace go_feap::ros_log

#define GO_FEAP_LOG_THROTTLE_STRINGIFY_(x) #x
#define GO_FEAP_LOG_THROTTLE_SITE_(line) __FILE__ ":" GO_FEAP_LOG_THROTTLE_STRINGIFY_(line)

/// NODELET_<LEVEL>_STREAM(...) at most once per `period` s of ROS time for this call site of this nodelet
/// (the first always): the nodelet class holds a go_feap::ros_log::Throttle log_throttle_.
#define GO_FEAP_NODELET_THROTTLE(LEVEL, period, ...)                                                    \
  do {                                                                                                  \
    if (log_throttle_.pass(GO_FEAP_LOG_THROTTLE_SITE_(__LINE__), (period), ::ros::Time::now().toSec())) \
      NODELET_##LEVEL##_STREAM(__VA_ARGS__);                                                            \
  } while (false)
