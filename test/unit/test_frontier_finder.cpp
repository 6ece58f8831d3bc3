// Frontier detection against hand-built grids and a full recomputation.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <random>
#include <set>

#include "go_feap/frontier/frontier_finder.h"

using namespace go_feap;
using common::Aabb;
using common::Index3;
using common::Vec3;
using map::VoxelState;

namespace {

const Aabb kBox{Vec3(0, 0, 0), Vec3(3.0, 2.0, 1.0)};  // 30 x 20 x 10 voxels

map::OccupancyConfig mapConfig() {
  map::OccupancyConfig c;
  c.margin = 0.3;
  return c;
}

// Sets every voxel whose centre lies in [lo, hi] (metres) to s; returns the index range.
std::pair<Index3, Index3> paint(map::OccupancyMap& m, const Vec3& lo, const Vec3& hi, VoxelState s) {
  Index3 a, b;
  m.geometry().centreRange({lo, hi}, a, b);
  for (int z = a.z(); z < b.z(); ++z)
    for (int y = a.y(); y < b.y(); ++y)
      for (int x = a.x(); x < b.x(); ++x) m.setState(Index3(x, y, z), s);
  return {a, b - Index3::Ones()};
}

std::set<std::vector<std::size_t>> clusterSets(const frontier::FrontierFinder& f, const common::GridGeometry& g) {
  std::set<std::vector<std::size_t>> out;
  for (const auto& fr : f.frontiers()) {
    std::vector<std::size_t> v;
    for (const Index3& c : fr.cells) v.push_back(g.linear(c));
    std::sort(v.begin(), v.end());
    out.insert(v);
  }
  return out;
}

}  // namespace

TEST(FrontierFinder, KnownFreeBlockInUnknownSpace) {
  map::OccupancyMap m(mapConfig(), kBox);
  // Known free block x in [1.0, 2.0], y in [0.5, 1.5], whole height; the rest unknown.
  paint(m, Vec3(1.0, 0.5, 0.0), Vec3(2.0, 1.5, 1.0), VoxelState::kFree);
  frontier::FrontierConfig cfg;
  cfg.max_cluster_extent = 100.0;
  frontier::FrontierFinder f(cfg, m.geometry(), kBox);
  f.recomputeAll(m, 0.0);
  // Expected: the block's cells on its four x/y side faces (top and bottom border the
  // box: no unknown neighbour inside it).
  std::set<std::size_t> expect, got;
  const auto& g = m.geometry();
  for (std::size_t l = 0; l < g.size(); ++l) {
    const Vec3 c = g.indexToCoord(g.unlinear(l));
    const bool in_block = c.x() > 1.0 && c.x() < 2.0 && c.y() > 0.5 && c.y() < 1.5 && c.z() > 0.0 && c.z() < 1.0;
    const bool side = std::abs(c.x() - 1.05) < 1e-6 || std::abs(c.x() - 1.95) < 1e-6 || std::abs(c.y() - 0.55) < 1e-6 ||
                      std::abs(c.y() - 1.45) < 1e-6;
    if (in_block && side) expect.insert(l);
  }
  for (const auto& fr : f.frontiers())
    for (const Index3& c : fr.cells) got.insert(g.linear(c));
  EXPECT_EQ(expect.size(), 36u * 10);
  EXPECT_EQ(got, expect);
  ASSERT_EQ(f.frontiers().size(), 1u);  // one connected ring
  EXPECT_LT((f.frontiers()[0].average - Vec3(1.5, 1.0, 0.5)).norm(), 1e-9);
  // Its box B is that of the cell cubes (Frontier.msg's aabb): here the painted block itself.
  const Aabb& box = f.frontiers()[0].box;
  EXPECT_LT((box.min - Vec3(1.0, 0.5, 0.0)).cwiseAbs().maxCoeff(), 1e-9) << box.min.transpose();
  EXPECT_LT((box.max - Vec3(2.0, 1.5, 1.0)).cwiseAbs().maxCoeff(), 1e-9) << box.max.transpose();
}

namespace {

// The oracle's definition of a frontier cell, straight from the map.
bool frontierCell(const map::OccupancyMap& m, const Index3& idx) {
  const auto& g = m.geometry();
  auto inBox = [&](const Index3& i) {
    const Vec3 c = g.indexToCoord(i);
    return g.inside(i) && (c.array() > kBox.min.array()).all() && (c.array() < kBox.max.array()).all();
  };
  if (!inBox(idx) || m.state(idx) != VoxelState::kFree) return false;
  for (const Index3& o : {Index3(1, 0, 0), Index3(-1, 0, 0), Index3(0, 1, 0), Index3(0, -1, 0), Index3(0, 0, 1),
                          Index3(0, 0, -1)})
    if (inBox(idx + o) && m.state(Index3(idx + o)) == VoxelState::kUnknown) return true;
  return false;
}

// The 26-connected components of `cells`.
std::vector<std::set<std::size_t>> components(const std::set<std::size_t>& cells, const common::GridGeometry& g) {
  std::set<std::size_t> left = cells;
  std::vector<std::set<std::size_t>> out;
  while (!left.empty()) {
    std::vector<std::size_t> stack{*left.begin()};
    std::set<std::size_t> component{*left.begin()};
    left.erase(left.begin());
    while (!stack.empty()) {
      const Index3 c = g.unlinear(stack.back());
      stack.pop_back();
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const Index3 nb = c + Index3(dx, dy, dz);
            if (!g.inside(nb)) continue;
            auto it = left.find(g.linear(nb));
            if (it != left.end()) stack.push_back(*it), component.insert(*it), left.erase(it);
          }
    }
    out.push_back(std::move(component));
  }
  return out;
}

std::vector<std::size_t> componentSizes(const std::set<std::size_t>& cells, const common::GridGeometry& g) {
  std::vector<std::size_t> sizes;
  for (const auto& c : components(cells, g)) sizes.push_back(c.size());
  return sizes;
}

// The oracle's clusters without a size limit: the 26-connected components of the frontier cells
// (frontierCell(), over the whole grid) with at least min_cluster_cells cells.
std::set<std::vector<std::size_t>> oracleClusters(const map::OccupancyMap& m, int min_cluster_cells) {
  const auto& g = m.geometry();
  std::set<std::size_t> cells;
  for (std::size_t l = 0; l < g.size(); ++l)
    if (frontierCell(m, g.unlinear(l))) cells.insert(l);
  std::set<std::vector<std::size_t>> out;
  for (const auto& c : components(cells, g))
    if (static_cast<int>(c.size()) >= min_cluster_cells) out.insert(std::vector<std::size_t>(c.begin(), c.end()));
  return out;
}

