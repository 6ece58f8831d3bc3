// UniformBspline against finite differences, polynomial reproduction, interpolation conditions and time
// scaling, for several degrees.
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "go_feap/trajectory/bspline.h"

using go_feap::common::Vec3;
using go_feap::trajectory::UniformBspline;

namespace {

// Uniform doubles from raw mt19937 output, the same on every standard library.
struct Rng {
  explicit Rng(unsigned seed) : engine(seed) {}
  double operator()(double lo, double hi) { return lo + (hi - lo) * (engine() / 4294967296.0); }
  std::mt19937 engine;
};

Eigen::MatrixXd randomPoints(Rng& rng, int dim, int n, double scale) {
  Eigen::MatrixXd m(dim, n);
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < dim; ++d) m(d, i) = rng(-scale, scale);
  return m;
}

// A random time at least `margin` away from every knot (derivatives of order p jump there).
double timeAwayFromKnots(Rng& rng, const UniformBspline& s, double margin) {
  for (;;) {
    const double t = rng(0.0, s.duration());
    const double f = t / s.knotSpan();
    if (std::abs(f - std::round(f)) * s.knotSpan() > margin) return t;
  }
}

TEST(Bspline, DerivativesMatchCentralDifferences) {
  Rng rng(1);
  for (int degree = 1; degree <= 5; ++degree) {
    for (int trial = 0; trial < 20; ++trial) {
      const double dt = rng(0.1, 0.7);
      const UniformBspline s(randomPoints(rng, 3, degree + 8, 3.0), degree, dt);
      const double h = 1e-5;
      for (int k = 0; k < 25; ++k) {
        const double t = timeAwayFromKnots(rng, s, 1e-3);
        for (int order = 1; order <= std::min(degree, 3); ++order) {
          const Eigen::VectorXd fd = (s.evaluate(t + h, order - 1) - s.evaluate(t - h, order - 1)) / (2 * h);
          const Eigen::VectorXd an = s.evaluate(t, order);
          const double scale = 1.0 + an.norm();
          EXPECT_LT((fd - an).norm(), 1e-5 * scale * std::pow(1.0 / dt, order))
              << "degree " << degree << " order " << order << " t " << t;
        }
      }
    }
  }
}

TEST(Bspline, DerivativeCurvesAgreeWithEvaluate) {
  Rng rng(2);
  for (int degree = 1; degree <= 5; ++degree) {
    const UniformBspline s(randomPoints(rng, 2, degree + 5, 2.0), degree, rng(0.05, 1.0));
    for (int order = 0; order <= degree; ++order) {
      const UniformBspline d = s.derivative(order);
      EXPECT_EQ(d.degree(), degree - order);
      EXPECT_EQ(d.numControlPoints(), s.numControlPoints() - order);
      EXPECT_NEAR(d.duration(), s.duration(), 1e-12);
      for (int k = 0; k <= 50; ++k) {
        const double t = s.duration() * k / 50.0;
        EXPECT_LT((d.value(t) - s.evaluate(t, order)).norm(), 1e-9 * (1.0 + d.value(t).norm()));
      }
    }
    // Beyond the degree every derivative vanishes.
    EXPECT_EQ(s.evaluate(0.3 * s.duration(), degree + 1).norm(), 0.0);
  }
}

TEST(Bspline, ReproducesConstantsAndLines) {
  // Control points a + b * i give the straight line a + b * (t / dt + (p - 1) / 2) (Greville abscissae).
  const Eigen::Vector3d a(1.0, -2.0, 0.5), b(0.3, 0.1, -0.2);
  for (int degree = 0; degree <= 5; ++degree) {
    const int n = degree + 6;
    const double dt = 0.4;
    Eigen::MatrixXd q(3, n);
    for (int i = 0; i < n; ++i) q.col(i) = a + b * i;
    const UniformBspline s(q, degree, dt);
    EXPECT_NEAR(s.duration(), (n - degree) * dt, 1e-12);
    if (degree == 0) continue;  // piecewise constant
    for (int k = 0; k <= 40; ++k) {
      const double t = s.duration() * k / 40.0;
      const Eigen::Vector3d expected = a + b * (t / dt + (degree - 1) / 2.0);
      EXPECT_LT((s.value(t) - expected).norm(), 1e-12) << "degree " << degree;
      EXPECT_LT((s.evaluate(t, 1) - b / dt).norm(), 1e-12);
    }
  }
}

