#include "go_feap/trajectory/bspline_optimizer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <new>
#include <nlopt.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace go_feap::trajectory {

using common::Result;
using common::Status;

namespace {

constexpr int kDegree = 3;

bool positive(double v) { return v > 0.0 && std::isfinite(v); }

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.4g", v);
  return buf;
}

}  // namespace

Status OptimizerConfig::validate() const {
  auto err = [](const char* key, const char* why) {
    return Status::Error(std::string("optimizer: ") + key + " " + why);
  };
  auto non_negative = [](double v) { return v >= 0.0 && std::isfinite(v); };
  if (!non_negative(lambda_smooth)) return err("lambda_smooth", "must be finite and >= 0");
  if (!non_negative(lambda_clearance)) return err("lambda_clearance", "must be finite and >= 0");
  if (!non_negative(lambda_feasibility)) return err("lambda_feasibility", "must be finite and >= 0");
  if (!non_negative(lambda_time)) return err("lambda_time", "must be finite and >= 0");
  if (!non_negative(min_clearance)) return err("min_clearance", "must be finite and >= 0");
  if (!non_negative(leave_distance)) return err("leave_distance", "must be finite and >= 0");
  if (!(std::isfinite(clearance) && clearance >= min_clearance))
    return err("clearance", "must be finite and >= min_clearance");
  if (!positive(v_max)) return err("v_max", "must be finite and > 0");
  if (!positive(a_max)) return err("a_max", "must be finite and > 0");
  if (!positive(yaw_rate_max)) return err("yaw_rate_max", "must be finite and > 0");
  if (!positive(yaw_acc_max)) return err("yaw_acc_max", "must be finite and > 0");
  // A half turn takes pi * yaw_acc_max / yaw_rate_max^2 spline spans (yawTurn): 1e-4 rad/s with 10 rad/s^2
  // was 3e9 spans, past an int.
  if (!(M_PI * yaw_acc_max / (yaw_rate_max * yaw_rate_max) <= 1000.0))
    return err("yaw_acc_max", "over yaw_rate_max squared must be at most 318 (a half turn in at most 1000 spline spans)");
  if (!(feasibility_margin > 0.0 && feasibility_margin <= 1.0))
    return err("feasibility_margin", "must be in (0, 1]");
  if (!non_negative(limit_tolerance)) return err("limit_tolerance", "must be finite and >= 0");
  // The optimiser's only time budget: 2^31 evaluations could run for hours.
  if (max_iterations < 1 || max_iterations > 100000) return err("max_iterations", "must be in [1, 100000]");
  if (!(relative_tolerance >= 0.0 && relative_tolerance < 1.0))
    return err("relative_tolerance", "must be in [0, 1)");
  if (!positive(min_knot_span)) return err("min_knot_span", "must be finite and > 0");
  if (!(std::isfinite(max_knot_span) && max_knot_span > min_knot_span))
    return err("max_knot_span", "must be finite and > min_knot_span");
  return Status::Ok();
}

