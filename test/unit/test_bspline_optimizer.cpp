// B-spline optimiser: every cost term's gradient against central differences, optimised trajectories on
// random obstacle fields against finite-difference dynamics and analytic distances to the obstacle boxes,
// the yaw spline, the replanning rule, collision prediction, the safe stop, and whole plans from a start
// state to a target (short hops included).
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "go_feap/map/esdf.h"
#include "go_feap/map/occupancy_map.h"
#include "go_feap/planning/astar.h"
#include "go_feap/trajectory/bspline.h"
#include "go_feap/trajectory/bspline_optimizer.h"
#include "go_feap/trajectory/replan.h"
#include "go_feap/trajectory/trajectory_planner.h"

using go_feap::common::Aabb;
using go_feap::common::GridGeometry;
using go_feap::common::Index3;
using go_feap::common::Vec3;
using go_feap::map::Esdf;
using go_feap::map::EsdfConfig;
using go_feap::map::OccupancyConfig;
using go_feap::map::OccupancyMap;
using go_feap::map::VoxelState;
using go_feap::planning::Astar;
using go_feap::planning::AstarConfig;
using go_feap::planning::PathResult;
using go_feap::planning::PathStatus;
namespace traj = go_feap::trajectory;
using traj::BsplineCost;
using traj::OptimizerConfig;
using traj::OptimizeStats;
using traj::ReplanConfig;
using traj::ReplanInputs;
using traj::ReplanReason;
using traj::UniformBspline;

namespace {

constexpr double kRes = 0.1;
constexpr double kPi = 3.14159265358979323846;

// Uniform doubles and integers from raw mt19937 output, the same on every standard library.
struct Rng {
  explicit Rng(unsigned seed) : engine(seed) {}
  double operator()(double lo, double hi) { return lo + (hi - lo) * (engine() / 4294967296.0); }
  int integer(int lo, int hi) { return lo + static_cast<int>(engine() % static_cast<unsigned>(hi - lo + 1)); }
  std::mt19937 engine;
};

EsdfConfig esdfConfig() {
  EsdfConfig c;
  c.max_distance = 1.0;
  return c;
}

OccupancyConfig occupancyConfig() {
  OccupancyConfig c;
  c.resolution = kRes;
  c.margin = 0.0;
  return c;
}

// A box world: occupancy map and ESDF over [0, size], obstacles given as inclusive voxel boxes. Also keeps,
// per obstacle box, the box spanned by its voxel centres: the distance from a point to it is a lower
// bound of the distance to the nearest obstacle voxel centre (the quantity the ESDF interpolates).
class World {
 public:
  explicit World(const Vec3& size)
      : occupancy_(occupancyConfig(), Aabb{Vec3::Zero(), size}), esdf_(occupancy_.geometry(), esdfConfig()) {}

  const GridGeometry& geo() const { return occupancy_.geometry(); }
  const OccupancyMap& occupancy() const { return occupancy_; }
  const Esdf& esdf() const { return esdf_; }

  void addBox(Index3 lo, Index3 hi) {
    lo = lo.cwiseMax(Index3::Zero());
    hi = hi.cwiseMin(geo().dims() - Index3::Ones());
    if ((hi.array() < lo.array()).any()) return;
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) {
          occupancy_.setState(Index3(x, y, z), VoxelState::kOccupied);
          pending_.push_back(geo().linear(Index3(x, y, z)));
        }
    centre_boxes_.push_back({geo().indexToCoord(lo), geo().indexToCoord(hi)});
  }
  /// Occupies the bottom and top layers of voxels (a room without walls).
  void addFloorAndCeiling() {
    const Index3 dims = geo().dims();
    addBox(Index3(0, 0, 0), Index3(dims.x() - 1, dims.y() - 1, 0));
    addBox(Index3(0, 0, dims.z() - 1), Index3(dims.x() - 1, dims.y() - 1, dims.z() - 1));
  }
  void setUnknown(const Index3& idx) { occupancy_.setState(idx, VoxelState::kUnknown); }
  /// Marks the voxels of an inclusive box free (mapped empty space).
  void setFree(const Index3& lo, const Index3& hi) {
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) occupancy_.setState(Index3(x, y, z), VoxelState::kFree);
  }
  void sync() {
    esdf_.update(pending_, {});
    pending_.clear();
  }
  /// Distance from p to the nearest obstacle box of voxel centres.
  double boxDistance(const Vec3& p) const {
    double best = std::numeric_limits<double>::infinity();
    for (const Aabb& b : centre_boxes_) {
      const Vec3 d = (b.min - p).cwiseMax(p - b.max).cwiseMax(Vec3::Zero());
      best = std::min(best, d.norm());
    }
    return best;
  }

 private:
  OccupancyMap occupancy_;
  Esdf esdf_;
  std::vector<std::size_t> pending_;
  std::vector<Aabb> centre_boxes_;
};

// A room of `size` with only its floor and ceiling mapped, and a flight search that takes unknown space as
// free.
struct OpenRoom {
  explicit OpenRoom(const Vec3& size) : world(size), astar(furnished(world).occupancy(), world.esdf(), unknownFree()) {}
  static World& furnished(World& w) {
    w.addFloorAndCeiling();
    w.sync();
    return w;
  }
  static AstarConfig unknownFree() {
    AstarConfig c;
    c.unknown_is_free = true;
    return c;
  }
  World world;
  Astar astar;
};

// 8 x 8 x 3 m with floor, ceiling, pillars and floating boxes.
void fillRandomField(World& world, Rng& rng) {
  const Index3 dims = world.geo().dims();
  world.addFloorAndCeiling();
  const int pillars = rng.integer(4, 9);
  for (int i = 0; i < pillars; ++i) {
    const Index3 lo(rng.integer(5, dims.x() - 10), rng.integer(5, dims.y() - 10), 0);
    world.addBox(lo, lo + Index3(rng.integer(2, 9), rng.integer(2, 9), dims.z() - 1));
  }
  const int floating = rng.integer(2, 5);
  for (int i = 0; i < floating; ++i) {
    const Index3 lo(rng.integer(5, dims.x() - 10), rng.integer(5, dims.y() - 10),
                    rng.integer(5, dims.z() - 10));
    world.addBox(lo, lo + Index3(rng.integer(2, 9), rng.integer(2, 9), rng.integer(2, 6)));
  }
  world.sync();
}

OptimizerConfig optimizerConfig() {
  OptimizerConfig c;
  c.v_max = 2.0;
  c.a_max = 2.0;
  c.clearance = 0.5;
  c.min_clearance = 0.2;
  return c;
}

// The sampled speed and acceleration of a spline by finite differences of its positions (independent of
// its derivative curves), over `samples` equal time steps.
void finiteDifferenceDynamics(const UniformBspline& s, int samples, double& v_max, double& a_max) {
  const double h = 1e-4;
  v_max = a_max = 0.0;
  for (int k = 0; k <= samples; ++k) {
    const double t = std::clamp(s.duration() * k / samples, h, s.duration() - h);
    const Vec3 p0 = s.position(t - h), p1 = s.position(t), p2 = s.position(t + h);
    v_max = std::max(v_max, (p2 - p0).norm() / (2 * h));
    a_max = std::max(a_max, (p2 - 2 * p1 + p0).norm() / (h * h));
  }
}

// ---------------------------------------------------------------------------------------------------------
// Gradients.

struct TermCase {
  unsigned mask;
  const char* name;
};

// A term of the cost as BsplineCost's documentation writes it, from the control points of `s` (the
// spline the variables describe) and the ESDF's interpolated distance.
double documentedTerm(unsigned term, const UniformBspline& s, const Esdf& esdf, const OptimizerConfig& c) {
  const Eigen::MatrixXd& q = s.controlPoints();
  const int n = static_cast<int>(q.cols());
  const double dt = s.knotSpan();
  auto excess = [](double r) { return r > 1.0 ? (r - 1.0) * (r - 1.0) : 0.0; };
  double f = 0.0;
  if (term == traj::kSmoothness)
    for (int i = 0; i + 3 < n; ++i) f += c.lambda_smooth * (q.col(i + 3) - 3 * q.col(i + 2) + 3 * q.col(i + 1) - q.col(i)).squaredNorm();
  if (term == traj::kClearance)
    for (int i = 3; i < n - 3; ++i) {  // the free control points
      const double e = std::max(0.0, c.clearance - esdf.distance(Vec3(q.col(i))));
      f += c.lambda_clearance * e * e;
    }
  const double v = c.feasibility_margin * c.v_max, a = c.feasibility_margin * c.a_max;
  if (term == traj::kVelocity)
    for (int i = 0; i + 1 < n; ++i) f += c.lambda_feasibility * excess(((q.col(i + 1) - q.col(i)) / dt).squaredNorm() / (v * v));
  if (term == traj::kAcceleration)
    for (int i = 0; i + 2 < n; ++i)
      f += c.lambda_feasibility * excess(((q.col(i + 2) - 2 * q.col(i + 1) + q.col(i)) / (dt * dt)).squaredNorm() / (a * a));
  if (term == traj::kTime) f = c.lambda_time * (n - 3) * dt;
  return f;
}

TEST(BsplineCost, EachTermGradientMatchesCentralDifferences) {
  World world(Vec3(4.0, 4.0, 2.0));
  world.addBox(Index3(12, 12, 0), Index3(17, 17, 19));
  world.addBox(Index3(25, 5, 5), Index3(30, 30, 10));
  world.sync();
  OptimizerConfig config = optimizerConfig();
  config.v_max = 1.5;
  config.a_max = 1.5;
  // Weights away from their defaults (and from 1): a weight the cost ignored would leave its documented term.
  config.lambda_smooth = 2.5;
  config.lambda_clearance *= 1.7;
  config.lambda_feasibility *= 0.6;
  config.lambda_time *= 1.3;
  const TermCase cases[] = {
      {traj::kSmoothness, "smoothness"},     {traj::kClearance, "clearance"}, {traj::kVelocity, "velocity"},
      {traj::kAcceleration, "acceleration"}, {traj::kTime, "time"},           {traj::kAllTerms, "all"}};
  Rng rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    // Control points scattered around the obstacles, so every term is active; random boundary states.
    Eigen::MatrixXd q(3, 14);
    for (int i = 0; i < q.cols(); ++i) q.col(i) = Vec3(rng(0.8, 3.2), rng(0.8, 3.2), rng(0.5, 1.5));
    const UniformBspline init(q, 3, rng(0.15, 0.4));
    const BsplineCost cost(init, world.esdf(), config);
    std::vector<double> x = cost.variables(init);
    // The variables describe the same spline (boundary points rebuilt from the boundary states).
    EXPECT_LT((cost.spline(x.data()).controlPoints() - q).cwiseAbs().maxCoeff(), 1e-9);
    x.back() += rng(-0.2, 0.2);  // a different dt moves the boundary points too
    // Each term's value is the documented formula (the gradients below are checked against the values).
    const UniformBspline described = cost.spline(x.data());
    double sum = 0.0;
    for (const TermCase& c : cases) {
      if (c.mask == traj::kAllTerms) continue;
      const double expected = documentedTerm(c.mask, described, world.esdf(), config);
      EXPECT_NEAR(cost.evaluate(x, nullptr, c.mask), expected, 1e-9 * std::max(1.0, expected)) << c.name << " trial " << trial;
      sum += expected;
    }
    EXPECT_NEAR(cost.evaluate(x, nullptr, traj::kAllTerms), sum, 1e-9 * std::max(1.0, sum)) << "trial " << trial;
    for (const TermCase& c : cases) {
      std::vector<double> grad;
      const double f = cost.evaluate(x, &grad, c.mask);
      EXPECT_GT(f, 0.0) << c.name << " inactive";
      double scale = 1.0;
      for (double g : grad) scale = std::max(scale, std::abs(g));
      int compared = 0;
      for (std::size_t i = 0; i < x.size(); ++i) {
        const double h = 1e-6;
        std::vector<double> xp = x, xm = x;
        xp[i] += h;
        xm[i] -= h;
        const double fp = cost.evaluate(xp, nullptr, c.mask), fm = cost.evaluate(xm, nullptr, c.mask);
        const double forward = (fp - f) / h, backward = (f - fm) / h;
        // The ESDF interpolant has kinks on voxel faces: skip the rare variable whose step crosses one.
        if (std::abs(forward - backward) > 1e-3 * scale) continue;
        ++compared;
        EXPECT_NEAR(grad[i], (fp - fm) / (2 * h), 1e-5 * scale)
            << c.name << " variable " << i << " trial " << trial;
      }
      EXPECT_GE(compared, static_cast<int>(x.size()) - 2) << c.name;
    }
  }
}

// ---------------------------------------------------------------------------------------------------------
// Random obstacle fields.

TEST(BsplineOptimizer, RandomFieldsMeetLimitsOrFail) {
  const OptimizerConfig config = optimizerConfig();
  int fields = 0, successes = 0, attempts = 0;
  double worst_v = 0.0, worst_a = 0.0, worst_clearance = std::numeric_limits<double>::infinity();
  double total_ms = 0.0, max_ms = 0.0;
  int total_points = 0, total_evaluations = 0;
  std::map<std::string, int> nlopt_results;
  std::vector<std::string> failures;
  for (unsigned seed = 1; fields < 100 && seed < 400; ++seed) {
    Rng rng(1000 + seed);
    World world(Vec3(8.0, 8.0, 3.0));
    fillRandomField(world, rng);
    AstarConfig astar_config;
    astar_config.clearance = 0.4;
    astar_config.unknown_is_free = true;
    const Astar astar(world.occupancy(), world.esdf(), astar_config);
    // A start and goal at least 4 m apart in open space, joined by an A* path.
    std::optional<PathResult> found;
    Vec3 start, goal;
    for (int tries = 0; tries < 50 && !found; ++tries) {
      start = Vec3(rng(0.8, 7.2), rng(0.8, 7.2), rng(0.8, 2.2));
      goal = Vec3(rng(0.8, 7.2), rng(0.8, 7.2), rng(0.8, 2.2));
      if ((goal - start).norm() < 4.0) continue;
      if (world.esdf().distance(start) < 0.6 || world.esdf().distance(goal) < 0.6) continue;
      PathResult r = astar.search(start, goal, 0.0);
      if (r.status == PathStatus::kFound) found = std::move(r);
    }
    ++attempts;
    if (!found) continue;
    ++fields;
    // The path's ends are voxel centres; fly from and to them at rest.
    const std::vector<Vec3> samples = UniformBspline::resamplePolyline(found->path, 0.3);
    const UniformBspline init =
        UniformBspline::fitPath(samples, 0.3 / config.v_max, Vec3::Zero(), Vec3::Zero());
    total_points += init.numControlPoints();

    OptimizeStats stats;
    const auto t0 = std::chrono::steady_clock::now();
    const auto result = traj::optimize(init, world.esdf(), config, &stats);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    total_ms += ms;
    max_ms = std::max(max_ms, ms);
    total_evaluations += stats.evaluations;
    ++nlopt_results[std::to_string(stats.nlopt_result)];
    if (!result.ok()) {
      EXPECT_FALSE(result.message().empty());
      failures.push_back("seed " + std::to_string(seed) + ": " + result.message());
      continue;
    }
    ++successes;
    // ok() must mean every check holds, by oracles independent of the optimiser's own check.
    const UniformBspline& s = *result;
    double v = 0.0, a = 0.0;
    finiteDifferenceDynamics(s, 4000, v, a);
    EXPECT_LE(v, config.v_max * 1.05 + 1e-3) << "seed " << seed;
    EXPECT_LE(a, config.a_max * 1.05 + 1e-2) << "seed " << seed;
    worst_v = std::max(worst_v, v / config.v_max);
    worst_a = std::max(worst_a, a / config.a_max);
    double clearance = std::numeric_limits<double>::infinity();
    const int n = std::max(2000, static_cast<int>(s.duration() * 400));
    for (int k = 0; k <= n; ++k)
      clearance = std::min(clearance, world.boxDistance(s.position(s.duration() * k / n)));
    // The ESDF interpolates centre distances: allow one voxel of interpolation error.
    EXPECT_GE(clearance, config.min_clearance - kRes) << "seed " << seed;
    worst_clearance = std::min(worst_clearance, clearance);
    // Start and end states are kept.
    EXPECT_LT((s.position(0.0) - found->path.front()).norm(), 1e-6);
    EXPECT_LT((s.position(s.duration()) - found->path.back()).norm(), 1e-6);
    EXPECT_LT(s.evaluate(0.0, 1).norm(), 1e-6);
    EXPECT_LT(s.evaluate(s.duration(), 1).norm(), 1e-6);
  }
  ASSERT_EQ(fields, 100);
  const double rate = successes / 100.0;
  std::printf(
      "[ optimizer ] %d/%d fields succeeded (%.0f %%); worst v/v_max %.4f, a/a_max %.4f, "
      "min distance to obstacle centres %.3f m\n",
      successes, fields, 100 * rate, worst_v, worst_a, worst_clearance);
  std::printf(
      "[ optimizer ] mean %.2f ms, max %.2f ms per optimisation, mean %.1f control points, "
      "%.0f cost evaluations\n",
      total_ms / fields, max_ms, static_cast<double>(total_points) / fields,
      static_cast<double>(total_evaluations) / fields);
  for (const auto& [code, count] : nlopt_results)
    std::printf("[ optimizer ] nlopt result %s: %d\n", code.c_str(), count);
  for (const std::string& f : failures) std::printf("[ optimizer ] failure: %s\n", f.c_str());
  EXPECT_GE(rate, 0.8);
}

TEST(BsplineOptimizer, ImpossibleProblemsFailAndReturnNothing) {
  World world(Vec3(4.0, 4.0, 2.0));
  world.addBox(Index3(18, 0, 0), Index3(21, 39, 19));  // a wall across the whole map
  world.sync();
  const OptimizerConfig config = optimizerConfig();
  // Straight through the wall: the unsigned ESDF has no gradient inside it.
  std::vector<Vec3> line = UniformBspline::resamplePolyline({Vec3(0.5, 2, 1), Vec3(3.5, 2, 1)}, 0.3);
  const UniformBspline through = UniformBspline::fitPath(line, 0.3, Vec3::Zero(), Vec3::Zero());
  OptimizeStats stats;
  auto r = traj::optimize(through, world.esdf(), config, &stats);
  EXPECT_FALSE(r.ok());
  EXPECT_LT(stats.min_distance, config.min_clearance);
  EXPECT_NE(r.message().find("min_clearance"), std::string::npos) << r.message();
  // A start state faster than v_max: kept as it is, so no result can pass.
  line = UniformBspline::resamplePolyline({Vec3(0.5, 0.5, 1), Vec3(1.5, 0.5, 1)}, 0.2);
  const UniformBspline fast = UniformBspline::fitPath(line, 0.2, Vec3(3.0, 0, 0), Vec3::Zero());
  r = traj::optimize(fast, world.esdf(), config, &stats);
  EXPECT_FALSE(r.ok());
  EXPECT_GT(stats.max_velocity, config.v_max * 1.05);
  EXPECT_NE(r.message().find("v_max"), std::string::npos) << r.message();
  // Too few control points, bad config, clearance beyond the ESDF's range.
  EXPECT_FALSE(
      traj::optimize(UniformBspline(Eigen::MatrixXd::Zero(3, 6), 3, 0.1), world.esdf(), config).ok());
  OptimizerConfig bad = config;
  bad.v_max = -1.0;
  r = traj::optimize(through, world.esdf(), bad);
  EXPECT_FALSE(r.ok());
  EXPECT_NE(r.message().find("v_max"), std::string::npos);
  bad = config;
  bad.clearance = 1.5;
  EXPECT_NE(bad.validate(world.esdf().config()).message().find("clearance"), std::string::npos);
  // optimize() itself refuses it (the ESDF's distances stop at max_distance, 1 m here), before any evaluation.
  for (double clearance : {1.0, 1.5}) {
    bad.clearance = clearance;
    OptimizeStats none;
    r = traj::optimize(through, world.esdf(), bad, &none);
    EXPECT_FALSE(r.ok()) << clearance;
    EXPECT_NE(r.message().find("max_distance"), std::string::npos) << r.message();
    EXPECT_EQ(none.evaluations, 0) << clearance;
  }
  // A margin above 1 aims past the limits; no evaluation budget is no budget at all (NLopt's 0: unlimited).
  bad = config;
  bad.feasibility_margin = 1.2;
  EXPECT_NE(bad.validate().message().find("feasibility_margin"), std::string::npos);
  bad.feasibility_margin = 1.0;
  EXPECT_TRUE(bad.validate().ok()) << bad.validate().message();
  for (int iterations : {0, -1, 100001, std::numeric_limits<int>::max()}) {  // the only time budget
    bad = config;
    bad.max_iterations = iterations;
    EXPECT_NE(bad.validate().message().find("max_iterations"), std::string::npos) << iterations;
  }
  bad = config;
  bad.min_clearance = 0.8;
  EXPECT_NE(bad.validate().message().find("clearance"), std::string::npos);
  bad = config;
  bad.max_knot_span = 0.01;
  EXPECT_NE(bad.validate().message().find("max_knot_span"), std::string::npos);
  EXPECT_TRUE(config.validate().ok());
}

