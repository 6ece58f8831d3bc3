// Gradient-based optimisation of a cubic position B-spline against the ESDF (DESIGN §3.7), and a yaw
// B-spline that respects the yaw-rate limit.
#pragma once

#include <vector>

#include "go_feap/common/result.h"
#include "go_feap/map/esdf.h"
#include "go_feap/trajectory/bspline.h"

namespace go_feap::trajectory {

struct OptimizerConfig {
  /// Weight of the sum of squared third differences of the control points (m^2).
  double lambda_smooth = 1.0;
  /// Weight of the squared clearance shortfall of the free control points (m^2).
  double lambda_clearance = 20.0;
  /// Weight of the squared relative speed / acceleration excess of the control polygon.
  double lambda_feasibility = 100.0;
  double lambda_time = 1.0;    ///< weight of the duration (s)
  double clearance = 0.5;      ///< m, ESDF distance the free control points are pushed to (< max_distance)
  double min_clearance = 0.2;  ///< m, hard limit: a result whose sampled curve comes closer fails
  /// m, a curve starting closer than min_clearance must reach it within this much travel (ClearanceRule).
  double leave_distance = 1.0;
  double v_max = 2.0;          ///< m/s
  double a_max = 2.0;          ///< m/s^2
  double yaw_rate_max = 1.0;   ///< rad/s (yawTurn)
  double yaw_acc_max = 5.0;    ///< rad/s^2, how fast the yaw rate may rise and fall (yawTurn)
  /// Share of v_max / a_max the penalties aim at, leaving room for the small excess a penalty allows.
  double feasibility_margin = 0.95;
  /// Accepted excess of the sampled speed, acceleration and yaw rate over their limits (0.05 = 5 %).
  double limit_tolerance = 0.05;
  int max_iterations = 300;          ///< cost evaluations per NLopt run (no clocks: the only time budget)
  double relative_tolerance = 1e-5;  ///< NLopt ftol_rel and xtol_rel
  double min_knot_span = 0.02;       ///< s, bounds on the knot span while it is optimised
  double max_knot_span = 2.0;        ///< s

  /// Checks every key; the message names the bad one, e.g. "optimizer: v_max must be finite and > 0".
  common::Status validate() const;
  /// validate() plus clearance < esdf max_distance (distances are truncated there, so nothing could be
  /// pushed farther).
  common::Status validate(const map::EsdfConfig& esdf) const;
};

/// Cost terms, as bits of a mask for BsplineCost::evaluate().
enum CostTerm : unsigned {
  kSmoothness = 1u << 0,
  kClearance = 1u << 1,
  kVelocity = 1u << 2,      ///< feasibility, weighted by lambda_feasibility
  kAcceleration = 1u << 3,  ///< feasibility, weighted by lambda_feasibility
  kTime = 1u << 4,
  kAllTerms = (1u << 5) - 1,
};

/// The cost optimize() minimises, over the variables x = (free control points, column by column, then
/// log of the knot span). For a cubic spline with n control points, Q_0..Q_2 and Q_{n-3}..Q_{n-1} are not
/// free: they are the unique control points giving the start (end) position, velocity and acceleration of
/// the initial spline at the current knot span, so changing dt keeps the boundary states (when those
/// velocities and accelerations are zero the boundary points simply stay where they are). Terms:
///   smoothness    lambda_smooth * sum |Q_{i+3} - 3 Q_{i+2} + 3 Q_{i+1} - Q_i|^2 (independent of dt, so
///                 it shapes the path and leaves the timing to the other terms);
///   clearance     lambda_clearance * sum over free Q_i of max(0, clearance - d(Q_i))^2, d the ESDF;
///   velocity      lambda_feasibility * sum max(0, |V_i|^2 / (m v_max)^2 - 1)^2, V_i = (Q_{i+1} - Q_i) / dt;
///   acceleration  lambda_feasibility * sum max(0, |A_i|^2 / (m a_max)^2 - 1)^2,
///                 A_i = (Q_{i+2} - 2 Q_{i+1} + Q_i) / dt^2  (m = feasibility_margin; dimensionless, so
///                 the two limits weigh alike whatever their units);
///   time          lambda_time * (n - 3) * dt.
/// The velocity (acceleration) curve lies in the convex hull of the V_i (A_i), so meeting the limits on
/// the control polygon meets them everywhere. Gradients are analytic.
class BsplineCost {
 public:
  /// Throws std::invalid_argument unless `init` is a 3-D cubic with at least 7 control points (so one is
  /// free). Keeps a reference to esdf.
  BsplineCost(const UniformBspline& init, const map::Esdf& esdf, const OptimizerConfig& config);

