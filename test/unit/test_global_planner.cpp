// Omission likelihood, NearCur_IDs selection and the global planner against brute force.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include "go_feap/planning/global_planner.h"
#include "go_feap/planning/omission.h"

using namespace go_feap::planning;
using go_feap::common::Vec3;

namespace {

OmissionConfig omissionConfig() {
  OmissionConfig c;
  c.alpha_max = 1.5;
  c.c_small = 20;
  c.w_t = 2.0;
  c.t_max = 10.0;
  c.n_t = 3.0;
  c.n_max = 4;
  return c;
}

std::vector<FrontierSummary> frontiersAtDistances(const std::vector<double>& d) {
  std::vector<FrontierSummary> f(d.size());
  for (std::size_t j = 0; j < d.size(); ++j) {
    f[j].id = static_cast<unsigned>(100 + j);
    f[j].average = Vec3(d[j], 0.0, 1.0);
  }
  return f;
}

}  // namespace

TEST(Omission, FactorEdges) {
  const OmissionConfig c = omissionConfig();
  struct Row {
    const char* what;
    double value, expected;
  };
  const double below = std::nextafter(c.t_max, 0.0);
  const Row rows[] = {
      {"alpha(0)", alpha(c, 0), 1.5},
      {"alpha(-3)", alpha(c, -3), 1.5},
      {"alpha(c_small)", alpha(c, 20), 1.5},
      {"alpha(2 c_small)", alpha(c, 40), 0.75},
      {"alpha(10 c_small)", alpha(c, 200), 0.15},
      {"omega(0)", omega(c, 0.0), 2.0},
      {"omega(just below t_max)", omega(c, below), 2.0},
      {"omega(t_max)", omega(c, c.t_max), 0.0},
      {"omega(2 t_max)", omega(c, 2.0 * c.t_max), 0.0},
      {"beta(0)", beta(c, 0), 0.0},
      {"beta(1)", beta(c, 1), 3.0},
      {"beta(n_max - 1)", beta(c, c.n_max - 1), 3.0},
      {"beta(n_max)", beta(c, c.n_max), 0.0},
      {"beta(n_max + 5)", beta(c, c.n_max + 5), 0.0},
      {"xi(small, young, grouped)", xi(c, 10, 1.0, 2), 1.5 * 2.0 * 3.0},
      {"xi(large, young, grouped)", xi(c, 40, 1.0, 2), 0.75 * 2.0 * 3.0},
      {"xi(old)", xi(c, 10, c.t_max, 2), 0.0},
      {"xi(alone)", xi(c, 10, 1.0, 0), 0.0},
      {"xi(crowded)", xi(c, 10, 1.0, c.n_max), 0.0},
  };
  for (const Row& r : rows) EXPECT_DOUBLE_EQ(r.value, r.expected) << r.what;
  // alpha never increases with size.
  for (int cells = 0; cells < 500; ++cells) EXPECT_GE(alpha(c, cells), alpha(c, cells + 1)) << cells;
}

TEST(Omission, ValidateNamesTheKey) {
  EXPECT_TRUE(OmissionConfig().validate().ok());
  EXPECT_TRUE(omissionConfig().validate().ok());
  struct Row {
    void (*spoil)(OmissionConfig&);
    const char* message;
  };
  const Row rows[] = {
      {[](OmissionConfig& c) { c.alpha_max = -1.0; }, "omission: alpha_max must be >= 0"},
      {[](OmissionConfig& c) { c.alpha_max = std::nan(""); }, "omission: alpha_max must be >= 0"},
      {[](OmissionConfig& c) { c.c_small = 0; }, "omission: c_small must be > 0"},
      {[](OmissionConfig& c) { c.w_t = -0.1; }, "omission: w_t must be >= 0"},
      {[](OmissionConfig& c) { c.t_max = 0.0; }, "omission: t_max must be > 0"},
      {[](OmissionConfig& c) { c.n_t = std::numeric_limits<double>::infinity(); },
       "omission: n_t must be >= 0"},
      {[](OmissionConfig& c) { c.n_t = -1.0; }, "omission: n_t must be >= 0"},
      {[](OmissionConfig& c) { c.n_max = 1; }, "omission: n_max must be > 1"},
  };
  for (const Row& r : rows) {
    OmissionConfig c;
    r.spoil(c);
    EXPECT_EQ(c.validate().message(), r.message);
  }
}

