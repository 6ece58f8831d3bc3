// A* grid search against exhaustive shortest paths (Dijkstra over every voxel of the same 26-connected
// graph) and a brute-force blocking rule, on small random maps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "go_feap/planning/astar.h"
#include "go_feap/planning/tour_planner.h"

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
using go_feap::planning::PathDistance;
using go_feap::planning::pathDistance;
using go_feap::planning::PathResult;
using go_feap::planning::PathStatus;

namespace {

constexpr double kRes = 0.1;
constexpr double kInf = std::numeric_limits<double>::infinity();

OccupancyConfig occupancyConfig() {
  OccupancyConfig c;
  c.resolution = kRes;
  c.margin = 0.0;
  return c;
}

EsdfConfig esdfConfig() {
  EsdfConfig c;
  c.max_distance = 1.0;
  return c;
}

AstarConfig astarConfig(double clearance, bool unknown_is_free) {
  AstarConfig c;
  c.clearance = clearance;
  c.unknown_is_free = unknown_is_free;
  return c;
}

// An occupancy map of dims voxels with its corner at the origin, and its ESDF kept in step through
// Esdf::update() with the occupied voxels' linear indices.
class World {
 public:
  explicit World(const Index3& dims)
      : occupancy_(occupancyConfig(), Aabb{Vec3::Zero(), dims.cast<double>() * kRes}),
        esdf_(occupancy_.geometry(), esdfConfig()),
        synced_(occupancy_.geometry().size(), 0) {}

  const GridGeometry& geo() const { return occupancy_.geometry(); }
  const OccupancyMap& occupancy() const { return occupancy_; }
  const Esdf& esdf() const { return esdf_; }

  /// Sets the voxels of [lo, hi] (inclusive, clipped to the grid) and brings the ESDF up to date.
  void set(const Index3& lo, const Index3& hi, VoxelState s) {
    for (int z = std::max(0, lo.z()); z <= std::min(hi.z(), geo().dims().z() - 1); ++z)
      for (int y = std::max(0, lo.y()); y <= std::min(hi.y(), geo().dims().y() - 1); ++y)
        for (int x = std::max(0, lo.x()); x <= std::min(hi.x(), geo().dims().x() - 1); ++x)
          occupancy_.setState(Index3(x, y, z), s);
    sync();
  }
  void fill(VoxelState s) { set(Index3::Zero(), geo().dims(), s); }
  bool occupied(std::size_t l) const { return occupancy_.stateAt(l) == VoxelState::kOccupied; }

 private:
  void sync() {
    std::vector<std::size_t> inserted, removed;
    for (std::size_t l = 0; l < synced_.size(); ++l) {
      const std::uint8_t now = occupied(l) ? 1 : 0;
      if (now == synced_[l]) continue;
      (now ? inserted : removed).push_back(l);
      synced_[l] = now;
    }
    esdf_.update(inserted, removed);
  }

  OccupancyMap occupancy_;
  Esdf esdf_;
  std::vector<std::uint8_t> synced_;
};

// Small deterministic integers, the same on every standard library.
struct Rng {
  explicit Rng(unsigned seed) : engine(seed) {}
  int operator()(int lo, int hi) {
    return lo + static_cast<int>(engine() % static_cast<unsigned>(hi - lo + 1));
  }
  std::mt19937 engine;
};

Index3 randomVoxel(Rng& rng, const Index3& dims) {
  return Index3(rng(0, dims.x() - 1), rng(0, dims.y() - 1), rng(0, dims.z() - 1));
}

void addRandomBoxes(World& world, Rng& rng, int count, VoxelState s) {
  for (int i = 0; i < count; ++i) {
    const Index3 lo = randomVoxel(rng, world.geo().dims());
    const Index3 size(rng(0, 7), rng(0, 7), rng(0, 5));
    world.set(lo, lo + size, s);
  }
}

// Blocking rule from first principles: occupied, unknown when unknown is not free, or nearer than the
// clearance to an occupied voxel centre (nearest one found by scanning every voxel).
std::vector<std::uint8_t> bruteForceTraversable(const World& world, const AstarConfig& config) {
  const GridGeometry& g = world.geo();
  std::vector<Index3> obstacles;
  for (std::size_t l = 0; l < g.size(); ++l)
    if (world.occupied(l)) obstacles.push_back(g.unlinear(l));
  std::vector<Index3> unknown;
  for (std::size_t l = 0; l < g.size(); ++l)
    if (world.occupancy().stateAt(l) == VoxelState::kUnknown) unknown.push_back(g.unlinear(l));
  std::vector<std::uint8_t> ok(g.size(), 0);
  for (std::size_t l = 0; l < g.size(); ++l) {
    const VoxelState s = world.occupancy().stateAt(l);
    if (s == VoxelState::kOccupied || (s == VoxelState::kUnknown && !config.unknown_is_free)) continue;
    const Index3 v = g.unlinear(l);
    // The vehicle stays inside the exploration box, `clearance` away from its faces.
    const Vec3 c = g.indexToCoord(v);
    const Aabb& box = world.occupancy().box();
    if ((c.array() < box.min.array() + config.clearance - 1e-9).any() ||
        (c.array() > box.max.array() - config.clearance + 1e-9).any())
      continue;
    double nearest = esdfConfig().max_distance;
    for (const Index3& o : obstacles) nearest = std::min(nearest, kRes * (o - v).cast<double>().norm());
    ok[l] = nearest >= config.clearance - 1e-9;
    if (ok[l] && config.known_clearance) {  // the voxels `clearance` away along each axis are known
      const int k = std::max(1, static_cast<int>(std::ceil(config.clearance / kRes - 1e-9)));
      for (int a = 0; a < 3; ++a)
        for (int sgn : {-1, 1}) {
          Index3 n = v;
          n[a] += sgn * k;
          if (world.occupancy().state(n) == VoxelState::kUnknown) ok[l] = 0;
        }
      // and nothing unseen within known_radius: the nearest unknown voxel, or the nearest one outside the
      // grid (unknown too, straight out through the nearest face), is farther.
      double unseen = kInf;
      for (int a = 0; a < 3; ++a) unseen = std::min(unseen, kRes * std::min(v[a] + 1, g.dims()[a] - v[a]));
      for (const Index3& u : unknown) unseen = std::min(unseen, kRes * (u - v).cast<double>().norm());
      if (unseen <= config.known_radius + 1e-9) ok[l] = 0;
    }
  }
  return ok;
}

// Whether the move from v by d (a 26-neighbour offset) keeps to traversable voxels: the target and, for
// a diagonal move, every voxel around the edge or corner it passes through (v + e, e_a in {0, d_a}).
bool moveAllowed(const GridGeometry& g, const std::vector<std::uint8_t>& ok, const Index3& v,
                 const Index3& d) {
  for (int ez = 0; ez <= std::abs(d.z()); ++ez)
    for (int ey = 0; ey <= std::abs(d.y()); ++ey)
      for (int ex = 0; ex <= std::abs(d.x()); ++ex) {
        const Index3 n = v + Index3(ex * d.x(), ey * d.y(), ez * d.z());
        if (n != v && (!g.inside(n) || !ok[g.linear(n)])) return false;
      }
  return true;
}

// Shortest path costs (m) from `source` over the lattice of voxels `stride` apart through it, by textbook
// Dijkstra over every lattice voxel: a move from v to one of its 26 lattice neighbours v + stride * d
// is taken when allowed(v, d). Voxels off the lattice stay at infinity.
template <typename Allowed>
std::vector<double> dijkstra(const GridGeometry& g, const Index3& source, int stride, Allowed&& allowed) {
  std::vector<double> cost(g.size(), kInf);
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  cost[g.linear(source)] = 0.0;
  queue.push({0.0, g.linear(source)});
  while (!queue.empty()) {
    const auto [c, l] = queue.top();
    queue.pop();
    if (c > cost[l]) continue;
    const Index3 v = g.unlinear(l);
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const Index3 d(dx, dy, dz);
          if (d == Index3::Zero() || !allowed(v, d)) continue;
          const std::size_t n = g.linear(v + stride * d);
          const double next = c + stride * kRes * std::sqrt(static_cast<double>(d.squaredNorm()));
          if (next < cost[n]) {
            cost[n] = next;
            queue.push({next, n});
          }
        }
  }
  return cost;
}

// Shortest path costs (m) from `source` to every voxel over traversable voxels, 26-connected with move
// costs 1, sqrt 2, sqrt 3 voxels and no corner cutting.
std::vector<double> shortestCosts(const GridGeometry& g, const std::vector<std::uint8_t>& ok,
                                  const Index3& source) {
  return dijkstra(g, source, 1, [&](const Index3& v, const Index3& d) { return moveAllowed(g, ok, v, d); });
}

double polylineLength(const std::vector<Vec3>& path) {
  double length = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) length += (path[i] - path[i - 1]).norm();
  return length;
}

// Every point sampled every res / 20 along every segment lies in a traversable voxel.
void expectSegmentsTraversable(const Astar& astar, const std::vector<Vec3>& path) {
  for (std::size_t i = 1; i < path.size(); ++i) {
    const int samples = static_cast<int>(std::ceil((path[i] - path[i - 1]).norm() / (kRes / 20))) + 1;
    for (int s = 0; s <= samples; ++s) {
      const Vec3 p = path[i - 1] + (path[i] - path[i - 1]) * (static_cast<double>(s) / samples);
      ASSERT_TRUE(astar.traversable(astar.geometry().coordToIndex(p)))
          << "segment " << i << " sample " << s << " at " << p.transpose();
    }
  }
}

// Shape of a found path: raw path continuous through traversable voxels between the two end voxels,
// lengths consistent, shortened path traversable and between the straight line and the raw path.
// With `stride` > 1 the raw path's steps are moves on that lattice, each a traversable segment.
void expectWellFormed(const Astar& astar, const PathResult& r, const Index3& start, const Index3& goal,
                      int stride = 1) {
  const GridGeometry& g = astar.geometry();
  ASSERT_EQ(r.status, PathStatus::kFound);
  ASSERT_FALSE(r.raw_path.empty());
  EXPECT_EQ(g.coordToIndex(r.raw_path.front()), start);
  EXPECT_EQ(g.coordToIndex(r.raw_path.back()), goal);
  for (std::size_t i = 0; i < r.raw_path.size(); ++i) {
    const Index3 v = g.coordToIndex(r.raw_path[i]);
    ASSERT_TRUE(r.raw_path[i].isApprox(g.indexToCoord(v), 1e-12)) << "not a voxel centre";
    ASSERT_TRUE(astar.traversable(v)) << "raw voxel " << i << " blocked";
    if (i > 0) {
      const Index3 step = v - g.coordToIndex(r.raw_path[i - 1]);
      ASSERT_EQ(step.cwiseAbs().maxCoeff(), stride) << "raw path jumps at " << i;
      for (int a = 0; a < 3; ++a) ASSERT_EQ(step[a] % stride, 0) << "raw path leaves the lattice at " << i;
    }
  }
  if (stride > 1) expectSegmentsTraversable(astar, r.raw_path);
  EXPECT_NEAR(r.raw_length, polylineLength(r.raw_path), 1e-9);
  ASSERT_GE(r.path.size(), 1u);
  EXPECT_EQ(r.path.front(), r.raw_path.front());
  EXPECT_EQ(r.path.back(), r.raw_path.back());
  EXPECT_NEAR(r.length, polylineLength(r.path), 1e-9);
  EXPECT_LE(r.length, r.raw_length + 1e-9);
  EXPECT_GE(r.length, (r.path.back() - r.path.front()).norm() - 1e-9);
  expectSegmentsTraversable(astar, r.path);
  // The path is the raw path's shortening: its points are raw points in order, and each kept point is the
  // last one seen from the one before it (the raw point after it is not), short of the goal.
  std::size_t at = 0;
  std::vector<std::size_t> kept;
  for (const Vec3& p : r.path) {
    while (at < r.raw_path.size() && r.raw_path[at] != p) ++at;
    ASSERT_LT(at, r.raw_path.size()) << "a path point that is no raw point, in order";
    kept.push_back(at);
  }
  for (std::size_t i = 1; i + 1 < kept.size(); ++i)
    EXPECT_FALSE(astar.segmentTraversable(r.raw_path[kept[i - 1]], r.raw_path[kept[i] + 1]))
        << "the path could have gone on past raw point " << kept[i];
}

