#include "go_feap/trajectory/bspline.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace go_feap::trajectory {

UniformBspline::UniformBspline(Eigen::MatrixXd control_points, int degree, double dt)
    : control_points_(std::move(control_points)), degree_(degree), dt_(dt) {
  if (degree < 0 || degree > kMaxDegree)
    throw std::invalid_argument("UniformBspline: degree must be in [0, " + std::to_string(kMaxDegree) +
                                "], got " + std::to_string(degree));
  if (!(dt > 0.0 && std::isfinite(dt)))
    throw std::invalid_argument("UniformBspline: dt must be finite and > 0");
  if (control_points_.cols() <= degree)
    throw std::invalid_argument("UniformBspline: needs more than degree (" + std::to_string(degree) +
                                ") control points, got " + std::to_string(control_points_.cols()));
}

void UniformBspline::basisWeights(int degree, double s, int order, double* weights) {
  // A negative order would make more weights than the buffers hold.
  if (order < 0) throw std::invalid_argument("UniformBspline: a derivative order must be >= 0, got " + std::to_string(order));
  std::fill(weights, weights + degree + 1, 0.0);
  if (order > degree) return;
  // Cox-de Boor on the integer knots of one span: every denominator of level j equals j.
  const int q = degree - order;
  double n[kMaxDegree + 1] = {1.0};
  for (int j = 1; j <= q; ++j) {
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      const double temp = n[r] / j;
      const double right = r + 1 - s;
      const double left = s + j - r - 1;
      n[r] = saved + right * temp;
      saved = left * temp;
    }
    n[j] = saved;
  }
  // Each derivative turns a weight w_j on difference D_j = Q_{j+1} - Q_j into +w_j on Q_{j+1}, -w_j on Q_j.
  int len = q + 1;
  std::copy(n, n + len, weights);
  for (int r = 0; r < order; ++r) {
    double next[kMaxDegree + 1] = {0.0};
    for (int j = 0; j < len; ++j) {
      next[j + 1] += weights[j];
      next[j] -= weights[j];
    }
    ++len;
    std::copy(next, next + len, weights);
  }
}

void UniformBspline::locate(double t, int& span, double& s) const {
  const int segments = numControlPoints() - degree_;
  // NaN reads as the start (clamping passes it through, and the cast below would be undefined).
  const double f = std::isnan(t) ? 0.0 : std::clamp(t / dt_, 0.0, static_cast<double>(segments));
  int k = static_cast<int>(std::floor(f));
  if (k >= segments) k = segments - 1;
  s = f - k;
  span = k + degree_;
}

Eigen::VectorXd UniformBspline::evaluate(double t, int order) const {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(dimension());
  if (empty() || order > degree_) return out;
  int span;
  double s;
  locate(t, span, s);
  double w[kMaxDegree + 1];
  basisWeights(degree_, s, order, w);
  const double scale = std::pow(dt_, -order);
  for (int j = 0; j <= degree_; ++j) out += (w[j] * scale) * control_points_.col(span - degree_ + j);
  return out;
}

UniformBspline UniformBspline::derivative() const {
  if (empty() || degree_ == 0)
    throw std::invalid_argument("UniformBspline::derivative: needs a non-empty spline of degree >= 1");
  const int n = numControlPoints();
  Eigen::MatrixXd d = (control_points_.rightCols(n - 1) - control_points_.leftCols(n - 1)) / dt_;
  return UniformBspline(std::move(d), degree_ - 1, dt_);
}

UniformBspline UniformBspline::derivative(int order) const {
  UniformBspline out = *this;
  for (int r = 0; r < order; ++r) out = out.derivative();
  return out;
}

void UniformBspline::setKnotSpan(double dt) {
  if (!(dt > 0.0 && std::isfinite(dt)))
    throw std::invalid_argument("UniformBspline::setKnotSpan: dt must be finite and > 0");
  dt_ = dt;
}