// What a local update guarantees, checked against the map and a full recomputation: clusters are
// disjoint sets of frontier cells no wider than max_cluster_extent (pieces of 26-connected regions: a
// split may cut a bent region apart, or leave a piece below min_cluster_cells); they hold only cells
// the full recomputation clusters too, and what they leave out of those falls into connected pieces
// smaller than min_cluster_cells.
void expectValidLocalClusters(const frontier::FrontierFinder& f, const frontier::FrontierFinder& full,
                              const map::OccupancyMap& m, const frontier::FrontierConfig& cfg, const std::string& what) {
  const auto& g = m.geometry();
  std::set<std::size_t> held, all;
  for (const auto& fr : f.frontiers()) {
    Vec3 mean = Vec3::Zero();
    for (const Index3& c : fr.cells) {
      EXPECT_TRUE(frontierCell(m, c)) << what << ": cluster " << fr.id << " holds a cell that is not a frontier";
      EXPECT_TRUE(held.insert(g.linear(c)).second) << what << ": a cell in two clusters";
      mean += g.indexToCoord(c);
    }
    mean /= static_cast<double>(fr.cells.size());
    EXPECT_LT((fr.average - mean).norm(), 1e-9) << what;
    for (const Index3& c : fr.cells) EXPECT_LE((g.indexToCoord(c) - mean).norm(), cfg.max_cluster_extent + 1e-9) << what;
  }
  for (const auto& fr : full.frontiers())
    for (const Index3& c : fr.cells) all.insert(g.linear(c));
  std::set<std::size_t> left;
  for (std::size_t l : all)
    if (!held.count(l)) left.insert(l);
  for (std::size_t l : held) EXPECT_TRUE(all.count(l)) << what << ": a held cell the full recomputation drops";
  for (std::size_t n : componentSizes(left, g))
    EXPECT_LT(static_cast<int>(n), cfg.min_cluster_cells) << what << ": a left-out piece of " << n << " cells";
}

// Runs 6 seeds x 40 random box updates (free, occupied or unknown) on a map, updating one finder by
// box and one by voxel list, and hands both with a full recomputation to `check` after each; stops at
// the first failure.
void randomUpdates(const frontier::FrontierConfig& cfg,
                   const std::function<void(const frontier::FrontierFinder& box, const frontier::FrontierFinder& list,
                                            const frontier::FrontierFinder& full, const map::OccupancyMap& m,
                                            const std::string& at)>& check) {
  for (int seed = 0; seed < 6; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> ux(0.0, 3.0), uy(0.0, 2.0), uz(0.0, 1.0), size(0.1, 0.9);
    std::uniform_int_distribution<int> state(0, 9);
    map::OccupancyMap m(mapConfig(), kBox);
    frontier::FrontierFinder inc(cfg, m.geometry(), kBox), listed(cfg, m.geometry(), kBox);
    inc.recomputeAll(m, 0.0);
    listed.recomputeAll(m, 0.0);
    for (int step = 0; step < 40; ++step) {
      const Vec3 c(ux(rng), uy(rng), uz(rng));
      const Vec3 h(size(rng), size(rng), size(rng));
      const int k = state(rng);
      const VoxelState s = k < 6 ? VoxelState::kFree : (k < 9 ? VoxelState::kOccupied : VoxelState::kUnknown);
      std::vector<std::size_t> changed;  // voxels whose state really changes
      Index3 a, b;
      m.geometry().centreRange({c - h, c + h}, a, b);
      for (int z = a.z(); z < b.z(); ++z)
        for (int y = a.y(); y < b.y(); ++y)
          for (int x = a.x(); x < b.x(); ++x)
            if (m.state(Index3(x, y, z)) != s) changed.push_back(m.geometry().linear(Index3(x, y, z)));
      const auto [lo, hi] = paint(m, c - h, c + h, s);
      if ((hi.array() < lo.array()).any()) continue;
      inc.update(m, lo, hi, step + 1.0);
      listed.update(m, changed, step + 1.0);
      frontier::FrontierFinder full(cfg, m.geometry(), kBox);
      full.recomputeAll(m, step + 1.0);
      check(inc, listed, full, m, "seed " + std::to_string(seed) + " step " + std::to_string(step));
      if (::testing::Test::HasFailure()) return;
    }
    EXPECT_GT(inc.frontiers().size(), 0u);
  }
}

frontier::FrontierConfig randomUpdateConfig() {
  frontier::FrontierConfig cfg;
  cfg.min_cluster_cells = 4;
  cfg.max_cluster_extent = 0.6;
  return cfg;
}

}  // namespace

// Regions below max_regrow_cells (all of them here) are regrown whole: the result is the full one.
TEST(FrontierFinder, IncrementalEqualsFullRecomputationOnRandomUpdates) {
  randomUpdates(randomUpdateConfig(), [](const auto& box, const auto& list, const auto& full, const auto& m,
                                         const std::string& at) {
    ASSERT_EQ(clusterSets(box, m.geometry()), clusterSets(full, m.geometry())) << at;
    ASSERT_EQ(clusterSets(list, m.geometry()), clusterSets(full, m.geometry())) << "list, " << at;
  });
}