// A rest-to-rest fit of `corners` (resampled at 0.3 m) three times too fast, its cost, and the smallest knot
// span at which given terms of that cost are zero, found by bisection on the cost itself.
struct TooFastFit {
  TooFastFit(const World& world, const OptimizerConfig& config, const std::vector<Vec3>& corners)
      : init(UniformBspline::fitPath(UniformBspline::resamplePolyline(corners, 0.3), 0.3 / (3.0 * config.v_max),
                                     Vec3::Zero(), Vec3::Zero())),
        cost(init, world.esdf(), config),
        x(cost.variables(init)) {}
  double costAt(double span, unsigned terms) {
    x.back() = std::log(span);
    return cost.evaluate(x, nullptr, terms);
  }
  double smallestSpan(unsigned terms) {
    double lo = init.knotSpan(), hi = 100.0 * init.knotSpan();
    EXPECT_GT(costAt(lo, terms), 0.0);
    EXPECT_EQ(costAt(hi, terms), 0.0);
    for (int k = 0; k < 200 && hi - lo > 1e-15 * hi; ++k) (costAt(0.5 * (lo + hi), terms) == 0.0 ? hi : lo) = 0.5 * (lo + hi);
    return hi;
  }
  /// The initial cost the optimiser reports for this fit.
  double reportedInitialCost(const World& world, const OptimizerConfig& config) const {
    OptimizeStats stats;
    EXPECT_TRUE(traj::optimize(init, world.esdf(), config, &stats).ok());
    return stats.initial_cost;
  }
  UniformBspline init;
  BsplineCost cost;
  std::vector<double> x;
};

// The optimiser starts from the knot span at which the control polygon just meets the margin-reduced limits:
// for a rest-to-rest fit three times too fast, the smallest knot span whose velocity and acceleration terms
// are zero is where the reported initial cost is taken. Starting at the fit's own span, or without the margin,
// gives another initial cost.
TEST(BsplineOptimizer, StartsAtTheKnotSpanThatJustMeetsTheLimits) {
  World world(Vec3(6.0, 4.0, 2.0));
  world.sync();
  const OptimizerConfig config = optimizerConfig();
  TooFastFit fit(world, config, {Vec3(0.5, 2, 1), Vec3(3.0, 2.5, 1.2), Vec3(5.5, 1.5, 1)});
  const double span = fit.smallestSpan(traj::kVelocity | traj::kAcceleration);
  ASSERT_GT(span, config.min_knot_span);
  ASSERT_LT(span, config.max_knot_span);
  const double expected = fit.costAt(span, traj::kAllTerms);
  EXPECT_NEAR(fit.reportedInitialCost(world, config), expected, 1e-9 * expected);
  EXPECT_GT(std::abs(fit.costAt(fit.init.knotSpan(), traj::kAllTerms) - expected), 1e-6 * expected);
}

// The same where the velocity bounds the span: with an a_max so high that the accelerations ask for less
// stretch than the speed does, the span the velocity term alone needs is the one both need, and the initial
// cost is taken there (dropping the margin from the velocity's stretch alone gives another).
TEST(BsplineOptimizer, StartsAtTheKnotSpanWhereTheVelocityMeetsItsLimit) {
  World world(Vec3(8.0, 4.0, 2.0));
  world.sync();
  OptimizerConfig config = optimizerConfig();
  config.a_max = 40.0;
  ASSERT_TRUE(config.validate().ok()) << config.validate().message();
  TooFastFit fit(world, config, {Vec3(0.5, 2, 1), Vec3(4.0, 2.5, 1.2), Vec3(7.5, 1.5, 1)});
  const double for_velocity = fit.smallestSpan(traj::kVelocity);
  const double span = fit.smallestSpan(traj::kVelocity | traj::kAcceleration);
  ASSERT_NEAR(span, for_velocity, 1e-12 * for_velocity) << "the velocity should bound the span";
  ASSERT_LT(fit.smallestSpan(traj::kAcceleration), 0.9 * for_velocity);
  ASSERT_GT(span, config.min_knot_span);
  ASSERT_LT(span, config.max_knot_span);
  const double expected = fit.costAt(span, traj::kAllTerms);
  EXPECT_NEAR(fit.reportedInitialCost(world, config), expected, 1e-9 * expected);
}

// What NLopt minimises is BsplineCost with every term: the reported final cost is the full cost of the
// result, no more than the initial cost; and a straight flight 0.3 m past a block's edge (inside
// `clearance`, outside `min_clearance`) is pushed off it, the free control points' shortfall cut.
// The starting knot span is clamped into [min_knot_span, max_knot_span] before NLopt sees it (NLopt refuses a
// start outside its bounds): a fit far slower than the limits (3 s spans) and one far quicker than any span
// allows (6 mm in 0.01 s spans) are optimised, within the span bounds.
TEST(BsplineOptimizer, StartingSpansOutsideTheBoundsAreClampedIntoThem) {
  World world(Vec3(6.0, 4.0, 2.0));
  world.sync();
  const OptimizerConfig config = optimizerConfig();
  const UniformBspline slow = UniformBspline::fitPath(
      UniformBspline::resamplePolyline({Vec3(0.5, 2, 1), Vec3(5.5, 2, 1)}, 0.3), 3.0, Vec3::Zero(), Vec3::Zero());
  ASSERT_GT(slow.knotSpan(), config.max_knot_span);
  const UniformBspline tiny = UniformBspline::fitPath(
      UniformBspline::resamplePolyline({Vec3(3.0, 2, 1), Vec3(3.006, 2, 1)}, 0.001), 0.01, Vec3::Zero(), Vec3::Zero());
  ASSERT_GE(tiny.numControlPoints(), 7);
  for (const UniformBspline* init : {&slow, &tiny}) {
    OptimizeStats stats;
    const auto r = traj::optimize(*init, world.esdf(), config, &stats);
    ASSERT_TRUE(r.ok()) << r.message();
    EXPECT_LE(r->knotSpan(), config.max_knot_span * (1.0 + 1e-12));
    EXPECT_GE(r->knotSpan(), config.min_knot_span * (1.0 - 1e-12));
  }
}

TEST(BsplineOptimizer, MinimisesTheFullCostAndPushesThePathOffAnEdge) {
  World world(Vec3(6.0, 4.0, 2.0));
  world.addBox(Index3(25, 0, 0), Index3(34, 16, 19));  // x 2.5-3.5 m, y up to 1.7 m, full height
  world.sync();
  const OptimizerConfig config = optimizerConfig();
  const std::vector<Vec3> line = UniformBspline::resamplePolyline({Vec3(0.5, 2, 1), Vec3(5.5, 2, 1)}, 0.3);
  const UniformBspline init = UniformBspline::fitPath(line, 0.3 / config.v_max, Vec3::Zero(), Vec3::Zero());
  auto closest = [&](const UniformBspline& s) {
    double d = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= 2000; ++k) d = std::min(d, world.esdf().distance(s.position(s.duration() * k / 2000)));
    return d;
  };
  ASSERT_LT(closest(init), config.clearance - 0.1);
  ASSERT_GT(closest(init), config.min_clearance);
  OptimizeStats stats;
  const auto r = traj::optimize(init, world.esdf(), config, &stats);
  ASSERT_TRUE(r.ok()) << r.message();
  const BsplineCost cost(init, world.esdf(), config);
  const double full = cost.evaluate(cost.variables(*r), nullptr, traj::kAllTerms);
  EXPECT_NEAR(stats.final_cost, full, 1e-9 * full) << "NLopt minimised something else than the full cost";
  EXPECT_LE(stats.final_cost, stats.initial_cost);
  const double before = documentedTerm(traj::kClearance, init, world.esdf(), config);
  const double after = documentedTerm(traj::kClearance, *r, world.esdf(), config);
  ASSERT_GT(before, 0.0);
  EXPECT_LT(after, 0.25 * before);
  EXPECT_GT(closest(*r), closest(init) + 0.1);
}

// checkTrajectory() samples densely enough (every half voxel of a span's control polygon) that the
// closest approach it reports is within a quarter voxel of a 20000-sample search, and its speed and
// acceleration within 1 % of finite differences, on long spans (1-2 m) weaving between blocks.
// Speed is judged against v_max and acceleration against a_max, each alone: a straight line at exactly
// 3 m/s (a uniform B-spline reproduces it, no acceleration) and a parabola at 2 m/s^2, in open space.
TEST(CheckTrajectory, SpeedIsJudgedAgainstVmaxAndAccelerationAgainstAmax) {
  const World world(Vec3(6.0, 4.0, 2.0));
  Eigen::MatrixXd line(3, 10), parabola(3, 10);
  for (int i = 0; i < 10; ++i) {
    line.col(i) = Vec3(1.0 + 0.3 * i, 2.0, 1.0);
    parabola.col(i) = Vec3(1.0 + 0.01 * i * i, 2.0, 1.0);
  }
  const UniformBspline fast(line, 3, 0.1), bending(parabola, 3, 0.1);
  OptimizerConfig config = optimizerConfig();
  config.v_max = 1.0;
  config.a_max = 5.0;
  OptimizeStats stats;
  go_feap::common::Status s = traj::checkTrajectory(fast, world.esdf(), config, &stats);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("v_max"), std::string::npos) << s.message();
  EXPECT_NEAR(stats.max_velocity, 3.0, 1e-6);
  config.v_max = 3.5;
  EXPECT_TRUE(traj::checkTrajectory(fast, world.esdf(), config).ok());
  config.v_max = 10.0;
  config.a_max = 1.0;
  s = traj::checkTrajectory(bending, world.esdf(), config, &stats);
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("a_max"), std::string::npos) << s.message();
  EXPECT_NEAR(stats.max_acceleration, 2.0, 1e-6);
  config.a_max = 2.5;
  EXPECT_TRUE(traj::checkTrajectory(bending, world.esdf(), config).ok());
}

TEST(CheckTrajectory, SamplesLongSpansDenselyEnoughToFindTheClosestApproach) {
  World world(Vec3(6.0, 6.0, 2.0));
  world.addBox(Index3(20, 20, 0), Index3(22, 40, 19));
  world.addBox(Index3(35, 10, 0), Index3(37, 30, 19));
  world.sync();
  const OptimizerConfig config = optimizerConfig();
  Rng rng(5);
  double worst = 0.0;
  for (int trial = 0; trial < 30; ++trial) {
    Eigen::MatrixXd q(3, 8);
    for (int i = 0; i < q.cols(); ++i) q.col(i) = Vec3(rng(0.5, 5.5), rng(0.5, 5.5), rng(0.5, 1.5));
    const UniformBspline s(q, 3, rng(0.5, 1.5));
    OptimizeStats stats;
    traj::checkTrajectory(s, world.esdf(), config, &stats);
    double fine = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= 20000; ++k) fine = std::min(fine, world.esdf().distance(s.position(s.duration() * k / 20000)));
    EXPECT_NEAR(stats.min_distance, fine, 0.25 * kRes) << "trial " << trial;
    worst = std::max(worst, std::abs(stats.min_distance - fine));
    double v = 0.0, a = 0.0;
    finiteDifferenceDynamics(s, 20000, v, a);
    EXPECT_NEAR(stats.max_velocity, v, 0.01 * v) << "trial " << trial;
    EXPECT_NEAR(stats.max_acceleration, a, 0.01 * a) << "trial " << trial;
  }
  std::printf("[ check    ] worst closest-approach error %.4f m\n", worst);
}

// Straight, fast splines (control points 1.5 m apart: a span's polygon three times its arc) passing a
// one-voxel pole at 0.15 to 0.35 m, at random offsets and phases: the closest approach found within half the
// sample spacing the rule gives (a span's 1.5 m arc over 4.5 m / half a voxel = 90 samples: 1.67 cm; the
// distance changes by at most as much as the position) of a 20000-sample search. Random curves cross walls (both report 0) or have polygons far longer than their
// arcs (dense samples whatever the rule); these are where a sparser rule would overstate the clearance.
TEST(CheckTrajectory, FindsTheClosestApproachOfAStraightFlightPastAPole) {
  World world(Vec3(8.0, 4.0, 2.0));
  world.addBox(Index3(40, 20, 0), Index3(40, 20, 19));  // x in [4.0, 4.1], y in [2.0, 2.1]
  world.sync();
  const OptimizerConfig config = optimizerConfig();
  Rng rng(11);
  double worst = 0.0;
  const double tolerance = 0.5 * 1.5 / std::ceil(4.5 / (0.5 * kRes));
  for (int trial = 0; trial < 200; ++trial) {
    const double offset = rng(0.15, 0.35) * (trial % 2 ? 1.0 : -1.0), phase = rng(0.0, 1.5);
    const Vec3 from(0.5 - phase, 2.05 + offset, 1.0), step(1.5, rng(-0.02, 0.02), 0.0);
    Eigen::MatrixXd q(3, 8);
    for (int i = 0; i < q.cols(); ++i) q.col(i) = from + i * step;
    const UniformBspline s(q, 3, 1.0);
    OptimizeStats stats;
    traj::checkTrajectory(s, world.esdf(), config, &stats);
    double fine = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= 20000; ++k) fine = std::min(fine, world.esdf().distance(s.position(s.duration() * k / 20000)));
    ASSERT_LT(fine, 0.4) << "trial " << trial << " does not pass the pole";
    EXPECT_NEAR(stats.min_distance, fine, tolerance) << "trial " << trial;
    worst = std::max(worst, std::abs(stats.min_distance - fine));
  }
  std::printf("[ check    ] worst closest-approach error past a pole %.4f m\n", worst);
}

// A spline starting closer than min_clearance (a wall mapped late beside the vehicle) may leave, moving
// away or along, but not come nearer before it is min_clearance away, nor skim along for longer than
// leave_distance (1 m); once away, the usual rule holds. A start inside an obstacle voxel has no way out,
// at a wall's face or at a pole's corner. Wall voxels at x in [1.0, 1.1] (centres 1.05), a one-voxel pole at
// x in [3.0, 3.1], y in [3.5, 3.6].
TEST(CheckTrajectory, AStartTooNearAnObstacleMayLeaveButNotComeNearerNorStayNear) {
  World world(Vec3(4.0, 4.0, 2.0));
  world.addBox(Index3(10, 0, 0), Index3(10, 39, 19));
  world.addBox(Index3(30, 35, 0), Index3(30, 35, 19));
  world.sync();
  const OptimizerConfig config = optimizerConfig();  // min_clearance 0.2, leave_distance 1
  ASSERT_EQ(config.leave_distance, 1.0);
  auto line = [](std::vector<Vec3> corners) {  // 0.2 m/s: well within the limits
    return UniformBspline::fitPath(UniformBspline::resamplePolyline(corners, 0.1), 0.5, Vec3::Zero(), Vec3::Zero());
  };
  auto check = [&](std::vector<Vec3> corners) { return traj::checkTrajectory(line(corners), world.esdf(), config); };
  auto says = [](const go_feap::common::Status& st, const std::string& what) {
    return !st && st.message().find(what) != std::string::npos;
  };
  const Vec3 near(1.2, 2.0, 1.0);  // 0.15 m from the wall's centres
  ASSERT_NEAR(world.esdf().distance(near), 0.15, 1e-9);
  const go_feap::common::Status away = check({near, Vec3(3.0, 2.0, 1.0)});
  EXPECT_TRUE(away) << away.message();
  const go_feap::common::Status along = check({near, Vec3(1.2, 2.5, 1.0), Vec3(2.5, 2.5, 1.0)});
  EXPECT_TRUE(along) << along.message();
  const go_feap::common::Status skims = check({near, Vec3(1.2, 3.5, 1.0), Vec3(2.5, 3.5, 1.0)});
  EXPECT_TRUE(says(skims, "leave_distance")) << skims.message();
  const go_feap::common::Status nearer = check({near, Vec3(1.17, 2.5, 1.0), Vec3(2.5, 2.5, 1.0)});
  EXPECT_TRUE(says(nearer, "comes nearer")) << nearer.message();
  // Away and back: past min_clearance the usual rule holds.
  const go_feap::common::Status back_again = check({near, Vec3(2.0, 2.0, 1.0), Vec3(1.22, 2.5, 1.0)});
  EXPECT_TRUE(says(back_again, "passes 0.1")) << back_again.message();
  // In a wall voxel (0.03 m from its centre), and at the corner of the pole's voxel (0.078 m from its
  // centre by the trilinear distance, more than half a voxel): no way out.
  const Vec3 in_wall(1.08, 2.0, 1.0), in_pole(3.09, 3.59, 1.0);
  ASSERT_GT(world.esdf().distance(in_pole), 0.5 * kRes);
  for (const auto& [start, to] : {std::pair{in_wall, Vec3(3.0, 2.0, 1.0)}, std::pair{in_pole, Vec3(3.09, 2.5, 1.0)}}) {
    const go_feap::common::Status stuck = check({start, to});
    EXPECT_TRUE(says(stuck, "passes")) << stuck.message();
    EXPECT_TRUE(traj::firstCollisionTime(line({start, to}), 0.0, world.esdf(), config.min_clearance,
                                         config.leave_distance, 100.0));
  }
  // The flown trajectory is judged as it was planned: leaving is no collision, at any time on the way;
  // coming nearer is, as is skimming past leave_distance.
  const UniformBspline leaving = line({near, Vec3(1.2, 2.5, 1.0), Vec3(2.5, 2.5, 1.0)});
  for (double t = 0.0; t <= leaving.duration(); t += 0.1)
    EXPECT_FALSE(traj::firstCollisionTime(leaving, t, world.esdf(), config.min_clearance, config.leave_distance, 100.0))
        << "at " << t << " s";
  const UniformBspline back = line({near, Vec3(1.17, 2.5, 1.0), Vec3(3.0, 2.5, 1.0)});
  const std::optional<double> t =
      traj::firstCollisionTime(back, 0.0, world.esdf(), config.min_clearance, config.leave_distance, 100.0);
  ASSERT_TRUE(t.has_value());
  EXPECT_LT(world.esdf().distance(back.position(*t)), 0.15 - 0.1 * kRes);
  const UniformBspline skimming = line({near, Vec3(1.2, 3.5, 1.0), Vec3(2.5, 3.5, 1.0)});
  const std::optional<double> t_skim =
      traj::firstCollisionTime(skimming, 0.0, world.esdf(), config.min_clearance, config.leave_distance, 100.0);
  ASSERT_TRUE(t_skim.has_value());
  EXPECT_NEAR((skimming.position(*t_skim) - near).norm(), 1.0, 0.1);
  // From a time on the way, only what lies ahead counts (the skim beyond 1 m still does).
  double t_away = *t;
  while (t_away < back.duration() && world.esdf().distance(back.position(t_away)) < 0.3) t_away += 0.05;
  ASSERT_LT(t_away, back.duration());
  EXPECT_EQ(traj::firstCollisionTime(back, t_away, world.esdf(), config.min_clearance, config.leave_distance, 100.0),
            std::nullopt);
  EXPECT_TRUE(traj::firstCollisionTime(skimming, 1.0, world.esdf(), config.min_clearance, config.leave_distance, 100.0));
  // leave_distance is counted from the trajectory's start, not from the time asked: 0.8 m along the skim, the
  // collision is still the one 1 m from the start.
  double t_mid = 0.0;
  while (t_mid < skimming.duration() && (skimming.position(t_mid) - near).norm() < 0.8) t_mid += 0.01;
  ASSERT_LT(t_mid, *t_skim);
  const std::optional<double> t_skim_mid =
      traj::firstCollisionTime(skimming, t_mid, world.esdf(), config.min_clearance, config.leave_distance, 100.0);
  ASSERT_TRUE(t_skim_mid.has_value());
  EXPECT_NEAR((skimming.position(*t_skim_mid) - near).norm(), 1.0, 0.1);
  // A NaN time reads as the start.
  EXPECT_EQ(traj::firstCollisionTime(back, std::nan(""), world.esdf(), config.min_clearance, config.leave_distance, 100.0),
            t);
}

// Along a staircase wall (voxels on a 45 degree diagonal) the distance ripples by millimetres. A leaving
// spline that passed the check is no predicted collision at any time on the way: the flown check keeps the
// floor of the spline's start, where it used to take the distance wherever the vehicle was as the floor
// (13 of 53 times along such a spline were collisions).
TEST(CheckTrajectory, ALeavingSplineThatPassedIsNoCollisionAnywhereOnTheWay) {
  World world(Vec3(4.0, 4.0, 2.0));
  for (int k = 0; k < 30; ++k) world.addBox(Index3(5 + k, 5 + k, 0), Index3(5 + k, 5 + k, 19));
  world.sync();
  const OptimizerConfig config = optimizerConfig();
  const Vec3 along = Vec3(1, 1, 0).normalized(), out = Vec3(1, -1, 0).normalized();
  int accepted = 0;
  for (double s = 0.0; s < 0.3; s += 0.013) {
    const Vec3 start = Vec3(1.0, 1.0, 1.0) + s * along + 0.15 * out;
    const UniformBspline spline = UniformBspline::fitPath(
        UniformBspline::resamplePolyline({start, start + 0.6 * along, start + 0.6 * along + 1.0 * out}, 0.1), 0.5,
        Vec3::Zero(), Vec3::Zero());
    if (!traj::checkTrajectory(spline, world.esdf(), config)) continue;
    ++accepted;
    for (double t = 0.0; t <= spline.duration(); t += 0.05)
      EXPECT_FALSE(traj::firstCollisionTime(spline, t, world.esdf(), config.min_clearance, config.leave_distance, 100.0))
          << "start offset " << s << ", at " << t << " s";
  }
  EXPECT_GE(accepted, 10);
}