  int numVariables() const { return 3 * num_free_ + 1; }
  /// Variables of a spline with the same number of control points (its free points and log dt).
  std::vector<double> variables(const UniformBspline& spline) const;
  /// The spline the variables describe (boundary points recomputed for their dt).
  UniformBspline spline(const double* x) const;
  /// Sum of the terms selected by `terms` (CostTerm bits); writes the gradient to grad when not null.
  double evaluate(const double* x, double* grad, unsigned terms = kAllTerms) const;
  double evaluate(const std::vector<double>& x, std::vector<double>* grad, unsigned terms = kAllTerms) const;

  /// Number of cost evaluations so far.
  int evaluations() const { return evaluations_; }

 private:
  /// All control points for dt, and (when d_boundary is not null) the derivative of the six boundary
  /// points with respect to dt (columns 0..2 start, 3..5 end).
  void controlPoints(const double* x, double dt, Eigen::Matrix3Xd& q,
                     Eigen::Matrix<double, 3, 6>* d_boundary) const;

  const map::Esdf& esdf_;
  OptimizerConfig config_;
  int n_ = 0;
  int num_free_ = 0;
  Vec3 start_[3], end_[3];  // position, velocity, acceleration at t = 0 and t = duration
  mutable int evaluations_ = 0;
  mutable Eigen::Matrix3Xd q_, g_;  // scratch
};

/// What optimize() found, filled whether it succeeded or not.
struct OptimizeStats {
  int evaluations = 0;   ///< cost evaluations
  int nlopt_result = 0;  ///< nlopt::result code (negative when NLopt threw)
  double initial_cost = 0.0;
  double final_cost = 0.0;
  double max_velocity = 0.0;      ///< m/s, sampled, of the last iterate
  double max_acceleration = 0.0;  ///< m/s^2
  double min_distance = 0.0;      ///< m, smallest ESDF distance along the sampled curve
};

/// The clearance a curve keeps, judged sample by sample in time order from its start: min_clearance,
/// except that a curve starting closer (a wall mapped late beside the vehicle, a braking stop) may leave.
/// Until it first reaches min_clearance, and for at most leave_distance of travel, no sample may come
/// closer than its start less a tenth of a voxel: it moves away or along, never nearer, and does not
/// skim along the obstacle for longer. A start in an obstacle voxel has no such way out: every sample
/// below min_clearance fails.
class ClearanceRule {
 public:
  /// For a curve starting at `start`.
  ClearanceRule(const map::Esdf& esdf, const Vec3& start, double min_clearance, double leave_distance);
  /// Whether a sample at `distance` from the nearest obstacle, `travelled` m along the curve from its
  /// start, passes; the samples come in time order.
  bool accept(double distance, double travelled);
  /// Whether the curve started closer than min_clearance and may still be leaving.
  bool leaving() const { return leaving_; }

 private:
  double min_clearance_;
  double leave_distance_;
  double leave_floor_;
  bool leaving_;
};

/// Samples the spline densely (every half voxel or finer) and checks speed and acceleration against
/// v_max, a_max (times 1 + limit_tolerance), the ESDF distance against min_clearance (a ClearanceRule:
/// a spline starting closer must leave within leave_distance without coming nearer), and that every
/// control point is finite. The message says which check failed and by how much. Fills `stats`' three
/// sampled fields when not null.
common::Status checkTrajectory(const UniformBspline& spline, const map::Esdf& esdf,
                               const OptimizerConfig& config, OptimizeStats* stats = nullptr);

/// Optimises a 3-D cubic spline (at least 7 control points, e.g. UniformBspline::fitPath() of a resampled
/// A* path) with NLopt L-BFGS over the free control points and the knot span (see BsplineCost). The start
/// and end states of `init` are kept. The knot span starts stretched, if need be, until init's control
/// polygon meets the margin-reduced limits (time re-allocation), then is optimised with the rest. Fails, and
/// never returns a trajectory, when the config is invalid, NLopt throws (round-off limited, forced stop,
/// invalid arguments, out of memory, generic failure) or the result does not pass checkTrajectory().
common::Result<UniformBspline> optimize(const UniformBspline& init, const map::Esdf& esdf,
                                        const OptimizerConfig& config, OptimizeStats* stats = nullptr);

/// 1-D cubic yaw spline that turns from yaw0 to yaw1 the short way round (|turn| <= pi) in about the
/// least time the limits allow: from the rate rate0 (clamped to yaw_rate_max; the reference's rate, so that
/// a replan mid-turn goes on turning instead of starting from rest), the rate moves to a constant at most
/// yaw_rate_max within one knot span (through rest first when the turn goes against rate0), stays there,
/// and falls back to rest in the last span. The rate and acceleration bounds (yaw_acc_max) hold exactly:
/// the derivatives lie in the hulls of their control values. It lasts at least min_duration (the turn is
/// spread over it, slower). Fails on non-finite input or an invalid config.
common::Result<UniformBspline> yawTurn(double yaw0, double yaw1, double min_duration, const OptimizerConfig& config,
                                       double rate0 = 0.0);

}  // namespace go_feap::trajectory