Status OptimizerConfig::validate(const map::EsdfConfig& esdf) const {
  if (Status s = validate(); !s) return s;
  if (!(clearance < esdf.max_distance))
    return Status::Error("optimizer: clearance must be < the ESDF's max_distance (" + num(esdf.max_distance) +
                         ")");
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------------------
// Cost.

BsplineCost::BsplineCost(const UniformBspline& init, const map::Esdf& esdf, const OptimizerConfig& config)
    : esdf_(esdf), config_(config) {
  if (init.dimension() != 3 || init.degree() != kDegree || init.numControlPoints() < 7)
    throw std::invalid_argument("BsplineCost: needs a 3-D cubic spline with at least 7 control points");
  n_ = init.numControlPoints();
  num_free_ = n_ - 6;
  const double t_end = init.duration();
  for (int r = 0; r < 3; ++r) {
    start_[r] = init.evaluate(0.0, r);
    end_[r] = init.evaluate(t_end, r);
  }
  q_.resize(3, n_);
  g_.resize(3, n_);
}

void BsplineCost::controlPoints(const double* x, double dt, Eigen::Matrix3Xd& q,
                                Eigen::Matrix<double, 3, 6>* d_boundary) const {
  // Inverse of (position, velocity, acceleration) = ((Q0 + 4 Q1 + Q2) / 6, (Q2 - Q0) / (2 dt),
  // (Q0 - 2 Q1 + Q2) / dt^2) at a cubic's knot.
  auto boundary = [&](const Vec3* state, int first, int d_col) {
    const Vec3& p = state[0];
    const Vec3& v = state[1];
    const Vec3& a = state[2];
    q.col(first) = p - dt * v + dt * dt / 3.0 * a;
    q.col(first + 1) = p - dt * dt / 6.0 * a;
    q.col(first + 2) = p + dt * v + dt * dt / 3.0 * a;
    if (d_boundary) {
      d_boundary->col(d_col) = -v + 2.0 * dt / 3.0 * a;
      d_boundary->col(d_col + 1) = -dt / 3.0 * a;
      d_boundary->col(d_col + 2) = v + 2.0 * dt / 3.0 * a;
    }
  };
  q.resize(3, n_);
  boundary(start_, 0, 0);
  boundary(end_, n_ - 3, 3);
  for (int i = 0; i < num_free_; ++i) q.col(3 + i) = Vec3(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
}

std::vector<double> BsplineCost::variables(const UniformBspline& spline) const {
  if (spline.numControlPoints() != n_ || spline.dimension() != 3)
    throw std::invalid_argument("BsplineCost::variables: spline has a different size");
  std::vector<double> x(numVariables());
  for (int i = 0; i < num_free_; ++i)
    for (int k = 0; k < 3; ++k) x[3 * i + k] = spline.controlPoints()(k, 3 + i);
  x.back() = std::log(spline.knotSpan());
  return x;
}

UniformBspline BsplineCost::spline(const double* x) const {
  const double dt = std::exp(x[3 * num_free_]);
  Eigen::Matrix3Xd q;
  controlPoints(x, dt, q, nullptr);
  return UniformBspline(q, kDegree, dt);
}

double BsplineCost::evaluate(const std::vector<double>& x, std::vector<double>* grad, unsigned terms) const {
  if (static_cast<int>(x.size()) != numVariables())
    throw std::invalid_argument("BsplineCost::evaluate: wrong number of variables");
  if (grad) grad->assign(x.size(), 0.0);
  return evaluate(x.data(), grad ? grad->data() : nullptr, terms);
}

double BsplineCost::evaluate(const double* x, double* grad, unsigned terms) const {
  ++evaluations_;
  const double dt = std::exp(x[3 * num_free_]);
  Eigen::Matrix<double, 3, 6> d_boundary;
  controlPoints(x, dt, q_, &d_boundary);
  g_.setZero(3, n_);
  double gdt = 0.0;  // explicit derivative with respect to dt
  double f = 0.0;

  if (terms & kSmoothness) {
    const double w = config_.lambda_smooth;
    for (int i = 0; i + 3 < n_; ++i) {
      const Vec3 j = q_.col(i + 3) - 3.0 * q_.col(i + 2) + 3.0 * q_.col(i + 1) - q_.col(i);
      f += w * j.squaredNorm();
      const Vec3 gj = 2.0 * w * j;
      g_.col(i + 3) += gj;
      g_.col(i + 2) -= 3.0 * gj;
      g_.col(i + 1) += 3.0 * gj;
      g_.col(i) -= gj;
    }
  }
  if (terms & kClearance) {
    const double w = config_.lambda_clearance;
    Vec3 gd;
    for (int i = 3; i < n_ - 3; ++i) {
      const double d = esdf_.distanceAndGradient(q_.col(i), gd);
      const double e = config_.clearance - d;
      if (e <= 0.0) continue;
      f += w * e * e;
      g_.col(i) -= 2.0 * w * e * gd;
    }
  }
  if (terms & kVelocity) {
    const double w = config_.lambda_feasibility;
    const double limit = config_.feasibility_margin * config_.v_max;
    const double inv = 1.0 / (dt * dt * limit * limit);
    for (int i = 0; i + 1 < n_; ++i) {
      const Vec3 d = q_.col(i + 1) - q_.col(i);
      const double r = d.squaredNorm() * inv;  // |V_i|^2 / limit^2
      const double h = r - 1.0;
      if (h <= 0.0) continue;
      f += w * h * h;
      const Vec3 gq = (4.0 * w * h * inv) * d;
      g_.col(i + 1) += gq;
      g_.col(i) -= gq;
      gdt += 2.0 * w * h * (-2.0 * r / dt);
    }
  }
  if (terms & kAcceleration) {
    const double w = config_.lambda_feasibility;
    const double limit = config_.feasibility_margin * config_.a_max;
    const double inv = 1.0 / (dt * dt * dt * dt * limit * limit);
    for (int i = 0; i + 2 < n_; ++i) {
      const Vec3 d = q_.col(i + 2) - 2.0 * q_.col(i + 1) + q_.col(i);
      const double r = d.squaredNorm() * inv;  // |A_i|^2 / limit^2
      const double h = r - 1.0;
      if (h <= 0.0) continue;
      f += w * h * h;
      const Vec3 gq = (4.0 * w * h * inv) * d;
      g_.col(i + 2) += gq;
      g_.col(i + 1) -= 2.0 * gq;
      g_.col(i) += gq;
      gdt += 2.0 * w * h * (-4.0 * r / dt);
    }
  }
  if (terms & kTime) {
    f += config_.lambda_time * (n_ - kDegree) * dt;
    gdt += config_.lambda_time * (n_ - kDegree);
  }

  if (grad) {
    for (int i = 0; i < num_free_; ++i)
      for (int k = 0; k < 3; ++k) grad[3 * i + k] = g_(k, 3 + i);
    for (int b = 0; b < 3; ++b) {
      gdt += g_.col(b).dot(d_boundary.col(b));
      gdt += g_.col(n_ - 3 + b).dot(d_boundary.col(3 + b));
    }
    grad[3 * num_free_] = gdt * dt;  // chain rule through dt = exp(x_last)
  }
  return f;
}

// ---------------------------------------------------------------------------------------------------------
// Checks and optimisation.

ClearanceRule::ClearanceRule(const map::Esdf& esdf, const Vec3& start, double min_clearance, double leave_distance)
    : min_clearance_(min_clearance), leave_distance_(leave_distance) {
  const auto& geo = esdf.geometry();
  const double d = esdf.distance(start);
  const common::Index3 idx = geo.clampedIndex(start);
  leave_floor_ = d - 0.1 * geo.resolution();
  leaving_ = d < min_clearance && !(geo.inside(idx) && esdf.isObstacle(idx));
}

bool ClearanceRule::accept(double distance, double travelled) {
  if (leaving_ && (distance >= min_clearance_ || !(travelled <= leave_distance_))) leaving_ = false;
  return leaving_ ? distance >= leave_floor_ : distance >= min_clearance_;
}

Status checkTrajectory(const UniformBspline& spline, const map::Esdf& esdf, const OptimizerConfig& config,
                       OptimizeStats* stats) {
  if (spline.empty() || spline.dimension() != 3) return Status::Error("trajectory check: not a 3-D spline");
  if (!spline.controlPoints().allFinite() || !std::isfinite(spline.knotSpan()))
    return Status::Error("trajectory check: non-finite control points or knot span");
  const int p = spline.degree();
  const Eigen::MatrixXd& q = spline.controlPoints();
  // The arc length of a span is at most the length of its control polygon: sample every half voxel.
  double longest = 0.0;
  for (int span = p; span < spline.numControlPoints(); ++span) {
    double len = 0.0;
    for (int j = span - p; j < span; ++j) len += (q.col(j + 1) - q.col(j)).norm();
    longest = std::max(longest, len);
  }
  // Clamped before the cast: a polygon kilometres long (finite, absurd) overflowed the int.
  const int samples =
      static_cast<int>(std::clamp(std::ceil(longest / (0.5 * esdf.geometry().resolution())), 8.0, 1000.0));
  const double v = spline.maxDerivativeNorm(1, samples);
  const double a = spline.maxDerivativeNorm(2, samples);
  double min_distance = std::numeric_limits<double>::infinity();
  Eigen::MatrixXd weights(p + 1, samples + 1);
  for (int i = 0; i <= samples; ++i)
    UniformBspline::basisWeights(p, static_cast<double>(i) / samples, 0, weights.col(i).data());
  ClearanceRule rule(esdf, spline.position(0.0), config.min_clearance, config.leave_distance);
  // The first sample that broke the rule: how far from the obstacle, and whether the curve was still
  // leaving a near start (it came nearer) or had just run out of leave_distance.
  bool too_close = false, came_nearer = false, left_too_long = false;
  double failed_at = 0.0;
  double travelled = 0.0;
  Vec3 last = spline.position(0.0);
  for (int span = p; span < spline.numControlPoints(); ++span) {
    const Eigen::MatrixXd points = q.middleCols(span - p, p + 1) * weights;
    for (int i = 0; i <= samples; ++i) {
      const Vec3 point = points.col(i);
      travelled += (point - last).norm();
      last = point;
      const double d = esdf.distance(point);
      min_distance = std::min(min_distance, d);
      const bool leaving = rule.leaving();
      if (!too_close && !rule.accept(d, travelled)) {
        too_close = true;
        came_nearer = leaving && rule.leaving();
        left_too_long = leaving && !rule.leaving();
        failed_at = d;
      }
    }
  }
  if (stats) {
    stats->max_velocity = v;
    stats->max_acceleration = a;
    stats->min_distance = min_distance;
  }
  const double scale = 1.0 + config.limit_tolerance;
  if (!(v <= config.v_max * scale))
    return Status::Error("trajectory check: speed " + num(v) + " m/s exceeds v_max " + num(config.v_max));
  if (!(a <= config.a_max * scale))
    return Status::Error("trajectory check: acceleration " + num(a) + " m/s^2 exceeds a_max " +
                         num(config.a_max));
  if (too_close) {
    const std::string start = num(esdf.distance(spline.position(0.0)));
    if (came_nearer)
      return Status::Error("trajectory check: starts " + start + " m from an obstacle, below min_clearance " +
                           num(config.min_clearance) + ", and comes nearer (" + num(failed_at) +
                           " m) before it is that far away");
    if (left_too_long)
      return Status::Error("trajectory check: starts " + start + " m from an obstacle and is still " +
                           num(failed_at) + " m from one after leave_distance " + num(config.leave_distance) +
                           " m, below min_clearance " + num(config.min_clearance));
    return Status::Error("trajectory check: passes " + num(failed_at) + " m from an obstacle, below min_clearance " +
                         num(config.min_clearance));
  }
  return Status::Ok();
}

namespace {

double nloptObjective(unsigned /*n*/, const double* x, double* grad, void* data) {
  return static_cast<const BsplineCost*>(data)->evaluate(x, grad);
}

}  // namespace

Result<UniformBspline> optimize(const UniformBspline& init, const map::Esdf& esdf,
                                const OptimizerConfig& config, OptimizeStats* stats) {
  OptimizeStats local;
  OptimizeStats& st = stats ? *stats : local;
  st = OptimizeStats();
  if (Status s = config.validate(esdf.config()); !s) return s;
  if (init.dimension() != 3 || init.degree() != kDegree || init.numControlPoints() < 7)
    return Result<UniformBspline>::Error(
        "optimizer: needs a 3-D cubic spline with at least 7 control points");
  if (!init.controlPoints().allFinite())
    return Result<UniformBspline>::Error("optimizer: initial spline has non-finite control points");

  const BsplineCost cost(init, esdf, config);
  std::vector<double> x = cost.variables(init);
  // Start from a knot span at which the control polygon meets the (margin-reduced) limits: the penalties
  // grow with the fourth power of the excess, and starting far inside them leaves L-BFGS badly scaled.
  const Eigen::MatrixXd& q = init.controlPoints();
  const double dt0 = init.knotSpan();
  double stretch = 1.0;
  for (int i = 0; i + 1 < q.cols(); ++i)
    stretch = std::max(stretch,
                       (q.col(i + 1) - q.col(i)).norm() / dt0 / (config.feasibility_margin * config.v_max));
  for (int i = 0; i + 2 < q.cols(); ++i)
    stretch = std::max(stretch, std::sqrt((q.col(i + 2) - 2.0 * q.col(i + 1) + q.col(i)).norm() /
                                          (dt0 * dt0) / (config.feasibility_margin * config.a_max)));
  const double lo = std::log(config.min_knot_span), hi = std::log(config.max_knot_span);
  x.back() = std::clamp(std::log(dt0 * stretch), lo, hi);
  st.initial_cost = cost.evaluate(x.data(), nullptr);

  const unsigned nvars = static_cast<unsigned>(x.size());
  std::string failure;
  try {
    nlopt::opt opt(nlopt::LD_LBFGS, nvars);
    std::vector<double> lower(nvars, -HUGE_VAL), upper(nvars, HUGE_VAL);
    lower.back() = lo;
    upper.back() = hi;
    opt.set_lower_bounds(lower);
    opt.set_upper_bounds(upper);
    opt.set_min_objective(nloptObjective, const_cast<BsplineCost*>(&cost));
    opt.set_maxeval(config.max_iterations);
    opt.set_ftol_rel(config.relative_tolerance);
    opt.set_xtol_rel(config.relative_tolerance);
    double f = 0.0;
    st.nlopt_result = opt.optimize(x, f);
    st.final_cost = f;
  } catch (const nlopt::roundoff_limited&) {
    st.nlopt_result = nlopt::ROUNDOFF_LIMITED;
    failure = "round-off limited";
  } catch (const nlopt::forced_stop&) {
    st.nlopt_result = nlopt::FORCED_STOP;
    failure = "forced stop";
  } catch (const std::invalid_argument& e) {
    st.nlopt_result = nlopt::INVALID_ARGS;
    failure = std::string("invalid arguments: ") + e.what();
  } catch (const std::bad_alloc&) {
    st.nlopt_result = nlopt::OUT_OF_MEMORY;
    failure = "out of memory";
  } catch (const std::runtime_error& e) {
    st.nlopt_result = nlopt::FAILURE;
    failure = std::string("failure: ") + e.what();
  }
  st.evaluations = cost.evaluations();
  UniformBspline result = cost.spline(x.data());
  if (!failure.empty()) {
    st.final_cost = cost.evaluate(x.data(), nullptr);
    checkTrajectory(result, esdf, config, &st);
    return Result<UniformBspline>::Error("optimizer: NLopt stopped: " + failure);
  }
  if (Status s = checkTrajectory(result, esdf, config, &st); !s)
    return Result<UniformBspline>::Error("optimizer: result rejected: " + s.message());
  return result;
}

Result<UniformBspline> yawTurn(double yaw0, double yaw1, double min_duration, const OptimizerConfig& config,
                               double rate0) {
  if (Status s = config.validate(); !s) return s;
  if (!std::isfinite(yaw0) || !std::isfinite(yaw1) || !std::isfinite(min_duration) || !std::isfinite(rate0))
    return Result<UniformBspline>::Error("yawTurn: yaws, min_duration and rate0 must be finite");
  const double turn = std::remainder(yaw1 - yaw0, 2.0 * M_PI);
  const double rate_max = config.yaw_rate_max;
  const double w0 = std::clamp(rate0, -rate_max, rate_max);
  // The rate's control values r_i = (q_{i+1} - q_i) / dt: w0 twice (the start's rate, no acceleration),
  // a 0 where the turn goes against w0 (the rate passes through rest), k equal values c, then 0 twice (end at
  // rest). The curve starts at q_1 = yaw0 and ends at the last control point, yaw0 + turn, so the middle
  // values sum to turn / dt - w0. Between neighbours the rate steps by at most yaw_acc_max dt, and the span
  // that reaches yaw_rate_max at yaw_acc_max is yaw_rate_max / yaw_acc_max. From rest (w0 = 0) this is k
  // steps of turn / (k dt), the least k at that span, spread over min_duration when that is longer.
  const double dt0 = rate_max / config.yaw_acc_max;
  const int k0 = std::max(1, static_cast<int>(std::ceil(std::abs(turn) / (rate_max * dt0) - 1e-9)));
  int k = 0, bridge = 0;
  double dt = dt0;
  // Some k up to k0 + 1 with the bridge fits: |c| <= (|turn| / dt0 + rate_max) / (k0 + 1) <= rate_max.
  for (int spans = k0 + 2; spans <= k0 + 4 && k == 0; ++spans)
    for (int b = 0; b <= 1 && k == 0; ++b) {
      const int n = spans - 2 - b;
      if (n < 1) continue;
      const double span = std::max(dt0, min_duration / spans);
      const double v = (turn / span - w0) / n;
      const double step = config.yaw_acc_max * span * (1.0 + 1e-9);
      if (std::abs(v) > rate_max * (1.0 + 1e-9) || std::abs(v) > step) continue;
      if (b == 0 && std::abs(v - w0) > step) continue;
      k = n, bridge = b, dt = span;
    }
  if (k == 0) return Result<UniformBspline>::Error("yawTurn: no rate profile fits (a bug)");
  // Control points: yaw0 - w0 dt, yaw0, yaw0 + w0 dt (twice with the bridge), then k equal steps of
  // c dt = (turn - w0 dt) / k, and yaw0 + turn twice more.
  const int j0 = 2 + bridge;
  Eigen::MatrixXd q(1, j0 + k + 3);
  q(0, 0) = yaw0 - w0 * dt;
  q(0, 1) = yaw0;
  for (int j = 2; j <= j0; ++j) q(0, j) = yaw0 + w0 * dt;
  for (int i = 1; i <= k; ++i) q(0, j0 + i) = yaw0 + w0 * dt + (turn - w0 * dt) * i / k;
  q(0, j0 + k + 1) = q(0, j0 + k + 2) = q(0, j0 + k);
  return UniformBspline(q, kDegree, dt);
}

}  // namespace go_feap::trajectory
