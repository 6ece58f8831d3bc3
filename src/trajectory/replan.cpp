#include "go_feap/trajectory/replan.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "go_feap/trajectory/bspline_optimizer.h"

namespace go_feap::trajectory {

using common::Status;

const char* toString(ReplanReason reason) {
  switch (reason) {
    case ReplanReason::kNone:
      return "none";
    case ReplanReason::kNewTarget:
      return "new_target";
    case ReplanReason::kShortTimeLeft:
      return "short_time_left";
    case ReplanReason::kPredictedCollision:
      return "predicted_collision";
    case ReplanReason::kNoTrajectory:
      return "no_trajectory";
  }
  return "unknown";
}

Status ReplanConfig::validate() const {
  if (!(min_time_left >= 0.0 && std::isfinite(min_time_left)))
    return Status::Error("replan: min_time_left must be finite and >= 0");
  if (!(target_tolerance >= 0.0 && std::isfinite(target_tolerance)))
    return Status::Error("replan: target_tolerance must be finite and >= 0");
  if (!(yaw_tolerance >= 0.0 && std::isfinite(yaw_tolerance)))
    return Status::Error("replan: yaw_tolerance must be finite and >= 0");
  return Status::Ok();
}

bool targetMoved(const Vec3& old_position, double old_yaw, const Vec3& new_position, double new_yaw,
                 const ReplanConfig& config) {
  const double turn = std::remainder(new_yaw - old_yaw, 2.0 * M_PI);
  return (new_position - old_position).norm() > config.target_tolerance || std::abs(turn) > config.yaw_tolerance;
}

ReplanReason shouldReplan(const ReplanInputs& inputs, const ReplanConfig& config) {
  if (!inputs.has_trajectory) return ReplanReason::kNoTrajectory;
  if (inputs.collision_time) return ReplanReason::kPredictedCollision;
  if (inputs.target_changed || inputs.target_distance_to_end > config.target_tolerance)
    return ReplanReason::kNewTarget;
  if (inputs.time_left < config.min_time_left) return ReplanReason::kShortTimeLeft;
  return ReplanReason::kNone;
}

bool serverDropped(std::uint32_t current_id, double sent_time, bool following, std::uint32_t following_id,
                   double report_time, double grace) {
  if (!(report_time >= sent_time + grace)) return false;  // a report from before it could arrive
  return !following || following_id != current_id;
}

std::optional<double> firstCollisionTime(const UniformBspline& trajectory, double t_now, const map::Esdf& esdf,
                                         double min_clearance, double leave_distance, double horizon) {
  if (trajectory.empty() || trajectory.dimension() != 3) return std::nullopt;
  if (std::isnan(t_now)) t_now = 0.0;  // as UniformBspline::evaluate() reads it
  const double t0 = std::clamp(t_now, 0.0, trajectory.duration());
  const double t1 = std::clamp(t_now + std::max(0.0, horizon), t0, trajectory.duration());
  // Judged as when it was planned (checkTrajectory()): a trajectory that starts closer than min_clearance
  // is followed from its start while it may still be leaving, so the floor is its start's, not wherever
  // the vehicle is now (a distance that ripples along a wall would move it); only times from t_now count.
  ClearanceRule rule(esdf, trajectory.position(0.0), min_clearance, leave_distance);
  const double ts = rule.leaving() ? 0.0 : t0;
  const Eigen::MatrixXd& q = trajectory.controlPoints();
  double speed_bound = 0.0;  // the velocity curve lies in the hull of the polygon's velocities
  for (int i = 0; i + 1 < trajectory.numControlPoints(); ++i)
    speed_bound = std::max(speed_bound, (q.col(i + 1) - q.col(i)).norm() / trajectory.knotSpan());
  // At most half a voxel apart; the count clamped as a double before the cast (a corrupt trajectory's
  // speed bound must not overflow it, nor make the check take seconds: past kMaxSteps the samples are
  // farther apart), NaN (an infinite bound over no time) read as 1.
  constexpr double kMaxSteps = 100000.0;
  const double wanted = std::ceil((t1 - ts) * speed_bound / (0.5 * esdf.geometry().resolution()));
  const int steps = wanted >= 1.0 ? static_cast<int>(std::min(wanted, kMaxSteps)) : 1;
  double travelled = 0.0;
  Vec3 last = trajectory.position(ts);
  for (int i = 0; i <= steps; ++i) {
    const double t = ts + (t1 - ts) * i / steps;
    const Vec3 p = trajectory.position(t);
    travelled += (p - last).norm();
    last = p;
    if (!rule.accept(esdf.distance(p), travelled) && t >= t0) return t;
  }
  return std::nullopt;
}

UniformBspline safeStop(const Vec3& p, const Vec3& v, double a_max) {
  if (!(a_max > 0.0 && std::isfinite(a_max)) || !p.allFinite() || !v.allFinite())
    throw std::invalid_argument("safeStop: a_max must be finite and > 0, p and v finite");
  constexpr double kTargetSpan = 0.05;  // s
  const double speed = v.norm();
  if (speed < 1e-9) return UniformBspline(p.replicate(1, 4), 3, kTargetSpan);
  const Vec3 dir = v / speed;
  // Velocity control points V_i = a dt (m - i) dir, i = 0..m, fall linearly to exactly 0 at V_m; the
  // average of V_0 and V_1 is the start velocity when dt = speed / (a (m - 1/2)). Every acceleration
  // control point is then -a_max dir or 0.
  // At most kMaxSpans spans (longer ones, past kMaxSpans * kTargetSpan s of braking, from a speed no vehicle
  // reaches): the size stays bounded whatever the speed, and the cast below defined.
  constexpr double kMaxSpans = 4000.0;
  const int m = static_cast<int>(std::clamp(std::ceil(speed / a_max / kTargetSpan) + 1.0, 2.0, kMaxSpans));
  const double dt = speed / (a_max * (m - 0.5));
  Eigen::Matrix3Xd q(3, m + 3);
  q.col(0).setZero();
  for (int i = 0; i <= m; ++i) q.col(i + 1) = q.col(i) + (a_max * dt * (m - i) * dt) * dir;
  q.col(m + 2) = q.col(m + 1);
  const Vec3 start = (q.col(0) + 4.0 * q.col(1) + q.col(2)) / 6.0;
  q.colwise() += p - start;
  return UniformBspline(q, 3, dt);
}

}  // namespace go_feap::trajectory