const Index3 kRandomDims(25, 20, 10);

bool onLattice(const Index3& v, const Index3& anchor, int stride) {
  for (int a = 0; a < 3; ++a)
    if ((v[a] - anchor[a]) % stride != 0) return false;
  return true;
}

// Whether the segment from the centre of voxel a to that of b meets the closed cube of every voxel it
// touches only where `ok`: slab clipping of the segment against each cube of the index box spanned by
// a and b (a segment between centres never leaves it), touching included.
bool segmentOk(const GridGeometry& g, const std::vector<std::uint8_t>& ok, const Index3& a, const Index3& b) {
  const Vec3 pa = a.cast<double>().array() + 0.5, d = (b - a).cast<double>();
  const Index3 lo = a.cwiseMin(b), hi = a.cwiseMax(b);
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const Index3 v(x, y, z);
        double t0 = 0.0, t1 = 1.0;
        for (int i = 0; i < 3 && t0 <= t1; ++i) {
          const double lo_i = v[i] - 1e-9, hi_i = v[i] + 1.0 + 1e-9;
          if (d[i] == 0.0) {
            if (pa[i] < lo_i || pa[i] > hi_i) t1 = -1.0;
            continue;
          }
          double ta = (lo_i - pa[i]) / d[i], tb = (hi_i - pa[i]) / d[i];
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
        }
        if (t0 <= t1 && (!g.inside(v) || !ok[g.linear(v)])) return false;
      }
  return true;
}

// Shortest path costs (m) from `source` over the lattice of voxels `stride` apart through it: a move to
// one of the 26 lattice neighbours needs the neighbour traversable and segmentOk().
std::vector<double> latticeCosts(const GridGeometry& g, const std::vector<std::uint8_t>& ok, const Index3& source,
                                 int stride) {
  return dijkstra(g, source, stride, [&](const Index3& v, const Index3& d) {
    const Index3 n = v + stride * d;
    return g.inside(n) && ok[g.linear(n)] && segmentOk(g, ok, v, n);
  });
}

}  // namespace

TEST(AstarConfig, ValidateNamesTheBadKey) {
  EXPECT_TRUE(AstarConfig().validate().ok());
  AstarConfig c;
  c.clearance = -0.1;
  EXPECT_NE(c.validate().message().find("clearance"), std::string::npos);
  c = AstarConfig();
  c.clearance = std::nan("");
  EXPECT_NE(c.validate().message().find("clearance"), std::string::npos);
  c = AstarConfig();
  c.max_expansions = 0;
  EXPECT_NE(c.validate().message().find("max_expansions"), std::string::npos);
  c.max_expansions = 50000001;  // node indices are 32-bit
  EXPECT_NE(c.validate().message().find("max_expansions"), std::string::npos);
  c.max_expansions = 50000000;
  EXPECT_TRUE(c.validate().ok()) << c.validate().message();
  c.probe_expansions = 50000001;
  EXPECT_NE(c.validate().message().find("probe_expansions"), std::string::npos);
  c = AstarConfig();
  c.probe_expansions = -1;
  EXPECT_NE(c.validate().message().find("probe_expansions"), std::string::npos);
  c = AstarConfig();
  c.tie_breaker = 0.99;
  EXPECT_NE(c.validate().message().find("tie_breaker"), std::string::npos);
  for (int stride : {0, 9}) {
    c = AstarConfig();
    c.stride = stride;
    c.name = "distance_astar";
    EXPECT_EQ(c.validate().message().rfind("distance_astar: stride", 0), 0u) << c.validate().message();
  }
  for (double r : {-0.1, std::nan(""), 0.25}) {
    c = AstarConfig();
    c.clearance = 0.2;
    c.known_radius = r;
    EXPECT_NE(c.validate().message().find("known_radius"), std::string::npos) << r;
  }
  c = AstarConfig();
  c.stride = 8;
  EXPECT_TRUE(c.validate().ok());
  c = AstarConfig();
  c.clearance = 1.5;
  EXPECT_TRUE(c.validate().ok());
  const std::string m = c.validate(esdfConfig()).message();
  EXPECT_NE(m.find("clearance"), std::string::npos) << m;
  EXPECT_NE(m.find("max_distance"), std::string::npos) << m;
}

TEST(Astar, ConstructorRefusesBadConfigAndMismatchedMaps) {
  World world(Index3(10, 10, 5)), other(Index3(10, 11, 5));
  EXPECT_THROW(Astar(world.occupancy(), world.esdf(), astarConfig(1.5, true)), std::invalid_argument);
  EXPECT_THROW(Astar(world.occupancy(), other.esdf(), astarConfig(0.2, true)), std::invalid_argument);
  EXPECT_NO_THROW(Astar(world.occupancy(), world.esdf(), astarConfig(0.2, true)));
}

TEST(Astar, StatusNames) {
  EXPECT_STREQ(toString(PathStatus::kFound), "found");
  EXPECT_STREQ(toString(PathStatus::kStartBlocked), "start_blocked");
  EXPECT_STREQ(toString(PathStatus::kGoalBlocked), "goal_blocked");
  EXPECT_STREQ(toString(PathStatus::kNoPath), "no_path");
  EXPECT_STREQ(toString(PathStatus::kBudgetExceeded), "budget_exceeded");
}

TEST(Astar, TraversableFollowsTheBlockingRule) {
  for (unsigned seed : {11u, 12u, 13u}) {
    World world(kRandomDims);
    Rng rng(seed);
    world.fill(VoxelState::kFree);
    addRandomBoxes(world, rng, 8, VoxelState::kUnknown);
    addRandomBoxes(world, rng, 10, VoxelState::kOccupied);
    for (double clearance : {0.0, 0.1, 0.2, 0.25})
      for (int mode = 0; mode < 5; ++mode) {
        // unknown free; unknown blocked; unknown blocked and kept `clearance` away along the axes (flight
        // paths), and also known_radius all round (half the clearance, and all of it)
        AstarConfig config = astarConfig(clearance, mode == 0);
        config.known_clearance = mode >= 2;
        config.known_radius = mode == 3 ? 0.5 * clearance : mode == 4 ? clearance : 0.0;
        const Astar astar(world.occupancy(), world.esdf(), config);
        const std::vector<std::uint8_t> want = bruteForceTraversable(world, config);
        std::size_t mismatches = 0, traversable = 0;
        for (std::size_t l = 0; l < want.size(); ++l) {
          const bool got = astar.traversable(world.geo().unlinear(l));
          mismatches += got != static_cast<bool>(want[l]);
          traversable += got;
        }
        EXPECT_EQ(mismatches, 0u) << "seed " << seed << " clearance " << clearance << " mode " << mode;
        EXPECT_GT(traversable, 0u);
        EXPECT_LT(traversable, want.size());
      }
    const Astar astar(world.occupancy(), world.esdf(), AstarConfig());
    EXPECT_FALSE(astar.traversable(Index3(-1, 0, 0)));
    EXPECT_FALSE(astar.traversable(kRandomDims));
  }
}

// What a trajectory on a path is checked with (traversableWith, up to known_radius) passes every voxel the
// search may use. The six axis voxels alone (known_radius 0) let a path pass one voxel from an unseen
// pocket, which that check refuses when it looks at the ball round the voxel.
TEST(Astar, EveryTraversableVoxelPassesTheTrajectoryCheck) {
  std::size_t refused_by_axes = 0;  // the disagreement the ball removes
  for (unsigned seed : {21u, 22u}) {
    World world(kRandomDims);
    Rng rng(seed);
    world.fill(VoxelState::kFree);
    addRandomBoxes(world, rng, 8, VoxelState::kOccupied);
    for (int k = 0; k < 60; ++k) {  // one-voxel pockets nobody has seen
      const Index3 v = randomVoxel(rng, kRandomDims);
      world.set(v, v, VoxelState::kUnknown);
    }
    AstarConfig config = astarConfig(0.3, false);
    config.known_clearance = true;
    const Astar axes(world.occupancy(), world.esdf(), config);
    for (double known_radius : {0.2, 0.3}) {
      config.known_radius = known_radius;
      const Astar astar(world.occupancy(), world.esdf(), config);
      std::size_t traversable = 0, refused = 0, beside_pockets = 0;
      for (std::size_t l = 0; l < world.geo().size(); ++l) {
        const Index3 v = world.geo().unlinear(l);
        if (axes.traversable(v) && !astar.traversable(v)) ++beside_pockets;
        refused_by_axes += axes.traversable(v) && !axes.traversableWith(v, 0.163);
        if (!astar.traversable(v)) continue;
        ++traversable;
        for (double d : {0.1, 0.163, known_radius}) refused += !astar.traversableWith(v, d);
      }
      EXPECT_GT(traversable, 20u) << "seed " << seed;
      EXPECT_EQ(refused, 0u) << "seed " << seed << " known_radius " << known_radius;
      EXPECT_GT(beside_pockets, 0u) << "seed " << seed << " known_radius " << known_radius;
    }
  }
  EXPECT_GT(refused_by_axes, 0u);
}

