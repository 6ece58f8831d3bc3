// A clock that never goes back, read from one that may.
#pragma once

#include <optional>

namespace go_feap::common {

/// Time (s) from a source clock that may go back (a ROS clock: a bag played again, a simulator restarted),
/// paused for as long as the source went back: timers and ages counted on it never go negative (a finished
/// band could not settle, a frontier's age read 0 for as long as the jump).
class MonotonicClock {
 public:
  /// The time at source time `t`; wentBack() then says by how much the source went back since the last
  /// reading (0 when it did not).
  double at(double t) {
    went_back_ = last_ && t < *last_ ? *last_ - t : 0.0;
    offset_ += went_back_;
    last_ = t;
    return t + offset_;
  }
  double wentBack() const { return went_back_; }

 private:
  std::optional<double> last_;  ///< the source's last reading
  double offset_ = 0.0;         ///< s the source went back in all
  double went_back_ = 0.0;
};

}  // namespace go_feap::common