TEST(Bspline, BasisWeightsFormAPartitionOfUnity) {
  Rng rng(3);
  double w[UniformBspline::kMaxDegree + 1];
  for (int degree = 0; degree <= UniformBspline::kMaxDegree; ++degree)
    for (int k = 0; k < 20; ++k) {
      UniformBspline::basisWeights(degree, rng(0.0, 1.0), 0, w);
      double sum = 0.0;
      for (int j = 0; j <= degree; ++j) {
        EXPECT_GE(w[j], -1e-15);
        sum += w[j];
      }
      EXPECT_NEAR(sum, 1.0, 1e-12);
    }
  // The cubic at a knot: (1, 4, 1) / 6.
  UniformBspline::basisWeights(3, 0.0, 0, w);
  EXPECT_NEAR(w[0], 1.0 / 6, 1e-15);
  EXPECT_NEAR(w[1], 4.0 / 6, 1e-15);
  EXPECT_NEAR(w[2], 1.0 / 6, 1e-15);
  EXPECT_NEAR(w[3], 0.0, 1e-15);
}

Eigen::VectorXd vec(const Vec3& v) { return v; }

TEST(Bspline, FitPathInterpolatesPointsAndEndVelocities) {
  Rng rng(4);
  for (int trial = 0; trial < 20; ++trial) {
    const int k = 2 + trial;
    const double dt = rng(0.1, 0.5);
    const Eigen::MatrixXd points = randomPoints(rng, 3, k, 3.0);
    const Vec3 v0(rng(-1, 1), rng(-1, 1), rng(-1, 1)), v1(rng(-1, 1), rng(-1, 1), rng(-1, 1));
    const UniformBspline s = UniformBspline::fitPath(points, dt, vec(v0), vec(v1));
    ASSERT_EQ(s.numControlPoints(), k + 2);
    EXPECT_NEAR(s.duration(), (k - 1) * dt, 1e-12);
    for (int i = 0; i < k; ++i) EXPECT_LT((s.value(i * dt) - points.col(i)).norm(), 1e-6) << "point " << i;
    EXPECT_LT((Vec3(s.evaluate(0.0, 1)) - v0).norm(), 1e-6);
    EXPECT_LT((Vec3(s.evaluate(s.duration(), 1)) - v1).norm(), 1e-6);
  }
  // 1-D (yaw).
  Eigen::MatrixXd yaw(1, 5);
  yaw << 0.0, 0.5, 1.5, 1.0, -0.5;
  const UniformBspline s =
      UniformBspline::fitPath(yaw, 0.3, Eigen::VectorXd::Constant(1, 0.2), Eigen::VectorXd::Zero(1));
  for (int i = 0; i < 5; ++i) EXPECT_NEAR(s.value(i * 0.3)[0], yaw(0, i), 1e-6);
  // Other degrees: least squares, still close to the points of a smooth path.
  for (int degree : {2, 4, 5}) {
    Eigen::MatrixXd pts(2, 15);
    for (int i = 0; i < 15; ++i) pts.col(i) << std::cos(0.2 * i), std::sin(0.2 * i);
    const Eigen::Vector2d v0(-std::sin(0.0), std::cos(0.0)), v1(-std::sin(2.8), std::cos(2.8));
    const UniformBspline f = UniformBspline::fitPath(pts, 0.2, v0, v1, degree);
    for (int i = 0; i < 15; ++i)
      EXPECT_LT((f.value(0.2 * i) - pts.col(i)).norm(), 0.02) << "degree " << degree;
  }
}