double UniformBspline::maxDerivativeNorm(int order, int samples_per_span) const {
  if (empty() || order > degree_) return 0.0;
  samples_per_span = std::max(1, samples_per_span);
  // The weights of a sample do not depend on the span (uniform knots): compute them once.
  Eigen::MatrixXd weights(degree_ + 1, samples_per_span + 1);
  for (int i = 0; i <= samples_per_span; ++i)
    basisWeights(degree_, static_cast<double>(i) / samples_per_span, order, weights.col(i).data());
  weights *= std::pow(dt_, -order);
  double best = 0.0;
  for (int span = degree_; span < numControlPoints(); ++span) {
    const Eigen::MatrixXd values = control_points_.middleCols(span - degree_, degree_ + 1) * weights;
    best = std::max(best, values.colwise().norm().maxCoeff());
  }
  return best;
}

UniformBspline UniformBspline::fitPath(const Eigen::MatrixXd& points, double dt,
                                       const Eigen::VectorXd& start_vel, const Eigen::VectorXd& end_vel,
                                       int degree, const Eigen::VectorXd& start_acc,
                                       const Eigen::VectorXd& end_acc) {
  const int dim = static_cast<int>(points.rows());
  const int k_points = static_cast<int>(points.cols());
  const bool with_acc = start_acc.size() > 0 || end_acc.size() > 0;
  if (k_points < 2) throw std::invalid_argument("UniformBspline::fitPath: needs at least 2 points");
  if (start_vel.size() != dim || end_vel.size() != dim ||
      (with_acc && (start_acc.size() != dim || end_acc.size() != dim)))
    throw std::invalid_argument(
        "UniformBspline::fitPath: velocities and accelerations must have the points' dimension");
  if (degree < (with_acc ? 2 : 1) || degree > kMaxDegree)
    throw std::invalid_argument("UniformBspline::fitPath: degree must be in [1, " +
                                std::to_string(kMaxDegree) + "], and >= 2 with accelerations");
  if (!(dt > 0.0 && std::isfinite(dt)))
    throw std::invalid_argument("UniformBspline::fitPath: dt must be finite and > 0");

  // Equality-constrained least squares, solved through its KKT system:
  //   min |A q - b|^2 + eps |D q|^2  subject to  C q = d.
  const int n = k_points + degree - 1;
  const int interior = k_points - 2;
  const int constraints = with_acc ? 6 : 4;
  if (n < constraints)
    throw std::invalid_argument("UniformBspline::fitPath: " + std::to_string(k_points) + " points give " +
                                std::to_string(n) + " control points of degree " + std::to_string(degree) +
                                ", fewer than its " + std::to_string(constraints) + " end conditions");
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(interior, n), b(interior, dim);
  Eigen::MatrixXd c = Eigen::MatrixXd::Zero(constraints, n), d(constraints, dim);
  double w[kMaxDegree + 1];
  // Point k lies at the start of span degree + k (control points k .. k + degree); the last one at the end
  // of the last span. Derivative rows are multiplied by dt^order so that all rows have comparable size.
  for (int k = 1; k + 1 < k_points; ++k) {
    basisWeights(degree, 0.0, 0, w);
    for (int j = 0; j <= degree; ++j) a(k - 1, k + j) = w[j];
    b.row(k - 1) = points.col(k).transpose();
  }
  const int last = n - 1 - degree;
  auto constrain = [&](int row, int first, double s, int order, const Eigen::VectorXd& value) {
    basisWeights(degree, s, order, w);
    for (int j = 0; j <= degree; ++j) c(row, first + j) = w[j];
    d.row(row) = std::pow(dt, order) * value.transpose();
  };
  constrain(0, 0, 0.0, 0, points.col(0));
  constrain(1, last, 1.0, 0, points.col(k_points - 1));
  constrain(2, 0, 0.0, 1, start_vel);
  constrain(3, last, 1.0, 1, end_vel);
  if (with_acc) {
    constrain(4, 0, 0.0, 2, start_acc);
    constrain(5, last, 1.0, 2, end_acc);
  }

  Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(n + constraints, n + constraints);
  kkt.topLeftCorner(n, n) = a.transpose() * a;
  constexpr double kRegularisation = 1e-9;
  for (int i = 0; i + 2 < n; ++i) {
    const double dd[3] = {1.0, -2.0, 1.0};
    for (int r = 0; r < 3; ++r)
      for (int col = 0; col < 3; ++col) kkt(i + r, i + col) += kRegularisation * dd[r] * dd[col];
  }
  kkt.topRightCorner(n, constraints) = c.transpose();
  kkt.bottomLeftCorner(constraints, n) = c;
  Eigen::MatrixXd rhs(n + constraints, dim);
  rhs.topRows(n) = a.transpose() * b;
  rhs.bottomRows(constraints) = d;
  const Eigen::MatrixXd sol = kkt.fullPivLu().solve(rhs);
  return UniformBspline(sol.topRows(n).transpose(), degree, dt);
}