TEST(Astar, CostEqualsExhaustiveShortestPathOnRandomGrids) {
  int found = 0, no_path = 0, probed = 0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    World world(kRandomDims);
    Rng rng(seed);
    world.fill(VoxelState::kFree);
    addRandomBoxes(world, rng, 6, VoxelState::kUnknown);
    addRandomBoxes(world, rng, 14, VoxelState::kOccupied);
    // Every other map is cut in two by a full wall, so that some goals are unreachable.
    if (seed % 2 == 0) world.set(Index3(12, 0, 0), Index3(12, 100, 100), VoxelState::kOccupied);
    const AstarConfig config = astarConfig(0.1 * (seed % 3), seed % 4 != 3);
    const Astar astar(world.occupancy(), world.esdf(), config);
    AstarConfig weighted = config;
    weighted.tie_breaker = 1.5;
    const Astar greedy(world.occupancy(), world.esdf(), weighted);
    // Searches that look from the goal's side after a few expansions find paths as short, and the same
    // unreachable goals.
    AstarConfig probing_config = config;
    probing_config.probe_expansions = 20 + 10 * static_cast<int>(seed);
    const Astar probing(world.occupancy(), world.esdf(), probing_config);
    const GridGeometry& g = world.geo();
    std::vector<std::uint8_t> ok(g.size());
    for (std::size_t l = 0; l < g.size(); ++l) ok[l] = astar.traversable(g.unlinear(l));

    for (int query = 0; query < 6; ++query) {
      Index3 start, goal;
      do start = randomVoxel(rng, g.dims());
      while (!ok[g.linear(start)]);
      const std::vector<double> cost = shortestCosts(g, ok, start);
      for (int k = 0; k < 4; ++k) {
        do goal = randomVoxel(rng, g.dims());
        while (!ok[g.linear(goal)]);
        const PathResult r = astar.search(g.indexToCoord(start), g.indexToCoord(goal), 0.0);
        const double want = cost[g.linear(goal)];
        SCOPED_TRACE("seed " + std::to_string(seed) + " query " + std::to_string(query) + "/" +
                     std::to_string(k));
        const PathResult p = probing.search(g.indexToCoord(start), g.indexToCoord(goal), 0.0);
        if (want == kInf) {
          EXPECT_EQ(r.status, PathStatus::kNoPath) << toString(r.status);
          EXPECT_TRUE(r.path.empty());
          EXPECT_TRUE(r.raw_path.empty());
          EXPECT_EQ(p.status, PathStatus::kNoPath) << toString(p.status);
          EXPECT_TRUE(p.raw_path.empty());
          ++no_path;
          continue;
        }
        expectWellFormed(probing, p, start, goal);
        EXPECT_NEAR(p.raw_length, want, 1e-9);
        if (p.expansions > probing_config.probe_expansions) ++probed;
        ++found;
        expectWellFormed(astar, r, start, goal);
        EXPECT_NEAR(r.raw_length, want, 1e-9);
        EXPECT_LE(r.expansions, config.max_expansions);
        // The scratch reused by the next search gives the same answer.
        const PathResult again = astar.search(g.indexToCoord(start), g.indexToCoord(goal), 0.0);
        EXPECT_EQ(again.raw_path, r.raw_path);
        // A heavier heuristic weight stays within its bound of the optimum.
        const PathResult w = greedy.search(g.indexToCoord(start), g.indexToCoord(goal), 0.0);
        expectWellFormed(greedy, w, start, goal);
        EXPECT_GE(w.raw_length, want - 1e-9);
        EXPECT_LE(w.raw_length, weighted.tie_breaker * want + 1e-9);
      }
    }
  }
  EXPECT_GT(found, 50);
  EXPECT_GT(no_path, 5);
  EXPECT_GT(probed, 10);  // the searches from the goal's side were exercised
}

TEST(Astar, CostEqualsExhaustiveShortestPathInLargeMazes) {
  // Long searches (thousands of expansions) through walls with few gaps, with one Astar reused
  // for searches of every size.
  int found = 0;
  for (unsigned seed : {21u, 22u}) {
    const Index3 dims(96, 64, 12);
    World world(dims);
    Rng rng(seed);
    world.fill(VoxelState::kFree);
    for (int x = 8; x < dims.x(); x += 10) {
      world.set(Index3(x, 0, 0), Index3(x + 1, dims.y(), dims.z()), VoxelState::kOccupied);
      for (int gap = 0; gap < 2; ++gap) {
        const int y = rng(0, dims.y() - 8), z = rng(0, dims.z() - 6);
        world.set(Index3(x, y, z), Index3(x + 1, y + 6, z + 4), VoxelState::kFree);
      }
    }
    for (int y = 10; y < dims.y(); y += 12) {
      const int x = rng(0, dims.x() - 40);
      world.set(Index3(x, y, 0), Index3(x + 30, y, dims.z()), VoxelState::kOccupied);
    }
    addRandomBoxes(world, rng, 6, VoxelState::kOccupied);
    const Astar astar(world.occupancy(), world.esdf(), astarConfig(0.1, true));
    const GridGeometry& g = world.geo();
    std::vector<std::uint8_t> ok(g.size());
    for (std::size_t l = 0; l < g.size(); ++l) ok[l] = astar.traversable(g.unlinear(l));
    for (int query = 0; query < 3; ++query) {
      Index3 start, goal;
      do start = Index3(rng(0, 6), rng(0, dims.y() - 1), rng(0, dims.z() - 1));
      while (!ok[g.linear(start)]);
      const std::vector<double> cost = shortestCosts(g, ok, start);
      for (int k = 0; k < 3; ++k) {
        const int min_x = dims.x() - 30 * (k + 1);  // farther and farther from the start
        do goal = Index3(rng(min_x, dims.x() - 1), rng(0, dims.y() - 1), rng(0, dims.z() - 1));
        while (!ok[g.linear(goal)]);
        SCOPED_TRACE("seed " + std::to_string(seed) + " query " + std::to_string(query) + "/" +
                     std::to_string(k));
        const PathResult r = astar.search(g.indexToCoord(start), g.indexToCoord(goal), 0.0);
        const double want = cost[g.linear(goal)];
        if (want == kInf) {
          EXPECT_EQ(r.status, PathStatus::kNoPath) << toString(r.status);
          continue;
        }
        expectWellFormed(astar, r, start, goal);
        EXPECT_NEAR(r.raw_length, want, 1e-9);
        ++found;
        if (k == 0) {
          EXPECT_GT(r.expansions, 5000);
        }
      }
    }
  }
  EXPECT_GE(found, 12);
}

TEST(Astar, CoarseLatticeCostEqualsExhaustiveShortestPathOnItsLattice) {
  // stride > 1: the search runs over the voxels stride apart from the start's, each move checked along
  // its segment (or proven clear by the ESDF at its ends); the oracle checks every move's segment
  // against every cube it touches. Random maps as above, some cut by a one-voxel wall that a coarse
  // lattice could step over if moves were not checked.
  int found = 0, no_path = 0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    World world(kRandomDims);
    Rng rng(seed + 100);
    world.fill(VoxelState::kFree);
    addRandomBoxes(world, rng, 6, VoxelState::kUnknown);
    addRandomBoxes(world, rng, 10, VoxelState::kOccupied);
    if (seed % 2 == 0) world.set(Index3(12, 0, 0), Index3(12, 100, 100), VoxelState::kOccupied);
    for (int stride : {2, 3}) {
      AstarConfig config = astarConfig(0.1 * (seed % 3), seed % 4 != 3);
      config.stride = stride;
      const Astar astar(world.occupancy(), world.esdf(), config);
      const GridGeometry& g = world.geo();
      std::vector<std::uint8_t> ok(g.size());
      for (std::size_t l = 0; l < g.size(); ++l) ok[l] = astar.traversable(g.unlinear(l));
      for (int query = 0; query < 4; ++query) {
        Index3 start, goal;
        do start = randomVoxel(rng, g.dims());
        while (!ok[g.linear(start)]);
        const std::vector<double> cost = latticeCosts(g, ok, start, stride);
        for (int k = 0; k < 4; ++k) {
          // A traversable goal on the start's lattice.
          do goal = randomVoxel(rng, g.dims());
          while (!ok[g.linear(goal)] || !onLattice(goal, start, stride));
          SCOPED_TRACE("seed " + std::to_string(seed) + " stride " + std::to_string(stride) + " query " +
                       std::to_string(query) + "/" + std::to_string(k));
          const PathResult r = astar.search(g.indexToCoord(start), g.indexToCoord(goal), 0.0);
          const double want = cost[g.linear(goal)];
          if (want == kInf) {
            EXPECT_EQ(r.status, PathStatus::kNoPath) << toString(r.status);
            ++no_path;
            continue;
          }
          expectWellFormed(astar, r, start, goal, stride);
          EXPECT_NEAR(r.raw_length, want, 1e-9);
          ++found;
        }
      }
    }
  }
  EXPECT_GT(found, 60);
  EXPECT_GT(no_path, 5);
}

TEST(Astar, CoarseLatticeCrossesOpenSpaceInFewExpansionsAndNeverThroughAThinWall) {
  // A hall with a one-voxel wall across it and one doorway: 4-voxel moves (0.4 m, FUEL's grid) with the
  // ESDF proving most of them clear. Same path cost as the exhaustive lattice search, and far fewer
  // expansions than the every-voxel search, which finds a path at most a few moves shorter.
  World world(Index3(80, 60, 20));
  world.fill(VoxelState::kFree);
  world.set(Index3(40, 0, 0), Index3(40, 59, 19), VoxelState::kOccupied);
  world.set(Index3(40, 50, 4), Index3(40, 56, 12), VoxelState::kFree);
  for (bool unknown_is_free : {true, false}) {
    AstarConfig fine_config = astarConfig(0.0, unknown_is_free), coarse_config = fine_config;
    coarse_config.stride = 4;
    const Astar fine(world.occupancy(), world.esdf(), fine_config), coarse(world.occupancy(), world.esdf(), coarse_config);
    const GridGeometry& g = world.geo();
    std::vector<std::uint8_t> ok(g.size());
    for (std::size_t l = 0; l < g.size(); ++l) ok[l] = coarse.traversable(g.unlinear(l));
    const Index3 start(6, 6, 8), goal(74, 6, 8);
    const std::vector<double> cost = latticeCosts(g, ok, start, 4);
    const PathResult c = coarse.search(g.indexToCoord(start), g.indexToCoord(goal), 0.0);
    expectWellFormed(coarse, c, start, goal, 4);
    EXPECT_NEAR(c.raw_length, cost[g.linear(goal)], 1e-9);
    const PathResult f = fine.search(g.indexToCoord(start), g.indexToCoord(goal), 0.0);
    expectWellFormed(fine, f, start, goal);
    EXPECT_GE(c.raw_length, f.raw_length - 1e-9);
    EXPECT_LE(c.length, f.length + 4 * 4 * kRes);
    EXPECT_LT(c.expansions * 10, f.expansions) << c.expansions << " against " << f.expansions;
    // Through the doorway, not the wall: the path crosses x = 40 only at y in the doorway.
    bool crossed = false;
    for (std::size_t i = 1; i < c.raw_path.size(); ++i) {
      const Index3 a = g.coordToIndex(c.raw_path[i - 1]), b = g.coordToIndex(c.raw_path[i]);
      if (a.x() < 40 && b.x() >= 40) {
        crossed = true;
        EXPECT_GE(std::min(a.y(), b.y()), 50);
        EXPECT_LE(std::max(a.y(), b.y()), 56);
      }
    }
    EXPECT_TRUE(crossed);
    // A goal off the lattice is snapped to the nearest lattice voxel within the radius.
    const Vec3 off = g.indexToCoord(Index3(73, 7, 9));
    const PathResult s = coarse.search(g.indexToCoord(start), off, 0.25);
    ASSERT_EQ(s.status, PathStatus::kFound);
    const Index3 end = g.coordToIndex(s.raw_path.back());
    EXPECT_TRUE(onLattice(end, start, 4)) << end.transpose();
    EXPECT_LE((s.raw_path.back() - off).norm(), 0.25);
  }
}