TEST(Bspline, FitPathWithAccelerationsKeepsEndStatesExactly) {
  Rng rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    // Samples of a smooth curve, with its own end velocities and accelerations: the fit keeps those
    // exactly and stays close to the samples in between.
    const Vec3 c0(rng(-2, 2), rng(-2, 2), rng(0, 2)), c1(rng(-1, 1), rng(-1, 1), rng(-1, 1)),
        c2(rng(-0.3, 0.3), rng(-0.3, 0.3), rng(-0.3, 0.3));
    auto curve = [&](double t) -> Vec3 { return c0 + c1 * t + c2 * t * t; };
    const double dt = rng(0.1, 0.4);
    const int k = 5 + trial;
    std::vector<Vec3> points;
    for (int i = 0; i < k; ++i) points.push_back(curve(i * dt));
    const double t_end = (k - 1) * dt;
    const Vec3 v0 = c1, v1 = c1 + 2 * c2 * t_end, acc = 2 * c2;
    const UniformBspline s = UniformBspline::fitPath(points, dt, v0, v1, acc, acc);
    EXPECT_LT((s.position(0.0) - points.front()).norm(), 1e-9);
    EXPECT_LT((s.position(t_end) - points.back()).norm(), 1e-9);
    EXPECT_LT((Vec3(s.evaluate(0.0, 1)) - v0).norm(), 1e-8);
    EXPECT_LT((Vec3(s.evaluate(t_end, 1)) - v1).norm(), 1e-8);
    EXPECT_LT((Vec3(s.evaluate(0.0, 2)) - acc).norm(), 1e-7);
    EXPECT_LT((Vec3(s.evaluate(t_end, 2)) - acc).norm(), 1e-7);
    // A cubic B-spline reproduces a quadratic: the samples are met exactly.
    for (int i = 0; i < k; ++i) EXPECT_LT((s.position(i * dt) - points[i]).norm(), 1e-7) << "point " << i;
  }
  // From rest to rest through points that ask for motion at once: end states still exact.
  std::vector<Vec3> line;
  for (int i = 0; i < 10; ++i) line.emplace_back(0.3 * i, 0, 1);
  const UniformBspline s = UniformBspline::fitPath(line, 0.15, Vec3::Zero(), Vec3::Zero());
  EXPECT_LT(s.evaluate(0.0, 1).norm() + s.evaluate(0.0, 2).norm(), 1e-8);
  EXPECT_LT(s.evaluate(s.duration(), 1).norm() + s.evaluate(s.duration(), 2).norm(), 1e-8);
}

// Timed samples as control points: exact start state and rest at the end, within a dt^2 / 6 of each
// sample (sample k at k dt), and speed and acceleration, sampled densely, never above the samples' own
// first and second differences (or the start's). The samples: a random walk of bounded steps, so their
// acceleration changes at every knot (an interpolating fit rings there).
TEST(Bspline, FromTimedSamplesKeepsTheSamplesSpeedAndAcceleration) {
  Rng rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    const double dt = rng(0.02, 0.2);
    const int n = 3 + trial;
    std::vector<Vec3> points{Vec3(rng(-2, 2), rng(-2, 2), rng(0, 2))};
    Vec3 v(rng(-1, 1), rng(-1, 1), rng(-1, 1));
    for (int i = 1; i < n; ++i) {
      v += dt * Vec3(rng(-2, 2), rng(-2, 2), rng(-2, 2));
      points.push_back(points.back() + dt * v);
    }
    const Vec3 v0(rng(-1, 1), rng(-1, 1), rng(-1, 1)), a0(rng(-2, 2), rng(-2, 2), rng(-2, 2));
    const UniformBspline s = UniformBspline::fromTimedSamples(points, dt, v0, a0);
    EXPECT_NEAR(s.duration(), n * dt, 1e-12);
    EXPECT_LT((s.position(0.0) - points.front()).norm(), 1e-12);
    EXPECT_LT((Vec3(s.evaluate(0.0, 1)) - v0).norm(), 1e-9);
    EXPECT_LT((Vec3(s.evaluate(0.0, 2)) - a0).norm(), 1e-9);
    EXPECT_LT((s.position(s.duration()) - points.back()).norm(), 1e-12);
    EXPECT_LT(s.evaluate(s.duration(), 1).norm() + s.evaluate(s.duration(), 2).norm(), 1e-9);
    // Bounds from the control polygon the start state and the samples make.
    const Vec3 q1 = points[0] - a0 * dt * dt / 6.0;
    std::vector<Vec3> q{q1 - v0 * dt + a0 * dt * dt / 2.0, q1, q1 + v0 * dt + a0 * dt * dt / 2.0};
    for (int i = 2; i < n; ++i) q.push_back(points[i]);
    q.push_back(points.back());
    q.push_back(points.back());
    double v_bound = 0.0, a_bound = 0.0, sd_max = 0.0;
    for (std::size_t i = 0; i + 1 < q.size(); ++i) v_bound = std::max(v_bound, (q[i + 1] - q[i]).norm() / dt);
    for (std::size_t i = 1; i + 1 < q.size(); ++i)
      a_bound = std::max(a_bound, (q[i + 1] - 2.0 * q[i] + q[i - 1]).norm() / (dt * dt));
    for (int i = 2; i + 1 < n; ++i)
      sd_max = std::max(sd_max, (points[i + 1] - 2.0 * points[i] + points[i - 1]).norm() / (dt * dt));
    for (int k = 0; k <= 2000; ++k) {
      const double t = s.duration() * k / 2000.0;
      EXPECT_LE(s.evaluate(t, 1).norm(), v_bound + 1e-9);
      EXPECT_LE(s.evaluate(t, 2).norm(), a_bound + 1e-9);
    }
    for (int i = 3; i + 2 < n; ++i)
      EXPECT_LE((s.position(i * dt) - points[i]).norm(), sd_max * dt * dt / 6.0 + 1e-12) << "sample " << i;
  }
  EXPECT_THROW(UniformBspline::fromTimedSamples({Vec3::Zero(), Vec3::Ones()}, 0.1, Vec3::Zero(), Vec3::Zero()),
               std::invalid_argument);
  EXPECT_THROW(UniformBspline::fromTimedSamples({Vec3::Zero(), Vec3::Ones(), Vec3::Ones()}, 0.0, Vec3::Zero(),
                                                Vec3::Zero()),
               std::invalid_argument);
  EXPECT_THROW(UniformBspline::fromTimedSamples({Vec3::Zero(), Vec3::Ones(), Vec3::Constant(std::nan(""))}, 0.1,
                                                Vec3::Zero(), Vec3::Zero()),
               std::invalid_argument);
}