// The frontier finder node's way with the mapper's updates (applyMapUpdate), against a finder recomputed from
// the map after each: an update in order takes its frame's list of changed voxels; one handled after the
// next frame was integrated takes its own box (the list is the later frame's: taken, this frame's changes
// were lost); after one missed, everything is recomputed. Random box edits stand for the frames, delivered
// in turn at once, late, after the next, or never.
TEST(FrontierFinder, MapUpdatesHandledLateOrAfterAMissedOneEndAsTheMap) {
  const frontier::FrontierConfig cfg = randomUpdateConfig();
  for (int seed = 0; seed < 4; ++seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> ux(0.0, 3.0), uy(0.0, 2.0), uz(0.0, 1.0), size(0.1, 0.9);
    std::uniform_int_distribution<int> state(0, 9);
    map::OccupancyMap m(mapConfig(), kBox);
    const common::GridGeometry& g = m.geometry();
    frontier::FrontierFinder f(cfg, g, kBox);
    f.recomputeAll(m, 0.0);
    std::uint64_t last = 0;  // the last update the finder took
    std::optional<frontier::MapUpdateNote> held;
    std::map<frontier::UpdatePath, int> paths;
    for (std::uint64_t frame = 1; frame <= 40; ++frame) {
      const std::string at = "seed " + std::to_string(seed) + " frame " + std::to_string(frame);
      // The frame: a box painted free, occupied or unknown; its note names the changed voxels' cubes.
      const Vec3 c(ux(rng), uy(rng), uz(rng)), h(size(rng), size(rng), size(rng));
      const int k = state(rng);
      const VoxelState s = k < 6 ? VoxelState::kFree : (k < 9 ? VoxelState::kOccupied : VoxelState::kUnknown);
      std::vector<std::size_t> changed;
      Index3 a, b;
      g.centreRange({c - h, c + h}, a, b);
      for (int z = a.z(); z < b.z(); ++z)
        for (int y = a.y(); y < b.y(); ++y)
          for (int x = a.x(); x < b.x(); ++x)
            if (m.state(Index3(x, y, z)) != s) changed.push_back(g.linear(Index3(x, y, z)));
      paint(m, c - h, c + h, s);
      frontier::MapUpdateNote note;
      note.sequence = frame;
      note.changed_voxels = changed.size();
      if (!changed.empty()) {
        Index3 lo = g.unlinear(changed.front()), hi = lo;
        for (std::size_t l : changed) lo = lo.cwiseMin(g.unlinear(l)), hi = hi.cwiseMax(g.unlinear(l));
        note.changed_min = g.origin() + lo.cast<double>() * g.resolution();
        note.changed_max = g.origin() + (hi + Index3::Ones()).cast<double>() * g.resolution();
      }
      auto deliver = [&](const frontier::MapUpdateNote& n) {
        const frontier::UpdatePath path = frontier::applyMapUpdate(f, m, frame, changed, last, n, static_cast<double>(frame));
        ++paths[path];
        if (n.sequence != last + 1) {
          EXPECT_EQ(path, frontier::UpdatePath::kRecomputed) << at;
        } else if (n.changed_voxels == 0) {
          EXPECT_EQ(path, frontier::UpdatePath::kUnchanged) << at;
        } else {
          EXPECT_EQ(path, n.sequence == frame ? frontier::UpdatePath::kListed : frontier::UpdatePath::kBoxed) << at;
        }
        last = n.sequence;
      };
      switch (frame % 4) {
        case 1: deliver(note); break;  // at once (after a missed one: recomputed)
        case 2: held = note; break;    // late: handled after the next frame is in the map
        case 3: deliver(*held), deliver(note); break;
        default: break;                // missed
      }
      if (frame % 4 == 2 || frame % 4 == 0) continue;  // the map has a change the finder has not heard of (yet)
      frontier::FrontierFinder full(cfg, g, kBox);
      full.recomputeAll(m, static_cast<double>(frame));
      ASSERT_EQ(clusterSets(f, g), clusterSets(full, g)) << at;
    }
    EXPECT_GT(paths[frontier::UpdatePath::kBoxed], 5) << "seed " << seed;
    EXPECT_GT(paths[frontier::UpdatePath::kListed], 5) << "seed " << seed;
    EXPECT_GT(paths[frontier::UpdatePath::kRecomputed], 5) << "seed " << seed;
  }
}

// Without a size limit, the clusters after any update are the oracle's: the 26-connected components of
// the frontier cells found voxel by voxel, those of min_cluster_cells or more.
TEST(FrontierFinder, UnsplitClustersAreTheConnectedComponentsOfTheFrontierCells) {
  frontier::FrontierConfig cfg = randomUpdateConfig();
  cfg.max_cluster_extent = 100.0;
  randomUpdates(cfg, [&](const auto& box, const auto& list, const auto& full, const auto& m, const std::string& at) {
    const auto oracle = oracleClusters(m, cfg.min_cluster_cells);
    ASSERT_EQ(clusterSets(full, m.geometry()), oracle) << at;
    ASSERT_EQ(clusterSets(box, m.geometry()), oracle) << "box, " << at;
    ASSERT_EQ(clusterSets(list, m.geometry()), oracle) << "list, " << at;
  });
}

// Frontier cells that touch only along an edge or at a corner are one cluster: a staircase of single
// free voxels in unknown space, each one voxel on in x and y (and z) from the last.
TEST(FrontierFinder, CellsTouchingOnlyDiagonallyAreOneCluster) {
  map::OccupancyMap m(mapConfig(), kBox);
  const auto& g = m.geometry();
  auto free = [&](double x, double y, double z) { m.setState(g.coordToIndex(Vec3(x, y, z)), VoxelState::kFree); };
  for (int i = 0; i < 8; ++i) {  // edge to edge, two staircases at different heights
    free(0.55 + 0.1 * i, 0.55 + 0.1 * i, 0.35);
    free(0.55 + 0.1 * i, 1.45 - 0.1 * i, 0.75);
  }
  for (int i = 0; i < 6; ++i) free(2.05 + 0.1 * i, 0.45 + 0.1 * i, 0.15 + 0.1 * i);  // corner to corner
  frontier::FrontierConfig cfg;
  cfg.min_cluster_cells = 5;
  cfg.max_cluster_extent = 100.0;
  frontier::FrontierFinder f(cfg, g, kBox);
  f.recomputeAll(m, 0.0);
  EXPECT_EQ(clusterSets(f, g), oracleClusters(m, cfg.min_cluster_cells));
  std::multiset<std::size_t> sizes;
  for (const auto& fr : f.frontiers()) sizes.insert(fr.cells.size());
  EXPECT_EQ(sizes, (std::multiset<std::size_t>{6, 8, 8}));
}

// Clusters of 4 cells or more, no wider than `extent`, and no region regrown past the clusters an update
// touches (max_regrow_cells 0, the fuel mode's setting).
frontier::FrontierConfig noRegrowConfig(double extent) {
  frontier::FrontierConfig cfg;
  cfg.min_cluster_cells = 4;
  cfg.max_cluster_extent = extent;
  cfg.max_regrow_cells = 0;
  return cfg;
}

// The frontiers of `m` in kBox, found at time 0.
frontier::FrontierFinder found(const map::OccupancyMap& m, const frontier::FrontierConfig& cfg) {
  frontier::FrontierFinder f(cfg, m.geometry(), kBox);
  f.recomputeAll(m, 0.0);
  return f;
}

// The frontiers of a free block [lo, hi] painted into `m` (unknown elsewhere), found with noRegrowConfig(extent).
frontier::FrontierFinder noRegrowFinder(map::OccupancyMap& m, const Vec3& lo, const Vec3& hi, double extent) {
  paint(m, lo, hi, VoxelState::kFree);
  return found(m, noRegrowConfig(extent));
}