TEST(GlobalPlannerConfig, ValidateNamesTheKey) {
  EXPECT_TRUE(GlobalPlannerConfig().validate().ok());
  struct Row {
    void (*spoil)(GlobalPlannerConfig&);
    const char* message;
  };
  const Row rows[] = {
      {[](GlobalPlannerConfig& c) { c.s_near = 0.0; }, "global: s_near must be > 0"},
      {[](GlobalPlannerConfig& c) { c.n_min_tsp = 0; }, "global: n_min_tsp must be >= 1"},
      {[](GlobalPlannerConfig& c) { c.n_max_tsp = 2; }, "global: n_max_tsp must be >= n_min_tsp"},
      {[](GlobalPlannerConfig& c) { c.lambda = -0.1; }, "global: lambda must be >= 0"},
      {[](GlobalPlannerConfig& c) { c.v_max = 0.0; }, "global: v_max must be > 0"},
      // Infinite: every leg would take no time, and the tour's order would be left to ties.
      {[](GlobalPlannerConfig& c) { c.v_max = std::numeric_limits<double>::infinity(); }, "global: v_max must be > 0"},
      {[](GlobalPlannerConfig& c) { c.max_exact = 17; }, "global: max_exact must be in [0, 16]"},
      {[](GlobalPlannerConfig& c) { c.max_exact = -1; }, "global: max_exact must be in [0, 16]"},
      {[](GlobalPlannerConfig& c) {  // with a rest leg: 17 nodes
         c.max_exact = 16;
         c.rest_weight = 1.0;
       },
       "global: max_exact must be <= 15 with a rest leg (rest_weight > 0): its node is solved with the candidates"},
      {[](GlobalPlannerConfig& c) { c.reuse_cell = 1e-310; }, "global: reuse_cell must be 0 or finite and >= 0.001"},
      {[](GlobalPlannerConfig& c) { c.rest_weight = -1.0; }, "global: rest_weight must be finite and >= 0"},
      {[](GlobalPlannerConfig& c) { c.rest_weight = std::nan(""); }, "global: rest_weight must be finite and >= 0"},
      {[](GlobalPlannerConfig& c) { c.rest_frontiers = 0; }, "global: rest_frontiers must be >= 1"},
      {[](GlobalPlannerConfig& c) { c.omission.t_max = -1.0; }, "omission: t_max must be > 0"},
      {[](GlobalPlannerConfig& c) {  // each finite, their product inf
         c.omission.alpha_max = 1e200;
         c.omission.w_t = 1e200;
       },
       "global: lambda times omission: alpha_max * w_t * n_t (the largest lambda xi of a frontier) must be <= 1e6"},
      {[](GlobalPlannerConfig& c) {
         c.lambda = 1e4;
         c.omission.n_t = 1e3;
       },
       "global: lambda times omission: alpha_max * w_t * n_t (the largest lambda xi of a frontier) must be <= 1e6"},
  };
  for (const Row& r : rows) {
    GlobalPlannerConfig c;
    r.spoil(c);
    EXPECT_EQ(c.validate().message(), r.message);
  }
  GlobalPlannerConfig most;  // the bound itself: 1 * 1 * 2 * 5e5
  most.lambda = 1.0;
  most.omission.alpha_max = 1.0;
  most.omission.w_t = 2.0;
  most.omission.n_t = 5e5;
  EXPECT_TRUE(most.validate().ok()) << most.validate().message();
}

TEST(SelectCandidates, NearOnesSortedByDistanceInactiveExcluded) {
  GlobalPlannerConfig c;
  c.s_near = 5.0;
  c.n_min_tsp = 2;
  c.n_max_tsp = 12;
  const std::vector<double> d = {4.0, 1.0, 6.0, 3.0, 2.0, 4.999, 5.0};
  auto f = frontiersAtDistances(d);
  f[3].active = false;
  EXPECT_EQ(selectCandidates(f, d, c), (std::vector<std::size_t>{1, 4, 0, 5}));
}