TEST(Bspline, SetKnotSpanScalesTime) {
  Rng rng(5);
  UniformBspline s(randomPoints(rng, 3, 10, 2.0), 3, 0.2);
  const UniformBspline before = s;
  const double factor = 2.5;
  s.setKnotSpan(0.2 * factor);
  EXPECT_NEAR(s.duration(), before.duration() * factor, 1e-12);
  for (int k = 0; k <= 30; ++k) {
    const double t = before.duration() * k / 30.0;
    EXPECT_LT((s.value(t * factor) - before.value(t)).norm(), 1e-12);
    EXPECT_LT((s.evaluate(t * factor, 1) * factor - before.evaluate(t, 1)).norm(), 1e-9);
    EXPECT_LT((s.evaluate(t * factor, 2) * factor * factor - before.evaluate(t, 2)).norm(), 1e-9);
  }
  EXPECT_NEAR(s.maxVelocity() * factor, before.maxVelocity(), 1e-9);
  EXPECT_NEAR(s.maxAcceleration() * factor * factor, before.maxAcceleration(), 1e-9);
  EXPECT_THROW(s.setKnotSpan(0.0), std::invalid_argument);
}

TEST(Bspline, MaxDerivativeNormMatchesDenseSampling) {
  Rng rng(6);
  for (int trial = 0; trial < 10; ++trial) {
    const UniformBspline s(randomPoints(rng, 3, 12, 2.0), 3, rng(0.1, 0.5));
    for (int order = 1; order <= 2; ++order) {
      double dense = 0.0;
      // 9 spans: 18000 samples include every knot.
      for (int k = 0; k <= 18000; ++k)
        dense = std::max(dense, s.evaluate(s.duration() * k / 18000.0, order).norm());
      const double sampled = s.maxDerivativeNorm(order, 64);
      EXPECT_LE(sampled, dense + 1e-9);
      EXPECT_GT(sampled, dense * (1.0 - 1e-3));
      if (order == 2) {
        EXPECT_NEAR(s.maxDerivativeNorm(2, 1), dense, 1e-9);  // piecewise linear: knots suffice
      }
    }
  }
}

TEST(Bspline, ResamplePolylineHasEqualStepsOnThePath) {
  const std::vector<Vec3> path = {Vec3(0, 0, 1), Vec3(2, 0, 1), Vec3(2, 1.5, 1), Vec3(2, 1.5, 2.2)};
  const double length = 2.0 + 1.5 + 1.2;
  const std::vector<Vec3> out = UniformBspline::resamplePolyline(path, 0.3);
  const int steps = static_cast<int>(std::ceil(length / 0.3));
  ASSERT_EQ(static_cast<int>(out.size()), steps + 1);
  EXPECT_EQ(out.front(), path.front());
  EXPECT_EQ(out.back(), path.back());
  for (const Vec3& p : out) {
    // On one of the three axis-aligned segments.
    const bool on0 = std::abs(p.y()) < 1e-12 && std::abs(p.z() - 1) < 1e-12;
    const bool on1 = std::abs(p.x() - 2) < 1e-12 && std::abs(p.z() - 1) < 1e-12;
    const bool on2 = std::abs(p.x() - 2) < 1e-12 && std::abs(p.y() - 1.5) < 1e-12;
    EXPECT_TRUE(on0 || on1 || on2) << p.transpose();
  }
  // Arc-length steps: distance along the path between consecutive samples is length / steps.
  auto arc = [](const Vec3& p) {
    if (std::abs(p.y()) < 1e-12 && std::abs(p.z() - 1) < 1e-12) return p.x();
    if (std::abs(p.z() - 1) < 1e-12) return 2.0 + p.y();
    return 3.5 + (p.z() - 1.0);
  };
  for (std::size_t i = 1; i < out.size(); ++i)
    EXPECT_NEAR(arc(out[i]) - arc(out[i - 1]), length / steps, 1e-9);
  EXPECT_EQ(UniformBspline::resamplePolyline({Vec3(1, 2, 3)}, 0.3).size(), 2u);
  EXPECT_TRUE(UniformBspline::resamplePolyline({}, 0.3).empty());
}

