// Uniform B-splines for the trajectories the planner flies (DESIGN §3.7): cubic in position (3-D
// control points), also used for yaw with 1-D control points.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "go_feap/common/grid.h"

namespace go_feap::trajectory {

using common::Vec3;

/// A uniform B-spline of degree p with n control points (columns of a dim x n matrix) and knot span dt
/// (s). Knot i sits at time (i - p) * dt, so the curve is defined on [0, duration] with
/// duration = (n - p) * dt; span k (p <= k < n) covers [(k - p) dt, (k - p + 1) dt) and is shaped by
/// control points k - p .. k. The curve lies in the convex hull of the control points of each span, and
/// its r-th derivative is a uniform B-spline of degree p - r over the r-th differences of the control
/// points divided by dt^r, so bounds on those differences bound velocity and acceleration everywhere.
class UniformBspline {
 public:
  /// Highest degree supported (basis weights live on the stack).
  static constexpr int kMaxDegree = 7;

  /// An empty spline (no control points; empty() is true).
  UniformBspline() = default;
  /// Throws std::invalid_argument unless 0 <= degree <= kMaxDegree, dt > 0 (finite) and there are more
  /// control points than the degree.
  UniformBspline(Eigen::MatrixXd control_points, int degree, double dt);

  /// Spline of `degree` whose value at time k * dt approximates points.col(k) (k = 0 .. K - 1, K >= 2), with
  /// K + degree - 1 control points. Exact: the first and last points, velocity start_vel at t = 0 and
  /// end_vel at t = (K - 1) dt, and, when start_acc / end_acc are not empty, those accelerations. The
  /// interior points are met in the least-squares sense (a tiny penalty on second differences of the
  /// control points resolves any freedom left) subject to those conditions: for a cubic without
  /// acceleration conditions that leaves no freedom and the curve interpolates every point; with them, it
  /// is the closest curve that starts and ends in the given states (the planner's case: a path's
  /// constant-speed samples cannot be followed exactly from rest). Throws std::invalid_argument on fewer
  /// than 2 points, mismatched dimensions, degree < 1 (< 2 with accelerations), dt <= 0, or fewer control
  /// points than end conditions (4, or 6 with accelerations: a cubic then needs K >= 4).
  static UniformBspline fitPath(const Eigen::MatrixXd& points, double dt, const Eigen::VectorXd& start_vel,
                                const Eigen::VectorXd& end_vel, int degree = 3,
                                const Eigen::VectorXd& start_acc = Eigen::VectorXd(),
                                const Eigen::VectorXd& end_acc = Eigen::VectorXd());
  /// fitPath() of 3-D points to a cubic, with exact start and end position, velocity and acceleration.
  static UniformBspline fitPath(const std::vector<Vec3>& points, double dt, const Vec3& start_vel,
                                const Vec3& end_vel, const Vec3& start_acc = Vec3::Zero(),
                                const Vec3& end_acc = Vec3::Zero());
  /// A cubic through timed samples (points[k] the position at k * dt, e.g. profileSamples()) that keeps
  /// their speed and acceleration: the samples are its control points (p(k dt) is within
  /// a dt^2 / 6 of points[k], a being their second difference / dt^2), so by the convex hull of its
  /// derivatives its speed never exceeds the largest |points[k + 1] - points[k]| / dt, nor its
  /// acceleration the largest second difference / dt^2 (or |start_acc|). An interpolating fit through
  /// the same samples rings where their acceleration changes within a few knots (about 40 % above it).
  /// It starts exactly at points[0] with start_vel and start_acc and ends at rest at points.back(), one
  /// span after the last sample's time (duration (n) dt for n samples). Throws std::invalid_argument on
  /// fewer than 3 points, dt <= 0 or non-finite input.
  static UniformBspline fromTimedSamples(const std::vector<Vec3>& points, double dt, const Vec3& start_vel,
                                         const Vec3& start_acc);
  /// Points at equal arc-length steps of at most `spacing` (m) along the polyline `path`, both ends
  /// included (at least 2 points; a single-point path gives that point twice). Empty for an empty path.
  static std::vector<Vec3> resamplePolyline(const std::vector<Vec3>& path, double spacing);

  bool empty() const { return control_points_.cols() == 0; }
  int degree() const { return degree_; }
  int dimension() const { return static_cast<int>(control_points_.rows()); }
  int numControlPoints() const { return static_cast<int>(control_points_.cols()); }
  const Eigen::MatrixXd& controlPoints() const { return control_points_; }
  double knotSpan() const { return dt_; }
  /// s; 0 for an empty spline.
  double duration() const { return empty() ? 0.0 : (numControlPoints() - degree_) * dt_; }

  /// Value at time t (clamped to [0, duration]; NaN reads as 0).
  Eigen::VectorXd value(double t) const { return evaluate(t, 0); }
  /// The order-th time derivative at t (clamped to [0, duration]; NaN reads as 0); zero when order > degree.
  /// Throws std::invalid_argument for a negative order (here and in maxDerivativeNorm).
  Eigen::VectorXd evaluate(double t, int order) const;
  /// 3-D value; the spline must have dimension 3.
  Vec3 position(double t) const { return value(t); }

  /// The derivative as a spline of degree p - 1 over (Q_{i+1} - Q_i) / dt, same time span. Throws
  /// std::invalid_argument for degree 0 or an empty spline.
  UniformBspline derivative() const;
  /// derivative() applied `order` times (order 0 returns a copy).
  UniformBspline derivative(int order) const;

  /// Sets the knot span (time scaling): the shape is kept, the duration becomes (n - p) * dt and the r-th
  /// derivative scales by (old dt / dt)^r. Throws std::invalid_argument unless dt > 0 (finite).
  void setKnotSpan(double dt);

  /// Largest norm of the order-th derivative over `samples_per_span` + 1 equally spaced samples of each
  /// span (knots included, which is exact for piecewise linear derivatives). 0 for an empty spline.
  double maxDerivativeNorm(int order, int samples_per_span = 16) const;
  double maxVelocity() const { return maxDerivativeNorm(1); }
  double maxAcceleration() const { return maxDerivativeNorm(2); }

  /// Weights of control points k - p .. k of a span of a degree-`degree` spline for the order-th
  /// derivative at local parameter s in [0, 1] of that span, in units of dt = 1 (divide by dt^order).
  /// `weights` gets degree + 1 entries (all zero when order > degree).
  static void basisWeights(int degree, double s, int order, double* weights);

 private:
  /// Span index k and local parameter s in [0, 1] of time t (clamped to the curve's time span).
  void locate(double t, int& span, double& s) const;

  Eigen::MatrixXd control_points_;
  int degree_ = 3;
  double dt_ = 0.1;
};

}  // namespace go_feap::trajectory