// With max_regrow_cells 0 (the fuel mode) either form of update() still rebuilds every cluster with a cell
// within reach of the change (the box form: 2 voxels; the list form: 26-adjacent to the changed voxel or a
// face neighbour of it): a voxel inside the block turned unknown makes 6 frontier cells, the nearest
// 26-adjacent to the ring 2 voxels away, so ring and newcomers are one region, as the oracle clusters them.
TEST(FrontierFinder, EitherUpdateRebuildsTheClustersWithinReachOfTheChange) {
  for (const bool list : {false, true}) {
    map::OccupancyMap m(mapConfig(), kBox);
    frontier::FrontierFinder f = noRegrowFinder(m, Vec3(1.0, 0.5, 0.0), Vec3(2.0, 1.5, 1.0), 100.0);
    ASSERT_EQ(f.frontiers().size(), 1u);
    const Index3 v = m.geometry().coordToIndex(Vec3(1.75, 1.05, 0.55));
    m.setState(v, VoxelState::kUnknown);
    if (list)
      f.update(m, std::vector<std::size_t>{m.geometry().linear(v)}, 1.0);
    else
      f.update(m, v, v, 1.0);
    EXPECT_EQ(clusterSets(f, m.geometry()), oracleClusters(m, noRegrowConfig(100.0).min_cluster_cells)) << list;
    EXPECT_EQ(f.frontiers().size(), 1u) << list;
  }
}

// With max_regrow_cells = 0 every update keeps the clusters it does not touch.
TEST(FrontierFinder, LocalUpdatesKeepValidClustersOnRandomUpdates) {
  frontier::FrontierConfig cfg = randomUpdateConfig();
  cfg.max_regrow_cells = 0;
  randomUpdates(cfg, [&](const auto& box, const auto& list, const auto& full, const auto& m, const std::string& at) {
    expectValidLocalClusters(box, full, m, cfg, "box, " + at);
    expectValidLocalClusters(list, full, m, cfg, "list, " + at);
  });
}

// With a limit the fill passes partway (a few cells), clusters the fill reached before the limit are rebuilt,
// all their cells: a split piece can hold cells the fill does not reach past the limit (a U-shaped region
// cut across its arms), and those were left out of every cluster, however many.
TEST(FrontierFinder, CutOffCellsOfRebuiltClustersAreNotLostPastTheRegrowLimit) {
  for (int limit : {3, 10, 30, 100}) {
    frontier::FrontierConfig cfg = randomUpdateConfig();
    cfg.max_regrow_cells = limit;
    randomUpdates(cfg, [&](const auto& box, const auto& list, const auto& full, const auto& m, const std::string& at) {
      const std::string where = "limit " + std::to_string(limit) + ", " + at;
      expectValidLocalClusters(box, full, m, cfg, "box, " + where);
      expectValidLocalClusters(list, full, m, cfg, "list, " + where);
    });
    if (::testing::Test::HasFailure()) return;
  }
}

// Past max_regrow_cells, a change at one end of a long frontier ring rebuilds the clusters there and
// keeps the others (ids and all): the cost of an update is the size of what it touches, not of the
// connected region. The clusters it may touch are those with a cell 26-adjacent to S, the changed voxels
// and their face neighbours (whose frontier status may change): the fill visits no more than their cells
// and the frontier cells no cluster held before; every other cluster is kept whole, its id unchanged.
TEST(FrontierFinder, UpdateKeepsTheClustersItDoesNotTouch) {
  map::OccupancyMap m(mapConfig(), kBox);
  frontier::FrontierFinder f = noRegrowFinder(m, Vec3(0.2, 0.5, 0.0), Vec3(2.5, 1.5, 1.0), 0.4);
  const frontier::FrontierConfig cfg = noRegrowConfig(0.4);
  const std::vector<frontier::Frontier> before = f.frontiers();
  ASSERT_GT(before.size(), 8u);
  // Grow the free block by 0.2 m at its x end.
  std::vector<std::size_t> changed;
  Index3 a, b;
  m.geometry().centreRange({Vec3(2.5, 0.5, 0.0), Vec3(2.7, 1.5, 1.0)}, a, b);
  for (int z = a.z(); z < b.z(); ++z)
    for (int y = a.y(); y < b.y(); ++y)
      for (int x = a.x(); x < b.x(); ++x)
        if (m.state(Index3(x, y, z)) != VoxelState::kFree) changed.push_back(m.geometry().linear(Index3(x, y, z)));
  paint(m, Vec3(2.5, 0.5, 0.0), Vec3(2.7, 1.5, 1.0), VoxelState::kFree);
  ASSERT_FALSE(changed.empty());
  // S, and the clusters within reach of it.
  const auto& geo = m.geometry();
  std::set<std::size_t> s;
  for (std::size_t l : changed) {
    const Index3 c = geo.unlinear(l);
    s.insert(l);
    for (const Index3& o : common::faceNeighbours())
      if (geo.inside(c + o)) s.insert(geo.linear(c + o));
  }
  auto nearS = [&](const Index3& c) {
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          if (const Index3 n = c + Index3(dx, dy, dz); geo.inside(n) && s.count(geo.linear(n))) return true;
    return false;
  };
  std::set<std::size_t> held;  // the cells of every cluster before
  std::size_t near_cells = 0, near = 0;
  std::vector<const frontier::Frontier*> far;
  for (const frontier::Frontier& fr : before) {
    for (const Index3& c : fr.cells) held.insert(geo.linear(c));
    if (std::any_of(fr.cells.begin(), fr.cells.end(), nearS)) {
      near_cells += fr.cells.size();
      ++near;
    } else {
      far.push_back(&fr);
    }
  }
  ASSERT_GT(near, 0u);
  ASSERT_GT(far.size(), before.size() / 2);
  const frontier::FrontierDelta delta = f.update(m, changed, 1.0);
  EXPECT_FALSE(delta.removed.empty());
  EXPECT_LE(delta.removed.size(), near);
  for (const frontier::Frontier* fr : far) {
    const frontier::Frontier* now = f.find(fr->id);
    ASSERT_NE(now, nullptr) << "cluster " << fr->id << ", far from the change, is gone";
    EXPECT_EQ(now->cells, fr->cells) << "cluster " << fr->id << ", far from the change, changed";
    EXPECT_DOUBLE_EQ(now->first_seen, fr->first_seen);
  }
  std::size_t unheld = 0;  // frontier cells now that no cluster held before
  for (int z = 0; z < geo.dims().z(); ++z)
    for (int y = 0; y < geo.dims().y(); ++y)
      for (int x = 0; x < geo.dims().x(); ++x)
        unheld += f.isFrontierCell(Index3(x, y, z)) && !held.count(geo.linear(Index3(x, y, z)));
  EXPECT_GT(delta.filled_cells, 0u);
  EXPECT_LE(delta.filled_cells, near_cells + unheld) << near << " clusters near the change";
  for (std::uint32_t id : delta.added) {
    const frontier::Frontier* fr = f.find(id);
    ASSERT_NE(fr, nullptr);
    EXPECT_GT(fr->box.max.x(), 1.5) << "a rebuilt cluster far from the change";
  }
  frontier::FrontierFinder full(cfg, m.geometry(), kBox);
  full.recomputeAll(m, 1.0);
  expectValidLocalClusters(f, full, m, cfg, "after growing the block");
}