TEST(BsplineOptimizer, KeepsMovingBoundaryStates) {
  World world(Vec3(6.0, 4.0, 2.0));
  world.sync();
  const OptimizerConfig config = optimizerConfig();
  const std::vector<Vec3> line = UniformBspline::resamplePolyline({Vec3(0.5, 2, 1), Vec3(5.5, 2, 1)}, 0.3);
  const Vec3 v0(1.0, 0.3, 0.0);
  const UniformBspline init = UniformBspline::fitPath(line, 0.25, v0, Vec3::Zero());
  const auto r = traj::optimize(init, world.esdf(), config);
  ASSERT_TRUE(r.ok()) << r.message();
  EXPECT_LT((r->position(0.0) - init.position(0.0)).norm(), 1e-9);
  EXPECT_LT((Vec3(r->evaluate(0.0, 1)) - v0).norm(), 1e-9);
  EXPECT_LT((Vec3(r->evaluate(0.0, 2)) - Vec3(init.evaluate(0.0, 2))).norm(), 1e-6);
  EXPECT_LT((r->position(r->duration()) - init.position(init.duration())).norm(), 1e-9);
  // Open space: the time term makes it use the speed limit (with the penalties' margin).
  EXPECT_GT(r->maxVelocity(), 0.8 * config.v_max);
  EXPECT_LE(r->maxVelocity(), 1.05 * config.v_max);
}

// ---------------------------------------------------------------------------------------------------------
// Yaw.

// The largest |rate| and |acceleration| of a 1-D spline by central differences, densely sampled.
std::pair<double, double> maxRateAndAcceleration(const UniformBspline& s) {
  double rate = 0.0, acc = 0.0;
  const double h = 1e-4;
  for (int j = 0; j <= 4000; ++j) {
    const double t = std::clamp(s.duration() * j / 4000, h, s.duration() - h);
    const double a = s.value(t - h)[0], b = s.value(t)[0], c = s.value(t + h)[0];
    rate = std::max(rate, std::abs(c - a) / (2 * h));
    acc = std::max(acc, std::abs(c - 2 * b + a) / (h * h));
  }
  return {rate, acc};
}

TEST(YawSpline, TurnsTheShortWayInNearlyTheLeastTimeWithinTheLimits) {
  OptimizerConfig config = optimizerConfig();
  Rng rng(21);
  for (int trial = 0; trial < 200; ++trial) {
    config.yaw_rate_max = rng(0.5, 2.0);
    config.yaw_acc_max = rng(2.0, 10.0);
    const double yaw0 = rng(-kPi, kPi), yaw1 = rng(-kPi, kPi);
    const double min_duration = trial % 2 ? rng(0.1, 6.0) : 0.0;
    const auto r = traj::yawTurn(yaw0, yaw1, min_duration, config);
    ASSERT_TRUE(r.ok()) << r.message();
    const UniformBspline& s = *r;
    ASSERT_EQ(s.dimension(), 1);
    EXPECT_GE(s.duration(), min_duration - 1e-9);
    // Starts and ends at the yaws, at rest, turning the short way (|turn| <= pi).
    const double turn = std::remainder(yaw1 - yaw0, 2 * kPi);
    EXPECT_NEAR(s.value(0.0)[0], yaw0, 1e-9);
    EXPECT_NEAR(s.value(s.duration())[0], yaw0 + turn, 1e-9);
    EXPECT_NEAR(s.evaluate(0.0, 1)[0], 0.0, 1e-9);
    EXPECT_NEAR(s.evaluate(s.duration(), 1)[0], 0.0, 1e-9);
    // Rate and acceleration by central differences, densely sampled, within the limits; no overshoot.
    const auto [rate, acc] = maxRateAndAcceleration(s);
    for (int j = 0; j <= 400; ++j) EXPECT_LE(std::abs(s.value(s.duration() * j / 400)[0] - yaw0), std::abs(turn) + 1e-9);
    EXPECT_LE(rate, config.yaw_rate_max * (1 + 1e-6)) << "trial " << trial;
    EXPECT_LE(acc, config.yaw_acc_max * 1.01) << "trial " << trial;
    // Without a minimum duration it is close to the bang-coast-bang optimum: at most one span of ramp
    // at each end plus one span of rounding beyond |turn| / rate + rate / acc.
    if (min_duration == 0.0) {
      const double span = config.yaw_rate_max / config.yaw_acc_max;
      EXPECT_LE(s.duration(), std::abs(turn) / config.yaw_rate_max + 3 * span + 1e-9) << "trial " << trial;
    }
  }
  EXPECT_FALSE(traj::yawTurn(std::nan(""), 1.0, 0.0, config).ok());
  EXPECT_FALSE(traj::yawTurn(0.0, 1.0, std::numeric_limits<double>::infinity(), config).ok());
  config.yaw_acc_max = 0.0;
  EXPECT_FALSE(traj::yawTurn(0.0, 1.0, 0.0, config).ok());
  // A slow turn with a hard start: a half turn would take 3e9 spans (past an int); named instead.
  config.yaw_rate_max = 1e-4;
  config.yaw_acc_max = 10.0;
  const auto slow = traj::yawTurn(0.0, 3.0, 0.0, config);
  ASSERT_FALSE(slow.ok());
  EXPECT_NE(slow.message().find("yaw_acc_max"), std::string::npos) << slow.message();
  config.yaw_rate_max = 0.1, config.yaw_acc_max = 3.18;  // at the limit: 999 spans for a half turn
  const auto limit = traj::yawTurn(0.0, M_PI, 0.0, config);
  ASSERT_TRUE(limit.ok()) << limit.message();
  EXPECT_LE(limit->numControlPoints(), 1005);
}

// From a start rate (a replan mid-turn): the spline starts at yaw0 with that rate (clamped to yaw_rate_max)
// and no acceleration, ends at rest at yaw0 + turn, keeps both limits (through rest first when the turn
// goes against the rate), and lasts little longer than from rest. A turn replanned halfway goes on at the
// rate it had (from rest it stepped the rate down by 1 rad/s within one command) and ends about when the
// first would have.
TEST(YawSpline, AStartRateIsKeptAndTheLimitsHold) {
  OptimizerConfig config = optimizerConfig();
  Rng rng(22);
  for (int trial = 0; trial < 300; ++trial) {
    config.yaw_rate_max = rng(0.5, 2.0);
    config.yaw_acc_max = rng(2.0, 10.0);
    const double yaw0 = rng(-kPi, kPi), yaw1 = rng(-kPi, kPi);
    const double rate0 = rng(-1.2, 1.2) * config.yaw_rate_max;  // past the limit too: clamped
    const double min_duration = trial % 3 == 0 ? rng(0.1, 6.0) : 0.0;
    const auto r = traj::yawTurn(yaw0, yaw1, min_duration, config, rate0);
    ASSERT_TRUE(r.ok()) << r.message();
    const UniformBspline& s = *r;
    const double turn = std::remainder(yaw1 - yaw0, 2 * kPi);
    const double span = config.yaw_rate_max / config.yaw_acc_max;
    EXPECT_GE(s.duration(), min_duration - 1e-9);
    EXPECT_NEAR(s.value(0.0)[0], yaw0, 1e-9);
    EXPECT_NEAR(s.evaluate(0.0, 1)[0], std::clamp(rate0, -config.yaw_rate_max, config.yaw_rate_max), 1e-9) << "trial " << trial;
    EXPECT_NEAR(s.evaluate(0.0, 2)[0], 0.0, 1e-6);
    EXPECT_NEAR(s.value(s.duration())[0], yaw0 + turn, 1e-9);
    EXPECT_NEAR(s.evaluate(s.duration(), 1)[0], 0.0, 1e-9);
    const auto [rate, acc] = maxRateAndAcceleration(s);
    EXPECT_LE(rate, config.yaw_rate_max * (1 + 1e-6)) << "trial " << trial;
    EXPECT_LE(acc, config.yaw_acc_max * 1.01) << "trial " << trial;
    if (min_duration == 0.0) {
      EXPECT_LE(s.duration(), std::abs(turn) / config.yaw_rate_max + 5 * span + 1e-9) << "trial " << trial;
    }
    // Without a start rate it is the turn from rest, control point for control point.
    const auto rest = traj::yawTurn(yaw0, yaw1, min_duration, config);
    const auto zero = traj::yawTurn(yaw0, yaw1, min_duration, config, 0.0);
    ASSERT_TRUE(rest.ok() && zero.ok());
    EXPECT_EQ(rest->controlPoints(), zero->controlPoints());
  }
  config = optimizerConfig();
  config.yaw_rate_max = 1.0, config.yaw_acc_max = 5.0;
  const auto first = traj::yawTurn(0.0, 3.0, 0.0, config);
  ASSERT_TRUE(first.ok());
  const double t = 1.0, yaw = first->value(t)[0], rate = first->evaluate(t, 1)[0];
  ASSERT_NEAR(rate, 1.0, 1e-9);
  const auto again = traj::yawTurn(yaw, 3.0, 0.0, config, rate);
  ASSERT_TRUE(again.ok());
  EXPECT_NEAR(again->evaluate(0.0, 1)[0], rate, 1e-9);
  // Nearly as it was (its rate spread over whole spans: 4e-4 rad behind 0.1 s on); from rest it is 0.075 rad behind.
  EXPECT_NEAR(again->value(0.1)[0], first->value(t + 0.1)[0], 0.01) << "the turn goes on as it was";
  EXPECT_LE(t + again->duration(), first->duration() + 0.2 + 1e-9);
  EXPECT_NEAR(again->value(again->duration())[0], 3.0, 1e-9);
  EXPECT_FALSE(traj::yawTurn(0.0, 1.0, 0.0, config, std::nan("")).ok());
}

// ---------------------------------------------------------------------------------------------------------
// Replanning.

TEST(Replan, EachReasonInPriorityOrder) {
  const ReplanConfig config;
  ASSERT_TRUE(config.validate().ok());
  ReplanInputs in;
  in.has_trajectory = true;
  in.time_left = 5.0;
  in.target_distance_to_end = 0.1;
  EXPECT_EQ(traj::shouldReplan(in, config), ReplanReason::kNone);
  ReplanInputs short_left = in;
  short_left.time_left = 0.5;
  EXPECT_EQ(traj::shouldReplan(short_left, config), ReplanReason::kShortTimeLeft);
  ReplanInputs moved = short_left;
  moved.target_distance_to_end = 0.5;
  EXPECT_EQ(traj::shouldReplan(moved, config), ReplanReason::kNewTarget);
  ReplanInputs changed = in;
  changed.target_changed = true;
  EXPECT_EQ(traj::shouldReplan(changed, config), ReplanReason::kNewTarget);
  ReplanInputs collision = moved;
  collision.collision_time = 1.2;
  EXPECT_EQ(traj::shouldReplan(collision, config), ReplanReason::kPredictedCollision);
  ReplanInputs none = collision;
  none.has_trajectory = false;
  EXPECT_EQ(traj::shouldReplan(none, config), ReplanReason::kNoTrajectory);
  EXPECT_STREQ(traj::toString(ReplanReason::kPredictedCollision), "predicted_collision");
  ReplanConfig bad;
  bad.target_tolerance = -1.0;
  EXPECT_NE(bad.validate().message().find("target_tolerance"), std::string::npos);
  // A negative heading tolerance made every target a new one (replanned for at every step).
  bad = ReplanConfig();
  bad.yaw_tolerance = -0.1;
  EXPECT_NE(bad.validate().message().find("yaw_tolerance"), std::string::npos);
  for (double t : {-1.0, std::numeric_limits<double>::infinity()}) {
    bad = ReplanConfig();
    bad.min_time_left = t;
    EXPECT_NE(bad.validate().message().find("min_time_left"), std::string::npos) << t;
  }
  // The planner's collision horizon: 0 checked only the present instant, never an obstacle mapped ahead.
  for (double horizon : {0.0, -1.0}) {
    traj::TrajectoryPlannerConfig planner;
    planner.collision_horizon = horizon;
    EXPECT_NE(planner.validate().message().find("collision_horizon"), std::string::npos) << horizon;
  }
  // Path samples at least 5 cm apart (1 mm would ask for gigabytes in the dense fit); a snap radius of at most 3 m
  // (the search waives its unseen-space checks within it).
  for (double spacing : {0.0, 0.001, 0.049}) {
    traj::TrajectoryPlannerConfig planner;
    planner.path_spacing = spacing;
    EXPECT_NE(planner.validate().message().find("planner: path_spacing"), std::string::npos) << spacing;
  }
  for (double radius : {-0.1, 3.01, 5000.0}) {
    traj::TrajectoryPlannerConfig planner;
    planner.snap_radius = radius;
    EXPECT_NE(planner.validate().message().find("planner: snap_radius"), std::string::npos) << radius;
  }
  traj::TrajectoryPlannerConfig edges;
  edges.path_spacing = 0.05;
  edges.snap_radius = 3.0;
  EXPECT_TRUE(edges.validate().ok()) << edges.validate().message();
}

// The tolerances are bounds the target may move within (a move of exactly target_tolerance, or a trajectory
// ending exactly that far from the target, is no new target; with time_left exactly min_time_left the time is
// not short), so that with every tolerance 0 an unchanged target is never replanned for. A target's heading
// counts by the turn between the two, the short way round.
TEST(Replan, TolerancesAreInclusiveAndHeadingsWrap) {
  ReplanConfig config;  // 0.3 m, 0.3 rad
  const Vec3 p(1, 2, 1);
  EXPECT_FALSE(traj::targetMoved(p, 3.1, p, -3.1, config));  // 0.083 rad across +-pi
  EXPECT_TRUE(traj::targetMoved(p, 0.0, p + Vec3(0.31, 0, 0), 0.0, config));
  EXPECT_FALSE(traj::targetMoved(p, 0.0, p + Vec3(0.29, 0, 0), 0.0, config));
  EXPECT_TRUE(traj::targetMoved(p, 0.0, p, 0.31, config));
  EXPECT_FALSE(traj::targetMoved(p, 0.0, p, 0.29, config));
  EXPECT_TRUE(traj::targetMoved(p, 0.0, p, 2.0 * M_PI + 0.31, config));
  ReplanConfig zero;
  zero.target_tolerance = zero.yaw_tolerance = zero.min_time_left = 0.0;
  ASSERT_TRUE(zero.validate().ok());
  EXPECT_FALSE(traj::targetMoved(p, 0.5, p, 0.5, zero));
  ReplanInputs steady;
  steady.has_trajectory = true;
  steady.time_left = 0.0;
  steady.target_distance_to_end = 0.0;
  EXPECT_EQ(traj::shouldReplan(steady, zero), ReplanReason::kNone);
  ReplanInputs at_limits;
  at_limits.has_trajectory = true;
  at_limits.time_left = config.min_time_left;
  at_limits.target_distance_to_end = config.target_tolerance;
  EXPECT_EQ(traj::shouldReplan(at_limits, config), ReplanReason::kNone);
}

// The server's report against the planner's trajectory 7, published at t = 10 s, grace 0.5 s.
TEST(Replan, ServerDroppedOnlyWhenAReportAfterTheGraceFollowsAnotherOrNone) {
  // Followed (running or completed): not dropped, however late the report.
  EXPECT_FALSE(go_feap::trajectory::serverDropped(7, 10.0, true, 7, 10.6, 0.5));
  EXPECT_FALSE(go_feap::trajectory::serverDropped(7, 10.0, true, 7, 100.0, 0.5));
  // Holding (no trajectory) or following another after the grace: dropped.
  EXPECT_TRUE(go_feap::trajectory::serverDropped(7, 10.0, false, 0, 10.5, 0.5));
  EXPECT_TRUE(go_feap::trajectory::serverDropped(7, 10.0, false, 7, 12.0, 0.5));
  EXPECT_TRUE(go_feap::trajectory::serverDropped(7, 10.0, true, 6, 10.7, 0.5));
  // Reports from before the trajectory could have reached the server say nothing about it.
  EXPECT_FALSE(go_feap::trajectory::serverDropped(7, 10.0, true, 6, 10.49, 0.5));
  EXPECT_FALSE(go_feap::trajectory::serverDropped(7, 10.0, false, 0, 9.0, 0.5));
  EXPECT_FALSE(go_feap::trajectory::serverDropped(7, 10.0, false, 0, std::nan(""), 0.5));
}

// replanReason() on a trajectory being flown: an obstacle mapped across its way ahead, within the collision
// horizon, is a predicted collision; one it has flown past, or beyond the horizon, is not; a trajectory
// ending at its target is flown out, a partial one is replanned before its end.
TEST(Replan, AnObstacleMappedAheadWithinTheHorizonIsAPredictedCollision) {
  World world(Vec3(6.0, 4.0, 2.0));
  world.sync();
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  const ReplanConfig replan;
  traj::Trajectory flown;
  flown.goal = Vec3(5.0, 2.0, 1.0);
  flown.position = UniformBspline::fitPath(UniformBspline::resamplePolyline({Vec3(1.0, 2.0, 1.0), flown.goal}, 0.3),
                                           0.3, Vec3::Zero(), Vec3::Zero());
  const double T = flown.duration();
  ASSERT_GT(T, 3.0);
  auto reason = [&](double t) {
    return traj::replanReason(&flown, t, flown.goal, false, world.esdf(), replan, optimizer, planner);
  };
  EXPECT_EQ(reason(0.2), ReplanReason::kNone);
  EXPECT_EQ(reason(T - 0.5), ReplanReason::kNone);  // ends at its target: flown out
  world.addBox(Index3(25, 10, 0), Index3(26, 30, 19));  // a wall across the way at x 2.5-2.7 m
  world.sync();
  double reach = -1.0;  // when the flight first comes within min_clearance of it
  for (int k = 0; k <= 10000 && reach < 0; ++k)
    if (world.esdf().distance(flown.position.position(T * k / 10000)) < optimizer.min_clearance) reach = T * k / 10000;
  ASSERT_GT(reach, 0.5);
  EXPECT_EQ(reason(0.2), ReplanReason::kPredictedCollision);
  EXPECT_EQ(reason(reach - 0.1), ReplanReason::kPredictedCollision);
  double past = reach;  // where it is clear of the wall again
  while (past < T && world.esdf().distance(flown.position.position(past)) < optimizer.min_clearance) past += 0.01;
  ASSERT_LT(past + 0.1, T - replan.min_time_left);
  EXPECT_EQ(reason(past + 0.1), ReplanReason::kNone);
  planner.collision_horizon = 0.5 * (reach - 0.2);
  EXPECT_EQ(reason(0.2), ReplanReason::kNone) << "beyond the horizon";
  flown.partial = true;
  EXPECT_EQ(reason(T - 0.5), ReplanReason::kShortTimeLeft);
}

// The collision check that asks for a replan is the planner's own: optimizer/min_clearance (a wall mapped beside
// the way ahead, nearer than that but not touching it, is a predicted collision) and optimizer/leave_distance
// (a flight leaving a wall it starts near, as every plan from a vehicle that came near one does, is none).
TEST(Replan, ThePredictedCollisionIsThePlannersClearanceAndLeaveRule) {
  OptimizerConfig optimizer = optimizerConfig();
  optimizer.min_clearance = 0.3;
  const traj::TrajectoryPlannerConfig planner;
  const ReplanConfig replan;
  auto flight = [](const Vec3& from, const Vec3& to) {
    traj::Trajectory t;
    t.goal = to;
    t.position = UniformBspline::fitPath(UniformBspline::resamplePolyline({from, to}, 0.3), 0.3, Vec3::Zero(), Vec3::Zero());
    return t;
  };
  auto closest = [](const traj::Trajectory& t, const go_feap::map::Esdf& esdf, double from) {
    double d = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= 2000; ++k) d = std::min(d, esdf.distance(t.position.position(from + (t.duration() - from) * k / 2000)));
    return d;
  };
  {
    World world(Vec3(6.0, 4.0, 2.0));
    world.addBox(Index3(25, 21, 0), Index3(35, 21, 19));  // a wall beside the way: x 2.5-3.6 m, y 2.1-2.2 m
    world.sync();
    const traj::Trajectory beside = flight(Vec3(1.0, 1.95, 1.05), Vec3(5.0, 1.95, 1.05));
    const double d = closest(beside, world.esdf(), 0.0);
    ASSERT_GT(d, 0.5 * optimizer.min_clearance);
    ASSERT_LT(d, optimizer.min_clearance);
    EXPECT_EQ(traj::replanReason(&beside, 0.2, beside.goal, false, world.esdf(), replan, optimizer, planner),
              ReplanReason::kPredictedCollision)
        << "the way passes " << d << " m from the wall";
  }
  {
    World world(Vec3(6.0, 4.0, 2.0));
    world.addBox(Index3(8, 0, 0), Index3(8, 39, 19));  // a wall behind the start: x 0.8-0.9 m
    world.sync();
    const traj::Trajectory away = flight(Vec3(1.05, 2.05, 1.05), Vec3(5.0, 2.05, 1.05));
    ASSERT_LT(world.esdf().distance(Vec3(1.05, 2.05, 1.05)), optimizer.min_clearance);
    EXPECT_EQ(traj::replanReason(&away, 0.0, away.goal, false, world.esdf(), replan, optimizer, planner),
              ReplanReason::kNone)
        << "a flight leaving the wall it starts " << world.esdf().distance(Vec3(1.05, 2.05, 1.05)) << " m from";
  }
}