// On the stride-2 lattice a goal off the start's lattice is snapped onto it (within the snap radius), as with
// every other stride: the search ends at a lattice voxel nearest the goal, not in a flood that never meets it.
TEST(Astar, AGoalOffTheStride2LatticeIsSnappedOntoIt) {
  World world(Index3(20, 20, 10));
  world.fill(VoxelState::kFree);
  AstarConfig config = astarConfig(0.0, true);
  config.stride = 2;
  const Astar astar(world.occupancy(), world.esdf(), config);
  const GridGeometry& g = world.geo();
  const Index3 start(4, 4, 4), goal(9, 6, 5);  // 5, 2 and 1 voxels apart: off the lattice in x and z
  const PathResult r = astar.search(g.indexToCoord(start), g.indexToCoord(goal), 0.25);
  ASSERT_EQ(r.status, PathStatus::kFound) << toString(r.status);
  const Index3 end = g.coordToIndex(r.raw_path.back());
  EXPECT_TRUE(onLattice(end, start, 2)) << end.transpose();
  // The nearest lattice voxels lie sqrt(2) voxels away (one step in x and one in z).
  EXPECT_NEAR((r.raw_path.back() - g.indexToCoord(goal)).norm(), std::sqrt(2.0) * kRes, 1e-9);
}

TEST(Astar, CorridorNarrowerThanTwiceTheClearanceIsImpassable) {
  // A wall across the whole grid at x = 15 with a slot of `width` voxels in y over the full height;
  // with clearance 0.25 m the slot needs a voxel 2.5 voxels from both sides.
  for (int width : {2, 4, 6, 8}) {
    World world(Index3(31, 21, 6));
    world.fill(VoxelState::kFree);
    world.set(Index3(15, 0, 0), Index3(15, 20, 5), VoxelState::kOccupied);
    world.set(Index3(15, 7, 0), Index3(15, 6 + width, 5), VoxelState::kFree);
    const Astar astar(world.occupancy(), world.esdf(), astarConfig(0.25, false));
    const Vec3 a = world.geo().indexToCoord(Index3(5, 10, 2)),
               b = world.geo().indexToCoord(Index3(25, 10, 2));
    const PathResult r = astar.search(a, b);
    SCOPED_TRACE("slot width " + std::to_string(width * kRes) + " m");
    if (width * kRes < 2 * 0.25) {
      EXPECT_EQ(r.status, PathStatus::kNoPath) << toString(r.status);
    } else {
      expectWellFormed(astar, r, Index3(5, 10, 2), Index3(25, 10, 2));
      // Without clearance any slot is passable.
    }
    const Astar bare(world.occupancy(), world.esdf(), astarConfig(0.0, false));
    EXPECT_EQ(bare.search(a, b).status, PathStatus::kFound);
  }
}

TEST(Astar, UnknownRegionIsTraversableOnlyWhenUnknownIsFree) {
  World world(Index3(31, 21, 6));
  world.fill(VoxelState::kFree);
  world.set(Index3(15, 0, 0), Index3(15, 20, 5), VoxelState::kOccupied);
  world.set(Index3(15, 6, 0), Index3(15, 14, 5), VoxelState::kFree);
  const Index3 start(5, 10, 2), goal(25, 10, 2);
  const Vec3 a = world.geo().indexToCoord(start), b = world.geo().indexToCoord(goal);
  {
    const Astar safe(world.occupancy(), world.esdf(), astarConfig(0.2, false));
    expectWellFormed(safe, safe.search(a, b), start, goal);
  }
  // Unknown space around the opening.
  world.set(Index3(13, 0, 0), Index3(17, 20, 5), VoxelState::kUnknown);
  world.set(Index3(15, 0, 0), Index3(15, 5, 5), VoxelState::kOccupied);
  world.set(Index3(15, 15, 0), Index3(15, 20, 5), VoxelState::kOccupied);
  const Astar optimistic(world.occupancy(), world.esdf(), astarConfig(0.2, true));
  const PathResult through = optimistic.search(a, b);
  expectWellFormed(optimistic, through, start, goal);
  bool crossed_unknown = false;
  for (const Vec3& p : through.raw_path)
    crossed_unknown |= world.occupancy().state(p) == VoxelState::kUnknown;
  EXPECT_TRUE(crossed_unknown);

  const Astar safe(world.occupancy(), world.esdf(), astarConfig(0.2, false));
  const PathResult blocked = safe.search(a, b);
  EXPECT_EQ(blocked.status, PathStatus::kNoPath) << toString(blocked.status);
  // A known-free path never touches unknown voxels.
  const PathResult same_side = safe.search(a, world.geo().indexToCoord(Index3(8, 3, 4)));
  ASSERT_EQ(same_side.status, PathStatus::kFound);
  for (const Vec3& p : same_side.raw_path) EXPECT_EQ(world.occupancy().state(p), VoxelState::kFree);
}

TEST(Astar, SearchStaysInsideTheGrid) {
  // A wall over the whole cross-section: outside the grid (unknown, hence optimistic) is no way round.
  World world(Index3(20, 10, 5));
  world.fill(VoxelState::kFree);
  world.set(Index3(10, 0, 0), Index3(10, 9, 4), VoxelState::kOccupied);
  const Astar astar(world.occupancy(), world.esdf(), astarConfig(0.0, true));
  const PathResult r = astar.search(Vec3(0.25, 0.55, 0.25), Vec3(1.75, 0.55, 0.25));
  EXPECT_EQ(r.status, PathStatus::kNoPath) << toString(r.status);
  EXPECT_GT(r.expansions, 0);
}

TEST(Astar, BlockedEndsSnapToTheNearestTraversableVoxel) {
  World world(Index3(30, 20, 10));
  world.fill(VoxelState::kFree);
  world.set(Index3(8, 8, 3), Index3(12, 12, 7), VoxelState::kOccupied);
  const Astar astar(world.occupancy(), world.esdf(), astarConfig(0.1, false));
  const GridGeometry& g = world.geo();
  const Vec3 inside_box(1.03, 1.01, 0.52), goal(2.55, 1.55, 0.55);
  ASSERT_FALSE(astar.traversable(g.coordToIndex(inside_box)));

  const PathResult r = astar.search(inside_box, goal, 0.5);
  ASSERT_EQ(r.status, PathStatus::kFound) << toString(r.status);
  const Index3 snapped = g.coordToIndex(r.path.front());
  EXPECT_TRUE(astar.traversable(snapped));
  double nearest = kInf;
  for (std::size_t l = 0; l < g.size(); ++l)
    if (astar.traversable(g.unlinear(l)))
      nearest = std::min(nearest, (g.indexToCoord(g.unlinear(l)) - inside_box).norm());
  EXPECT_NEAR((r.path.front() - inside_box).norm(), nearest, 1e-12);
  EXPECT_LE(nearest, 0.5);
  expectWellFormed(astar, r, snapped, g.coordToIndex(goal));

  EXPECT_EQ(astar.search(inside_box, goal, 0.1).status, PathStatus::kStartBlocked);
  EXPECT_EQ(astar.search(goal, inside_box, 0.1).status, PathStatus::kGoalBlocked);
  const PathResult reverse = astar.search(goal, inside_box, 0.5);
  ASSERT_EQ(reverse.status, PathStatus::kFound);
  EXPECT_EQ(reverse.path.back(), r.path.front());

  // A start just outside the grid snaps inside, to the first voxel clearance (0.1 m) from the box's
  // face; one far away does not.
  const PathResult outside = astar.search(Vec3(-0.2, 0.55, 0.55), goal, 0.5);
  ASSERT_EQ(outside.status, PathStatus::kFound);
  EXPECT_EQ(g.coordToIndex(outside.path.front()), Index3(1, 5, 5));
  EXPECT_EQ(astar.search(Vec3(-50.0, 0.5, 0.5), goal, 0.5).status, PathStatus::kStartBlocked);
  EXPECT_EQ(astar.search(Vec3(std::nan(""), 0.5, 0.5), goal, 0.5).status, PathStatus::kStartBlocked);
}

TEST(Astar, OpenSpaceGoesStraightToTheGoal) {
  World world(Index3(60, 40, 20));
  world.fill(VoxelState::kFree);
  const Astar astar(world.occupancy(), world.esdf(), AstarConfig());
  const Index3 start(2, 2, 3), goal(57, 31, 16);  // both 0.2 m (the clearance) inside the box
  const PathResult r = astar.search(world.geo().indexToCoord(start), world.geo().indexToCoord(goal));
  expectWellFormed(astar, r, start, goal);
  // The heuristic is exact here and ties go towards the goal: only path voxels are expanded.
  EXPECT_EQ(r.expansions, static_cast<int>(r.raw_path.size()));
  ASSERT_EQ(r.path.size(), 2u);
  EXPECT_NEAR(r.length, (world.geo().indexToCoord(goal) - world.geo().indexToCoord(start)).norm(), 1e-9);

  const PathResult same = astar.search(Vec3(0.31, 0.32, 0.33), Vec3(0.39, 0.38, 0.37));
  ASSERT_EQ(same.status, PathStatus::kFound);
  ASSERT_EQ(same.path.size(), 1u);
  EXPECT_EQ(same.length, 0.0);
  EXPECT_EQ(same.expansions, 1);
}