// Below max_regrow_cells a change regrows the whole connected region; the pieces whose cells did not
// change are the same clusters and keep their ids (they are neither removed nor added). Every piece used
// to take a new id: a blacklisted frontier metres from the change came back under a new one.
TEST(FrontierFinder, ARegrownClusterWhoseCellsDidNotChangeKeepsItsId) {
  const Aabb box{Vec3(0, 0, 0), Vec3(20, 4, 2)};
  map::OccupancyMap m(mapConfig(), box);
  paint(m, Vec3(0, 0, 0), Vec3(20, 2.0, 2), VoxelState::kFree);  // a 20 m x 2 m wall of frontier at y 1.95
  frontier::FrontierConfig cfg;
  cfg.min_cluster_cells = 200;
  cfg.max_cluster_extent = 2.5;
  cfg.max_regrow_cells = 20000;  // the whole region is regrown
  frontier::FrontierFinder f(cfg, m.geometry(), box);
  f.recomputeAll(m, 0.0);
  std::map<std::vector<std::size_t>, std::uint32_t> id_of;
  for (const auto& fr : f.frontiers()) {
    std::vector<std::size_t> v;
    for (const Index3& c : fr.cells) v.push_back(m.geometry().linear(c));
    id_of[v] = fr.id;
  }
  ASSERT_GE(id_of.size(), 6u);
  // Three voxels beyond the wall seen free at its far end.
  std::vector<std::size_t> changed;
  for (int k = 5; k < 8; ++k) {
    const Index3 i = m.geometry().coordToIndex(Vec3(19.55, 2.05, 0.05 + 0.1 * k));
    m.setState(i, VoxelState::kFree);
    changed.push_back(m.geometry().linear(i));
  }
  const frontier::FrontierDelta delta = f.update(m, changed, 1.0);
  std::size_t same_cells = 0;
  for (const auto& fr : f.frontiers()) {
    std::vector<std::size_t> v;
    for (const Index3& c : fr.cells) v.push_back(m.geometry().linear(c));
    const auto it = id_of.find(v);
    if (it == id_of.end()) {
      EXPECT_NE(std::find(delta.added.begin(), delta.added.end(), fr.id), delta.added.end()) << "a changed cluster not added";
      continue;
    }
    ++same_cells;
    EXPECT_EQ(fr.id, it->second) << "a cluster with the same cells took a new id";
    EXPECT_DOUBLE_EQ(fr.first_seen, 0.0);
    EXPECT_EQ(std::find(delta.added.begin(), delta.added.end(), fr.id), delta.added.end());
    EXPECT_EQ(std::find(delta.removed.begin(), delta.removed.end(), fr.id), delta.removed.end());
  }
  EXPECT_GE(same_cells, id_of.size() - 2) << "the change touched more than the wall's far end";
  EXPECT_FALSE(delta.added.empty()) << "the far end's cluster changed";
  for (std::uint32_t id : delta.removed) EXPECT_EQ(f.find(id), nullptr) << "removed " << id << " is still listed";
  // The clusters are those of a full recomputation, and every cell has its cluster as owner (an update
  // clearing the owners of the removed clusters' cells must not clear those of a kept one).
  frontier::FrontierFinder full(cfg, m.geometry(), box);
  full.recomputeAll(m, 1.0);
  EXPECT_EQ(clusterSets(f, m.geometry()), clusterSets(full, m.geometry()));
  std::vector<std::size_t> again;
  const Index3 i = m.geometry().coordToIndex(Vec3(0.55, 2.05, 1.05));
  m.setState(i, VoxelState::kFree);
  again.push_back(m.geometry().linear(i));
  f.update(m, again, 2.0);
  full.recomputeAll(m, 2.0);
  EXPECT_EQ(clusterSets(f, m.geometry()), clusterSets(full, m.geometry()));
  // A cluster that loses cells (three of the wall's frontier cells in its middle seen occupied) is a changed
  // one: its id goes, and no id is listed twice. Only a piece with every cell of the old cluster keeps it.
  const Index3 middle = m.geometry().coordToIndex(Vec3(10.05, 1.95, 0.95));
  std::uint32_t shrunk = 0;
  for (const auto& fr : f.frontiers())
    if (std::find(fr.cells.begin(), fr.cells.end(), middle) != fr.cells.end()) shrunk = fr.id;
  ASSERT_NE(shrunk, 0u);
  std::vector<std::size_t> seen;
  for (int k = 0; k < 3; ++k) {
    const Index3 i = middle + Index3(0, 0, k);
    m.setState(i, VoxelState::kOccupied);
    seen.push_back(m.geometry().linear(i));
  }
  const frontier::FrontierDelta shrink = f.update(m, seen, 3.0);
  EXPECT_NE(std::find(shrink.removed.begin(), shrink.removed.end(), shrunk), shrink.removed.end());
  EXPECT_EQ(f.find(shrunk), nullptr) << "the shrunk cluster kept its id";
  std::set<std::uint32_t> ids;
  for (const auto& fr : f.frontiers()) EXPECT_TRUE(ids.insert(fr.id).second) << "id " << fr.id << " listed twice";
  full.recomputeAll(m, 3.0);
  EXPECT_EQ(clusterSets(f, m.geometry()), clusterSets(full, m.geometry()));
}