TEST(Replan, FirstCollisionTimeMatchesFineSampling) {
  World world(Vec3(6.0, 4.0, 2.0));
  world.addBox(Index3(30, 0, 0), Index3(32, 39, 19));  // wall at x in [3.0, 3.3]
  world.sync();
  const double min_clearance = 0.2;
  Rng rng(31);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<Vec3> path = {Vec3(0.5, rng(0.5, 3.5), rng(0.5, 1.5)), Vec3(rng(1.0, 2.0), 2.0, 1.0),
                                    Vec3(5.5, rng(0.5, 3.5), rng(0.5, 1.5))};
    const UniformBspline s = UniformBspline::fitPath(UniformBspline::resamplePolyline(path, 0.3),
                                                     rng(0.1, 0.3), Vec3::Zero(), Vec3::Zero());
    double oracle = -1.0;
    for (int k = 0; k <= 200000 && oracle < 0; ++k) {
      const double t = s.duration() * k / 200000;
      if (world.esdf().distance(s.position(t)) < min_clearance) oracle = t;
    }
    ASSERT_GE(oracle, 0.0);
    const std::optional<double> t = traj::firstCollisionTime(s, 0.0, world.esdf(), min_clearance, 1.0, 100.0);
    ASSERT_TRUE(t.has_value());
    // Samples are at most half a voxel apart: the found time is within that much travel of the oracle.
    EXPECT_GE(*t, oracle - 1e-9);
    EXPECT_LE((s.position(*t) - s.position(oracle)).norm(), 0.5 * kRes + 1e-6);
    EXPECT_LT(world.esdf().distance(s.position(*t)), min_clearance);
    // A horizon ending before it, or a start after the wall, sees nothing.
    EXPECT_FALSE(traj::firstCollisionTime(s, 0.0, world.esdf(), min_clearance, 1.0, oracle - 0.05).has_value());
    double after = oracle;
    while (after < s.duration() && world.esdf().distance(s.position(after)) < 1.5) after += 0.01;
    EXPECT_FALSE(traj::firstCollisionTime(s, after, world.esdf(), min_clearance, 1.0, 100.0).has_value());
  }
}

TEST(SafeStop, BrakesToRestWithinTheStoppingDistance) {
  Rng rng(41);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 p(rng(-5, 5), rng(-5, 5), rng(0, 3));
    const Vec3 v = Vec3(rng(-1, 1), rng(-1, 1), rng(-1, 1)).normalized() * rng(0.01, 3.0);
    const double a_max = rng(0.3, 4.0);
    const UniformBspline s = traj::safeStop(p, v, a_max);
    const double speed = v.norm(), stop = speed * speed / (2 * a_max);
    EXPECT_LT((s.position(0.0) - p).norm(), 1e-9);
    EXPECT_LT((Vec3(s.evaluate(0.0, 1)) - v).norm(), 1e-9);
    EXPECT_LT(s.evaluate(s.duration(), 1).norm(), 1e-9);
    EXPECT_LT(s.evaluate(s.duration(), 2).norm(), 1e-9);
    const Vec3 travel = s.position(s.duration()) - p;
    EXPECT_LE(travel.norm(), stop + 1e-3);
    EXPECT_GE(travel.norm(), stop - 1e-9);
    EXPECT_LT((travel - travel.dot(v / speed) * v / speed).norm(), 1e-9);  // along v
    EXPECT_LE(s.duration(), speed / a_max + 0.05 + 1e-9);
    // Acceleration by finite differences of positions, and exactly (piecewise linear: knots suffice).
    double v_fd = 0.0, a_fd = 0.0;
    finiteDifferenceDynamics(s, 2000, v_fd, a_fd);
    EXPECT_LE(a_fd, a_max * (1 + 1e-3) + 1e-3);
    EXPECT_LE(s.maxDerivativeNorm(2, 1), a_max * (1 + 1e-9));
    EXPECT_LE(v_fd, speed * (1 + 1e-3) + 1e-6);
  }
  // From a speed no vehicle reaches (corrupt odometry: 1e7 m/s), the spline stays small and still brakes
  // from v at a_max to rest. It used to take one span per 0.05 s of braking: 1e8 of them, gigabytes.
  const Vec3 absurd = Vec3(1, -2, 0.5).normalized() * 1e7;
  const UniformBspline fast = traj::safeStop(Vec3(1, 2, 3), absurd, 2.0);
  EXPECT_LE(fast.numControlPoints(), 4003);
  EXPECT_LT((Vec3(fast.evaluate(0.0, 1)) - absurd).norm(), 1e-9 * 1e7);
  EXPECT_LE(fast.maxDerivativeNorm(2, 1), 2.0 * (1 + 1e-6));
  EXPECT_LT(fast.evaluate(fast.duration(), 1).norm(), 1e-6);
  EXPECT_NEAR(fast.duration(), 1e7 / 2.0, fast.knotSpan());
  const UniformBspline hold = traj::safeStop(Vec3(1, 2, 3), Vec3::Zero(), 1.0);
  EXPECT_LT((hold.position(0.3) - Vec3(1, 2, 3)).norm(), 1e-12);
  EXPECT_EQ(hold.maxVelocity(), 0.0);
}


// planTrajectory from rest to targets from 6 cm to 3 m away (the shortest within one voxel of the start,
// where the A* path is a single voxel) in an empty room: every plan succeeds, starts exactly at the
// start at rest, ends at rest within a voxel's half-diagonal of the target with the target's yaw, and
// keeps v_max and a_max (finite differences of positions, 5 % slack).
TEST(TrajectoryPlanner, HopsOfEveryLengthReachTheTargetWithinTheLimits) {
  OpenRoom room(Vec3(8, 8, 3));  // unmapped apart from floor and ceiling
  World& world = room.world;
  const Astar& astar = room.astar;
  const OptimizerConfig optimizer = optimizerConfig();
  const traj::TrajectoryPlannerConfig planner;
  Rng rng(7);
  int plans = 0;
  for (double distance : {0.06, 0.09, 0.12, 0.15, 0.2, 0.25, 0.3, 0.5, 1.0, 3.0}) {
    for (int trial = 0; trial < 6; ++trial) {
      traj::PlanRequest request;
      request.start = Vec3(4.0 + rng(-0.05, 0.05), 4.0 + rng(-0.05, 0.05), 1.5 + rng(-0.05, 0.05));
      do {  // targets stay clear of the floor and the ceiling
        request.target = request.start + distance * Vec3(rng(-1, 1), rng(-1, 1), rng(-0.5, 0.5)).normalized();
      } while (std::abs(request.target.z() - 1.5) > 0.7);
      request.yaw = rng(-kPi, kPi);
      request.target_yaw = rng(-kPi, kPi);
      traj::PlanReport report;
      const auto planned = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
      ASSERT_TRUE(planned) << "distance " << distance << " trial " << trial << ": " << planned.message();
      const traj::Trajectory& t = *planned;
      const traj::TrajectorySample first = traj::sampleTrajectory(t, 0.0), last = traj::sampleTrajectory(t, t.duration());
      EXPECT_LT((first.position - request.start).norm(), 1e-9);
      EXPECT_LT(first.velocity.norm(), 1e-9);
      EXPECT_LT((last.position - request.target).norm(), 0.5 * std::sqrt(3.0) * kRes + 1e-9)
          << "distance " << distance << " trial " << trial;
      EXPECT_LT(last.velocity.norm(), 1e-9);
      const traj::TrajectorySample settled = traj::sampleTrajectory(t, t.duration() + t.yaw.duration() + 1.0);
      EXPECT_NEAR(std::remainder(settled.yaw - request.target_yaw, 2 * kPi), 0.0, 1e-6);
      double v = 0.0, a = 0.0;
      finiteDifferenceDynamics(t.position, 2000, v, a);
      EXPECT_LE(v, 1.05 * optimizer.v_max);
      EXPECT_LE(a, 1.05 * optimizer.a_max);
      ++plans;
    }
  }
  EXPECT_EQ(plans, 60);
}

// A vehicle left closer to a wall than min_clearance (mapped late beside it) is planned away from it:
// every spline from there used to fail the clearance check at its own start, and the vehicle held there.
// A plan's turn goes on from the reference's yaw rate (no jump in the commanded rate): a hop, a turn in place,
// and a look round all start turning at the 0.8 rad/s the reference had.
TEST(TrajectoryPlanner, TurnsGoOnFromTheReferenceYawRate) {
  OpenRoom room(Vec3(12, 12, 3));
  const OptimizerConfig optimizer = optimizerConfig();
  const traj::TrajectoryPlannerConfig planner;
  traj::PlanRequest request;
  request.start = Vec3(4.05, 6.05, 1.55);
  request.yaw = 0.0;
  request.yaw_rate = 0.8;
  request.target_yaw = 2.0;
  for (const Vec3& offset : {Vec3(2.0, 0.0, 0.0), Vec3(0.01, 0.0, 0.0)}) {  // a hop, a turn in place
    request.target = request.start + offset;
    const auto planned = traj::planTrajectory(request, room.astar, room.world.esdf(), optimizer, planner);
    ASSERT_TRUE(planned) << planned.message();
    EXPECT_NEAR(traj::sampleTrajectory(*planned, 0.0).yaw_dot, 0.8, 1e-9) << offset.transpose();
  }
  const traj::Trajectory look = traj::lookAroundTrajectory(request, planner, optimizer);
  EXPECT_NEAR(traj::sampleTrajectory(look, 0.0).yaw_dot, 0.8, 1e-9);
}

// The goal may snap to flyable space only goal_tolerance far (the start up to snap_radius): a viewpoint inside a
// box, whose nearest flyable voxel the search reaches 0.3 .. 1 m off, is refused as goal_blocked, not flown to
// short of it.
TEST(TrajectoryPlanner, AGoalSnappedFartherThanTheToleranceIsRefused) {
  OpenRoom room(Vec3(6, 4, 3));
  room.world.addBox(Index3(30, 15, 0), Index3(35, 24, 29));  // x 3.0 .. 3.6 m, y 1.5 .. 2.5 m, full height
  room.world.sync();
  const OptimizerConfig optimizer = optimizerConfig();
  const traj::TrajectoryPlannerConfig planner;
  traj::PlanRequest request;
  request.start = Vec3(1.0, 2.0, 1.5);
  request.target = Vec3(3.3, 2.0, 1.5);
  const PathResult search = room.astar.search(request.start, request.target, planner.snap_radius);
  ASSERT_EQ(search.status, PathStatus::kFound);
  const double off = (search.path.back() - request.target).norm();
  ASSERT_GT(off, planner.goal_tolerance);
  ASSERT_LT(off, planner.snap_radius);
  traj::PlanReport report;
  const auto planned = traj::planTrajectory(request, room.astar, room.world.esdf(), optimizer, planner, &report);
  ASSERT_FALSE(planned);
  EXPECT_EQ(report.path_status, PathStatus::kGoalBlocked);
  EXPECT_NE(planned.message().find("goal_blocked"), std::string::npos) << planned.message();
}

// A path ends at its voxel's centre, up to half a voxel's diagonal from the target: a goal_tolerance below that
// refused a target at a voxel's corner in open space as blocked. It is refused against the map's resolution.
TEST(TrajectoryPlanner, AGoalToleranceUnderHalfAVoxelsDiagonalIsRefusedAgainstTheMap) {
  OpenRoom room(Vec3(6, 4, 3));
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  planner.goal_tolerance = 0.05;
  ASSERT_TRUE(planner.validate()) << planner.validate().message();
  traj::PlanRequest request;
  request.start = Vec3(1.05, 2.05, 1.55);
  request.target = Vec3(3.0, 2.0, 1.5);  // a voxel's corner, 0.087 m from the centres around it
  traj::PlanReport report;
  EXPECT_FALSE(traj::planTrajectory(request, room.astar, room.world.esdf(), optimizer, planner, &report));
  EXPECT_EQ(report.path_status, PathStatus::kGoalBlocked);
  OccupancyConfig occupancy;
  occupancy.resolution = kRes;
  EXPECT_EQ(planner.validate(occupancy).message(),
            "planner: goal_tolerance must be at least half a voxel's diagonal (0.086603 m at the map's resolution of "
            "0.100000 m): a path ends at a voxel's centre, and targets off it were refused as blocked");
  planner.goal_tolerance = 0.09;
  EXPECT_TRUE(planner.validate(occupancy)) << planner.validate(occupancy).message();
  const auto planned = traj::planTrajectory(request, room.astar, room.world.esdf(), optimizer, planner, &report);
  ASSERT_TRUE(planned) << planned.message();
  planner.goal_tolerance = std::numeric_limits<double>::quiet_NaN();  // validate() names it first
  EXPECT_NE(planner.validate(occupancy).message().find("planner: goal_tolerance must be finite and >= 0"), std::string::npos);
}

TEST(TrajectoryPlanner, AStartTooNearAWallIsPlannedAway) {
  OpenRoom room(Vec3(6, 4, 3));
  World& world = room.world;
  world.addBox(Index3(10, 0, 0), Index3(10, 39, 29));  // wall voxels at x in [1.0, 1.1]
  world.sync();
  const OptimizerConfig optimizer = optimizerConfig();
  const traj::TrajectoryPlannerConfig planner;
  for (double gap : {0.19, 0.15, 0.1}) {
    traj::PlanRequest request;
    request.start = Vec3(1.05 + gap, 2.0, 1.5);
    request.target = Vec3(4.5, 2.0, 1.5);
    const auto planned = traj::planTrajectory(request, room.astar, world.esdf(), optimizer, planner);
    ASSERT_TRUE(planned) << "gap " << gap << ": " << planned.message();
    bool left = false;
    for (int k = 0; k <= 2000; ++k) {
      const double d = world.esdf().distance(planned->position.position(planned->duration() * k / 2000));
      if (!left) {
        EXPECT_GE(d, gap - 0.1 * kRes) << "gap " << gap << " sample " << k;
      }
      left = left || d >= optimizer.min_clearance;
    }
    EXPECT_TRUE(left) << "gap " << gap;
  }
}

// An optimum that breaks a limit, where the plain fit of the path keeps every one, gives way to the fit
// (PlanReport::used_fit). With lambda_time 1e6 the optimiser shortens the knot spans until the speed
// breaks v_max, from whatever timing it starts: no slower refit mends that, and without the fit every
// plan fails.
TEST(TrajectoryPlanner, AFitThatPassesTheChecksIsFlownWhereTheOptimumBreaksALimit) {
  OpenRoom room(Vec3(8, 8, 3));
  OptimizerConfig optimizer = optimizerConfig();
  optimizer.lambda_time = 1e6;
  traj::TrajectoryPlannerConfig planner;
  planner.profile_acceleration = 0.0;  // no timed fit, no finer optimisation beside, no retry
  planner.fine_spans = 0;
  planner.unseen_retry = false;
  // A fit through samples at even times starts and stops abruptly: from rest it keeps a_max only when
  // slow enough (here after 3 refits, about 5 times the first timing, more than the shipped 3 allow).
  planner.max_refits = 8;
  planner.max_slowdown = 20.0;
  Rng rng(3);
  for (int trial = 0; trial < 6; ++trial) {
    traj::PlanRequest request;
    request.start = Vec3(4.0 + rng(-0.2, 0.2), 4.0 + rng(-0.2, 0.2), 1.5);
    const double heading = rng(-kPi, kPi), distance = rng(1.5, 3.0);
    request.target = request.start + distance * Vec3(std::cos(heading), std::sin(heading), rng(-0.1, 0.1));
    request.yaw = request.target_yaw = heading;
    // The optimum of the planner's own first fit breaks a limit.
    const double duration = distance / (planner.cruise_fraction * optimizer.v_max);
    const auto samples = UniformBspline::resamplePolyline({request.start, request.target}, planner.path_spacing);
    const auto optimum = traj::optimize(
        UniformBspline::fitPath(samples, duration / static_cast<double>(samples.size() - 1), Vec3::Zero(),
                                Vec3::Zero(), Vec3::Zero()),
        room.world.esdf(), optimizer);
    EXPECT_FALSE(optimum) << "trial " << trial << ": the optimum keeps the limits, max speed "
                          << (optimum ? optimum->maxVelocity() : 0.0);
    traj::PlanReport report;
    const auto planned = traj::planTrajectory(request, room.astar, room.world.esdf(), optimizer, planner, &report);
    ASSERT_TRUE(planned) << "trial " << trial << ": " << planned.message() << " refits " << report.refits
                         << " left_flyable " << report.left_flyable << " status " << static_cast<int>(report.path_status)
                         << " length " << report.path_length;
    EXPECT_TRUE(report.used_fit) << "trial " << trial;
    double v = 0.0, a = 0.0;
    finiteDifferenceDynamics(planned->position, 2000, v, a);
    EXPECT_LE(v, (1.0 + optimizer.limit_tolerance) * optimizer.v_max) << "trial " << trial;
    EXPECT_LE(a, (1.0 + optimizer.limit_tolerance) * optimizer.a_max) << "trial " << trial;
    const UniformBspline& p = planned->position;
    EXPECT_LT((p.position(p.duration()) - request.target).norm(), 0.5 * std::sqrt(3.0) * kRes + 1e-9) << "trial " << trial;
  }
}

// Arc length of the trapezoidal speed profile from rest (accelerate at a, cruise at v, brake at a to rest at
// length L) at time t, in closed form: the oracle for profileSamples().
double trapezoidArc(double t, double L, double v, double a) {
  double peak = std::min(v, std::sqrt(a * L));  // a triangle when L is too short to reach v
  const double t_acc = peak / a, d_acc = 0.5 * peak * t_acc;
  const double t_cruise = (L - 2.0 * d_acc) / peak, T = 2.0 * t_acc + t_cruise;
  if (t <= 0.0) return 0.0;
  if (t < t_acc) return 0.5 * a * t * t;
  if (t < t_acc + t_cruise) return d_acc + peak * (t - t_acc);
  if (t < T) return L - 0.5 * a * (T - t) * (T - t);
  return L;
}

// From rest along a straight line, the samples follow the trapezoidal profile averaged over the ramp
// (x(t) = mean of the trapezoid's arc length over [t - ramp, t], computed here by quadrature of the closed
// form), so the flight takes the trapezoid's time plus the ramp; speeds and accelerations of the samples
// stay within cruise and acceleration. Short (triangular) and long (cruising) hops alike.
TEST(ProfileSamples, FollowTheAveragedTrapezoidOnAStraightLine) {
  traj::SpeedProfile profile;
  profile.cruise = 1.9;
  profile.acceleration = 1.8;
  profile.ramp = 0.1;
  profile.knot_span = 0.05;
  for (double L : {0.4, 1.5, 5.0}) {
    const Vec3 a(1, 2, 1.5), dir = Vec3(2, -1, 0.5).normalized();
    double dt = 0.0;
    const std::vector<Vec3> samples = traj::profileSamples({a, a + 0.5 * L * dir, a + L * dir}, 0.0, 0.0, profile, &dt);
    ASSERT_GE(samples.size(), 7u) << L;
    const double peak = std::min(profile.cruise, std::sqrt(profile.acceleration * L));
    const double T_trap = 2.0 * peak / profile.acceleration + (L - peak * peak / profile.acceleration) / peak;
    EXPECT_NEAR(dt * (samples.size() - 1), T_trap + profile.ramp, 0.01) << L;
    EXPECT_LT((samples.front() - a).norm(), 1e-12);
    EXPECT_LT((samples.back() - (a + L * dir)).norm(), 1e-12);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const double t = dt * i;
      double mean = 0.0;
      constexpr int kQuad = 400;
      for (int q = 0; q < kQuad; ++q)
        mean += trapezoidArc(t - profile.ramp * (q + 0.5) / kQuad, L, profile.cruise, profile.acceleration);
      mean /= kQuad;
      EXPECT_NEAR((samples[i] - a).dot(dir), mean, 3e-3) << "L " << L << " sample " << i;
      EXPECT_LT((samples[i] - a - (samples[i] - a).dot(dir) * dir).norm(), 1e-9);  // on the line
      if (i + 1 < samples.size()) {
        EXPECT_LE((samples[i + 1] - samples[i]).norm() / dt, profile.cruise + 1e-3);
      }
      if (i + 2 < samples.size()) {
        EXPECT_LE((samples[i + 2] - 2.0 * samples[i + 1] + samples[i]).norm() / (dt * dt), profile.acceleration + 0.02);
      }
    }
  }
}