TEST(Astar, BudgetExceededFallsBackToEuclidean) {
  World world(Index3(60, 40, 20));
  world.fill(VoxelState::kFree);
  // A wall with a far-off opening, so that the search has to explore.
  world.set(Index3(30, 0, 0), Index3(30, 39, 19), VoxelState::kOccupied);
  world.set(Index3(30, 36, 0), Index3(30, 39, 3), VoxelState::kFree);
  const Vec3 a(0.55, 0.55, 1.05), b(5.55, 0.55, 1.05);

  AstarConfig small = astarConfig(0.1, true);
  small.max_expansions = 100;
  const Astar starved(world.occupancy(), world.esdf(), small);
  const PathResult r = starved.search(a, b);
  EXPECT_EQ(r.status, PathStatus::kBudgetExceeded) << toString(r.status);
  EXPECT_EQ(r.expansions, 100);
  EXPECT_TRUE(r.path.empty());
  const PathDistance fallback = pathDistance(starved, a, b);
  EXPECT_TRUE(fallback.euclidean_fallback);
  EXPECT_DOUBLE_EQ(fallback.metres, (b - a).norm());

  const Astar astar(world.occupancy(), world.esdf(), astarConfig(0.1, true));
  const PathResult full = astar.search(a, b);
  expectWellFormed(astar, full, world.geo().coordToIndex(a), world.geo().coordToIndex(b));
  EXPECT_GT(full.expansions, 100);
  const PathDistance d = pathDistance(astar, a, b);
  EXPECT_FALSE(d.euclidean_fallback);
  EXPECT_NEAR(d.metres, full.length, 1e-9);   // a and b are voxel centres
  EXPECT_GT(d.metres, (b - a).norm() + 2.0);  // the detour through the opening

  // A large tie_breaker (the fuel mode's greedy search) trades the optimum for fewer expansions: never shorter
  // than the optimal raw path above, found in fewer expansions.
  AstarConfig greedy_config = astarConfig(0.1, true);
  greedy_config.tie_breaker = 10000.0;
  const PathResult greedy = Astar(world.occupancy(), world.esdf(), greedy_config).search(a, b);
  ASSERT_EQ(greedy.status, PathStatus::kFound);
  EXPECT_GE(greedy.raw_length, full.raw_length - 1e-9);
  EXPECT_LT(greedy.expansions, full.expansions / 2);
  // Probes from both ends that run out (50 expansions each) are counted with the search that follows them,
  // which finds the same path.
  AstarConfig probe_config = astarConfig(0.1, true);
  probe_config.probe_expansions = 50;
  const PathResult probed = Astar(world.occupancy(), world.esdf(), probe_config).search(a, b);
  ASSERT_EQ(probed.status, PathStatus::kFound);
  EXPECT_EQ(probed.expansions, full.expansions + 2 * 50);
  EXPECT_EQ(probed.raw_path, full.raw_path);

  // Other failures fall back too: a start far outside the map.
  const Vec3 far(-20.0, 0.5, 1.0);
  const PathDistance blocked = pathDistance(astar, far, b);
  EXPECT_TRUE(blocked.euclidean_fallback);
  EXPECT_DOUBLE_EQ(blocked.metres, (b - far).norm());
}

TEST(Astar, PathDistanceCountsTheSnapsToVoxelCentres) {
  World world(Index3(20, 20, 10));
  world.fill(VoxelState::kFree);
  const Astar astar(world.occupancy(), world.esdf(), AstarConfig());
  const Vec3 a(0.52, 0.51, 0.53), b(1.23, 0.87, 0.61);
  const PathDistance d = pathDistance(astar, a, b);
  EXPECT_FALSE(d.euclidean_fallback);
  EXPECT_GE(d.metres, (b - a).norm() - 1e-12);
  const Vec3 ca = world.geo().indexToCoord(world.geo().coordToIndex(a));
  const Vec3 cb = world.geo().indexToCoord(world.geo().coordToIndex(b));
  EXPECT_NEAR(d.metres, (ca - a).norm() + (cb - ca).norm() + (b - cb).norm(), 1e-9);
}

TEST(Astar, CoarsePathDistanceIsTheStraightLineInPlainSight) {
  World world(Index3(40, 20, 10));
  world.fill(VoxelState::kFree);
  AstarConfig config;
  config.stride = 4;
  const Astar open(world.occupancy(), world.esdf(), config);
  // In plain sight: the straight line, however the lattice lies.
  const Vec3 a(0.52, 0.51, 0.53), b(3.23, 0.87, 0.61);
  ASSERT_TRUE(open.segmentTraversable(a, b));
  const PathDistance d = pathDistance(open, a, b);
  EXPECT_FALSE(d.euclidean_fallback);
  EXPECT_DOUBLE_EQ(d.metres, (b - a).norm());
  // Behind a wall: the lattice path between the snapped ends plus the snaps to them.
  world.set(Index3(18, 0, 0), Index3(19, 14, 9), VoxelState::kOccupied);
  const Astar behind(world.occupancy(), world.esdf(), config);
  ASSERT_FALSE(behind.segmentTraversable(a, b));
  const PathResult r = behind.search(a, b);
  ASSERT_EQ(r.status, PathStatus::kFound);
  const PathDistance around = pathDistance(behind, a, b);
  EXPECT_FALSE(around.euclidean_fallback);
  EXPECT_NEAR(around.metres, (r.path.front() - a).norm() + r.length + (b - r.path.back()).norm(), 1e-9);
  EXPECT_GT(around.metres, (b - a).norm() + 1.0);  // round the wall's end at y = 1.5 m
}

TEST(Astar, CoarseMovePastAVoxelAtItsCornerIsWalkedNotProvenClearByTheEsdf) {
  // With unknown space free and no known surroundings, a lattice move is proven clear by the ESDF at its
  // ends when their distances exceed twice the clearance plus the move's length by the spread of the
  // voxels the move touches round the segment (a half voxel diagonal at each end) and a voxel at each end
  // for ESDF overestimates. The diagonal move from (2,2) to (4,4) crosses the corner the voxel (3,2)
  // shares; with that voxel occupied the ends are 1 and sqrt(5) voxels from it, 0.41 voxel more than the
  // move's length: a bound without the spread takes the move, 0.28 m, through the occupied voxel. The
  // exact walk refuses it, and the path goes round by (2,4), 0.4 m, as the lattice oracle has it.
  World world(Index3(10, 10, 10));
  world.fill(VoxelState::kFree);
  world.set(Index3(3, 2, 4), Index3(3, 2, 4), VoxelState::kOccupied);
  AstarConfig config = astarConfig(0.0, true);
  config.stride = 2;
  const Astar astar(world.occupancy(), world.esdf(), config);
  const GridGeometry& g = world.geo();
  const Index3 start(2, 2, 4), goal(4, 4, 4);
  ASSERT_FALSE(astar.segmentTraversable(g.indexToCoord(start), g.indexToCoord(goal)));
  std::vector<std::uint8_t> ok(g.size());
  for (std::size_t l = 0; l < g.size(); ++l) ok[l] = astar.traversable(g.unlinear(l));
  const double want = latticeCosts(g, ok, start, 2)[g.linear(goal)];
  ASSERT_NEAR(want, 0.4, 1e-9);
  const PathResult r = astar.search(g.indexToCoord(start), g.indexToCoord(goal), 0.0);
  expectWellFormed(astar, r, start, goal, 2);
  EXPECT_NEAR(r.raw_length, want, 1e-9);
}

TEST(Astar, ShortenKeepsCornersAroundObstacles) {
  // An L-shaped path around the corner of a box: the shortcut through the box is refused, the two
  // straight legs are merged.
  World world(Index3(20, 20, 3));
  world.fill(VoxelState::kFree);
  world.set(Index3(5, 5, 0), Index3(19, 19, 2), VoxelState::kOccupied);
  const Astar astar(world.occupancy(), world.esdf(), astarConfig(0.0, false));
  const GridGeometry& g = world.geo();
  std::vector<Vec3> path;
  for (int x = 18; x >= 2; --x) path.push_back(g.indexToCoord(Index3(x, 2, 1)));
  for (int y = 3; y <= 18; ++y) path.push_back(g.indexToCoord(Index3(2, y, 1)));
  const std::vector<Vec3> short_path = astar.shorten(path);
  expectSegmentsTraversable(astar, short_path);
  EXPECT_EQ(short_path.front(), path.front());
  EXPECT_EQ(short_path.back(), path.back());
  EXPECT_LT(short_path.size(), path.size());
  EXPECT_GE(short_path.size(), 3u);
  EXPECT_LE(polylineLength(short_path), polylineLength(path));
  EXPECT_GE(polylineLength(short_path), (path.back() - path.front()).norm());
  EXPECT_FALSE(astar.segmentTraversable(path.front(), path.back()));

  // A diagonal segment through an edge where two voxels meet is refused when either of them is blocked.
  World edge(Index3(4, 4, 1));
  edge.fill(VoxelState::kFree);
  edge.set(Index3(1, 1, 0), Index3(1, 1, 0), VoxelState::kOccupied);
  const Astar tight(edge.occupancy(), edge.esdf(), astarConfig(0.0, false));
  const Vec3 p = edge.geo().indexToCoord(Index3(0, 1, 0)), q = edge.geo().indexToCoord(Index3(2, 3, 0));
  EXPECT_FALSE(tight.segmentTraversable(p, q));
  EXPECT_TRUE(tight.segmentTraversable(p, edge.geo().indexToCoord(Index3(0, 3, 0))));
  EXPECT_EQ(tight.shorten({p}).size(), 1u);

  // Nor does the search squeeze diagonally between two blocked voxels.
  World pocket(Index3(4, 4, 1));
  pocket.fill(VoxelState::kFree);
  pocket.set(Index3(1, 0, 0), Index3(1, 0, 0), VoxelState::kOccupied);
  pocket.set(Index3(0, 1, 0), Index3(0, 1, 0), VoxelState::kOccupied);
  const Astar strict(pocket.occupancy(), pocket.esdf(), astarConfig(0.0, false));
  const PathResult trapped = strict.search(pocket.geo().indexToCoord(Index3(0, 0, 0)),
                                           pocket.geo().indexToCoord(Index3(3, 3, 0)), 0.0);
  EXPECT_EQ(trapped.status, PathStatus::kNoPath) << toString(trapped.status);
  EXPECT_TRUE(tight.shorten({}).empty());
}

// Within snap_radius of the start the known-surroundings rule is waived (the camera has not seen beside a
// hovering vehicle): from a narrow known strip (unknown all around) into a known room, a start within
// snap_radius of the room gets out, and every voxel of its path farther than that from the start obeys the
// full rule; a start farther up the strip cannot leave, after expanding fewer voxels than the ball holds.
TEST(Astar, KnownSurroundingsRuleIsWaivedNearTheStart) {
  World world(Index3(60, 20, 20));
  world.fill(VoxelState::kUnknown);
  world.set(Index3(10, 9, 9), Index3(30, 11, 11), VoxelState::kFree);
  world.set(Index3(30, 2, 2), Index3(55, 17, 17), VoxelState::kFree);
  AstarConfig config = astarConfig(0.2, false);
  config.known_clearance = true;
  const Astar astar(world.occupancy(), world.esdf(), config);
  const double snap_radius = 1.0;
  const Vec3 goal = world.geo().indexToCoord(Index3(45, 10, 10));
  const Index3 near_start(22, 10, 10);
  EXPECT_FALSE(astar.traversable(near_start));  // its own surroundings are unknown
  const PathResult out = astar.search(world.geo().indexToCoord(near_start), goal, snap_radius);
  ASSERT_EQ(out.status, PathStatus::kFound) << toString(out.status);
  EXPECT_EQ(out.raw_path.front(), world.geo().indexToCoord(near_start));  // not snapped away
  for (const Vec3& p : out.raw_path) {
    EXPECT_EQ(world.occupancy().state(p), VoxelState::kFree);
    if ((p - out.raw_path.front()).norm() > snap_radius + 1e-9) {
      EXPECT_TRUE(astar.traversable(world.geo().coordToIndex(p))) << p.transpose();
    }
  }
  // Searched back from the goal (probe_expansions), the waiver is still around the vehicle's start.
  AstarConfig probing_config = config;
  probing_config.probe_expansions = 8;
  const Astar probing(world.occupancy(), world.esdf(), probing_config);
  const PathResult back = probing.search(world.geo().indexToCoord(near_start), goal, snap_radius);
  ASSERT_EQ(back.status, PathStatus::kFound) << toString(back.status);
  EXPECT_GT(back.expansions, 2 * probing_config.probe_expansions);  // found from the goal's side
  EXPECT_EQ(back.raw_path.front(), world.geo().indexToCoord(near_start));
  EXPECT_NEAR(back.raw_length, out.raw_length, 1e-9);
  const PathResult stuck = astar.search(world.geo().indexToCoord(Index3(12, 10, 10)), goal, snap_radius);
  EXPECT_EQ(stuck.status, PathStatus::kNoPath) << toString(stuck.status);
  const double r = snap_radius / kRes;
  EXPECT_LT(stuck.expansions, 4.0 / 3.0 * M_PI * r * r * r);
  EXPECT_GT(stuck.expansions, 0);
}