TEST(FrontierFinder, WideClustersAreSplitSmallRegionsDropped) {
  map::OccupancyMap m(mapConfig(), kBox);
  // A 3 m long, 1-voxel-high free strip at z in [0.4, 0.5): a long frontier.
  paint(m, Vec3(0.0, 0.94, 0.44), Vec3(3.0, 0.96, 0.46), VoxelState::kFree);
  // A tiny 2-cell free spot far away.
  paint(m, Vec3(1.45, 0.15, 0.85), Vec3(1.55, 0.15, 0.85), VoxelState::kFree);
  frontier::FrontierConfig cfg;
  cfg.min_cluster_cells = 5;
  cfg.max_cluster_extent = 0.5;
  frontier::FrontierFinder f(cfg, m.geometry(), kBox);
  f.recomputeAll(m, 0.0);
  std::size_t cells = 0;
  for (const auto& fr : f.frontiers()) {
    cells += fr.cells.size();
    for (const Index3& c : fr.cells) EXPECT_LE((m.geometry().indexToCoord(c) - fr.average).norm(), 0.5 + 1e-9);
    EXPECT_GT(fr.average.y(), 0.5) << "the 2-cell spot must be dropped";
  }
  EXPECT_EQ(cells, 30u);
  // Split only while too wide, at the mean along the strip: 30 cells (x 0.05 .. 2.95, 1.45 m from their mean)
  // -> 15 + 15 (0.7 m) -> 7 + 8 each (0.35 m from the mean of the 8, 0.3 m of the 7): four pieces, no more.
  std::multiset<std::size_t> sizes;
  for (const auto& fr : f.frontiers()) sizes.insert(fr.cells.size());
  EXPECT_EQ(sizes, (std::multiset<std::size_t>{7, 7, 8, 8}));
}

// A cluster is split only while a cell lies farther than max_cluster_extent from its mean: five cells in a row
// on a 0.25 m grid (centres exact in binary), the end ones exactly 0.5 m from the mean, stay one frontier at
// an extent of 0.5 m.
TEST(FrontierFinder, AClusterExactlyAtTheExtentIsNotSplit) {
  map::OccupancyConfig c;
  c.resolution = 0.25;
  c.margin = 0.5;
  ASSERT_TRUE(c.validate()) << c.validate().message();
  map::OccupancyMap m(c, kBox);
  ASSERT_EQ(m.geometry().indexToCoord(m.geometry().coordToIndex(Vec3(0.1, 0.9, 0.4))), Vec3(0.125, 0.875, 0.375));
  paint(m, Vec3(0.1, 0.87, 0.37), Vec3(1.13, 0.88, 0.38), VoxelState::kFree);
  frontier::FrontierConfig cfg;
  cfg.min_cluster_cells = 1;
  cfg.max_cluster_extent = 0.5;
  frontier::FrontierFinder f(cfg, m.geometry(), kBox);
  f.recomputeAll(m, 0.0);
  ASSERT_EQ(f.frontiers().size(), 1u);
  EXPECT_EQ(f.frontiers()[0].cells.size(), 5u);
  EXPECT_EQ(f.frontiers()[0].average, Vec3(0.625, 0.875, 0.375));
}

TEST(FrontierFinder, DurationInheritedFromTheOldestAncestor) {
  map::OccupancyMap m(mapConfig(), kBox);
  const auto [lo, hi] = paint(m, Vec3(0.5, 0.5, 0.0), Vec3(1.0, 1.0, 1.0), VoxelState::kFree);
  frontier::FrontierConfig cfg;
  cfg.max_cluster_extent = 100.0;
  frontier::FrontierFinder f(cfg, m.geometry(), kBox);
  f.update(m, lo, hi, 2.0);
  ASSERT_EQ(f.frontiers().size(), 1u);
  EXPECT_DOUBLE_EQ(f.frontiers()[0].first_seen, 2.0);
  // The free block grows at t = 7: the frontier is rebuilt but keeps its age.
  const auto [lo2, hi2] = paint(m, Vec3(1.0, 0.5, 0.0), Vec3(1.4, 1.0, 1.0), VoxelState::kFree);
  f.update(m, lo2, hi2, 7.0);
  ASSERT_EQ(f.frontiers().size(), 1u);
  EXPECT_DOUBLE_EQ(f.frontiers()[0].first_seen, 2.0);
  EXPECT_DOUBLE_EQ(f.frontiers()[0].duration(10.0), 8.0);
  // Asked at a clock that went back (a bag played again): no negative age.
  EXPECT_DOUBLE_EQ(f.frontiers()[0].duration(1.0), 0.0);
  // A separate new block at t = 9 is young.
  const auto [lo3, hi3] = paint(m, Vec3(2.3, 0.2, 0.0), Vec3(2.8, 0.6, 1.0), VoxelState::kFree);
  f.update(m, lo3, hi3, 9.0);
  ASSERT_EQ(f.frontiers().size(), 2u);
  std::set<double> ages;
  for (const auto& fr : f.frontiers()) ages.insert(fr.first_seen);
  EXPECT_EQ(ages, (std::set<double>{2.0, 9.0}));
}

// Two frontiers of different ages joined into one by an update: the joined one is as old as the older.
TEST(FrontierFinder, AJoinedFrontierIsAsOldAsItsOldestPart) {
  map::OccupancyMap m(mapConfig(), kBox);
  frontier::FrontierConfig cfg;
  cfg.max_cluster_extent = 100.0;
  frontier::FrontierFinder f(cfg, m.geometry(), kBox);
  const auto [lo1, hi1] = paint(m, Vec3(1.6, 0.5, 0.0), Vec3(2.0, 1.0, 1.0), VoxelState::kFree);
  f.update(m, lo1, hi1, 5.0);  // the younger first in id order
  const auto [lo0, hi0] = paint(m, Vec3(0.5, 0.5, 0.0), Vec3(0.9, 1.0, 1.0), VoxelState::kFree);
  f.update(m, lo0, hi0, 2.0);
  ASSERT_EQ(f.frontiers().size(), 2u);
  // The block between them at t = 9 joins them.
  const auto [lo2, hi2] = paint(m, Vec3(0.9, 0.5, 0.0), Vec3(1.6, 1.0, 1.0), VoxelState::kFree);
  f.update(m, lo2, hi2, 9.0);
  ASSERT_EQ(f.frontiers().size(), 1u);
  EXPECT_DOUBLE_EQ(f.frontiers()[0].first_seen, 2.0);
}

