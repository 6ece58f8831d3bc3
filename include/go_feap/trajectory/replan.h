// When to replan the local trajectory and how to stop when planning fails (DESIGN §3.7). Pure functions:
// the caller gathers the inputs (its clock, its target) and acts on the answer.
#pragma once

#include <cstdint>
#include <optional>

#include "go_feap/common/result.h"
#include "go_feap/map/esdf.h"
#include "go_feap/trajectory/bspline.h"

namespace go_feap::trajectory {

enum class ReplanReason { kNone, kNewTarget, kShortTimeLeft, kPredictedCollision, kNoTrajectory };

/// "none", "new_target", "short_time_left", "predicted_collision", "no_trajectory".
const char* toString(ReplanReason reason);

struct ReplanConfig {
  double min_time_left = 1.0;     ///< s; replan when less than this is left of the current trajectory
  double target_tolerance = 0.3;  ///< m; a target farther than this from the trajectory's end counts as new
  double yaw_tolerance = 0.3;     ///< rad; a target heading that turns more than this counts as new

  /// Checks every key; the message names the bad one, e.g. "replan: min_time_left must be finite and >= 0".
  common::Status validate() const;
};

struct ReplanInputs {
  bool has_trajectory = false;
  double time_left = 0.0;               ///< s left on the current trajectory
  bool target_changed = false;          ///< the caller switched targets
  double target_distance_to_end = 0.0;  ///< m from the current target to the trajectory's end position
  /// When the remaining trajectory first comes too close to an obstacle (firstCollisionTime()), if it does.
  std::optional<double> collision_time;
};

/// The most urgent reason to replan, in this order: no trajectory, predicted collision, new target
/// (target_changed or target_distance_to_end > target_tolerance), short time left
/// (time_left < min_time_left); kNone otherwise.
ReplanReason shouldReplan(const ReplanInputs& inputs, const ReplanConfig& config);

/// The trajectory server's last report (PositionCommand), stamped `report_time` (s): whether it follows a
/// trajectory and which (`following_id`). True when such a report, stamped at least `grace` s after
/// trajectory `current_id` was sent (`sent_time`, s: when it was published, not when its start state was
/// taken, so that a plan that took long is not judged before it could arrive), shows the server following
/// another trajectory or none: it dropped this one (on an odometry gap of its own, say) and holds
/// position. A planner still counting on a trajectory that ends at its target would wait for the vehicle
/// to arrive for ever.
bool serverDropped(std::uint32_t current_id, double sent_time, bool following, std::uint32_t following_id,
                   double report_time, double grace);

/// A new target, not the current one moved a little: its position moved more than target_tolerance or its
/// heading turned more than yaw_tolerance (wrapped).
bool targetMoved(const Vec3& old_position, double old_yaw, const Vec3& new_position, double new_yaw,
                 const ReplanConfig& config);
/// First time in [t_now, min(t_now + horizon, duration)] at which `trajectory` (3-D) comes closer than
/// min_clearance to an obstacle of the ESDF, judged as checkTrajectory() judged it when it was planned (a
/// ClearanceRule from its start: one starting closer may leave within leave_distance without coming
/// nearer), sampled at most half a voxel apart (the step comes from a bound on the speed: the largest
/// control-polygon velocity; at most 100000 samples). Points outside the ESDF's grid count as free (the
/// ESDF reports max_distance there). nullopt when none does, or for an empty trajectory. A NaN t_now
/// reads as 0.
std::optional<double> firstCollisionTime(const UniformBspline& trajectory, double t_now, const map::Esdf& esdf,
                                         double min_clearance, double leave_distance, double horizon);

/// Cubic spline from position p with velocity v that brakes along v at a_max (m/s^2, > 0) and then holds:
/// it starts at p with velocity v (acceleration -a_max along v), never exceeds a_max, and ends at rest
/// after |v| / a_max plus at most one knot span dt, at most |v|^2 / (2 a_max) + a_max dt^2 / 24 from p.
/// dt <= 0.05 s while the braking takes less than 200 s; beyond (a speed no vehicle reaches, from corrupt
/// odometry) the spline keeps 4000 spans and dt grows, so that its size stays bounded. A zero velocity gives a spline that holds p. Throws std::invalid_argument unless a_max > 0 and
/// the inputs are finite.
UniformBspline safeStop(const Vec3& p, const Vec3& v, double a_max);

}  // namespace go_feap::trajectory