TEST(SelectCandidates, TooFewNearAreFilledWithTheNearestOthers) {
  GlobalPlannerConfig c;
  c.s_near = 5.0;
  c.n_min_tsp = 3;
  const std::vector<double> d = {20.0, 9.0, 1.0, 7.0, 8.0};
  auto f = frontiersAtDistances(d);
  f[3].active = false;  // nearer than 4 but not in the band: never a filler
  EXPECT_EQ(selectCandidates(f, d, c), (std::vector<std::size_t>{2, 4, 1}));
  // Not enough active frontiers at all: all of them.
  c.n_min_tsp = 10;
  c.n_max_tsp = 10;
  EXPECT_EQ(selectCandidates(f, d, c), (std::vector<std::size_t>{2, 4, 1, 0}));
}

TEST(SelectCandidates, TooManyNearAreCappedNearestFirst) {
  GlobalPlannerConfig c;
  c.s_near = 50.0;
  c.n_min_tsp = 2;
  c.n_max_tsp = 3;
  const std::vector<double> d = {5.0, 4.0, 3.0, 2.0, 1.0, 0.5};
  auto f = frontiersAtDistances(d);
  f[5].active = false;
  EXPECT_EQ(selectCandidates(f, d, c), (std::vector<std::size_t>{4, 3, 2}));
}

TEST(SelectCandidates, UnreachableAndMismatchedInput) {
  GlobalPlannerConfig c;
  c.n_min_tsp = 3;
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<double> d = {inf, 2.0, std::nan(""), 30.0, -1.0};
  const auto f = frontiersAtDistances(d);
  EXPECT_EQ(selectCandidates(f, d, c), (std::vector<std::size_t>{1, 3}));
  EXPECT_TRUE(selectCandidates(f, {1.0, 2.0}, c).empty());
}

namespace {

// Frontiers on a small floor plan; distances are Euclidean, except a wall that makes going
// from frontier index 2 to index 4 a detour (asymmetric on purpose).
struct Fixture {
  std::vector<FrontierSummary> frontiers;
  Vec3 uav = Vec3(0.0, 0.0, 1.0);
  std::vector<std::size_t> from_uav_calls;

  Fixture() {
    const Vec3 positions[] = {{3, 1, 1}, {-2, 2, 1},  {1, -3, 1}, {6, 2, 1},
                              {2, 4, 1}, {-4, -1, 1}, {0, 6, 1}};
    const int cells[] = {10, 80, 15, 12, 300, 25, 8};
    const double durations[] = {1.0, 3.0, 15.0, 2.0, 0.5, 4.0, 1.0};
    const int n_near[] = {2, 1, 2, 0, 3, 2, 1};
    for (int j = 0; j < 7; ++j) {
      FrontierSummary s;
      s.id = static_cast<unsigned>(10 * j + 7);
      s.average = positions[j];
      s.cell_count = cells[j];
      s.duration = durations[j];
      s.n_near = n_near[j];
      frontiers.push_back(s);
    }
    frontiers[6].active = false;
  }

  double between(std::size_t i, std::size_t j) const {
    const double d = (frontiers[i].average - frontiers[j].average).norm();
    return (i == 2 && j == 4) ? 1.8 * d : d;
  }
  // Brute force's J of an order: travel time to the last one plus lambda * sum xi * arrival time, with
  // the straight line from the UAV.
  double openPathCost(const std::vector<std::size_t>& order, const GlobalPlannerConfig& c) const {
    double t = (frontiers[order[0]].average - uav).norm() / c.v_max;
    const auto& f0 = frontiers[order[0]];
    double penalty = xi(c.omission, f0.cell_count, f0.duration, f0.n_near) * t;
    for (std::size_t m = 1; m < order.size(); ++m) {
      t += between(order[m - 1], order[m]) / c.v_max;
      const auto& f = frontiers[order[m]];
      penalty += xi(c.omission, f.cell_count, f.duration, f.n_near) * t;
    }
    return t + c.lambda * penalty;
  }
  PathDistances distances() {
    PathDistances d;  // no lower bound: every active frontier is asked about
    d.from_uav = [this](std::size_t j) {
      from_uav_calls.push_back(j);
      return (frontiers[j].average - uav).norm();
    };
    d.between = [this](std::size_t i, std::size_t j) { return between(i, j); };
    return d;
  }
};

}  // namespace