TEST(Astar, CoarseLatticeWaivesTheKnownSurroundingsRuleNearTheStartToo) {
  // The flight search's rules on a 0.2 m lattice (the retry of a flight search over budget): a vehicle in
  // a known tube whose surroundings are unseen must be able to leave on it as on the every-voxel lattice.
  // Oracle: the exhaustive lattice search over voxels that pass the rule without surroundings within
  // snap_radius of the start and the full rule elsewhere, every touched voxel of each move checked.
  World world(Index3(60, 20, 20));
  world.fill(VoxelState::kUnknown);
  world.set(Index3(10, 9, 9), Index3(30, 11, 11), VoxelState::kFree);
  world.set(Index3(30, 2, 2), Index3(55, 17, 17), VoxelState::kFree);
  world.set(Index3(40, 2, 2), Index3(41, 12, 17), VoxelState::kOccupied);  // a wall to go round
  AstarConfig config = astarConfig(0.2, false);
  config.known_clearance = true;
  config.stride = 2;
  const Astar astar(world.occupancy(), world.esdf(), config);
  AstarConfig bare = config;
  bare.known_clearance = false;
  const GridGeometry& g = world.geo();
  const std::vector<std::uint8_t> full = bruteForceTraversable(world, config);
  const std::vector<std::uint8_t> near = bruteForceTraversable(world, bare);
  const double snap_radius = 1.0;
  const double exempt = snap_radius / kRes;
  const Index3 start(22, 10, 10), goal(48, 10, 10);
  ASSERT_FALSE(full[g.linear(start)]);  // its own surroundings are unknown
  std::vector<std::uint8_t> ok(g.size());
  for (std::size_t l = 0; l < g.size(); ++l)
    ok[l] = (g.unlinear(l) - start).squaredNorm() <= std::floor(exempt * exempt) ? near[l] : full[l];
  const double want = latticeCosts(g, ok, start, 2)[g.linear(goal)];
  ASSERT_LT(want, kInf);
  const PathResult r = astar.search(g.indexToCoord(start), g.indexToCoord(goal), snap_radius);
  ASSERT_EQ(r.status, PathStatus::kFound) << toString(r.status);
  EXPECT_EQ(r.raw_path.front(), g.indexToCoord(start));
  EXPECT_NEAR(r.raw_length, want, 1e-9);
  EXPECT_GT(r.raw_length, (g.indexToCoord(goal) - g.indexToCoord(start)).norm() + 0.2);  // round the wall
  for (std::size_t i = 1; i < r.raw_path.size(); ++i)
    EXPECT_TRUE(segmentOk(g, ok, g.coordToIndex(r.raw_path[i - 1]), g.coordToIndex(r.raw_path[i]))) << i;
  // From deeper in the tube, farther than snap_radius from known surroundings: no way out.
  const PathResult stuck = astar.search(g.indexToCoord(Index3(12, 10, 10)), g.indexToCoord(goal), snap_radius);
  EXPECT_EQ(stuck.status, PathStatus::kNoPath) << toString(stuck.status);
}

// A search that finds no path returns, in `toward`, the shortened path to the expanded voxel nearest
// the goal: through a wall without an opening, the voxel next to the wall in front of the goal; with the
// budget exhausted, a path that ends nearer the goal than the start. A found path has none.
TEST(Astar, FailedSearchesPointTowardTheGoal) {
  World world(Index3(40, 20, 10));
  world.fill(VoxelState::kFree);
  world.set(Index3(25, 0, 0), Index3(25, 19, 9), VoxelState::kOccupied);
  const Astar astar(world.occupancy(), world.esdf(), astarConfig(0.2, false));
  const Vec3 start = world.geo().indexToCoord(Index3(5, 5, 5)), goal = world.geo().indexToCoord(Index3(35, 10, 5));
  const PathResult walled = astar.search(start, goal);
  ASSERT_EQ(walled.status, PathStatus::kNoPath);
  ASSERT_GE(walled.toward.size(), 2u);
  EXPECT_EQ(walled.toward.front(), start);
  // Nearest by the lattice distance: on the goal's row and level, as close to the wall as the clearance lets.
  EXPECT_EQ(world.geo().coordToIndex(walled.toward.back()), Index3(23, 10, 5));
  for (std::size_t i = 1; i < walled.toward.size(); ++i)
    EXPECT_TRUE(astar.segmentTraversable(walled.toward[i - 1], walled.toward[i]));

  world.set(Index3(25, 0, 0), Index3(25, 19, 9), VoxelState::kFree);
  AstarConfig small = astarConfig(0.2, false);
  small.max_expansions = 10;
  const Astar budget(world.occupancy(), world.esdf(), small);
  const PathResult ran_out = budget.search(start, goal);
  ASSERT_EQ(ran_out.status, PathStatus::kBudgetExceeded);
  ASSERT_FALSE(ran_out.toward.empty());
  EXPECT_LT((ran_out.toward.back() - goal).norm(), (start - goal).norm() - 0.5);
  const PathResult found = astar.search(start, goal);
  ASSERT_EQ(found.status, PathStatus::kFound);
  EXPECT_TRUE(found.toward.empty());
}

// A goal in a sealed pocket: a plain search floods the start's whole side before it gives up; with
// probe_expansions the search from the goal runs out of pocket and fails at once, still pointing toward
// the goal. A goal around a wall is found from its side with the same length.
TEST(Astar, ProbeFromTheGoalFailsFastWhenTheGoalIsCutOff) {
  World world(Index3(80, 60, 20));
  world.fill(VoxelState::kFree);
  world.set(Index3(60, 20, 4), Index3(68, 28, 12), VoxelState::kOccupied);
  world.set(Index3(62, 22, 6), Index3(66, 26, 10), VoxelState::kFree);  // the pocket: 5^3 voxels inside a shell
  const Vec3 start = world.geo().indexToCoord(Index3(5, 5, 8)), goal = world.geo().indexToCoord(Index3(64, 24, 8));
  const Astar plain(world.occupancy(), world.esdf(), astarConfig(0.0, false));
  const PathResult flood = plain.search(start, goal);
  EXPECT_EQ(flood.status, PathStatus::kNoPath) << toString(flood.status);
  EXPECT_GT(flood.expansions, 50000);

  AstarConfig config = astarConfig(0.0, false);
  config.probe_expansions = 500;
  const Astar probing(world.occupancy(), world.esdf(), config);
  const PathResult fast = probing.search(start, goal);
  EXPECT_EQ(fast.status, PathStatus::kNoPath) << toString(fast.status);
  EXPECT_LE(fast.expansions, 500 + 125 + 1);
  ASSERT_GE(fast.toward.size(), 2u);
  EXPECT_EQ(fast.toward.front(), start);
  EXPECT_LT((fast.toward.back() - goal).norm(), (start - goal).norm() - 1.0);

  // The pocket opened through a corridor on its far side: the long way round, as short as without probing.
  world.set(Index3(67, 24, 8), Index3(79, 24, 8), VoxelState::kFree);
  const Astar plain_open(world.occupancy(), world.esdf(), astarConfig(0.0, false));
  const Astar probing_open(world.occupancy(), world.esdf(), config);
  const PathResult want = plain_open.search(start, goal);
  const PathResult got = probing_open.search(start, goal);
  ASSERT_EQ(want.status, PathStatus::kFound) << toString(want.status);
  expectWellFormed(probing_open, got, world.geo().coordToIndex(start), world.geo().coordToIndex(goal));
  EXPECT_NEAR(got.raw_length, want.raw_length, 1e-9);
}

namespace {

// Free space split by a wall with one gap (y >= 3 m): frontiers on either side are far apart by path.
void splitByWallWithGap(World& world) {
  world.fill(VoxelState::kFree);
  world.set(Index3(30, 0, 0), Index3(31, 29, 9), VoxelState::kOccupied);
}

// The same wall with no gap: x >= 3.2 m is cut off.
void cutOffByWall(World& world) {
  world.fill(VoxelState::kFree);
  world.set(Index3(30, 0, 0), Index3(31, 39, 9), VoxelState::kOccupied);
}

// Free space everywhere.
void openWorld(World& world) { world.fill(VoxelState::kFree); }

// The TourPlanner tests' world, 6 x 4 x 1 m shaped by `shape`, its distance search, and a config that prices
// every frontier's leg from the UAV by path (s_near 100 m); each test sets what else it varies.
struct TourWorld {
  explicit TourWorld(void (*shape)(World&)) { shape(world); }
  World world{Index3(60, 40, 10)};
  const Astar astar{world.occupancy(), world.esdf(), astarConfig(0.2, true)};
  go_feap::planning::GlobalPlannerConfig config = [] {
    go_feap::planning::GlobalPlannerConfig c;
    c.s_near = 100.0;
    return c;
  }();
};

// Two frontiers either side of cutOffByWall's wall: id 1 beyond it, id 2 on the UAV's side.
std::vector<go_feap::planning::FrontierSummary> acrossTheWall() {
  std::vector<go_feap::planning::FrontierSummary> frontiers(2);
  frontiers[0].id = 1, frontiers[0].average = Vec3(4.5, 1.0, 0.5);
  frontiers[1].id = 2, frontiers[1].average = Vec3(1.5, 1.0, 0.5);
  for (auto& f : frontiers) f.cell_count = 100;
  return frontiers;
}

}  // namespace

