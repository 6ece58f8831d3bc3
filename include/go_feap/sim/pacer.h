// Simulated time paced against wall time.
#pragma once

namespace go_feap::sim {

/// Paces simulated time at `rate_factor` simulated seconds per wall second, without racing to catch up
/// after a stall: the simulation of simulated time t is due at wall time anchor + t / rate_factor, and when
/// the wall clock has passed a step's due time by more than `max_lag` (a machine that stalled the
/// simulation thread), the anchor moves so that the lag is dropped. Catching up ran the stalled seconds
/// times rate_factor without a pause, faster than the planners (on wall time for their computing) could
/// answer: their commands timed out and the vehicle hovered. Times are seconds (wall from any start).
class WallPacer {
 public:
  WallPacer(double rate_factor, double max_lag) : rate_factor_(rate_factor), max_lag_(max_lag) {}
  /// The wall time at which simulated time `t` is due.
  double due(double t) const { return anchor_ + t / rate_factor_; }
  /// Woken at wall time `wall` after the step up to simulated time `t`: the lag dropped (s of wall time
  /// over max_lag behind; 0 when on time or within max_lag).
  double settle(double t, double wall) {
    const double lag = wall - due(t);
    if (!(lag > max_lag_)) return 0.0;
    anchor_ += lag;
    return lag;
  }

 private:
  double rate_factor_, max_lag_;
  double anchor_ = 0.0;
};

}  // namespace go_feap::sim