TEST(PlanTour, FixtureMatchesBruteForce) {
  Fixture fx;
  GlobalPlannerConfig c;
  c.s_near = 100.0;
  c.lambda = 0.4;
  c.omission = omissionConfig();
  const auto result = planTour(fx.frontiers, fx.distances(), c);
  ASSERT_TRUE(result.ok()) << result.message();
  const GlobalTour& tour = *result;
  EXPECT_TRUE(tour.exact);
  EXPECT_EQ(tour.lambda, 0.4);

  // The inactive frontier is neither planned for nor asked about.
  EXPECT_EQ(std::count(fx.from_uav_calls.begin(), fx.from_uav_calls.end(), 6u), 0);
  EXPECT_EQ(fx.from_uav_calls.size(), 6u);

  // Brute force over every order of the six active frontiers, straight from the positions:
  // travel time to the last one plus lambda * sum xi * arrival time.
  std::vector<std::size_t> order = {0, 1, 2, 3, 4, 5};
  double best = std::numeric_limits<double>::infinity();
  std::vector<std::size_t> best_order;
  do {
    const double j = fx.openPathCost(order, c);
    if (j < best) best = j, best_order = order;
  } while (std::next_permutation(order.begin(), order.end()));

  EXPECT_EQ(tour.indices, best_order);
  EXPECT_NEAR(tour.cost, best, 1e-9 * best);
  ASSERT_EQ(tour.frontier_ids.size(), 6u);
  for (std::size_t m = 0; m < 6; ++m) {
    const auto& f = fx.frontiers[best_order[m]];
    EXPECT_EQ(tour.frontier_ids[m], f.id);
    EXPECT_EQ(tour.waypoints[m], f.average);
    EXPECT_DOUBLE_EQ(tour.xi[m], xi(c.omission, f.cell_count, f.duration, f.n_near));
  }

  // The omission term matters on this fixture: without it the order differs.
  GlobalPlannerConfig plain = c;
  plain.lambda = 0.0;
  const auto plain_tour = planTour(fx.frontiers, fx.distances(), plain);
  ASSERT_TRUE(plain_tour.ok());
  EXPECT_NE(plain_tour->indices, tour.indices);
}

TEST(PlanTour, UsesOnlyNearCandidatesAndTheHeuristicAboveMaxExact) {
  Fixture fx;
  GlobalPlannerConfig c;
  c.s_near = 3.5;  // indices 0 (3.2 m), 1 (2.8 m), 2 (3.2 m) are near
  c.n_min_tsp = 2;
  c.omission = omissionConfig();
  auto result = planTour(fx.frontiers, fx.distances(), c);
  ASSERT_TRUE(result.ok()) << result.message();
  std::vector<std::size_t> planned = result->indices;
  std::sort(planned.begin(), planned.end());
  EXPECT_EQ(planned, (std::vector<std::size_t>{0, 1, 2}));

  c.s_near = 100.0;
  c.max_exact = 4;
  result = planTour(fx.frontiers, fx.distances(), c);
  ASSERT_TRUE(result.ok());
  EXPECT_FALSE(result->exact);
  EXPECT_EQ(result->indices.size(), 6u);
}

// The hint (frontier ids, the last tour) warm-starts the heuristic: with every frontier at the same
// distance from the UAV and from each other except along a line, an equally good order in the hint is
// kept, named by id; ids that are not candidates (an inactive frontier, an unknown id) are skipped.
TEST(PlanTour, HintOfIdsWarmStartsTheHeuristic) {
  Fixture fx;
  fx.frontiers.resize(6);
  const double xs[] = {1.0, 2.0, 3.0, -1.0, -2.0, -3.0};
  for (int j = 0; j < 6; ++j) fx.frontiers[j].average = Vec3(xs[j], 0.0, 1.0);
  fx.uav = Vec3(0.0, 0.0, 1.0);
  PathDistances d;
  d.from_uav = [&](std::size_t j) { return (fx.frontiers[j].average - fx.uav).norm(); };
  d.between = [&](std::size_t i, std::size_t j) { return (fx.frontiers[i].average - fx.frontiers[j].average).norm(); };
  GlobalPlannerConfig c;
  c.s_near = 100.0;
  c.lambda = 0.0;
  c.max_exact = 0;
  const auto cold = planTour(fx.frontiers, d, c);
  ASSERT_TRUE(cold.ok()) << cold.message();
  EXPECT_FALSE(cold->exact);
  std::vector<unsigned> mirrored;  // the same order on the other side
  for (std::size_t j : cold->indices) mirrored.push_back(fx.frontiers[(j + 3) % 6].id);
  std::vector<unsigned> hint = mirrored;
  hint.insert(hint.begin() + 2, 9999u);  // not a frontier
  const auto warm = planTour(fx.frontiers, d, c, hint);
  ASSERT_TRUE(warm.ok()) << warm.message();
  EXPECT_EQ(warm->frontier_ids, mirrored);
  EXPECT_DOUBLE_EQ(warm->cost, cold->cost);
  // Exact solving ignores the hint.
  c.max_exact = 12;
  EXPECT_EQ(planTour(fx.frontiers, d, c, mirrored)->frontier_ids, planTour(fx.frontiers, d, c)->frontier_ids);
}