TEST(Bspline, RejectsBadArguments) {
  EXPECT_THROW(UniformBspline(Eigen::MatrixXd::Zero(3, 3), 3, 0.1), std::invalid_argument);
  EXPECT_THROW(UniformBspline(Eigen::MatrixXd::Zero(3, 5), 3, 0.0), std::invalid_argument);
  EXPECT_THROW(UniformBspline(Eigen::MatrixXd::Zero(3, 5), -1, 0.1), std::invalid_argument);
  // Above kMaxDegree the basis would not fit its fixed-size arrays: refused, while kMaxDegree itself works.
  EXPECT_THROW(UniformBspline(Eigen::MatrixXd::Zero(3, 12), UniformBspline::kMaxDegree + 1, 0.1),
               std::invalid_argument);
  EXPECT_NO_THROW(UniformBspline(Eigen::MatrixXd::Zero(3, 12), UniformBspline::kMaxDegree, 0.1));
  EXPECT_THROW(UniformBspline::fitPath(std::vector<Vec3>{Vec3::Zero()}, 0.1, Vec3::Zero(), Vec3::Zero()),
               std::invalid_argument);
  EXPECT_THROW(UniformBspline::fitPath(Eigen::MatrixXd::Zero(2, 4), 0.1, Eigen::VectorXd::Zero(3),
                                       Eigen::VectorXd::Zero(2)),
               std::invalid_argument);
  EXPECT_THROW(UniformBspline(Eigen::MatrixXd::Zero(3, 5), 0, 0.1).derivative(), std::invalid_argument);
  // Fewer control points (K + degree - 1) than end conditions: they could not all be met.
  const std::vector<Vec3> three = {Vec3::Zero(), Vec3(1, 0, 0), Vec3(2, 1, 0)};
  EXPECT_THROW(UniformBspline::fitPath(three, 0.1, Vec3::Zero(), Vec3::Zero(), Vec3::Zero(), Vec3::Zero()),
               std::invalid_argument);
  EXPECT_THROW(UniformBspline::fitPath(Eigen::MatrixXd::Zero(2, 3), 0.1, Eigen::VectorXd::Zero(2),
                                       Eigen::VectorXd::Zero(2), 1),
               std::invalid_argument);
  EXPECT_NO_THROW(UniformBspline::fitPath(Eigen::MatrixXd::Zero(2, 4), 0.1, Eigen::VectorXd::Zero(2),
                                          Eigen::VectorXd::Zero(2), 1));
  // Times out of range are clamped; NaN reads as the start (its cast to a span index was undefined).
  const UniformBspline line = UniformBspline::fitPath({Vec3::Zero(), Vec3(1, 0, 0), Vec3(2, 1, 0), Vec3(3, 1, 0)},
                                                     0.1, Vec3::Zero(), Vec3::Zero());
  EXPECT_EQ(line.value(std::nan("")), line.value(0.0));
  EXPECT_EQ(line.evaluate(std::nan(""), 1), line.evaluate(0.0, 1));
  EXPECT_EQ(line.value(INFINITY), line.value(line.duration()));
  EXPECT_EQ(line.value(-INFINITY), line.value(0.0));
  // A negative derivative order is refused (it wrote past the weights' buffers).
  EXPECT_THROW(line.evaluate(0.5, -1), std::invalid_argument);
  EXPECT_THROW(line.maxDerivativeNorm(-5), std::invalid_argument);
  const UniformBspline empty;
  EXPECT_TRUE(empty.empty());
  EXPECT_EQ(empty.duration(), 0.0);
}

}  // namespace