// Starting at speed: the samples leave at that speed, with no jump in acceleration (it ramps up from zero),
// and still end at the path's end at rest; a corner is rounded no faster than its corner speed
// sqrt(a cut / (1 / cos(theta / 2) - 1)); too short a path for the start speed, fewer than two points and a
// bad profile are refused.
TEST(ProfileSamples, StartAtSpeedSlowForCornersAndRefuseWhatTheyCannotTime) {
  traj::SpeedProfile profile;
  profile.cruise = 1.9;
  profile.acceleration = 1.8;
  profile.ramp = 0.1;
  profile.knot_span = 0.02;
  double dt = 0.0;
  const std::vector<Vec3> line = traj::profileSamples({Vec3(0, 0, 1), Vec3(3, 0, 1)}, 1.0, 0.0, profile, &dt);
  ASSERT_GE(line.size(), 7u);
  EXPECT_NEAR((line[1] - line[0]).x() / dt, 1.0, 0.02);
  EXPECT_NEAR((line[2] - 2.0 * line[1] + line[0]).x() / (dt * dt), 0.0, 0.5 * profile.acceleration);
  const std::size_t n = line.size();
  EXPECT_NEAR((line[n - 1] - line[n - 2]).norm() / dt, 0.0, 0.01);
  EXPECT_LT((line.back() - Vec3(3, 0, 1)).norm(), 1e-12);
  // Speeding up already: the samples leave with that acceleration too.
  const std::vector<Vec3> pushing = traj::profileSamples({Vec3(0, 0, 1), Vec3(3, 0, 1)}, 1.0, 1.2, profile, &dt);
  ASSERT_GE(pushing.size(), 7u);
  EXPECT_NEAR((pushing[1] - pushing[0]).x() / dt, 1.0 + 0.5 * 1.2 * dt, 0.02);
  EXPECT_NEAR((pushing[2] - 2.0 * pushing[1] + pushing[0]).x() / (dt * dt), 1.2, 0.2 * profile.acceleration);
  EXPECT_LT((pushing.back() - Vec3(3, 0, 1)).norm(), 1e-12);

  // A right angle at (2, 0): its corner speed with a 0.1 m cut.
  profile.corner_cut = 0.1;
  const std::vector<Vec3> bend = traj::profileSamples({Vec3(0, 0, 1), Vec3(2, 0, 1), Vec3(2, 2, 1)}, 0.0, 0.0, profile, &dt);
  ASSERT_GE(bend.size(), 7u);
  const double corner_speed = std::sqrt(profile.acceleration * profile.corner_cut / (1.0 / std::cos(kPi / 4) - 1.0));
  double slowest_near_corner = 1e9;
  for (std::size_t i = 0; i + 1 < bend.size(); ++i)
    if ((bend[i] - Vec3(2, 0, 1)).norm() < 0.05)
      slowest_near_corner = std::min(slowest_near_corner, (bend[i + 1] - bend[i]).norm() / dt);
  EXPECT_LE(slowest_near_corner, corner_speed + 0.05);
  EXPECT_GT(slowest_near_corner, 0.5 * corner_speed);  // slowed for the corner, not stopped

  EXPECT_TRUE(traj::profileSamples({Vec3(0, 0, 1), Vec3(0.06, 0, 1)}, 1.9, 0.0, profile, &dt).empty());
  EXPECT_TRUE(traj::profileSamples({Vec3(0, 0, 1)}, 0.0, 0.0, profile, &dt).empty());
  traj::SpeedProfile bad = profile;
  bad.acceleration = 0.0;
  EXPECT_THROW(traj::profileSamples({Vec3(0, 0, 1), Vec3(3, 0, 1)}, 0.0, 0.0, bad, &dt), std::invalid_argument);
  bad = profile;
  bad.ramp = -0.1;
  EXPECT_THROW(traj::profileSamples({Vec3(0, 0, 1), Vec3(3, 0, 1)}, 0.0, 0.0, bad, &dt), std::invalid_argument);
  EXPECT_THROW(traj::profileSamples({Vec3(0, 0, 1), Vec3(3, 0, 1)}, std::nan(""), 0.0, profile, &dt), std::invalid_argument);
  EXPECT_THROW(traj::profileSamples({Vec3(0, 0, 1), Vec3(3, 0, 1)}, 0.0, std::nan(""), profile, &dt), std::invalid_argument);
}

// Hops from rest in an empty room take little more than the quickest flight the limits allow (the
// bang-bang oracle: accelerate at a_max, cruise at v_max, brake at a_max): the timed fit is flown, within
// the limits (finite differences). Without it (profile_acceleration 0) the optimised spline is slower, and
// the finer second optimisation (fine_spans) makes most short hops quicker than the 6-span one alone
// (and none slower: the quicker one is kept).
TEST(TrajectoryPlanner, HopsFromRestTakeCloseToTheQuickestFlight) {
  OpenRoom room(Vec3(12, 12, 3));  // unmapped apart from floor and ceiling
  World& world = room.world;
  const Astar& astar = room.astar;
  OptimizerConfig optimizer = optimizerConfig();
  optimizer.lambda_feasibility = 10.0;  // the weights of config/trajectory.yaml
  optimizer.lambda_time = 5.0;
  traj::TrajectoryPlannerConfig planner;
  traj::TrajectoryPlannerConfig optimised = planner;
  optimised.profile_acceleration = 0.0;
  traj::TrajectoryPlannerConfig coarse = optimised;
  coarse.fine_spans = 0;
  int fine_wins = 0;
  for (double L : {1.0, 1.5, 3.0, 5.0}) {
    for (double angle : {0.0, 0.7, 2.0}) {
      traj::PlanRequest request;
      request.start = Vec3(6.05, 6.05, 1.55);
      request.target = request.start + L * Vec3(std::cos(angle), std::sin(angle), 0.0);
      const double peak = std::min(optimizer.v_max, std::sqrt(optimizer.a_max * L));
      const double quickest = 2.0 * peak / optimizer.a_max + (L - peak * peak / optimizer.a_max) / peak;
      traj::PlanReport report;
      const auto timed = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
      ASSERT_TRUE(timed) << L << " " << angle << ": " << timed.message();
      EXPECT_TRUE(report.profiled) << L << " " << angle;
      EXPECT_LE(timed->duration(), 1.15 * quickest) << L << " " << angle;
      double v = 0.0, a = 0.0;
      finiteDifferenceDynamics(timed->position, 2000, v, a);
      EXPECT_LE(v, 1.05 * optimizer.v_max);
      EXPECT_LE(a, 1.05 * optimizer.a_max);
      EXPECT_LT((timed->position.position(timed->duration()) - request.target).norm(), 0.5 * std::sqrt(3.0) * kRes + 1e-9);
      const auto slow = traj::planTrajectory(request, astar, world.esdf(), optimizer, optimised, &report);
      ASSERT_TRUE(slow) << slow.message();
      EXPECT_FALSE(report.profiled);
      EXPECT_LT(timed->duration(), slow->duration()) << L << " " << angle;
      if (L <= 1.5) {
        const bool fine = report.fine;
        const auto six = traj::planTrajectory(request, astar, world.esdf(), optimizer, coarse, &report);
        ASSERT_TRUE(six) << six.message();
        EXPECT_FALSE(report.fine);
        EXPECT_LE(slow->duration(), six->duration() + 1e-9) << L << " " << angle;  // the quicker one is kept
        if (fine && slow->duration() < six->duration()) ++fine_wins;
      }
    }
  }
  EXPECT_GE(fine_wins, 3);  // of the 6 short hops
}

// A replan keeps the reference's acceleration as well as its velocity (clamped to the optimiser's
// margin-reduced a_max), with the timed fit (start velocity along the path) and with the optimiser
// (start velocity across it) alike.
TEST(TrajectoryPlanner, ReplansKeepTheReferenceAcceleration) {
  OpenRoom room(Vec3(12, 12, 3));  // unmapped apart from floor and ceiling
  World& world = room.world;
  const Astar& astar = room.astar;
  const OptimizerConfig optimizer = optimizerConfig();
  const traj::TrajectoryPlannerConfig planner;
  struct Case {
    Vec3 velocity, acceleration;
    bool profiled;
  };
  const double limit = optimizer.feasibility_margin * optimizer.a_max;
  for (const Case& c : {Case{Vec3(1.0, 0, 0), Vec3(0.8, 0.3, 0), true}, Case{Vec3(0, 1.0, 0), Vec3(-0.5, 0.6, 0), false},
                        Case{Vec3(0, 1.0, 0), Vec3(0, 6.0, 0), false}}) {
    traj::PlanRequest request;
    request.start = Vec3(4.05, 6.05, 1.55);
    request.target = Vec3(8.05, 6.05, 1.55);
    request.velocity = c.velocity;
    request.acceleration = c.acceleration;
    traj::PlanReport report;
    const auto planned = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
    ASSERT_TRUE(planned) << planned.message();
    EXPECT_EQ(report.profiled, c.profiled);
    const traj::TrajectorySample first = traj::sampleTrajectory(*planned, 0.0);
    EXPECT_LT((first.velocity - c.velocity).norm(), 1e-6);
    const Vec3 expected = c.acceleration.norm() > limit ? Vec3(c.acceleration * (limit / c.acceleration.norm())) : c.acceleration;
    EXPECT_LT((first.acceleration - expected).norm(), 1e-6) << c.acceleration.transpose();
  }
}

// A start velocity with a small part across the path's first leg (0.08 m/s, within profile_max_cross_speed)
// is still flown by the timed fit when the profile leaves acceleration across the path (profile_acceleration
// 0.8 of a_max against the 0.95 margin: 1.02 m/s^2): the crossing part fades out within Te = 4 |v_cross| /
// a_cross, after which the flight runs along the path, and the limits hold throughout.
TEST(TrajectoryPlanner, AStartVelocityAcrossThePathFadesOutInTheTimedFit) {
  OpenRoom room(Vec3(12, 12, 3));
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  planner.profile_acceleration = 0.8;
  traj::PlanRequest request;
  request.start = Vec3(4.05, 6.05, 1.55);
  request.target = Vec3(8.05, 6.05, 1.55);
  request.velocity = Vec3(1.0, 0.08, 0.0);
  traj::PlanReport report;
  const auto planned = traj::planTrajectory(request, room.astar, room.world.esdf(), optimizer, planner, &report);
  ASSERT_TRUE(planned) << planned.message();
  EXPECT_TRUE(report.profiled);
  EXPECT_LT((traj::sampleTrajectory(*planned, 0.0).velocity - request.velocity).norm(), 1e-6);
  const double a_limit = optimizer.feasibility_margin * optimizer.a_max;
  const double a_along = planner.profile_acceleration * optimizer.a_max;
  const double te = 4.0 * 0.08 / std::sqrt(a_limit * a_limit - a_along * a_along);
  double drift = 0.0;  // the largest offset across the path
  for (double t = 0.0; t <= planned->duration(); t += 0.01) {
    const traj::TrajectorySample s = traj::sampleTrajectory(*planned, t);
    drift = std::max(drift, std::abs(s.position.y() - 6.05));
    if (t > te + 2 * planner.profile_knot_span) {
      EXPECT_LT(std::abs(s.velocity.y()), 1e-3) << "at " << t << " s";
    }
  }
  // v_cross t (1 - t / Te)^2 peaks at t = Te / 3: 4 / 27 v_cross Te across the path.
  EXPECT_NEAR(drift, 4.0 / 27.0 * 0.08 * te, 0.25 * 4.0 / 27.0 * 0.08 * te);
  double v = 0.0, a = 0.0;
  finiteDifferenceDynamics(planned->position, 4000, v, a);
  EXPECT_LE(v, (1.0 + optimizer.limit_tolerance) * optimizer.v_max);
  EXPECT_LE(a, (1.0 + optimizer.limit_tolerance) * optimizer.a_max);
}

// A fade that outlasts the flight would move the timed fit's end off the path's: a 1 m/s start across a 2 m
// hop fades over Te = 4 / sqrt(1.9^2 - 1.8^2) = 6.6 s at profile_acceleration 0.9. That fit is not flown
// (it ended a metre beside the goal); what is flown ends at the target.
TEST(TrajectoryPlanner, ATimedFitWhoseFadeOutlastsTheFlightIsNotFlown) {
  OpenRoom room(Vec3(12, 12, 3));
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  planner.profile_acceleration = 0.9;
  planner.profile_max_cross_speed = 1.0;
  ASSERT_TRUE(planner.validate()) << planner.validate().message();
  traj::PlanRequest request;
  request.start = Vec3(4.05, 6.05, 1.55);
  request.target = Vec3(6.05, 6.05, 1.55);
  request.velocity = Vec3(0.3, 1.0, 0.0);
  traj::PlanReport report;
  const auto planned = traj::planTrajectory(request, room.astar, room.world.esdf(), optimizer, planner, &report);
  ASSERT_TRUE(planned) << planned.message();
  EXPECT_FALSE(report.profiled);
  EXPECT_FALSE(planned->partial);
  const Vec3 end = planned->position.position(planned->duration());
  EXPECT_LT((end - request.target).norm(), 0.5 * std::sqrt(3.0) * kRes) << end.transpose();
  EXPECT_LT((traj::sampleTrajectory(*planned, 0.0).velocity - request.velocity).norm(), 1e-6);
}

// A path longer than the horizon is flown only that far along it (partial, the goal kept), and such a
// trajectory is replanned when little time is left on it, while one that ends at its goal is not; a goal
// farther than target_tolerance from the target is a new target. Without a horizon the whole corridor is
// flown, no slower than max_slowdown times the first timing.
TEST(TrajectoryPlanner, LongPathsAreFlownToTheHorizonAndReplannedOnTheWay) {
  OpenRoom room(Vec3(20, 4, 3));  // unmapped apart from floor and ceiling
  World& world = room.world;
  const Astar& astar = room.astar;
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  planner.horizon = 6.0;
  const ReplanConfig replan;
  traj::PlanRequest request;
  request.start = Vec3(1.0, 2.0, 1.5);
  request.target = Vec3(18.0, 2.0, 1.5);
  request.yaw = 0.0;
  request.target_yaw = 0.5;
  const auto partial = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner);
  ASSERT_TRUE(partial) << partial.message();
  EXPECT_TRUE(partial->partial);
  EXPECT_LT((partial->goal - request.target).norm(), 1e-12);
  const Vec3 end = partial->position.position(partial->duration());
  EXPECT_NEAR((end - request.start).norm(), planner.horizon, 0.5 * std::sqrt(3.0) * kRes);
  double v = 0.0, a = 0.0;
  finiteDifferenceDynamics(partial->position, 2000, v, a);
  EXPECT_LE(v, 1.05 * optimizer.v_max);
  EXPECT_LE(a, 1.05 * optimizer.a_max);
  const double late = partial->duration() - 0.5 * replan.min_time_left;
  auto reason = [&](const traj::Trajectory& t, double at, const Vec3& target) {
    return traj::replanReason(&t, at, target, false, world.esdf(), replan, optimizer, planner);
  };
  EXPECT_EQ(reason(*partial, 0.5, request.target), ReplanReason::kNone);
  EXPECT_EQ(reason(*partial, late, request.target), ReplanReason::kShortTimeLeft);
  EXPECT_EQ(reason(*partial, 0.5, request.target + Vec3(0, 0.5, 0)), ReplanReason::kNewTarget);

  planner.horizon = 0.0;
  const auto whole = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner);
  ASSERT_TRUE(whole) << whole.message();
  EXPECT_FALSE(whole->partial);
  // The target is a voxel corner: the path ends at a centre of its voxels, half a diagonal away.
  EXPECT_LT((whole->position.position(whole->duration()) - request.target).norm(), 0.5 * std::sqrt(3.0) * kRes + 1e-9);
  EXPECT_EQ(reason(*whole, whole->duration() - 0.5 * replan.min_time_left, request.target), ReplanReason::kNone);
  const double length = (request.target - request.start).norm();
  EXPECT_LE(whole->duration(), planner.max_slowdown * length / (planner.cruise_fraction * optimizer.v_max) + 1e-9);
}

// A failed search is the vehicle's predicament when the start was blocked or the search ran dry inside
// the snap_radius ball; then the vehicle turns in place towards the target (or on by enclosed_turn when it
// already faces it), holding still for the whole turn, and retries the target before the turn ends.
TEST(TrajectoryPlanner, EnclosedStartsLookAroundInsteadOfFailingTheTarget) {
  const OptimizerConfig optimizer = optimizerConfig();
  const traj::TrajectoryPlannerConfig planner;
  const double res = 0.1;
  const double ball = 4.0 / 3.0 * kPi * std::pow(planner.snap_radius / res, 3);
  traj::PlanReport report;
  report.path_status = PathStatus::kStartBlocked;
  EXPECT_TRUE(traj::startEnclosed(report, planner, res));
  report.path_status = PathStatus::kNoPath;
  report.path_expansions = static_cast<int>(ball) - 1;
  EXPECT_TRUE(traj::startEnclosed(report, planner, res));
  report.path_expansions = static_cast<int>(ball) + 1;
  EXPECT_FALSE(traj::startEnclosed(report, planner, res));
  report.path_expansions = 10;
  report.path_status = PathStatus::kBudgetExceeded;
  EXPECT_FALSE(traj::startEnclosed(report, planner, res));
  report.path_status = PathStatus::kGoalBlocked;
  EXPECT_FALSE(traj::startEnclosed(report, planner, res));

  traj::PlanRequest request;
  request.start = Vec3(1.0, 2.0, 1.0);
  request.yaw = 0.0;
  request.target = Vec3(1.0, 5.0, 1.5);  // straight to the left: turn to pi/2
  const traj::Trajectory look = traj::lookAroundTrajectory(request, planner, optimizer);
  EXPECT_TRUE(look.partial);
  EXPECT_LT((look.goal - request.target).norm(), 1e-12);
  EXPECT_GE(look.duration(), look.yaw.duration() - 1e-9);
  for (int i = 0; i <= 100; ++i) {
    const traj::TrajectorySample s = traj::sampleTrajectory(look, look.duration() * i / 100);
    EXPECT_LT((s.position - request.start).norm(), 1e-9);
    EXPECT_LE(std::abs(s.yaw_dot), optimizer.yaw_rate_max * (1 + 1e-6));
  }
  EXPECT_NEAR(traj::sampleTrajectory(look, look.duration()).yaw, kPi / 2, 1e-9);
  // Already facing the target: turn on by enclosed_turn.
  request.yaw = kPi / 2 + 0.1;
  const traj::Trajectory on = traj::lookAroundTrajectory(request, planner, optimizer);
  EXPECT_NEAR(std::remainder(traj::sampleTrajectory(on, on.duration() + on.yaw.duration()).yaw - (request.yaw + planner.enclosed_turn), 2 * kPi), 0.0, 1e-9);
  // Moving: it brakes (and the target is retried from wherever that ends).
  request.velocity = Vec3(1.0, 0.0, 0.0);
  const traj::Trajectory braking = traj::lookAroundTrajectory(request, planner, optimizer);
  EXPECT_LT(traj::sampleTrajectory(braking, braking.duration()).velocity.norm(), 1e-9);
  // Moving, slowly or fast: the stop is held for as long as the turn takes (a stop over at once, as from an
  // odometry's 1e-4 m/s, made the next plan start the turn from rest again), from the start's velocity on.
  for (double speed : {1e-4, 0.05, 1.0}) {
    request.velocity = Vec3(0.0, speed, 0.0);
    const traj::Trajectory slow = traj::lookAroundTrajectory(request, planner, optimizer);
    EXPECT_GE(slow.position.duration(), slow.yaw.duration() - 1e-9) << speed;
    EXPECT_LT(traj::sampleTrajectory(slow, slow.duration()).velocity.norm(), 1e-9) << speed;
    EXPECT_LT((traj::sampleTrajectory(slow, slow.duration()).position - request.start).norm(), 0.3) << speed;
    if (speed > 0.01) {
      EXPECT_NEAR(traj::sampleTrajectory(slow, 0.0).velocity.y(), speed, 1e-9) << speed;
    }
  }
  request.velocity.setZero();
  // The replanning rule retries the target shortly before the turn ends, not at once.
  World world(Vec3(4, 4, 3));
  world.sync();
  const ReplanConfig replan;
  auto reason = [&](double at) {
    return traj::replanReason(&look, at, request.target, false, world.esdf(), replan, optimizer, planner);
  };
  ASSERT_GT(look.duration(), replan.min_time_left + 0.2);
  EXPECT_EQ(reason(0.1), ReplanReason::kNone);
  EXPECT_EQ(reason(look.duration() - 0.5 * replan.min_time_left), ReplanReason::kShortTimeLeft);
}