// With a lower bound of the UAV distances (here the straight line, the fixture's UAV distances being
// straight lines scaled up by a detour factor per frontier), the tour is the same as with every
// distance asked for, and frontiers that cannot be among the n_max_tsp nearest are not asked about.
// Distances from the UAV that say "unreachable" (NaN, negative: PathDistances' word for it) take no place among
// the nearest found while the lower bound prunes: the candidates are those of the whole list. A -1 kept among
// them ended the search early, and a NaN broke the heap's order.
TEST(PlanTour, UnreachableDistancesDoNotEndTheLowerBoundsSearch) {
  Fixture fx;
  for (int n_max = 1; n_max <= 6; ++n_max)
    for (const double bad : {-1.0, std::numeric_limits<double>::quiet_NaN()}) {
      GlobalPlannerConfig c;
      c.s_near = 100.0;
      c.n_min_tsp = 1;
      c.n_max_tsp = n_max;
      c.lambda = 0.4;
      c.omission = omissionConfig();
      PathDistances full = fx.distances();
      std::size_t nearest = 0;  // the active frontier nearest the UAV: unreachable here
      for (std::size_t j = 0; j < fx.frontiers.size(); ++j)
        if (fx.frontiers[j].active && (fx.frontiers[j].average - fx.uav).norm() <
                                          (fx.frontiers[nearest].average - fx.uav).norm())
          nearest = j;
      full.from_uav = [&](std::size_t j) { return j == nearest ? bad : (fx.frontiers[j].average - fx.uav).norm(); };
      const auto want = planTour(fx.frontiers, full, c);
      PathDistances bounded = full;
      bounded.from_uav_lower_bound = [&](std::size_t j) { return (fx.frontiers[j].average - fx.uav).norm(); };
      const auto got = planTour(fx.frontiers, bounded, c);
      ASSERT_EQ(want.ok(), got.ok()) << "n_max " << n_max << " bad " << bad;
      if (!want.ok()) continue;
      EXPECT_EQ(got->indices, want->indices) << "n_max " << n_max << " bad " << bad;
    }
}