TEST(TourPlanner, SearchesEachPairOnceAndFindsTheShortestOpenTour) {
  TourWorld tour_world(splitByWallWithGap);
  auto& [world, astar, config] = tour_world;
  config.lambda = 0.0;  // travel time only: the brute force below is the whole objective
  go_feap::planning::TourPlanner planner(config, astar);
  std::vector<go_feap::planning::FrontierSummary> frontiers;
  const std::vector<Vec3> at{Vec3(1.0, 1.0, 0.5), Vec3(5.0, 0.8, 0.5), Vec3(2.5, 3.5, 0.5), Vec3(4.0, 2.5, 0.5),
                             Vec3(0.6, 3.0, 0.5)};
  for (std::size_t k = 0; k < at.size(); ++k) {
    go_feap::planning::FrontierSummary f;
    f.id = static_cast<unsigned>(10 * (k + 1) % 7 + 1);  // ids not in list order
    f.average = at[k];
    f.cell_count = 100;
    frontiers.push_back(f);
  }
  const Vec3 uav(2.0, 0.5, 0.5);
  const auto tour = planner.plan(frontiers, uav, 0.0);
  ASSERT_TRUE(tour) << tour.message();
  const std::size_t n = frontiers.size();
  ASSERT_EQ(tour->indices.size(), n);
  EXPECT_EQ(planner.cacheSize(), n * (n - 1) / 2);  // one search per unordered pair

  // Brute force over every order, with the same path lengths (one per pair, the lower id first).
  auto between = [&](std::size_t i, std::size_t j) {
    if (frontiers[j].id < frontiers[i].id) std::swap(i, j);
    return pathDistance(astar, frontiers[i].average, frontiers[j].average).metres;
  };
  std::vector<std::size_t> order(n);
  for (std::size_t k = 0; k < n; ++k) order[k] = k;
  double best = kInf;
  do {
    double s = pathDistance(astar, uav, frontiers[order[0]].average).metres;
    for (std::size_t k = 1; k < n; ++k) s += between(order[k - 1], order[k]);
    best = std::min(best, s / config.v_max);
  } while (std::next_permutation(order.begin(), order.end()));
  EXPECT_NEAR(tour->cost, best, 1e-9);

  // Planning again searches nothing new; a frontier that is gone takes its pairs with it.
  ASSERT_TRUE(planner.plan(frontiers, uav, 0.0));
  EXPECT_EQ(planner.cacheSize(), n * (n - 1) / 2);
  frontiers.pop_back();
  ASSERT_TRUE(planner.plan(frontiers, uav, 0.0));
  EXPECT_EQ(planner.cacheSize(), (n - 1) * (n - 2) / 2);
}

// Distances that fell back to a straight line are counted once each: the tour solver asks for a pair
// both ways round and again when pricing rests, and each ask used to count.
TEST(TourPlanner, CountsEachEuclideanFallbackOnce) {
  TourWorld tour_world(cutOffByWall);
  auto& [world, astar, config] = tour_world;
  go_feap::planning::TourPlanner planner(config, astar);
  std::vector<go_feap::planning::FrontierSummary> frontiers;
  const std::vector<Vec3> at{Vec3(1.0, 1.0, 0.5), Vec3(2.5, 3.0, 0.5), Vec3(5.0, 2.0, 0.5)};  // the last cut off
  for (std::size_t k = 0; k < at.size(); ++k) {
    go_feap::planning::FrontierSummary f;
    f.id = static_cast<unsigned>(k + 1);
    f.average = at[k];
    f.cell_count = 100;
    frontiers.push_back(f);
  }
  for (int round = 0; round < 2; ++round) {  // the second round reads every pair from the cache
    std::size_t fallbacks = 0;
    ASSERT_TRUE(planner.plan(frontiers, Vec3(2.0, 0.5, 0.5), 0.0, &fallbacks));
    // From the UAV to the cut-off frontier, and from each of the other two to it.
    EXPECT_EQ(fallbacks, 3u) << "round " << round;
  }
}

// A length that fell back to a straight line (the frontier cut off in the known map) is kept for reuse_time
// only, then searched again: once a way has opened, the pair is priced by it. Kept for the pair's life, the
// straight line (3 m across the wall) stood for a way round of about 6 m as long as both frontiers lived.
TEST(TourPlanner, SearchesAFallenBackLengthAgainAfterReuseTime) {
  TourWorld tour_world(cutOffByWall);
  auto& [world, astar, config] = tour_world;
  config.lambda = 0.0;  // travel time only
  config.reuse_cell = 0.0;  // no reuse between cells: every search is one for the pair
  config.reuse_time = 1.0;
  go_feap::planning::TourPlanner planner(config, astar);
  std::vector<go_feap::planning::FrontierSummary> frontiers = acrossTheWall();
  const Vec3 uav = frontiers[1].average + Vec3(0.0, 0.4, 0.0);
  const double straight = (frontiers[0].average - frontiers[1].average).norm();
  ASSERT_TRUE(pathDistance(astar, frontiers[1].average, frontiers[0].average).euclidean_fallback);
  std::size_t fallbacks = 0;
  ASSERT_TRUE(planner.plan(frontiers, uav, 0.0, &fallbacks));
  EXPECT_EQ(fallbacks, 2u);  // from the UAV to the far frontier, and between the two
  const std::size_t searched = planner.searches();

  world.set(Index3(30, 34, 0), Index3(31, 39, 9), VoxelState::kFree);  // a way round opens at y >= 3.4 m
  const auto round = pathDistance(astar, frontiers[1].average, frontiers[0].average);
  ASSERT_FALSE(round.euclidean_fallback);
  ASSERT_GT(round.metres, straight + 2.5);
  // Within reuse_time the pair's length is the kept straight line (the two legs from the UAV are searched
  // at every call): two searches, one fallback left.
  ASSERT_TRUE(planner.plan(frontiers, uav, 0.5, &fallbacks));
  EXPECT_EQ(planner.searches(), searched + 2);
  EXPECT_EQ(fallbacks, 1u);
  // Past it the pair is searched again and priced by the way round.
  const auto tour = planner.plan(frontiers, uav, 1.6, &fallbacks);
  ASSERT_TRUE(tour) << tour.message();
  EXPECT_EQ(planner.searches(), searched + 5);
  EXPECT_EQ(fallbacks, 0u);
  ASSERT_EQ(tour->frontier_ids, (std::vector<unsigned>{2, 1}));
  const double from_uav = pathDistance(astar, uav, frontiers[1].average).metres;
  EXPECT_NEAR(tour->cost, (from_uav + round.metres) / config.v_max, 1e-9);
  // A found length stays for the pair's life, however long.
  ASSERT_TRUE(planner.plan(frontiers, uav, 100.0));
  EXPECT_EQ(planner.searches(), searched + 7);  // the legs from the UAV only
}

// A fallen-back length from a later clock (a bag played again with the planner kept) is searched again at
// once: its age is unknown. Kept, the straight line across the wall priced a way round that had opened.
TEST(TourPlanner, AFallenBackLengthFromALaterClockIsSearchedAgain) {
  TourWorld tour_world(cutOffByWall);
  auto& [world, astar, config] = tour_world;
  config.reuse_cell = 0.0;
  config.reuse_time = 1.0;
  go_feap::planning::TourPlanner planner(config, astar);
  std::vector<go_feap::planning::FrontierSummary> frontiers = acrossTheWall();
  const Vec3 uav = frontiers[1].average + Vec3(0.0, 0.4, 0.0);
  std::size_t fallbacks = 0;
  ASSERT_TRUE(planner.plan(frontiers, uav, 100.0, &fallbacks));
  ASSERT_EQ(fallbacks, 2u);
  world.set(Index3(30, 34, 0), Index3(31, 39, 9), VoxelState::kFree);  // a way round opens
  ASSERT_TRUE(planner.plan(frontiers, uav, 5.0, &fallbacks));
  EXPECT_EQ(fallbacks, 0u) << "the straight line from the later clock was kept";
}

// Lengths are cached by id pair, and checked against the averages they were searched between: the same ids
// at other places (a frontier list from a bag or a tool, whose ids mean other frontiers) are searched again.
TEST(TourPlanner, TheSameIdsElsewhereAreSearchedAgain) {
  TourWorld tour_world(splitByWallWithGap);
  auto& [world, astar, config] = tour_world;
  config.lambda = 0.0;
  config.reuse_cell = 0.0;
  go_feap::planning::TourPlanner planner(config, astar);
  std::vector<go_feap::planning::FrontierSummary> frontiers(2);
  frontiers[0].id = 1, frontiers[0].average = Vec3(1.0, 1.0, 0.5);
  frontiers[1].id = 2, frontiers[1].average = Vec3(2.5, 1.0, 0.5);  // the wall's near side
  for (auto& f : frontiers) f.cell_count = 100;
  const Vec3 uav(0.5, 1.0, 0.5);
  ASSERT_TRUE(planner.plan(frontiers, uav, 0.0));
  frontiers[1].average = Vec3(4.0, 1.0, 0.5);  // id 2 now beyond the wall: the way round through the gap
  const auto tour = planner.plan(frontiers, uav, 0.1);
  ASSERT_TRUE(tour) << tour.message();
  ASSERT_EQ(tour->frontier_ids, (std::vector<unsigned>{1, 2}));
  const double want = pathDistance(astar, uav, frontiers[0].average).metres +
                      pathDistance(astar, frontiers[0].average, frontiers[1].average).metres;
  EXPECT_NEAR(tour->cost, want / config.v_max, 1e-9);
}

// Reuse cells are floors of the coordinates over reuse_cell, negative ones too: points 0.2 m apart either
// side of 0 lie in two cells (truncated, the cell round 0 was twice as wide, and a length was reused
// 0.8 m off). The pillar and office scenes straddle 0.
TEST(TourPlanner, ReuseCellsEitherSideOfZeroAreTwo) {
  TourWorld tour_world(openWorld);
  auto& [world, astar, config] = tour_world;
  config.reuse_cell = 0.4;
  config.reuse_time = 10.0;
  go_feap::planning::TourPlanner planner(config, astar);
  const Vec3 uav(1.0, 1.0, 0.5);
  std::vector<go_feap::planning::FrontierSummary> one(1);
  one[0].id = 1, one[0].average = Vec3(-0.1, 1.0, 0.5), one[0].cell_count = 100;
  ASSERT_TRUE(planner.plan(one, uav, 0.0));
  const std::size_t searched = planner.searches();
  one[0].id = 2, one[0].average = Vec3(0.1, 1.0, 0.5);  // the next cell
  ASSERT_TRUE(planner.plan(one, uav, 0.1));
  EXPECT_EQ(planner.searches(), searched + 1);
  one[0].id = 3, one[0].average = Vec3(0.3, 1.0, 0.5);  // the same cell as 0.1
  ASSERT_TRUE(planner.plan(one, uav, 0.2));
  EXPECT_EQ(planner.searches(), searched + 1);
}

// Beyond the n_max_tsp nearest by straight line (a lower bound of the path), no frontier's path from the UAV
// is searched: 30 frontiers in open space, all within s_near, cost about the cap's searches from the UAV,
// not 30.
TEST(TourPlanner, FrontiersThatCannotBeCandidatesAreNotSearchedFromTheUav) {
  TourWorld tour_world(openWorld);
  auto& [world, astar, config] = tour_world;
  config.reuse_cell = 0.0;
  go_feap::planning::TourPlanner planner(config, astar);
  std::vector<go_feap::planning::FrontierSummary> frontiers;
  for (int k = 0; k < 30; ++k) {
    go_feap::planning::FrontierSummary f;
    f.id = static_cast<unsigned>(k + 1);
    f.average = Vec3(0.5 + 0.18 * k, 0.5 + 0.1 * (k % 3), 0.5);
    f.cell_count = 100;
    frontiers.push_back(f);
  }
  ASSERT_TRUE(planner.plan(frontiers, Vec3(0.3, 0.5, 0.5), 0.0));
  const std::size_t from_uav = planner.searches() - planner.cacheSize();  // each cached pair one search
  std::cout << from_uav << " searches from the UAV, " << planner.cacheSize() << " pairs\n";
  EXPECT_LE(from_uav, static_cast<std::size_t>(config.n_max_tsp + config.rest_frontiers + 2));
}