// Known free space with walls across the room every `width` voxels, their gap alternating at either end:
// a zig-zag corridor (0.9-1.2 m wide for width 8-10).
void zigZagCorridor(World& world, int width) {
  const Index3 dims = world.geo().dims();
  world.setFree(Index3::Zero(), dims - Index3::Ones());
  for (int k = 1; k * width < dims.x() - 5; ++k) {
    const int x = k * width;
    if (k % 2) {
      world.addBox(Index3(x, 0, 0), Index3(x + 1, dims.y() - 9, dims.z() - 1));
    } else {
      world.addBox(Index3(x, 8, 0), Index3(x + 1, dims.y() - 1, dims.z() - 1));
    }
  }
  world.sync();
}

// A zig-zag corridor of trial's width (8 + trial % 3 voxels), its flight search, and a request starting in
// its first leg at a random y.
struct ZigZagRoom {
  ZigZagRoom(int trial, Rng& rng, const AstarConfig& config)
      : width(8 + trial % 3), world(Vec3(8, 8, 2)), astar(built(world, width).occupancy(), world.esdf(), config) {
    request.start = Vec3(0.5 * width * 0.1, 4.0 + rng(-2.0, 2.0), 1.0);
  }
  static World& built(World& w, int width) {
    zigZagCorridor(w, width);
    return w;
  }
  int width;
  World world;
  Astar astar;
  traj::PlanRequest request;
};

// Through zig-zag corridors (mapped walls, known free space) 0.8-1.0 m wide, from a start already moving
// along the first leg: every plan succeeds or fails with a reason, and every returned trajectory keeps
// min_clearance from the walls beyond snap_radius (dense sampling of the ESDF) and the limits.
TEST(TrajectoryPlanner, TightCornersAreFlownWithClearance) {
  const OptimizerConfig optimizer = optimizerConfig();
  const traj::TrajectoryPlannerConfig planner;
  AstarConfig astar_config;
  astar_config.unknown_is_free = false;
  astar_config.known_clearance = true;
  astar_config.clearance = 0.3;
  Rng rng(5);
  int ok = 0, total = 0;
  for (int trial = 0; trial < 30; ++trial) {
    ZigZagRoom room(trial, rng, astar_config);
    const World& world = room.world;
    const Astar& astar = room.astar;
    traj::PlanRequest& request = room.request;
    request.velocity = Vec3(0.0, rng(-1.2, 1.2), 0.0);  // along the first leg
    request.target = Vec3(7.4, 4.0 + rng(-2.0, 2.0), 1.0);
    request.yaw = 0.0;
    request.target_yaw = 0.0;
    ++total;
    const auto planned = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner);
    if (!planned) {
      EXPECT_FALSE(planned.message().empty());
      continue;
    }
    ++ok;
    const UniformBspline& p = planned->position;
    for (int i = 0; i <= 4000; ++i) {
      const Vec3 q = p.position(p.duration() * i / 4000);
      if ((q - request.start).norm() <= planner.snap_radius) continue;
      ASSERT_GE(world.esdf().distance(q), optimizer.min_clearance - 1e-9) << "trial " << trial << " at " << q.transpose();
    }
    double v = 0.0, a = 0.0;
    finiteDifferenceDynamics(p, 4000, v, a);
    EXPECT_LE(v, 1.05 * optimizer.v_max);
    EXPECT_LE(a, 1.05 * optimizer.a_max);
  }
  EXPECT_GE(ok, total - 1) << ok << " of " << total << " plans succeeded";
}

// Fitted to samples 1 m apart, the optimum cuts the zig-zag corridor's corners (too close to the walls, or
// through space the search did not vouch for): every first attempt fails. The refits, each at half the
// spacing (and slower where a limit broke), hug the searched path closer until one passes: with max_refits
// 0, or max_slowdown 1, no plan succeeds; with the defaults every one does, after one refit or more,
// keeping min_clearance.
TEST(TrajectoryPlanner, RefitsCloserToThePathRescueOptimaThatCutCorners) {
  const OptimizerConfig optimizer = optimizerConfig();
  AstarConfig astar_config;
  astar_config.unknown_is_free = false;
  astar_config.known_clearance = true;
  astar_config.clearance = 0.3;
  traj::TrajectoryPlannerConfig planner;
  planner.path_spacing = 1.0;
  planner.profile_acceleration = 0.0;  // no timed fit, no finer optimisation beside, no retry: the refits alone
  planner.fine_spans = 0;
  planner.unseen_retry = false;
  ASSERT_GE(planner.max_refits, 2);
  Rng rng(5);
  int rescued = 0;
  for (int trial = 0; trial < 12; ++trial) {
    ZigZagRoom room(trial, rng, astar_config);
    const World& world = room.world;
    const Astar& astar = room.astar;
    traj::PlanRequest& request = room.request;
    request.target = Vec3(7.4, 4.0 + rng(-2.0, 2.0), 1.0);
    traj::TrajectoryPlannerConfig once = planner;
    once.max_refits = 0;
    EXPECT_FALSE(traj::planTrajectory(request, astar, world.esdf(), optimizer, once)) << "trial " << trial;
    // Every refit is slower than the one before (by 1.5 at least): with max_slowdown 1 there is none.
    traj::TrajectoryPlannerConfig capped = planner;
    capped.max_slowdown = 1.0;
    traj::PlanReport capped_report;
    EXPECT_FALSE(traj::planTrajectory(request, astar, world.esdf(), optimizer, capped, &capped_report)) << "trial " << trial;
    EXPECT_EQ(capped_report.refits, 0) << "trial " << trial;
    traj::PlanReport report;
    const auto planned = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
    ASSERT_TRUE(planned) << "trial " << trial << ": " << planned.message();
    EXPECT_GE(report.refits, 1) << "trial " << trial;
    rescued += report.refits >= 1;
    const UniformBspline& p = planned->position;
    for (int i = 0; i <= 4000; ++i) {
      const Vec3 q = p.position(p.duration() * i / 4000);
      if ((q - request.start).norm() <= planner.snap_radius) continue;
      ASSERT_GE(world.esdf().distance(q), optimizer.min_clearance - 1e-9) << "trial " << trial << " at " << q.transpose();
    }
    if (!planned->partial) {  // else it ends `horizon` along the path
      EXPECT_LT((p.position(p.duration()) - request.target).norm(), 0.5 * std::sqrt(3.0) * kRes + 1e-9) << "trial " << trial;
    }
  }
  EXPECT_EQ(rescued, 12);
}

// Two known rooms with unseen space between: no path through known space, so the trajectory goes
// towards the target, to the search's nearest point (partial, the goal kept, known flyable space
// throughout); with min_progress above what that gains, the plan fails with the search's status.
// Two known-free rooms, x in [0, 4] m and [5, 8] m, with unknown space between them.
void twoRooms(World& world) {
  world.setFree(Index3(0, 0, 0), Index3(39, 39, 19));
  world.setFree(Index3(50, 0, 0), Index3(79, 39, 19));
  world.sync();
}

// The flight search's settings: known space only, its surroundings known 0.3 m out.
AstarConfig flightAstarConfig() {
  AstarConfig c;
  c.unknown_is_free = false;
  c.known_clearance = true;
  c.clearance = 0.3;
  return c;
}

TEST(TrajectoryPlanner, WithoutAKnownPathItFliesTowardsTheTarget) {
  World world(Vec3(8, 4, 2));
  twoRooms(world);
  const Astar astar(world.occupancy(), world.esdf(), flightAstarConfig());
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  traj::PlanRequest request;
  request.start = Vec3(1.0, 2.0, 1.0);
  request.target = Vec3(7.0, 2.0, 1.0);
  traj::PlanReport report;
  const auto planned = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_TRUE(planned) << planned.message();
  EXPECT_TRUE(report.toward);
  EXPECT_EQ(report.path_status, PathStatus::kNoPath);
  EXPECT_TRUE(planned->partial);
  EXPECT_LT((planned->goal - request.target).norm(), 1e-12);
  const Vec3 end = planned->position.position(planned->duration());
  EXPECT_GT(end.x(), 3.0);  // at the first room's far side
  EXPECT_LT(end.x(), 3.7);
  const double res = world.geo().resolution();
  EXPECT_TRUE(traj::staysFlyable(planned->position, astar, optimizer.min_clearance - 0.5 * std::sqrt(3.0) * res,
                                 planner.snap_radius));
  planner.min_progress = 3.0;  // more than the 2.6 m it gains
  const auto refused = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.message().find("no_path"), std::string::npos) << refused.message();
  EXPECT_FALSE(report.toward);
}

// Two known rooms whose only connection, a 1.5 m gap in the wall between them, nobody has seen: the flight
// search finds no path, and the target is too far past the wall for min_progress. The scout search (unknown
// space free) finds the way through the gap; its start in known flyable space is flown, facing along it.
TEST(TrajectoryPlanner, WithoutAKnownWayItScoutsAlongAWayThroughUnseenSpace) {
  auto rooms = [](World& world, bool gap_open) {
    world.setFree(Index3(0, 0, 0), Index3(29, 39, 19));   // room A: x 0-3 m
    world.setFree(Index3(40, 0, 0), Index3(79, 39, 19));  // room B: x 4-8 m
    world.addBox(Index3(30, 0, 0), Index3(39, gap_open ? 24 : 39, 19));  // the wall; y 2.5-4 m unseen if open
    world.sync();
  };
  World world(Vec3(8, 4, 2));
  rooms(world, true);
  const Astar astar(world.occupancy(), world.esdf(), flightAstarConfig());
  AstarConfig scout_config;
  scout_config.unknown_is_free = true;
  scout_config.known_clearance = false;
  scout_config.clearance = 0.3;
  const Astar scout(world.occupancy(), world.esdf(), scout_config);
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  planner.min_progress = 0.0;  // no flying towards the target through the wall's side
  traj::PlanRequest request;
  request.start = Vec3(1.0, 1.0, 1.0);
  request.target = Vec3(6.0, 1.0, 1.0);
  traj::PlanReport report;
  const auto blind = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_FALSE(blind);
  EXPECT_NE(blind.message().find("no_path"), std::string::npos) << blind.message();

  const auto planned = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report, nullptr, &scout);
  ASSERT_TRUE(planned) << planned.message();
  EXPECT_TRUE(report.scouted);
  EXPECT_FALSE(report.toward);  // not the search's nearest point: the scout's way
  EXPECT_TRUE(planned->partial);
  EXPECT_LT((planned->goal - request.target).norm(), 1e-12);
  const Vec3 end = planned->position.position(planned->duration());
  EXPECT_LT(end.x(), 3.0);  // still in room A, in known space ...
  EXPECT_GT(end.y(), 2.0);  // ... but at the gap, not at the wall straight ahead
  EXPECT_GT((end - request.start).norm(), planner.scout_min_length);
  const double res = world.geo().resolution();
  EXPECT_TRUE(traj::staysFlyable(planned->position, astar, optimizer.min_clearance - 0.5 * std::sqrt(3.0) * res,
                                 planner.snap_radius));
  // Facing the way on: the gap's middle is ahead.
  const double yaw = traj::sampleTrajectory(*planned, planned->duration() + planned->yaw.duration()).yaw;
  const Vec3 to_gap = Vec3(3.5, 3.25, 1.0) - end;
  EXPECT_GT(std::cos(yaw - std::atan2(to_gap.y(), to_gap.x())), 0.5) << "yaw " << yaw;
  // The known start of the way is every flyable piece of it, and no more.
  const PathResult way = scout.search(request.start, request.target, planner.snap_radius);
  ASSERT_EQ(way.status, PathStatus::kFound);
  const std::vector<Vec3> prefix = traj::flyablePrefix(way.path, astar);
  ASSERT_GE(prefix.size(), 2u);
  for (std::size_t i = 1; i < prefix.size(); ++i) EXPECT_TRUE(astar.segmentTraversable(prefix[i - 1], prefix[i]));
  EXPECT_FALSE(astar.segmentTraversable(prefix.back(), prefix.back() + (way.path.back() - prefix.back()).normalized() * res));

  planner.scout_min_length = 0.0;  // off
  EXPECT_FALSE(traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report, nullptr, &scout));
  planner.scout_min_length = 0.5;
  World closed(Vec3(8, 4, 2));  // no way at all: the plan fails as before
  rooms(closed, false);
  const Astar closed_astar(closed.occupancy(), closed.esdf(), flightAstarConfig());
  const Astar closed_scout(closed.occupancy(), closed.esdf(), scout_config);
  const auto none =
      traj::planTrajectory(request, closed_astar, closed.esdf(), optimizer, planner, &report, nullptr, &closed_scout);
  ASSERT_FALSE(none);
  EXPECT_FALSE(report.scouted);
  planner.scout_min_length = -1.0;
  EXPECT_NE(planner.validate().message().find("scout_min_length"), std::string::npos);
}

// A start inside a cup whose bottom faces the target: the way out and round is 13 m long, and the fine
// search's budget runs out flooding the cup. The coarse search (the flight search's rules on a 0.3 m lattice)
// finds the way round; it is flown whole, joined to the target's voxel off the lattice, within the limits,
// in flyable space, and no shorter than the exhaustive fine search's path. Without a coarse search, or with
// one that runs out as well, the plan fails with the fine search's status as before.
// A sample's heading lies in (-pi, pi], the reference the controller and a flight controller's bridge take,
// though the yaw spline may lie a turn or more away (a heading unwrapped from the one before), during the
// flight and after it.
TEST(TrajectoryPlanner, ASampledHeadingLiesWithinOneTurn) {
  traj::Trajectory t;
  t.position = UniformBspline(Eigen::MatrixXd::Zero(3, 4), 3, 0.5);
  for (const double heading : {2 * kPi + 0.3, -2 * kPi - 3.0, 5 * kPi - 1e-3, -3 * kPi + 1e-3}) {
    t.yaw = UniformBspline(Eigen::MatrixXd::Constant(1, 4, heading), 3, 0.5);
    for (const double at : {0.0, 0.3, 5.0}) {
      const traj::TrajectorySample s = traj::sampleTrajectory(t, at);
      EXPECT_TRUE(s.yaw > -kPi && s.yaw <= kPi) << heading << " at " << at << " s: " << s.yaw;
      EXPECT_NEAR(std::remainder(s.yaw - heading, 2 * kPi), 0.0, 1e-9) << heading << " at " << at << " s";
    }
  }
}

TEST(TrajectoryPlanner, AFlightSearchOverBudgetIsSearchedAgainOnTheCoarseLattice) {
  World world(Vec3(8, 8, 2));
  world.setFree(Index3(0, 0, 0), Index3(79, 79, 19));
  world.addBox(Index3(50, 10, 0), Index3(51, 70, 19));  // the cup's bottom, x 5.0-5.2 m
  world.addBox(Index3(20, 10, 0), Index3(51, 11, 19));  // its sides, y 1.0-1.2 m and 6.9-7.1 m
  world.addBox(Index3(20, 69, 0), Index3(51, 70, 19));
  world.sync();
  AstarConfig fine_config = flightAstarConfig();
  fine_config.max_expansions = 5000;
  const Astar astar(world.occupancy(), world.esdf(), fine_config);
  AstarConfig coarse_config = flightAstarConfig();
  coarse_config.stride = 3;
  coarse_config.max_expansions = 5000;
  const Astar coarse(world.occupancy(), world.esdf(), coarse_config);
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  planner.horizon = 0.0;  // the whole way
  traj::PlanRequest request;
  request.start = Vec3(4.05, 4.05, 1.05);
  request.target = Vec3(6.55, 4.05, 1.05);  // a voxel centre, 2.5 m from the start: off the start's lattice
  traj::PlanReport report;
  const auto fine_only = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_FALSE(fine_only);
  EXPECT_NE(fine_only.message().find("budget_exceeded"), std::string::npos) << fine_only.message();
  EXPECT_FALSE(report.coarse);

  const auto planned =
      traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report, nullptr, nullptr, &coarse);
  ASSERT_TRUE(planned) << planned.message();
  EXPECT_TRUE(report.coarse);
  EXPECT_EQ(report.path_status, PathStatus::kFound);
  EXPECT_GT(report.path_expansions, fine_config.max_expansions);  // both searches counted
  EXPECT_FALSE(planned->partial);
  const Vec3 end = planned->position.position(planned->duration());
  EXPECT_LT((end - request.target).norm(), 0.05) << end.transpose();
  AstarConfig exhaustive_config = flightAstarConfig();
  exhaustive_config.max_expansions = 5000000;
  const Astar exhaustive(world.occupancy(), world.esdf(), exhaustive_config);
  const PathResult shortest = exhaustive.search(request.start, request.target, planner.snap_radius);
  ASSERT_EQ(shortest.status, PathStatus::kFound);
  EXPECT_GT(shortest.expansions, fine_config.max_expansions);
  EXPECT_GE(report.path_length, shortest.length - 1e-9);
  EXPECT_LE(report.path_length, 1.2 * shortest.length);
  const double res = world.geo().resolution();
  EXPECT_TRUE(traj::staysFlyable(planned->position, astar, optimizer.min_clearance - 0.5 * std::sqrt(3.0) * res,
                                 planner.snap_radius));
  EXPECT_TRUE(traj::checkTrajectory(planned->position, world.esdf(), optimizer).ok());
  for (int i = 0; i <= 400; ++i) {  // never through the cup
    const Vec3 p = planned->position.position(planned->duration() * i / 400.0);
    EXPECT_GT(world.boxDistance(p), optimizer.min_clearance - 1e-6) << p.transpose();
  }

  planner.coarse_retry = false;  // switched off: as without a coarse search
  const auto off =
      traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report, nullptr, nullptr, &coarse);
  ASSERT_FALSE(off);
  EXPECT_NE(off.message().find("budget_exceeded"), std::string::npos) << off.message();
  EXPECT_EQ(off.message().find("coarse"), std::string::npos) << off.message();
  EXPECT_FALSE(report.coarse);
  planner.coarse_retry = true;

  coarse_config.max_expansions = 50;
  const Astar starved(world.occupancy(), world.esdf(), coarse_config);
  const auto neither =
      traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report, nullptr, nullptr, &starved);
  ASSERT_FALSE(neither);
  EXPECT_NE(neither.message().find("budget_exceeded (coarse search: budget_exceeded)"), std::string::npos)
      << neither.message();
  EXPECT_FALSE(report.coarse);
}

// A way through unseen space that flying its known start does not bring into view (here the map never
// changes, as when the camera cannot see the gap from where the scouts end): the target is scouted
// max_scouts times, and the next scout counts a failed attempt instead of being flown. Plans that are not
// scouts do not count; 0 means no limit. (Resetting the count with each new target is the callers' part.)
// Two rooms mapped free, a wall between with a gap at y 2.5-4 m that stays unseen, and a scout search
// (unknown space free) beside the flight search.
struct UnseenGap {
  UnseenGap() : world(Vec3(8, 4, 2)), astar(mapped(world).occupancy(), world.esdf(), flightAstarConfig()),
                scout(world.occupancy(), world.esdf(), scoutConfig()) {}
  static World& mapped(World& w) {
    w.setFree(Index3(0, 0, 0), Index3(29, 39, 19));
    w.setFree(Index3(40, 0, 0), Index3(79, 39, 19));
    w.addBox(Index3(30, 0, 0), Index3(39, 24, 19));
    w.sync();
    return w;
  }
  static AstarConfig scoutConfig() {
    AstarConfig c;
    c.unknown_is_free = true;
    c.clearance = 0.3;
    return c;
  }
  World world;
  Astar astar, scout;
};

TEST(TrajectoryPlanner, ATargetScoutedTooOftenCountsAFailedAttempt) {
  UnseenGap gap;
  const World& world = gap.world;
  const Astar& astar = gap.astar;
  const Astar& scout = gap.scout;
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  planner.min_progress = 0.0;
  ASSERT_EQ(planner.max_scouts, 5);
  traj::PlanRequest request;
  request.start = Vec3(1.0, 1.0, 1.0);
  request.target = Vec3(6.0, 1.0, 1.0);
  int scouts = 0;
  for (int i = 1; i <= planner.max_scouts + 1; ++i) {
    traj::PlanReport report;
    const auto planned = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report, nullptr, &scout);
    ASSERT_TRUE(planned) << planned.message();
    ASSERT_TRUE(report.scouted);
    EXPECT_EQ(traj::scoutedTooOften(report, planner, &scouts), i > planner.max_scouts) << "scout " << i;
    EXPECT_EQ(scouts, i);  // the same way each time, as for a vehicle flown back and forth along it
  }
  // A plan through known space (the target in room A) is no scout and changes nothing.
  traj::PlanRequest inside = request;
  inside.target = Vec3(1.0, 1.0, 1.0);
  traj::PlanReport known;
  ASSERT_TRUE(traj::planTrajectory(inside, astar, world.esdf(), optimizer, planner, &known, nullptr, &scout));
  EXPECT_FALSE(known.scouted);
  int before = scouts;
  EXPECT_FALSE(traj::scoutedTooOften(known, planner, &before));
  EXPECT_EQ(before, scouts);
  // No limit.
  traj::TrajectoryPlannerConfig unlimited = planner;
  unlimited.max_scouts = 0;
  traj::PlanReport scouted;
  scouted.scouted = true;
  int many = 1000;
  EXPECT_FALSE(traj::scoutedTooOften(scouted, unlimited, &many));
  EXPECT_TRUE(unlimited.validate().ok());
  unlimited.max_scouts = -1;
  EXPECT_NE(unlimited.validate().message().find("max_scouts"), std::string::npos);
}