TEST(FrontierFinder, NearCountsAndActiveBand) {
  map::OccupancyMap m(mapConfig(), {Vec3(0, 0, 0), Vec3(10, 2, 1)});
  const Aabb box{Vec3(0, 0, 0), Vec3(10, 2, 1)};
  // Three free pockets (each its own frontier) with averages at x = 1, 2.5 and 8.
  for (double x : {1.0, 2.5, 8.0}) paint(m, Vec3(x - 0.2, 0.8, 0.0), Vec3(x + 0.2, 1.2, 1.0), VoxelState::kFree);
  frontier::FrontierConfig cfg;
  cfg.max_cluster_extent = 100.0;
  cfg.s_near = 2.0;
  frontier::FrontierFinder f(cfg, m.geometry(), box);
  f.recomputeAll(m, 0.0);
  ASSERT_EQ(f.frontiers().size(), 3u);
  for (const auto& fr : f.frontiers()) EXPECT_EQ(fr.n_near, fr.average.x() < 5.0 ? 1 : 0) << fr.average.transpose();
  // Just inside and just outside s_near: 1.5 m apart counts at s_near 1.51, not at 1.49.
  cfg.s_near = 1.51;
  frontier::FrontierFinder wider(cfg, m.geometry(), box);
  wider.recomputeAll(m, 0.0);
  for (const auto& fr : wider.frontiers()) EXPECT_EQ(fr.n_near, fr.average.x() < 5.0 ? 1 : 0) << fr.average.transpose();
  cfg.s_near = 1.49;
  frontier::FrontierFinder narrower(cfg, m.geometry(), box);
  narrower.recomputeAll(m, 0.0);
  for (const auto& fr : narrower.frontiers()) EXPECT_EQ(fr.n_near, 0) << fr.average.transpose();
  f.setActiveBand(0.6, 2.0);
  for (const auto& fr : f.frontiers()) EXPECT_FALSE(fr.active);
  f.setActiveBand(0.0, 1.0);
  for (const auto& fr : f.frontiers()) EXPECT_TRUE(fr.active);
}

// A band holds both its bounds: a frontier whose average lies exactly on the boundary of two bands is active
// in either (z centres 0.375 and 0.625 at 0.25 m: the average is exactly 0.5).
TEST(FrontierFinder, AnAverageOnABandBoundaryIsInBothBands) {
  map::OccupancyConfig c;
  c.resolution = 0.25;
  c.margin = 0.5;
  map::OccupancyMap m(c, kBox);
  paint(m, Vec3(1.0, 0.75, 0.25), Vec3(1.5, 1.25, 0.75), VoxelState::kFree);
  frontier::FrontierConfig cfg;
  cfg.min_cluster_cells = 1;
  frontier::FrontierFinder f = found(m, cfg);
  ASSERT_EQ(f.frontiers().size(), 1u);
  ASSERT_EQ(f.frontiers()[0].average.z(), 0.5);
  f.setActiveBand(0.5, 1.0);
  EXPECT_TRUE(f.frontiers()[0].active);
  f.setActiveBand(0.0, 0.5);
  EXPECT_TRUE(f.frontiers()[0].active);
  f.setActiveBand(0.51, 1.0);
  EXPECT_FALSE(f.frontiers()[0].active);
}

// A band that splits the frontiers by height: only those whose average lies within [z_min, z_max] are active,
// after setActiveBand and for the clusters an update makes or remakes afterwards.
TEST(FrontierFinder, ActiveBandSplitsFrontiersByHeight) {
  const Aabb box{Vec3(0, 0, 0), Vec3(10, 2, 3)};
  map::OccupancyMap m(mapConfig(), box);
  // Free pockets (each its own frontier) with averages at z = 0.5, 1.5 and 2.5.
  for (const Vec3& c : {Vec3(1, 1, 0.5), Vec3(4, 1, 1.5), Vec3(7, 1, 2.5)})
    paint(m, c - Vec3(0.2, 0.2, 0.2), c + Vec3(0.2, 0.2, 0.2), VoxelState::kFree);
  frontier::FrontierConfig cfg;
  cfg.max_cluster_extent = 100.0;
  frontier::FrontierFinder f(cfg, m.geometry(), box);
  f.recomputeAll(m, 0.0);
  ASSERT_EQ(f.frontiers().size(), 3u);
  auto expectBand = [&](double lo, double hi, std::size_t active_count, const char* when) {
    std::size_t active = 0;
    for (const auto& fr : f.frontiers()) {
      EXPECT_EQ(fr.active, fr.average.z() >= lo && fr.average.z() <= hi) << when << ": " << fr.average.transpose();
      active += fr.active;
    }
    EXPECT_EQ(active, active_count) << when;
  };
  f.setActiveBand(1.0, 2.0);
  expectBand(1.0, 2.0, 1, "band [1, 2]");
  f.setActiveBand(0.0, 2.0);
  expectBand(0.0, 2.0, 2, "band [0, 2]");
  f.setActiveBand(1.0, 2.0);
  // New pockets at z = 1.5 (active) and 2.5 (not), and the one at z = 0.5 grown (remade, still below).
  auto [lo, hi] = paint(m, Vec3(8.8, 0.8, 1.3), Vec3(9.2, 1.2, 1.7), VoxelState::kFree);
  f.update(m, lo, hi, 1.0);
  std::tie(lo, hi) = paint(m, Vec3(2.3, 0.8, 2.3), Vec3(2.7, 1.2, 2.7), VoxelState::kFree);
  f.update(m, lo, hi, 1.0);
  std::tie(lo, hi) = paint(m, Vec3(0.8, 0.8, 0.3), Vec3(1.4, 1.2, 0.7), VoxelState::kFree);
  f.update(m, lo, hi, 1.0);
  ASSERT_EQ(f.frontiers().size(), 5u);
  expectBand(1.0, 2.0, 2, "after updates");
}

namespace {

// Cells of the regions the finder holds, against a full recomputation by a finder without hysteresis
// (revive_factor 1): the plain size limit's clusters.
std::size_t heldCells(const frontier::FrontierFinder& f) {
  std::size_t n = 0;
  for (const auto& fr : f.frontiers()) n += fr.cells.size();
  return n;
}

// A free strip one voxel high and wide at y = 0.95 (or 0.55), z = 0.45, over voxel centres x in [x0, x1]:
// every cell of it is a frontier cell (unknown above and below).
std::pair<Index3, Index3> strip(map::OccupancyMap& m, double x0, double x1, double y, VoxelState s) {
  return paint(m, Vec3(x0, y - 0.01, 0.44), Vec3(x1, y + 0.01, 0.46), s);
}

}  // namespace