UniformBspline UniformBspline::fitPath(const std::vector<Vec3>& points, double dt, const Vec3& start_vel,
                                       const Vec3& end_vel, const Vec3& start_acc, const Vec3& end_acc) {
  Eigen::MatrixXd m(3, static_cast<Eigen::Index>(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) m.col(static_cast<Eigen::Index>(i)) = points[i];
  return fitPath(m, dt, start_vel, end_vel, 3, start_acc, end_acc);
}

UniformBspline UniformBspline::fromTimedSamples(const std::vector<Vec3>& points, double dt, const Vec3& start_vel,
                                                const Vec3& start_acc) {
  if (points.size() < 3) throw std::invalid_argument("UniformBspline::fromTimedSamples: needs at least 3 points");
  if (!(dt > 0.0 && std::isfinite(dt)) || !start_vel.allFinite() || !start_acc.allFinite())
    throw std::invalid_argument("UniformBspline::fromTimedSamples: dt must be finite and > 0, the start state finite");
  for (const Vec3& p : points)
    if (!p.allFinite()) throw std::invalid_argument("UniformBspline::fromTimedSamples: points must be finite");
  // A cubic's state at the start of its first span: p = (q0 + 4 q1 + q2) / 6, v = (q2 - q0) / (2 dt),
  // a = (q0 - 2 q1 + q2) / dt^2. Solved for the start state, then q_{k+1} = points[k] from k = 2 on, and
  // the last point twice more: the last span ends there at rest.
  const auto n = static_cast<Eigen::Index>(points.size());
  Eigen::MatrixXd q(3, n + 3);
  const Vec3 q1 = points[0] - start_acc * (dt * dt / 6.0);
  q.col(0) = q1 - start_vel * dt + start_acc * (0.5 * dt * dt);
  q.col(1) = q1;
  q.col(2) = q1 + start_vel * dt + start_acc * (0.5 * dt * dt);
  for (Eigen::Index k = 2; k < n; ++k) q.col(k + 1) = points[static_cast<std::size_t>(k)];
  q.col(n + 1) = points.back();
  q.col(n + 2) = points.back();
  return UniformBspline(std::move(q), 3, dt);
}

std::vector<Vec3> UniformBspline::resamplePolyline(const std::vector<Vec3>& path, double spacing) {
  if (!(spacing > 0.0 && std::isfinite(spacing)))
    throw std::invalid_argument("UniformBspline::resamplePolyline: spacing must be finite and > 0");
  if (path.empty()) return {};
  std::vector<double> cumulative(path.size(), 0.0);
  for (std::size_t i = 1; i < path.size(); ++i)
    cumulative[i] = cumulative[i - 1] + (path[i] - path[i - 1]).norm();
  const double length = cumulative.back();
  if (length <= 0.0) return {path.front(), path.front()};
  const int steps = std::max(1, static_cast<int>(std::ceil(length / spacing - 1e-9)));
  std::vector<Vec3> out;
  out.reserve(steps + 1);
  std::size_t seg = 1;
  for (int i = 0; i <= steps; ++i) {
    const double target = length * i / steps;
    while (seg + 1 < path.size() && cumulative[seg] < target) ++seg;
    const double seg_len = cumulative[seg] - cumulative[seg - 1];
    const double f = seg_len > 0.0 ? std::clamp((target - cumulative[seg - 1]) / seg_len, 0.0, 1.0) : 1.0;
    out.push_back(path[seg - 1] + f * (path[seg] - path[seg - 1]));
  }
  out.back() = path.back();
  return out;
}

}  // namespace go_feap::trajectory