// Two rooms mapped free with an unseen gap between, and a request from the first to the second: no way
// through known space, nor a known start of one, nor (min_progress 0) flying towards the target.
struct NoWayBetweenRooms {
  NoWayBetweenRooms() : world(Vec3(8, 4, 2)), astar(mapped(world).occupancy(), world.esdf(), flightAstarConfig()) {
    planner.min_progress = 0.0;  // no flying towards: the room's far side is a plain failure
    planner.failed_search_memory = 3.0;
    request.start = Vec3(1.0, 2.0, 1.0);
    request.target = Vec3(7.0, 2.0, 1.0);
    request.time = 10.0;
  }
  static World& mapped(World& w) {
    twoRooms(w);
    return w;
  }
  World world;
  Astar astar;
  OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  traj::SearchMemory memory;
  traj::PlanRequest request;
};

// A search that found no path is remembered: the same request (start within snap_radius, goal within
// goal_tolerance) within failed_search_memory fails at once with the same status and expansions (so
// startEnclosed() judges it the same); another goal, a later time or no memory searches again, and a
// toward trajectory is not a failure to remember.
TEST(TrajectoryPlanner, FailedSearchesAreRememberedForAWhile) {
  NoWayBetweenRooms rooms;
  const World& world = rooms.world;
  const Astar& astar = rooms.astar;
  const OptimizerConfig& optimizer = rooms.optimizer;
  traj::TrajectoryPlannerConfig& planner = rooms.planner;
  traj::SearchMemory& memory = rooms.memory;
  const traj::PlanRequest request = rooms.request;
  auto plan = [&](const traj::PlanRequest& r, traj::SearchMemory* m, traj::PlanReport& report) {
    return traj::planTrajectory(r, astar, world.esdf(), optimizer, planner, &report, m);
  };
  traj::PlanReport first;
  ASSERT_FALSE(plan(request, &memory, first));
  EXPECT_FALSE(first.remembered);
  EXPECT_EQ(first.path_status, PathStatus::kNoPath);
  EXPECT_GT(first.path_expansions, 1000);
  EXPECT_EQ(memory.size(), 1u);

  traj::PlanRequest again = request;
  again.start += Vec3(0.5, 0.3, 0.0);
  again.target += Vec3(0.0, 0.2, 0.0);
  again.time = 12.0;
  traj::PlanReport second;
  const auto recalled = plan(again, &memory, second);
  ASSERT_FALSE(recalled);
  EXPECT_TRUE(second.remembered);
  EXPECT_EQ(second.path_status, first.path_status);
  EXPECT_EQ(second.path_expansions, first.path_expansions);
  EXPECT_EQ(traj::startEnclosed(second, planner, world.geo().resolution()),
            traj::startEnclosed(first, planner, world.geo().resolution()));
  EXPECT_NE(recalled.message().find("no_path"), std::string::npos) << recalled.message();

  traj::PlanReport other;
  traj::PlanRequest elsewhere = again;
  elsewhere.target = Vec3(7.0, 1.0, 1.0);  // 1 m from the remembered goal
  EXPECT_FALSE(plan(elsewhere, &memory, other));
  EXPECT_FALSE(other.remembered);
  traj::PlanReport unmemorised;
  EXPECT_FALSE(plan(again, nullptr, unmemorised));
  EXPECT_FALSE(unmemorised.remembered);
  traj::PlanReport later;
  again.time = 13.5;  // 3.5 s after the first failure
  EXPECT_FALSE(plan(again, &memory, later));
  EXPECT_FALSE(later.remembered);
  EXPECT_GT(later.path_expansions, 1000);

  // Flying towards the target is not a failure: nothing is remembered.
  planner.min_progress = 1.5;
  traj::SearchMemory fresh;
  traj::PlanReport toward;
  ASSERT_TRUE(plan(request, &fresh, toward));
  EXPECT_TRUE(toward.toward);
  EXPECT_EQ(fresh.size(), 0u);
  planner.failed_search_memory = -1.0;
  EXPECT_NE(planner.validate().message().find("failed_search_memory"), std::string::npos);
  // A timed-fit knot span of 1e-9 s overflowed its knot count (an int) on any path.
  traj::TrajectoryPlannerConfig fine;
  fine.profile_knot_span = 1e-9;
  EXPECT_NE(fine.validate().message().find("profile_knot_span must be in [0.005, 1] s"), std::string::npos)
      << fine.validate().message();
  fine.profile_knot_span = 0.005;
  EXPECT_TRUE(fine.validate().ok()) << fine.validate().message();
}

// staysFlyable(): a spline through mapped free space passes; the same spline fails once a voxel it
// crosses is unknown or has an unknown voxel within min_distance, or lies within min_distance of the
// box's faces or of a mapped obstacle, except within exempt_radius of its start.
TEST(TrajectoryPlanner, StaysFlyableFollowsTheSearchRulesWithTheGivenClearance) {
  World world(Vec3(6, 4, 3));
  const Index3 dims = world.geo().dims();
  world.setFree(Index3::Zero(), dims - Index3::Ones());
  world.sync();
  AstarConfig config;
  config.unknown_is_free = false;
  config.known_clearance = true;
  config.clearance = 0.3;
  const Astar astar(world.occupancy(), world.esdf(), config);
  std::vector<Vec3> line;
  for (int i = 0; i <= 10; ++i) line.push_back(Vec3(1.0 + 0.4 * i, 2.0, 1.5));
  const UniformBspline spline = UniformBspline::fitPath(line, 0.3, Vec3::Zero(), Vec3::Zero());
  EXPECT_TRUE(traj::staysFlyable(spline, astar, 0.2, 0.5));
  // Free space but for the voxel of `unknown`.
  auto freeBut = [&](World& w, const Vec3& unknown) {
    w.setFree(Index3::Zero(), dims - Index3::Ones());
    w.setUnknown(w.geo().coordToIndex(unknown));
    w.sync();
  };
  // An unknown voxel on the way.
  World holed(Vec3(6, 4, 3));
  freeBut(holed, Vec3(3.0, 2.0, 1.5));
  const Astar holed_astar(holed.occupancy(), holed.esdf(), config);
  EXPECT_FALSE(traj::staysFlyable(spline, holed_astar, 0.2, 0.5));
  // Along the top face: 0.65 m below it passes with 0.6 m of clearance, not with 0.8 m.
  std::vector<Vec3> high = line;
  for (Vec3& p : high) p.z() = 2.3;
  const UniformBspline high_spline = UniformBspline::fitPath(high, 0.3, Vec3::Zero(), Vec3::Zero());
  EXPECT_TRUE(traj::staysFlyable(high_spline, astar, 0.6, 0.5));
  EXPECT_FALSE(traj::staysFlyable(high_spline, astar, 0.8, 0.5));
  // Near a mapped obstacle: within exempt_radius of the start it is allowed, farther out it is not.
  World walled(Vec3(6, 4, 3));
  walled.setFree(Index3::Zero(), dims - Index3::Ones());
  walled.addBox(Index3(26, 15, 10), Index3(28, 25, 20));
  walled.sync();
  const Astar walled_astar(walled.occupancy(), walled.esdf(), config);
  std::vector<Vec3> away, towards;
  for (int i = 0; i <= 6; ++i) away.push_back(Vec3(3.0 + 0.2 * i, 2.0, 1.5));
  towards.assign(away.rbegin(), away.rend());
  const UniformBspline away_spline = UniformBspline::fitPath(away, 0.2, Vec3::Zero(), Vec3::Zero());
  EXPECT_TRUE(traj::staysFlyable(away_spline, walled_astar, 0.25, 0.3));
  EXPECT_FALSE(traj::staysFlyable(away_spline, walled_astar, 0.25, 0.0));
  EXPECT_FALSE(traj::staysFlyable(UniformBspline::fitPath(towards, 0.2, Vec3::Zero(), Vec3::Zero()), walled_astar, 0.25, 0.3));
  // Unknown space within the exempt radius is allowed too, not at the end: a hop that ends in the unseen voxel
  // is refused however near its start (a known voxel there instead lets it through).
  EXPECT_TRUE(traj::staysFlyable(spline, holed_astar, 0.2, 2.5));
  std::vector<Vec3> into;
  for (int i = 0; i <= 6; ++i) into.push_back(Vec3(2.45 + 0.1 * i, 2.05, 1.55));
  const UniformBspline hop = UniformBspline::fitPath(into, 0.3, Vec3::Zero(), Vec3::Zero());
  ASSERT_EQ(holed.geo().coordToIndex(hop.value(hop.duration())), holed.geo().coordToIndex(Vec3(3.0, 2.0, 1.5)));
  EXPECT_FALSE(traj::staysFlyable(hop, holed_astar, 0.2, 2.5));
  EXPECT_TRUE(traj::staysFlyable(hop, astar, 0.2, 2.5));
  // An unknown voxel beside the way, 0.1 m off the curve: within min_distance it fails (an obstacle
  // there, unseen, would be that close), with a smaller min_distance it passes.
  World beside(Vec3(6, 4, 3));
  freeBut(beside, Vec3(3.05, 2.15, 1.55));
  const Astar beside_astar(beside.occupancy(), beside.esdf(), config);
  EXPECT_FALSE(traj::staysFlyable(spline, beside_astar, 0.2, 0.5));
  EXPECT_TRUE(traj::staysFlyable(spline, beside_astar, 0.09, 0.5));
  // Where it failed for unseen space alone, it says where: a sample within min_distance (plus the
  // sample's offset in its voxel) of the unseen voxel; an obstacle or the box's face is not unseen space.
  std::optional<Vec3> unseen_at;
  EXPECT_FALSE(traj::staysFlyable(spline, beside_astar, 0.2, 0.5, &unseen_at));
  ASSERT_TRUE(unseen_at.has_value());
  EXPECT_LT((*unseen_at - beside.geo().indexToCoord(beside.geo().coordToIndex(Vec3(3.05, 2.15, 1.55)))).norm(),
            0.2 + 0.5 * std::sqrt(3.0) * 0.1);
  EXPECT_FALSE(traj::staysFlyable(spline, holed_astar, 0.2, 0.5, &unseen_at));
  ASSERT_TRUE(unseen_at.has_value());
  EXPECT_LT((*unseen_at - holed.geo().indexToCoord(holed.geo().coordToIndex(Vec3(3.0, 2.0, 1.5)))).norm(),
            0.2 + 0.5 * std::sqrt(3.0) * 0.1);
  EXPECT_LT(unseen_at->x(), 3.0);  // the first refused sample, before the hole
  EXPECT_TRUE(traj::staysFlyable(spline, beside_astar, 0.09, 0.5, &unseen_at));
  EXPECT_FALSE(unseen_at.has_value());
  EXPECT_FALSE(traj::staysFlyable(high_spline, astar, 0.8, 0.5, &unseen_at));
  EXPECT_FALSE(unseen_at.has_value());
  EXPECT_FALSE(traj::staysFlyable(away_spline, walled_astar, 0.25, 0.0, &unseen_at));
  EXPECT_FALSE(unseen_at.has_value());
}

// Every voxel mapped free but `unseen`, when given.
void mapFreeBut(World& world, const std::optional<Vec3>& unseen) {
  world.setFree(Index3::Zero(), world.geo().dims() - Index3::Ones());
  if (unseen) world.setUnknown(world.geo().coordToIndex(*unseen));
  world.sync();
}

// The flight search checks the known surroundings of a voxel 0.3 m out along each axis, the flight check
// every voxel within min_clearance: one unseen voxel right beside a straight way (the vehicle stopped
// mid-turn and never looked there) lets the search through and refuses every spline along it. Without
// the search again that keeps it away (planner unseen_retry, next test), the plan fails and says where;
// the vehicle turns to look there (once the heading is more than look_tolerance
// off it) instead of failing the frontier, and with that voxel seen the same plan succeeds.
TEST(TrajectoryPlanner, AWayRefusedForUnseenSpaceBesideItLooksThere) {
  const Vec3 unseen(3.05, 2.15, 1.05);  // beside the way's voxels at y 2.05
  auto corridor = [&](World& world, bool seen) { mapFreeBut(world, seen ? std::nullopt : std::optional<Vec3>(unseen)); };
  World world(Vec3(6, 4, 2));
  corridor(world, false);
  const Astar astar(world.occupancy(), world.esdf(), flightAstarConfig());
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  planner.unseen_retry = false;  // no search again keeping it away (see the next test)
  traj::PlanRequest request;
  request.start = Vec3(1.05, 2.05, 1.05);
  request.target = Vec3(5.05, 2.05, 1.05);
  request.yaw = kPi / 2;  // facing +y: the way (+x) is off to the right
  const PathResult path = astar.search(request.start, request.target, planner.snap_radius);
  ASSERT_EQ(path.status, PathStatus::kFound);  // the search lets it through
  traj::PlanReport report;
  const auto refused = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.message().find("leaves known flyable space"), std::string::npos) << refused.message();
  ASSERT_TRUE(report.unseen_at.has_value());
  EXPECT_LT((*report.unseen_at - unseen).norm(), 0.3);
  // A 3 m way (under fine_spans x path_spacing, 3.6 m) is also optimised with finer spans: that optimum must
  // keep out of the unseen pocket too, or it would be flown past it.
  {
    traj::TrajectoryPlannerConfig short_way = planner;
    short_way.profile_acceleration = 0.0;  // no timed fit flown as it is: the optimisations decide
    traj::PlanRequest hop = request;
    hop.start = Vec3(1.55, 2.05, 1.05);
    hop.target = Vec3(4.55, 2.05, 1.05);
    ASSERT_LT((hop.target - hop.start).norm(), short_way.fine_spans * short_way.path_spacing);
    traj::PlanReport hop_report;
    const auto hop_refused = traj::planTrajectory(hop, astar, world.esdf(), optimizer, short_way, &hop_report);
    ASSERT_FALSE(hop_refused);
    EXPECT_NE(hop_refused.message().find("leaves known flyable space"), std::string::npos) << hop_refused.message();
    EXPECT_FALSE(hop_report.fine);
  }

  // Look there: brake, hold still and turn to face it; the target is retried when the turn is nearly done.
  const auto look = traj::lookAtUnseen(request, report, planner, optimizer);
  ASSERT_TRUE(look.has_value());
  EXPECT_TRUE(look->partial);
  EXPECT_LT((look->goal - request.target).norm(), 1e-12);
  EXPECT_GE(look->duration(), look->yaw.duration() - 1e-9);
  for (int i = 0; i <= 50; ++i)
    EXPECT_LT((traj::sampleTrajectory(*look, look->duration() * i / 50).position - request.start).norm(), 1e-9);
  const Vec3 to = *report.unseen_at - request.start;
  EXPECT_NEAR(std::remainder(traj::sampleTrajectory(*look, look->duration()).yaw - std::atan2(to.y(), to.x()), 2 * kPi),
              0.0, 1e-9);
  // Already facing it: a look cannot mend the way, and the failure counts.
  traj::PlanRequest facing = request;
  facing.yaw = std::atan2(to.y(), to.x()) + 0.9 * planner.look_tolerance;
  EXPECT_FALSE(traj::lookAtUnseen(facing, report, planner, optimizer).has_value());
  facing.yaw = std::atan2(to.y(), to.x()) - 1.1 * planner.look_tolerance;
  EXPECT_TRUE(traj::lookAtUnseen(facing, report, planner, optimizer).has_value());
  // Steeply above or below: turning does not bring it into view.
  traj::PlanReport steep = report;
  steep.unseen_at = request.start + Vec3(0.0, -0.3, 0.5);
  EXPECT_FALSE(traj::lookAtUnseen(request, steep, planner, optimizer).has_value());
  // No unseen point (another failure), or looking switched off.
  traj::PlanReport other;
  EXPECT_FALSE(traj::lookAtUnseen(request, other, planner, optimizer).has_value());
  traj::TrajectoryPlannerConfig off = planner;
  off.look_tolerance = 0.0;
  EXPECT_FALSE(traj::lookAtUnseen(request, report, off, optimizer).has_value());
  off.look_tolerance = 4.0;
  EXPECT_NE(off.validate().message().find("look_tolerance"), std::string::npos);
  off.look_tolerance = -0.1;
  EXPECT_NE(off.validate().message().find("look_tolerance"), std::string::npos);

  // With the voxel seen (what the look brings), the same plan succeeds.
  World seen(Vec3(6, 4, 2));
  corridor(seen, true);
  const Astar seen_astar(seen.occupancy(), seen.esdf(), flightAstarConfig());
  const auto planned = traj::planTrajectory(request, seen_astar, seen.esdf(), optimizer, planner, &report);
  ASSERT_TRUE(planned) << planned.message();
  EXPECT_FALSE(report.unseen_at.has_value());
}

// The same way, with the retry on (planner unseen_retry, the default): every spline along the first path
// is refused for the pocket beside it, so the way is searched again keeping unseen space as far away all
// round as the check looks (flyableClearance()); that path passes the pocket at a distance and is flown,
// with nothing to look at. A dead end whose only way out passed such a pocket, never seen from inside,
// failed every plan out of it and blacklisted frontier after frontier (maze seed 26).
TEST(TrajectoryPlanner, AWayRefusedForUnseenSpaceBesideItIsSearchedAgainKeepingItAway) {
  const Vec3 pocket(3.05, 2.15, 1.05);
  World world(Vec3(6, 4, 2));
  mapFreeBut(world, pocket);
  const OptimizerConfig optimizer = optimizerConfig();
  const double res = world.geo().resolution();
  const double check = traj::flyableClearance(optimizer, res);
  EXPECT_NEAR(check, optimizer.min_clearance - 0.5 * std::sqrt(3.0) * res, 1e-12);
  const Astar astar(world.occupancy(), world.esdf(), flightAstarConfig());
  traj::TrajectoryPlannerConfig planner;
  ASSERT_TRUE(planner.unseen_retry);
  traj::PlanRequest request;
  request.start = Vec3(1.05, 2.05, 1.05);
  request.target = Vec3(5.05, 2.05, 1.05);
  request.yaw = kPi / 2;
  traj::PlanReport report;
  const auto planned = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_TRUE(planned) << planned.message();
  EXPECT_TRUE(report.widened);
  EXPECT_GT(report.left_flyable, 0);  // the first path's splines were refused
  EXPECT_FALSE(report.unseen_at.has_value());
  EXPECT_FALSE(planned->partial);
  EXPECT_LT((planned->goal - request.target).norm(), 1e-12);
  // The curve keeps the pocket farther than the check's radius, and passes the check (from the start).
  for (int i = 0; i <= 400; ++i)
    EXPECT_GT((planned->position.position(planned->duration() * i / 400) - pocket).norm(), check);
  EXPECT_TRUE(traj::staysFlyable(planned->position, astar, check, 0.0));
  // The search that looks all round finds that path at once.
  AstarConfig wide = flightAstarConfig();
  wide.known_radius = check;
  const Astar wide_astar(world.occupancy(), world.esdf(), wide);
  traj::PlanReport direct;
  ASSERT_TRUE(traj::planTrajectory(request, wide_astar, world.esdf(), optimizer, planner, &direct));
  EXPECT_FALSE(direct.widened);
  EXPECT_EQ(direct.left_flyable, 0);
  // A replan to a target whose plan was widened asks for the wide search from the start
  // (PlanRequest::widen): no refused first path, and the same clearance from the pocket.
  traj::PlanRequest replan = request;
  replan.widen = true;
  const auto again = traj::planTrajectory(replan, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_TRUE(again) << again.message();
  EXPECT_TRUE(report.widened);
  EXPECT_EQ(report.left_flyable, 0);
  for (int i = 0; i <= 400; ++i)
    EXPECT_GT((again->position.position(again->duration() * i / 400) - pocket).norm(), check);
  // With the retry off the failure stands (and says where, for a look there), asked to widen or not.
  planner.unseen_retry = false;
  EXPECT_FALSE(traj::planTrajectory(replan, astar, world.esdf(), optimizer, planner, &report));
  EXPECT_FALSE(report.widened);
  const auto refused = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_FALSE(refused);
  EXPECT_FALSE(report.widened);
  EXPECT_TRUE(report.unseen_at.has_value());
}

// A refit samples the path at half the spacing that failed, down to half a voxel; a short hop that started
// finer than that keeps its spacing. It used to be raised to half a voxel, so that a 0.25 m hop (6 spans of
// 4.2 cm) was refitted with 5 samples, fewer than the optimiser's 7 control points need.
TEST(TrajectoryPlanner, ARefitNeverSamplesThePathMoreCoarsely) {
  const double res = 0.1;
  EXPECT_DOUBLE_EQ(traj::refitSpacing(0.3, res), 0.15);
  EXPECT_DOUBLE_EQ(traj::refitSpacing(0.08, res), 0.05);  // half of it would be finer than half a voxel
  EXPECT_DOUBLE_EQ(traj::refitSpacing(0.05, res), 0.05);
  EXPECT_DOUBLE_EQ(traj::refitSpacing(0.25 / 6.0, res), 0.25 / 6.0);
  for (double spacing = 0.001; spacing < 1.0; spacing *= 1.1) {
    const double next = traj::refitSpacing(spacing, res);
    EXPECT_LE(next, spacing) << spacing;
    EXPECT_GE(next, 0.5 * spacing) << spacing;
    EXPECT_GE(next, std::min(spacing, 0.5 * res) - 1e-15) << spacing;
  }
  // What that means for the samples of a 0.25 m hop: never fewer than its first fit's 7.
  const std::vector<Vec3> hop{Vec3(1.0, 1.0, 1.0), Vec3(1.25, 1.0, 1.0)};
  double spacing = 0.25 / 6.0;
  std::size_t samples = traj::UniformBspline::resamplePolyline(hop, spacing).size();
  ASSERT_GE(samples, 7u);
  for (int refit = 0; refit < 4; ++refit) {
    spacing = traj::refitSpacing(spacing, res);
    const std::size_t now = traj::UniformBspline::resamplePolyline(hop, spacing).size();
    EXPECT_GE(now, samples) << "refit " << refit;
    samples = now;
  }
}

// A flight search whose clearance (0.12 m) is below the check's radius (0.25 m less half a voxel
// diagonal: 0.163 m, which takes in the diagonal neighbours) cannot be widened to the check: the retry's
// search keeps unseen space 0.12 m away all round, which leaves out a pocket diagonal to the way, so it
// finds the same way and every spline along it is refused again. The retry is then not tried at all
// (once widened, the search does not look farther): the plan fails and says where. It used to retry
// the same search from inside the retry, without end, until the stack ran out.
TEST(TrajectoryPlanner, ARetryThatCannotLookFartherIsNotRepeated) {
  const Vec3 pocket(3.15, 2.15, 1.05);  // diagonal to the way's voxels at y 2.05
  World world(Vec3(6, 4, 2));
  mapFreeBut(world, pocket);
  OptimizerConfig optimizer = optimizerConfig();
  optimizer.min_clearance = 0.25;
  const double res = world.geo().resolution();
  const double check = traj::flyableClearance(optimizer, res);
  ASSERT_GT(check, std::sqrt(2.0) * res);  // the check looks at the diagonal neighbours
  AstarConfig narrow = flightAstarConfig();
  narrow.clearance = 0.12;
  ASSERT_TRUE(narrow.validate().ok()) << narrow.validate().message();
  ASSERT_LT(narrow.clearance, std::sqrt(2.0) * res);  // a search widened to it does not
  const Astar astar(world.occupancy(), world.esdf(), narrow);
  traj::TrajectoryPlannerConfig planner;
  ASSERT_TRUE(planner.unseen_retry);
  traj::PlanRequest request;
  request.start = Vec3(1.05, 2.05, 1.05);
  request.target = Vec3(5.05, 2.05, 1.05);
  request.yaw = 0.0;
  traj::PlanReport report;
  const auto planned = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_FALSE(planned);
  EXPECT_NE(planned.message().find("leaves known flyable space"), std::string::npos) << planned.message();
  ASSERT_TRUE(report.unseen_at.has_value());
  EXPECT_LT((*report.unseen_at - pocket).norm(), check + 0.5 * std::sqrt(3.0) * res);
  // Asked to widen from the start (a replan after a widened plan): one wide search, the same answer.
  request.widen = true;
  EXPECT_FALSE(traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report));
}