// Candidates topped up from beyond s_near are chosen by straight-line distance, but their legs from the
// UAV are priced by path: a frontier 2 m away behind the wall (about 6 m by path through the gap) used to
// be priced at 2 m and visited first, ahead of one 2.9 m away on the UAV's side.
TEST(TourPlanner, CandidatesBeyondSNearArePricedByPathFromTheUav) {
  TourWorld tour_world(splitByWallWithGap);
  auto& [world, astar, config] = tour_world;
  config.lambda = 0.0;  // travel time only: the brute force below is the whole objective
  config.s_near = 1.0;  // both beyond: topped up (n_min_tsp 2)
  config.n_min_tsp = 2;
  config.rest_weight = 0.0;
  const Vec3 uav(2.0, 0.5, 0.5);
  std::vector<go_feap::planning::FrontierSummary> frontiers(2);
  frontiers[0].id = 1, frontiers[0].average = Vec3(4.0, 0.5, 0.5);  // behind the wall
  frontiers[1].id = 2, frontiers[1].average = Vec3(0.5, 3.0, 0.5);  // the UAV's side
  for (auto& f : frontiers) f.cell_count = 100;
  const double behind = pathDistance(astar, uav, frontiers[0].average).metres;
  const double beside = pathDistance(astar, uav, frontiers[1].average).metres;
  const double between = pathDistance(astar, frontiers[0].average, frontiers[1].average).metres;
  ASSERT_GT(behind, beside + 2.0);  // the test's premise: behind the wall is far by path
  ASSERT_LT((frontiers[0].average - uav).norm(), (frontiers[1].average - uav).norm());  // near in line
  go_feap::planning::TourPlanner planner(config, astar);
  const auto tour = planner.plan(frontiers, uav, 0.0);
  ASSERT_TRUE(tour) << tour.message();
  ASSERT_EQ(tour->frontier_ids.size(), 2u);
  EXPECT_EQ(tour->frontier_ids.front(), 2u) << "the frontier behind the wall was visited first";
  EXPECT_NEAR(tour->cost, (std::min(behind, beside) + between) / config.v_max, 1e-9);
}

// What the tour planner takes from a frontier: the bench's go_feap mode weighs frontiers by these, so a
// field lost here (N_near, say) would silently plan without the omission terms.
TEST(TourPlanner, SummarizeKeepsWhatTheOmissionTermsWeigh) {
  go_feap::frontier::Frontier f;
  f.id = 7;
  f.cells.assign(10, Index3(1, 2, 3));
  f.average = Vec3(1.5, -2.0, 0.75);
  f.first_seen = 2.0;
  f.n_near = 2;
  f.active = false;
  const go_feap::planning::FrontierSummary s = go_feap::planning::summarize(f, 5.0);
  EXPECT_EQ(s.id, 7u);
  EXPECT_EQ(s.cell_count, 10);
  EXPECT_EQ(s.average, f.average);
  EXPECT_DOUBLE_EQ(s.duration, 3.0);
  EXPECT_EQ(s.n_near, 2);
  EXPECT_FALSE(s.active);
  EXPECT_DOUBLE_EQ(go_feap::planning::summarize(f, 1.0).duration, 0.0);  // a clock that went back
  f.active = true;
  EXPECT_TRUE(go_feap::planning::summarize(f, 5.0).active);
}

// Regrown clusters (new ids, averages moved a little) and a UAV that moved a little reuse the lengths
// searched between the same reuse_cell cells for reuse_time s, either way round; after that, or with
// reuse_cell 0, they are searched again.
TEST(TourPlanner, ReusesLengthsBetweenTheSameCellsForReuseTime) {
  TourWorld tour_world(splitByWallWithGap);
  auto& [world, astar, config] = tour_world;
  config.reuse_cell = 0.4;
  config.reuse_time = 1.0;
  // Cell centres (0.4 m cells from the origin), so that a 0.1 m move stays in the cell.
  const std::vector<Vec3> at{Vec3(1.0, 1.0, 0.6), Vec3(5.0, 0.6, 0.6), Vec3(2.6, 3.4, 0.6), Vec3(4.2, 2.6, 0.6)};
  auto summaries = [&](unsigned first_id, const Vec3& shift, bool reversed_ids) {
    std::vector<go_feap::planning::FrontierSummary> out;
    for (std::size_t k = 0; k < at.size(); ++k) {
      go_feap::planning::FrontierSummary f;
      f.id = first_id + static_cast<unsigned>(reversed_ids ? at.size() - 1 - k : k);
      f.average = at[k] + shift;
      f.cell_count = 100;
      out.push_back(f);
    }
    return out;
  };
  const Vec3 uav(2.2, 0.6, 0.6);
  const std::size_t n = at.size(), fresh = n + n * (n - 1) / 2;  // from the UAV, and between pairs

  go_feap::planning::TourPlanner planner(config, astar);
  const auto first = planner.plan(summaries(1, Vec3::Zero(), false), uav, 0.0);
  ASSERT_TRUE(first) << first.message();
  EXPECT_EQ(planner.searches(), fresh);
  // New ids in the other order (each pair searched from its other end), everything 0.1 m away: no search.
  const Vec3 shift(0.1, -0.1, 0.05);
  const auto again = planner.plan(summaries(100, shift, true), uav + shift, 0.5);
  ASSERT_TRUE(again) << again.message();
  EXPECT_EQ(planner.searches(), fresh);
  EXPECT_NEAR(again->cost, first->cost, 1e-9);
  std::vector<Vec3> first_at, again_at;
  for (const Vec3& p : first->waypoints) first_at.push_back(p);
  for (const Vec3& p : again->waypoints) again_at.push_back(p - shift);
  EXPECT_EQ(first_at, again_at);  // the same order
  // 1.5 s after they were searched the lengths have expired: new ids search everything again.
  ASSERT_TRUE(planner.plan(summaries(200, shift, false), uav, 1.5));
  EXPECT_EQ(planner.searches(), 2 * fresh);
  // A frontier moved into another cell is searched anew (its pairs and its length from the UAV).
  auto moved = summaries(300, shift, false);
  moved[0].average += Vec3(0.4, 0.0, 0.0);
  ASSERT_TRUE(planner.plan(moved, uav, 1.6));
  EXPECT_EQ(planner.searches(), 2 * fresh + n);
  // A clock that went back (a bag played again, the planner kept) drops what was searched "later": the map
  // they were searched in is gone.
  go_feap::planning::TourPlanner rewound(config, astar);
  ASSERT_TRUE(rewound.plan(summaries(1, Vec3::Zero(), false), uav, 10.0));
  ASSERT_TRUE(rewound.plan(summaries(100, shift, true), uav + shift, 2.0));
  EXPECT_EQ(rewound.searches(), 2 * fresh);

  config.reuse_cell = 0.0;  // never reused
  go_feap::planning::TourPlanner plain(config, astar);
  ASSERT_TRUE(plain.plan(summaries(1, Vec3::Zero(), false), uav, 0.0));
  ASSERT_TRUE(plain.plan(summaries(100, shift, true), uav + shift, 0.5));
  EXPECT_EQ(plain.searches(), 2 * fresh);

  for (double bad : {-0.1, kInf}) {
    go_feap::planning::GlobalPlannerConfig c;
    c.reuse_cell = bad;
    EXPECT_NE(c.validate().message().find("reuse_cell"), std::string::npos);
    c = go_feap::planning::GlobalPlannerConfig();
    c.reuse_time = bad;
    EXPECT_NE(c.validate().message().find("reuse_time"), std::string::npos);
  }
}

// The last tour warm-starts the next: frontiers on a line, a planner that first planned from the left end
// (so its tour runs left to right) and one that planned from the right end, then both plan from the
// middle, where going either way first costs the same. Each gets what planTour() gives with its own last
// tour as the hint, and the two differ, so a planner that dropped its hint or kept another's would give
// one of them the other's tour; a planner without a last tour gets the cold tour. (A coarse lattice
// answers pairs in plain sight by the straight line, and the positions are binary fractions, so the ties
// are exact: the solver keeps a warm start that nothing beats strictly.)
TEST(TourPlanner, TheLastTourWarmStartsTheNext) {
  TourWorld tour_world(openWorld);
  auto& [world, fine_astar, config] = tour_world;
  AstarConfig coarse = fine_astar.config();
  coarse.stride = 2;
  const Astar astar(world.occupancy(), world.esdf(), coarse);
  config.lambda = 0.0;
  config.max_exact = 0;  // heuristic: exact solving ignores hints
  std::vector<go_feap::planning::FrontierSummary> frontiers;
  for (unsigned k = 0; k < 8; ++k) {
    go_feap::planning::FrontierSummary f;
    f.id = 20 - 2 * k;  // ids against the order along the line
    f.average = Vec3(0.5 * (k < 4 ? k + 1 : k + 3), 2.0, 0.5);
    f.cell_count = 100;
    frontiers.push_back(f);
  }
  const Vec3 middle(2.75, 2.0, 0.5);
  go_feap::planning::PathDistances d;  // the lengths TourPlanner searches, from the middle
  d.from_uav = [&](std::size_t j) { return pathDistance(astar, middle, frontiers[j].average).metres; };
  d.between = [&](std::size_t i, std::size_t j) {
    return pathDistance(astar, frontiers[i].average, frontiers[j].average).metres;
  };
  std::vector<std::vector<unsigned>> expected;
  for (const Vec3& start : {Vec3(0.25, 2.0, 0.5), Vec3(5.25, 2.0, 0.5)}) {
    go_feap::planning::TourPlanner planner(config, astar);
    const auto first = planner.plan(frontiers, start, 0.0);
    ASSERT_TRUE(first) << first.message();
    const auto hinted = go_feap::planning::planTour(frontiers, d, config, first->frontier_ids);
    ASSERT_TRUE(hinted.ok()) << hinted.message();
    const auto again = planner.plan(frontiers, middle, 1.0);
    ASSERT_TRUE(again) << again.message();
    EXPECT_EQ(again->frontier_ids, hinted->frontier_ids);
    expected.push_back(hinted->frontier_ids);
  }
  ASSERT_NE(expected[0], expected[1]);  // else the hint would not show
  go_feap::planning::TourPlanner cold(config, astar);
  const auto tour = cold.plan(frontiers, middle, 0.0);
  ASSERT_TRUE(tour) << tour.message();
  EXPECT_EQ(tour->frontier_ids, go_feap::planning::planTour(frontiers, d, config)->frontier_ids);
}