// A cluster's region that shrinks below min_cluster_cells is retired: it counts again only from
// revive_factor times that size while half of it or more is retired, and a region that was never a
// cluster is not held back. With revive_factor 1 the finder is the plain size limit (the full
// recomputation's result) at every step.
TEST(FrontierFinder, RemnantBelowTheSizeLimitComesBackOnlyPastTheReviveSize) {
  for (const double factor : {1.0, 1.5}) {
    SCOPED_TRACE("revive_factor " + std::to_string(factor));
    map::OccupancyMap m(mapConfig(), kBox);
    frontier::FrontierConfig cfg;
    cfg.min_cluster_cells = 10;
    cfg.max_cluster_extent = 100.0;
    cfg.revive_factor = factor;
    ASSERT_TRUE(cfg.validate().ok());
    frontier::FrontierFinder f(cfg, m.geometry(), kBox);
    frontier::FrontierConfig plain = cfg;
    plain.revive_factor = 1.0;
    double t = 0.0;
    auto step = [&](const std::pair<Index3, Index3>& changed) {
      t += 1.0;
      f.update(m, changed.first, changed.second, t);
      frontier::FrontierFinder full(plain, m.geometry(), kBox);
      full.recomputeAll(m, t);
      return heldCells(full);
    };
    // Each step paints a strip; `plain` is what the full recomputation (the plain limit) holds after it, and
    // the finder with hysteresis holds `revived` cells instead (with revive_factor 1 it holds `plain`).
    struct Step {
      double x0, x1, y;
      VoxelState state;
      std::size_t plain, revived;
      const char* what;
    };
    const VoxelState kFree = VoxelState::kFree, kOccupied = VoxelState::kOccupied;
    const std::vector<Step> steps = {
        {0.0, 1.2, 0.95, kFree, 12, 12, "12 cells (x centres 0.05 .. 1.15): a cluster"},
        {0.0, 0.4, 0.95, kOccupied, 0, 0, "its first four cells seen occupied: 8 left, below the limit"},
        {1.2, 1.6, 0.95, kFree, 12, 0, "back to 12 cells (8 retired, 4 new): over the plain limit, under 1.5 times it"},
        {1.6, 1.8, 0.95, kFree, 14, 0, "14 cells: still under 15 with hysteresis"},
        {1.8, 2.0, 0.95, kFree, 16, 16, "16 cells: past 1.5 times the limit, a cluster again"},
        {0.0, 0.8, 0.55, kFree, 16, 16, "a new region of 8 cells at y = 0.55 (never a cluster)"},
        {0.8, 1.2, 0.55, kFree, 28, 28, "... grown to 12: held either way"},
        // Once counted again it is a cluster like any other: its cells' old retirement was dropping it here.
        {0.4, 0.7, 0.95, kOccupied, 25, 25, "the revived cluster loses three cells: 13, over the limit, stays"},
        {0.7, 1.1, 0.95, kOccupied, 12, 12, "9 cells, under the limit: retired again"},
        {2.0, 2.4, 0.95, kFree, 25, 12, "13 cells (9 retired): not back"},
        {2.4, 2.6, 0.95, kFree, 27, 27, "15 cells: back past the revive size"},
        // Under half retired: it counts at once, under the revive size.
        {0.0, 1.0, 0.15, kFree, 37, 37, "a third cluster of 10 cells at y = 0.15"},
        {0.0, 0.5, 0.15, kOccupied, 27, 27, "... loses 5 (retired)"},
        {1.0, 1.7, 0.15, kFree, 39, 39, "... grows 7 new ones: 12 cells, 5 of them retired"},
        // Exactly half retired is held back ("half or more").
        {0.0, 1.2, 1.35, kFree, 51, 51, "a fourth cluster of 12 cells at y = 1.35"},
        {0.0, 0.6, 1.35, kOccupied, 39, 39, "... loses 6 (retired)"},
        {1.2, 1.8, 1.35, kFree, 51, 39, "... grows 6 new ones: 12 cells, 6 of them retired: not back"},
        {1.8, 2.4, 1.35, kFree, 57, 57, "... 18 cells: back past the revive size"},
    };
    for (const Step& s : steps) {
      SCOPED_TRACE(s.what);
      EXPECT_EQ(step(strip(m, s.x0, s.x1, s.y, s.state)), s.plain);
      EXPECT_EQ(heldCells(f), factor > 1.0 ? s.revived : s.plain);
    }
  }
}

TEST(FrontierFinder, ReviveFactorBelowOneIsRejected) {
  frontier::FrontierConfig cfg;
  cfg.revive_factor = 0.5;
  const common::Status s = cfg.validate();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("revive_factor"), std::string::npos);
  cfg.revive_factor = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(cfg.validate().ok());
}

// Distances the finder squares must be finite squared: an infinite s_near would make every frontier near every
// other (N_near past n_max, so every omission likelihood 0), an infinite extent would split no cluster.
TEST(FrontierFinder, InfiniteDistancesAreRejectedByName) {
  for (const double bad : {std::numeric_limits<double>::infinity(), 1e155}) {
    frontier::FrontierConfig cfg;
    cfg.s_near = bad;
    EXPECT_NE(cfg.validate().message().find("frontier: s_near"), std::string::npos) << bad;
    cfg = frontier::FrontierConfig();
    cfg.max_cluster_extent = bad;
    EXPECT_NE(cfg.validate().message().find("frontier: max_cluster_extent"), std::string::npos) << bad;
  }
  EXPECT_TRUE(frontier::FrontierConfig().validate().ok());
}

// A finder told to go on from another's ids hands out none below them, and never lowers its own.
TEST(FrontierFinder, IdsGoOnFromWhereAnotherFinderStopped) {
  map::OccupancyMap m(mapConfig(), kBox);
  paint(m, Vec3(0.2, 0.2, 0.0), Vec3(0.8, 0.8, 1.0), VoxelState::kFree);
  paint(m, Vec3(2.0, 0.5, 0.0), Vec3(2.8, 1.5, 1.0), VoxelState::kFree);
  frontier::FrontierConfig cfg;
  cfg.min_cluster_cells = 1;
  frontier::FrontierFinder first(cfg, m.geometry(), kBox);
  first.recomputeAll(m, 0.0);
  ASSERT_GE(first.frontiers().size(), 2u);
  std::uint32_t highest = 0;
  for (const auto& f : first.frontiers()) highest = std::max(highest, f.id);
  EXPECT_EQ(first.nextId(), highest + 1);
  frontier::FrontierFinder second(cfg, m.geometry(), kBox);
  second.continueIdsFrom(first.nextId());
  second.continueIdsFrom(1);  // no step back
  second.recomputeAll(m, 0.0);
  EXPECT_EQ(clusterSets(second, m.geometry()), clusterSets(first, m.geometry()));
  for (const auto& f : second.frontiers()) EXPECT_GT(f.id, highest);
  EXPECT_EQ(second.nextId(), first.nextId() + first.frontiers().size());
}