TEST(PlanTour, LowerBoundSkipsFrontiersThatCannotBeCandidates) {
  Fixture fx;
  const double detour[] = {1.0, 1.6, 1.1, 1.0, 1.3, 2.0, 1.0};
  for (int n_max = 1; n_max <= 6; ++n_max)
    for (double s_near : {2.0, 4.0, 100.0}) {
      GlobalPlannerConfig c;
      c.s_near = s_near;
      c.n_min_tsp = 1;
      c.n_max_tsp = n_max;
      c.lambda = 0.4;
      c.omission = omissionConfig();
      PathDistances full = fx.distances();
      full.from_uav = [&](std::size_t j) { return detour[j] * (fx.frontiers[j].average - fx.uav).norm(); };
      const auto want = planTour(fx.frontiers, full, c);
      std::vector<std::size_t> asked;
      PathDistances bounded = full;
      bounded.from_uav = [&](std::size_t j) {
        asked.push_back(j);
        return full.from_uav(j);
      };
      bounded.from_uav_lower_bound = [&](std::size_t j) { return (fx.frontiers[j].average - fx.uav).norm(); };
      const auto got = planTour(fx.frontiers, bounded, c);
      ASSERT_TRUE(want.ok() && got.ok());
      EXPECT_EQ(got->indices, want->indices) << "n_max " << n_max << " s_near " << s_near;
      EXPECT_NEAR(got->cost, want->cost, 1e-12);
      EXPECT_EQ(std::count(asked.begin(), asked.end(), 6u), 0);  // inactive
      // Exactly those the rule asks about: in increasing bound, until the cap (n_max_tsp, plus rest_frontiers
      // with a rest leg) nearest distances found so far are all no larger than the next bound.
      const std::size_t cap = static_cast<std::size_t>(n_max) +
                              (c.rest_weight > 0.0 ? static_cast<std::size_t>(c.rest_frontiers) : 0u);
      std::vector<std::pair<double, std::size_t>> by_bound;
      for (std::size_t j = 0; j < fx.frontiers.size(); ++j)
        if (fx.frontiers[j].active) by_bound.emplace_back((fx.frontiers[j].average - fx.uav).norm(), j);
      std::stable_sort(by_bound.begin(), by_bound.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
      std::vector<double> found;
      std::size_t expected = 0;
      for (const auto& [bound, j] : by_bound) {
        std::sort(found.begin(), found.end());
        if (found.size() >= cap && bound >= found[cap - 1]) break;
        ++expected;
        found.push_back(full.from_uav(j));
      }
      EXPECT_EQ(asked.size(), expected) << "n_max " << n_max << " s_near " << s_near;
      if (n_max <= 2) {
        EXPECT_LT(asked.size(), 6u) << "n_max " << n_max;
      }
    }
}

// The rest leg against brute force: every order of the candidates, costed as the open path plus
// rest_weight times the way on from the last one to the nearest of the rest_frontiers non-candidates
// nearest the UAV. It changes the order on this fixture (the candidates away from the rest first), gives
// the same tour with the lower bound of the UAV distances, and does nothing when every active frontier
// is a candidate.
TEST(PlanTour, RestLegMatchesBruteForceWithAnEndCost) {
  // Also with the candidates capped at two (n_max_tsp 2: the lower bound must leave room for the rest beyond
  // the cap), and max_exact at the candidates' count (the rest node is solved exactly on top of it).
  Fixture fx;
  int changed = 0;
  for (int n_max : {12, 2})
  for (int rest_frontiers : {1, 2, 3})
    for (double weight : {0.5, 1.0, 3.0})
      for (double s_near : {3.0, 3.5, 4.3}) {
        // Candidates and rest from the straight-line UAV distances of the fixture.
        std::vector<std::size_t> active = {0, 1, 2, 3, 4, 5};
        auto d_uav = [&](std::size_t j) { return (fx.frontiers[j].average - fx.uav).norm(); };
        std::stable_sort(active.begin(), active.end(), [&](std::size_t a, std::size_t b) { return d_uav(a) < d_uav(b); });
        std::size_t near = 0;
        while (near < active.size() && d_uav(active[near]) < s_near) ++near;
        near = std::min<std::size_t>(std::max<std::size_t>(near, 2), static_cast<std::size_t>(n_max));
        std::vector<std::size_t> order(active.begin(), active.begin() + near);
        const std::vector<std::size_t> rest(active.begin() + near,
                                            active.begin() + std::min(active.size(), near + rest_frontiers));
        ASSERT_FALSE(rest.empty());
        GlobalPlannerConfig c;
        c.s_near = s_near;
        c.n_min_tsp = 2;
        c.n_max_tsp = n_max;
        c.max_exact = static_cast<int>(near);
        c.lambda = 0.4;
        c.omission = omissionConfig();
        c.rest_weight = weight;
        c.rest_frontiers = rest_frontiers;
        const auto result = planTour(fx.frontiers, fx.distances(), c);
        ASSERT_TRUE(result.ok()) << result.message();
        std::sort(order.begin(), order.end());
        double best = std::numeric_limits<double>::infinity(), best_rest = 0.0;
        std::vector<std::size_t> best_order;
        do {
          double way_on = std::numeric_limits<double>::infinity();
          for (std::size_t r : rest) way_on = std::min(way_on, fx.between(order.back(), r));
          const double j = fx.openPathCost(order, c) + weight * way_on / c.v_max;
          if (j < best - 1e-12) best = j, best_order = order, best_rest = weight * way_on / c.v_max;
        } while (std::next_permutation(order.begin(), order.end()));
        const std::string where = "n_max_tsp " + std::to_string(n_max) + " rest_frontiers " +
                                  std::to_string(rest_frontiers) + " weight " + std::to_string(weight) + " s_near " +
                                  std::to_string(s_near);
        EXPECT_EQ(result->indices, best_order) << where;
        EXPECT_NEAR(result->cost, best, 1e-9 * best) << where;
        EXPECT_NEAR(result->rest_leg, best_rest, 1e-12) << where;
        EXPECT_TRUE(result->exact) << where;

        PathDistances bounded = fx.distances();
        bounded.from_uav_lower_bound = d_uav;
        const auto with_bound = planTour(fx.frontiers, bounded, c);
        ASSERT_TRUE(with_bound.ok());
        EXPECT_EQ(with_bound->indices, result->indices) << where;
        EXPECT_NEAR(with_bound->cost, best, 1e-9 * best) << where;
        EXPECT_NEAR(with_bound->rest_leg, best_rest, 1e-12) << where;

        GlobalPlannerConfig open = c;
        open.rest_weight = 0.0;
        const auto open_tour = planTour(fx.frontiers, fx.distances(), open);
        ASSERT_TRUE(open_tour.ok());
        EXPECT_EQ(open_tour->rest_leg, 0.0);
        changed += open_tour->indices != result->indices;
      }
  EXPECT_GE(changed, 3);

  // Every active frontier a candidate: no rest, the open path.
  GlobalPlannerConfig all;
  all.s_near = 100.0;
  all.lambda = 0.4;
  all.omission = omissionConfig();
  const auto open_tour = planTour(fx.frontiers, fx.distances(), all);
  all.rest_weight = 2.0;
  const auto rest_tour = planTour(fx.frontiers, fx.distances(), all);
  ASSERT_TRUE(open_tour.ok() && rest_tour.ok());
  EXPECT_EQ(rest_tour->indices, open_tour->indices);
  EXPECT_EQ(rest_tour->cost, open_tour->cost);
  EXPECT_EQ(rest_tour->rest_leg, 0.0);
}

// A candidate that can reach no rest frontier has no leg on (not an infinite one, which the solver would
// refuse): candidates 1 and 0 (s_near 3), rest 2, and 0 cut off from 2. Ending at 0 then costs nothing more,
// and the tour 1, 0 (sqrt(8) + sqrt(26) m at 2 m/s) beats 0, 1 with the way on from 1 to 2.
TEST(PlanTour, ACandidateThatReachesNoRestFrontierHasNoLegOn) {
  Fixture fx;
  GlobalPlannerConfig c;
  c.s_near = 3.0;
  c.n_min_tsp = 2;
  c.lambda = 0.0;
  c.rest_weight = 1.0;
  c.rest_frontiers = 1;
  PathDistances d = fx.distances();
  d.between = [&](std::size_t i, std::size_t j) {
    if ((i == 0 && j == 2) || (i == 2 && j == 0)) return std::numeric_limits<double>::infinity();
    return fx.between(i, j);
  };
  const auto tour = planTour(fx.frontiers, d, c);
  ASSERT_TRUE(tour.ok()) << tour.message();
  EXPECT_EQ(tour->indices, (std::vector<std::size_t>{1, 0}));
  EXPECT_EQ(tour->rest_leg, 0.0);
  EXPECT_NEAR(tour->cost, (std::sqrt(8.0) + std::sqrt(26.0)) / c.v_max, 1e-12);
}

TEST(PlanTour, EmptyAndBadInput) {
  Fixture fx;
  GlobalPlannerConfig c;
  for (auto& f : fx.frontiers) f.active = false;
  auto result = planTour(fx.frontiers, fx.distances(), c);
  ASSERT_TRUE(result.ok());
  EXPECT_TRUE(result->frontier_ids.empty());
  EXPECT_EQ(result->cost, 0.0);

  Fixture fy;
  PathDistances broken = fy.distances();
  broken.between = [](std::size_t i, std::size_t j) {
    return (i == 1 && j == 0) ? std::numeric_limits<double>::infinity() : 1.0;
  };
  result = planTour(fy.frontiers, broken, c);
  ASSERT_FALSE(result.ok());
  EXPECT_NE(result.message().find("from frontier 17 to frontier 7"), std::string::npos) << result.message();

  c.lambda = -1.0;
  result = planTour(fy.frontiers, fy.distances(), c);
  ASSERT_FALSE(result.ok());
  EXPECT_EQ(result.message(), "global: lambda must be >= 0");
}