// planForTarget(), the one order the bench and the nodelet follow, carries what it learnt about a target
// from plan to plan in the caller's TargetAttempts: a widened plan makes the next one wide from the start,
// a look at unseen space is flown once, and one scout too many brakes and fails the target. A fresh record
// (a new target) starts over.
TEST(TrajectoryPlanner, PlansForATargetCarryItsWideningLookAndScoutsFromPlanToPlan) {
  const OptimizerConfig optimizer = optimizerConfig();
  auto atRest = [](const traj::Trajectory& t) {
    return traj::sampleTrajectory(t, t.duration()).velocity.norm() < 1e-6;
  };
  {
    // The pocket beside the straight way (as above): the first plan is widened after its splines were refused.
    World world(Vec3(6, 4, 2));
    mapFreeBut(world, Vec3(3.05, 2.15, 1.05));
    const Astar astar(world.occupancy(), world.esdf(), flightAstarConfig());
    const traj::TrajectoryPlannerConfig planner;
    traj::PlanRequest request;
    request.start = Vec3(1.05, 2.05, 1.05);
    request.target = Vec3(5.05, 2.05, 1.05);
    request.yaw = kPi / 2;
    traj::TargetAttempts attempts;
    traj::FlightStep first = traj::planForTarget(request, &attempts, astar, world.esdf(), optimizer, planner);
    ASSERT_EQ(first.outcome, traj::FlightOutcome::kFly) << first.failure;
    EXPECT_FALSE(first.failsTarget());
    EXPECT_TRUE(first.newly_widened);
    EXPECT_TRUE(first.report.widened);
    EXPECT_GT(first.report.left_flyable, 0);
    EXPECT_TRUE(attempts.widened);
    EXPECT_LT((first.trajectory.goal - request.target).norm(), 1e-12);
    // The next plan to it searches wide from the start: nothing refused, and not newly widened.
    traj::FlightStep next = traj::planForTarget(request, &attempts, astar, world.esdf(), optimizer, planner);
    ASSERT_EQ(next.outcome, traj::FlightOutcome::kFly) << next.failure;
    EXPECT_TRUE(next.report.widened);
    EXPECT_EQ(next.report.left_flyable, 0);
    EXPECT_FALSE(next.newly_widened);
    // A new target's record starts narrow again, whatever the request says.
    traj::TargetAttempts fresh;
    traj::PlanRequest asks = request;
    asks.widen = true;
    traj::FlightStep again = traj::planForTarget(asks, &fresh, astar, world.esdf(), optimizer, planner);
    ASSERT_EQ(again.outcome, traj::FlightOutcome::kFly) << again.failure;
    EXPECT_GT(again.report.left_flyable, 0);
    EXPECT_TRUE(again.newly_widened);
  }
  {
    // No way between two rooms (no scouting, no flying towards): the first failure looks towards the
    // target, the second fails the target and brakes where the vehicle is.
    NoWayBetweenRooms rooms;
    traj::PlanRequest request = rooms.request;
    request.yaw = kPi / 2;
    request.velocity = Vec3(0.5, 0.0, 0.0);
    traj::TargetAttempts attempts;
    traj::FlightStep look = traj::planForTarget(request, &attempts, rooms.astar, rooms.world.esdf(), rooms.optimizer,
                                                rooms.planner, &rooms.memory);
    EXPECT_EQ(look.outcome, traj::FlightOutcome::kLookAtUnseen);
    EXPECT_FALSE(look.failsTarget());
    EXPECT_TRUE(attempts.looked_at_unseen);
    EXPECT_NE(look.failure.find("no path"), std::string::npos) << look.failure;
    EXPECT_TRUE(look.trajectory.partial);
    EXPECT_TRUE(atRest(look.trajectory));
    traj::FlightStep fail = traj::planForTarget(request, &attempts, rooms.astar, rooms.world.esdf(), rooms.optimizer,
                                                rooms.planner, &rooms.memory);
    EXPECT_EQ(fail.outcome, traj::FlightOutcome::kFail);
    EXPECT_TRUE(fail.failsTarget());
    EXPECT_FALSE(fail.trajectory.partial);
    EXPECT_TRUE(atRest(fail.trajectory));
    // A new target may look again (once the failed search is forgotten: the memory answers without a point
    // to look at).
    traj::TargetAttempts fresh;
    traj::SearchMemory forgotten;
    EXPECT_EQ(traj::planForTarget(request, &fresh, rooms.astar, rooms.world.esdf(), rooms.optimizer, rooms.planner,
                                  &forgotten)
                  .outcome,
              traj::FlightOutcome::kLookAtUnseen);
  }
  {
    // A way through an unseen gap, scouted: flown max_scouts times, then one scout too many brakes instead.
    UnseenGap gap;
    traj::TrajectoryPlannerConfig planner;
    planner.min_progress = 0.0;
    traj::PlanRequest request;
    request.start = Vec3(1.0, 1.0, 1.0);
    request.target = Vec3(6.0, 1.0, 1.0);
    traj::TargetAttempts attempts;
    for (int i = 1; i <= planner.max_scouts; ++i) {
      traj::FlightStep step =
          traj::planForTarget(request, &attempts, gap.astar, gap.world.esdf(), optimizer, planner, nullptr, &gap.scout);
      ASSERT_EQ(step.outcome, traj::FlightOutcome::kFly) << "scout " << i << ": " << step.failure;
      EXPECT_TRUE(step.report.scouted);
      EXPECT_EQ(attempts.scouts, i);
    }
    traj::FlightStep too_many =
        traj::planForTarget(request, &attempts, gap.astar, gap.world.esdf(), optimizer, planner, nullptr, &gap.scout);
    EXPECT_EQ(too_many.outcome, traj::FlightOutcome::kScoutedTooOften);
    EXPECT_TRUE(too_many.failsTarget());
    EXPECT_TRUE(atRest(too_many.trajectory));
    EXPECT_LT((too_many.trajectory.goal - request.start).norm(), 1e-9);  // from rest: it stops where it is
  }
}

TEST(TrajectoryPlanner, NoFlyableSplineFromAMovingStartBrakesToPlanAgainFromRest) {
  // The way from (1, 2) to (5, 2) passes an unseen voxel: no spline along it stays in known flyable space.
  World world(Vec3(6, 4, 2));
  mapFreeBut(world, Vec3(3.05, 2.15, 1.05));
  const Astar astar(world.occupancy(), world.esdf(), flightAstarConfig());
  const OptimizerConfig optimizer = optimizerConfig();
  traj::TrajectoryPlannerConfig planner;
  planner.brake_speed = 0.3;
  planner.unseen_retry = false;  // the way is not searched again keeping the voxel away
  traj::PlanRequest request;
  request.start = Vec3(1.05, 2.05, 1.05);
  request.velocity = Vec3(-0.6, 0.8, 0.0);  // 1 m/s, away from the target and across the way
  request.yaw = kPi / 2;
  request.target = Vec3(5.05, 2.05, 1.05);
  request.target_yaw = -0.5;
  traj::PlanReport report;
  const auto braked = traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_TRUE(braked) << braked.message();
  EXPECT_TRUE(report.braked);
  EXPECT_TRUE(braked->partial);  // replanned as it ends
  EXPECT_LT((braked->goal - request.target).norm(), 1e-12);
  // Continuous with the reference, braking along its velocity within a_max to rest, turning to the target's heading.
  const traj::TrajectorySample first = traj::sampleTrajectory(*braked, 0.0);
  EXPECT_LT((first.position - request.start).norm(), 1e-9);
  EXPECT_LT((first.velocity - request.velocity).norm(), 1e-9);
  double v_max = 0.0, a_max = 0.0;
  finiteDifferenceDynamics(braked->position, 2000, v_max, a_max);
  EXPECT_LE(a_max, optimizer.a_max * 1.01);
  const traj::TrajectorySample last = traj::sampleTrajectory(*braked, braked->duration());
  EXPECT_LT(last.velocity.norm(), 1e-6);
  const double stopping = request.velocity.squaredNorm() / (2.0 * optimizer.a_max);
  EXPECT_LE((last.position - request.start).norm(), stopping * 1.05 + 1e-6);
  EXPECT_GT((last.position - request.start).dot(request.velocity), 0.0);
  EXPECT_NEAR(std::remainder(traj::sampleTrajectory(*braked, braked->yaw.duration()).yaw - request.target_yaw, 2 * kPi),
              0.0, 1e-9);

  // From rest there is nothing to brake: the failure stands (and counts), as it does with braking off or
  // from a start slower than brake_speed.
  traj::PlanRequest at_rest = request;
  at_rest.velocity.setZero();
  auto failed = traj::planTrajectory(at_rest, astar, world.esdf(), optimizer, planner, &report);
  ASSERT_FALSE(failed);
  EXPECT_FALSE(report.braked);
  EXPECT_NE(failed.message().find("leaves known flyable space"), std::string::npos) << failed.message();
  traj::PlanRequest slow = request;
  slow.velocity = request.velocity * 0.25;
  EXPECT_FALSE(traj::planTrajectory(slow, astar, world.esdf(), optimizer, planner, &report));
  traj::TrajectoryPlannerConfig off = planner;
  off.brake_speed = 0.0;
  failed = traj::planTrajectory(request, astar, world.esdf(), optimizer, off, &report);
  ASSERT_FALSE(failed);
  EXPECT_FALSE(report.braked);
  // Where the spline is flyable, braking is not needed: the moving start plans straight on.
  World seen(Vec3(6, 4, 2));
  mapFreeBut(seen, std::nullopt);
  const Astar seen_astar(seen.occupancy(), seen.esdf(), flightAstarConfig());
  const auto planned = traj::planTrajectory(request, seen_astar, seen.esdf(), optimizer, planner, &report);
  ASSERT_TRUE(planned) << planned.message();
  EXPECT_FALSE(report.braked);
  EXPECT_FALSE(planned->partial);
  off.brake_speed = -0.1;
  EXPECT_NE(off.validate().message().find("brake_speed"), std::string::npos);
}

TEST(TrajectoryPlanner, NoWayThroughKnownSpaceLooksTowardsTheTargetOnceAndSearchesAgain) {
  NoWayBetweenRooms rooms;
  const World& world = rooms.world;
  const Astar& astar = rooms.astar;
  const OptimizerConfig& optimizer = rooms.optimizer;
  const traj::TrajectoryPlannerConfig& planner = rooms.planner;
  traj::SearchMemory& memory = rooms.memory;
  traj::PlanRequest request = rooms.request;
  request.yaw = kPi / 2;  // facing +y; the target lies along +x
  traj::PlanReport report;
  ASSERT_FALSE(traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &report, &memory));
  EXPECT_EQ(report.path_status, PathStatus::kNoPath);
  ASSERT_TRUE(report.unseen_at.has_value());  // the way is through unseen space: towards the target
  EXPECT_LT((*report.unseen_at - request.target).norm(), 1e-12);
  EXPECT_EQ(memory.size(), 1u);
  // Asked again at once, the memory answers, without a point to look at.
  traj::PlanReport remembered;
  ASSERT_FALSE(traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &remembered, &memory));
  EXPECT_TRUE(remembered.remembered);
  EXPECT_FALSE(remembered.unseen_at.has_value());

  // The recovery turns to face the target once and forgets the failed search, so that the plan after the
  // look searches the map it shows; the next failure for that target counts.
  bool looked = false;
  traj::RecoveryPlan r = traj::recoverFromFailedPlan(request, report, planner, optimizer, 0.1, &looked, &memory);
  ASSERT_EQ(r.kind, traj::Recovery::kLookAtUnseen);
  EXPECT_TRUE(looked);
  EXPECT_NEAR(std::remainder(traj::sampleTrajectory(r.trajectory, r.trajectory.yaw.duration()).yaw, 2 * kPi), 0.0,
              1e-9);
  EXPECT_EQ(memory.size(), 0u);
  traj::PlanReport after;
  ASSERT_FALSE(traj::planTrajectory(request, astar, world.esdf(), optimizer, planner, &after, &memory));
  EXPECT_FALSE(after.remembered);
  EXPECT_EQ(traj::recoverFromFailedPlan(request, after, planner, optimizer, 0.1, &looked, &memory).kind,
            traj::Recovery::kFail);
  // Another request's memory is kept by a forget that does not match it.
  memory.forget(request.start + Vec3(2.0, 0.0, 0.0), request.target, planner);
  EXPECT_EQ(memory.size(), 1u);
  memory.forget(request.start + Vec3(0.5, 0.0, 0.0), request.target + Vec3(0.0, 0.2, 0.0), planner);
  EXPECT_EQ(memory.size(), 0u);
}

TEST(TrajectoryPlanner, FailedPlanRecoveryLooksAroundThenAtUnseenSpaceOnceThenFails) {
  const OptimizerConfig optimizer = optimizerConfig();
  const traj::TrajectoryPlannerConfig planner;
  const double resolution = 0.1;
  traj::PlanRequest request;
  request.start = Vec3(1.0, 2.0, 1.0);
  request.velocity = Vec3(0.6, 0.0, 0.0);
  request.target = Vec3(5.0, 2.0, 1.0);
  request.yaw = kPi / 2;
  traj::PlanReport report;
  report.path_status = PathStatus::kFound;
  report.unseen_at = Vec3(3.0, 2.1, 1.0);  // ahead along +x, the heading faces +y
  auto facesUnseen = [&](const traj::Trajectory& t) {
    const Vec3 to = *report.unseen_at - request.start;
    // The turn outlasts the braking: sample the end of the turn.
    const double yaw = traj::sampleTrajectory(t, std::max(t.duration(), t.yaw.duration())).yaw;
    return std::abs(std::remainder(yaw - std::atan2(to.y(), to.x()), 2 * kPi)) < 1e-6;
  };
  auto endsAtRest = [&](const traj::Trajectory& t) {
    return traj::sampleTrajectory(t, t.duration()).velocity.norm() < 1e-6;
  };

  // An enclosed start looks around whatever else the report says, and the look at unseen space stays unused.
  bool looked = false;
  traj::PlanReport enclosed = report;
  enclosed.path_status = PathStatus::kStartBlocked;
  traj::RecoveryPlan r = traj::recoverFromFailedPlan(request, enclosed, planner, optimizer, resolution, &looked);
  EXPECT_EQ(r.kind, traj::Recovery::kLookAround);
  EXPECT_FALSE(looked);
  EXPECT_TRUE(r.trajectory.partial);
  EXPECT_LT((r.trajectory.goal - request.target).norm(), 1e-12);
  EXPECT_TRUE(endsAtRest(r.trajectory));

  // A way refused for unseen space: look there, once per target.
  r = traj::recoverFromFailedPlan(request, report, planner, optimizer, resolution, &looked);
  EXPECT_EQ(r.kind, traj::Recovery::kLookAtUnseen);
  EXPECT_TRUE(looked);
  EXPECT_TRUE(r.trajectory.partial);
  EXPECT_TRUE(facesUnseen(r.trajectory));
  EXPECT_TRUE(endsAtRest(r.trajectory));

  // The second refusal for the same target counts: brake where the vehicle is, heading held.
  r = traj::recoverFromFailedPlan(request, report, planner, optimizer, resolution, &looked);
  EXPECT_EQ(r.kind, traj::Recovery::kFail);
  EXPECT_FALSE(r.trajectory.partial);
  EXPECT_TRUE(endsAtRest(r.trajectory));
  EXPECT_NEAR(traj::sampleTrajectory(r.trajectory, r.trajectory.duration()).yaw, request.yaw, 1e-9);
  // The stop goes on from the reference's velocity (no jump to rest) and brakes over v^2 / (2 a_max).
  EXPECT_LT((traj::sampleTrajectory(r.trajectory, 0.0).velocity - request.velocity).norm(), 1e-9);
  EXPECT_NEAR((r.trajectory.goal - request.start).x(), 0.36 / (2.0 * optimizer.a_max), 1e-3);

  // Any other failure counts at once, and leaves the flag alone.
  bool fresh = false;
  traj::PlanReport other;
  other.path_status = PathStatus::kFound;
  r = traj::recoverFromFailedPlan(request, other, planner, optimizer, resolution, &fresh);
  EXPECT_EQ(r.kind, traj::Recovery::kFail);
  EXPECT_FALSE(fresh);

  // A stop from a reference turning at 0.8 rad/s goes on at that rate and brings it to rest without turning
  // back, within yaw_acc_max (the heading held where the stop began stepped the rate to 0 at once).
  traj::PlanRequest turning = request;
  turning.yaw_rate = 0.8;
  r = traj::recoverFromFailedPlan(turning, other, planner, optimizer, resolution, &fresh);
  ASSERT_EQ(r.kind, traj::Recovery::kFail);
  EXPECT_NEAR(traj::sampleTrajectory(r.trajectory, 0.0).yaw_dot, 0.8, 1e-9);
  EXPECT_NEAR(traj::sampleTrajectory(r.trajectory, 0.0).yaw, turning.yaw, 1e-9);
  const double end = std::max(r.trajectory.duration(), r.trajectory.yaw.duration());
  double last = turning.yaw;
  for (double t = 0.0; t <= end + 0.2; t += 0.01) {
    const traj::TrajectorySample s = traj::sampleTrajectory(r.trajectory, t);
    EXPECT_GE(s.yaw_dot, -1e-9) << "turning back at " << t << " s";
    EXPECT_GE(std::remainder(s.yaw - last, 2 * kPi), -1e-9) << "at " << t << " s";
    last = s.yaw;
  }
  EXPECT_EQ(traj::sampleTrajectory(r.trajectory, end + 0.2).yaw_dot, 0.0);
  EXPECT_LE(r.trajectory.yaw.maxDerivativeNorm(2), optimizer.yaw_acc_max * (1.0 + 1e-9));
  EXPECT_LE(r.trajectory.yaw.maxDerivativeNorm(1), optimizer.yaw_rate_max * (1.0 + 1e-9));
}

}  // namespace
