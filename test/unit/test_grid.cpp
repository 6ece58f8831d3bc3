#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include "go_feap/common/grid.h"
#include "go_feap/common/monotonic_clock.h"
#include "go_feap/common/raycast.h"

using go_feap::common::Aabb;
using go_feap::common::GridGeometry;
using go_feap::common::Index3;
using go_feap::common::Vec3;

TEST(GridGeometry, CoveringSnapsToResolutionMultiples) {
  const GridGeometry g = GridGeometry::covering({Vec3(-1.03, 0.0, 0.26), Vec3(2.0, 1.0, 1.0)}, 0.1);
  EXPECT_NEAR(g.origin().x(), -1.1, 1e-9);
  EXPECT_NEAR(g.origin().z(), 0.2, 1e-9);
  EXPECT_EQ(g.dims(), Index3(31, 10, 8));
  // Bounds that are multiples of the resolution but divide a hair off a whole number (0.3 / 0.1 is
  // 2.9999999999999996, -0.3 / 0.1 is -2.9999999999999996) take no extra voxel on either side.
  const GridGeometry h = GridGeometry::covering({Vec3(0.3, 0.0, 0.0), Vec3(1.1, 1.0, 1.0)}, 0.1);
  EXPECT_NEAR(h.origin().x(), 0.3, 1e-9);
  EXPECT_EQ(h.dims(), Index3(8, 10, 10));
  const GridGeometry below = GridGeometry::covering({Vec3(-1.0, 0.0, 0.0), Vec3(-0.3, 1.0, 1.0)}, 0.1);
  EXPECT_NEAR(below.origin().x(), -1.0, 1e-9);
  EXPECT_EQ(below.dims(), Index3(7, 10, 10));
}

TEST(Aabb, ValidNeedsAPositiveExtentOnEveryAxis) {
  EXPECT_FALSE((go_feap::common::Aabb{Vec3(0, 0, 1), Vec3(4, 4, 1)}).valid());  // no height
  EXPECT_FALSE((go_feap::common::Aabb{Vec3(0, 0, 1), Vec3(4, -1, 2)}).valid());
  EXPECT_TRUE((go_feap::common::Aabb{Vec3(0, 0, 1), Vec3(4, 4, 1.1)}).valid());
}

TEST(GridGeometry, IndexCoordRoundTrip) {
  const GridGeometry g(Vec3(-2.0, -1.0, 0.0), 0.1, Index3(40, 20, 10));
  for (std::size_t l = 0; l < g.size(); l += 37) {
    const Index3 idx = g.unlinear(l);
    EXPECT_EQ(g.linear(idx), l);
    EXPECT_EQ(g.coordToIndex(g.indexToCoord(idx)), idx);
  }
  EXPECT_FALSE(g.inside(g.coordToIndex(Vec3(-2.01, 0, 0.5))));
  EXPECT_TRUE(g.inside(g.coordToIndex(Vec3(-2.0, 0, 0.5))));
}

// clampedIndex() is coordToIndex() wherever that is within one voxel of the grid, and otherwise the
// nearest index just outside it: a point at 1e30 m (finite) or NaN never reaches the cast to int.
TEST(GridGeometry, ClampedIndexAgreesNearTheGridAndStaysJustOutsideFarFromIt) {
  const GridGeometry g(Vec3(-2.0, -1.0, 0.0), 0.1, Index3(40, 20, 10));
  for (double x = -2.095; x < 2.095; x += 0.013)
    EXPECT_EQ(g.clampedIndex(Vec3(x, 0.42, 0.5)), g.coordToIndex(Vec3(x, 0.42, 0.5))) << x;
  EXPECT_EQ(g.clampedIndex(Vec3(1e30, -1e30, 0.55)), Index3(40, -1, 5));
  EXPECT_EQ(g.clampedIndex(Vec3(-1e300, 1e300, 1e12)), Index3(-1, 20, 10));
  const double nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(g.clampedIndex(Vec3(nan, 0.0, 0.0)), Index3(-1, 10, 0));
  EXPECT_FALSE(g.inside(g.clampedIndex(Vec3(nan, 0.0, 0.0))));
}

TEST(GridGeometry, CentreRangeHoldsExactlyTheCentresInsideTheBox) {
  const GridGeometry g(Vec3(0, 0, 0), 0.1, Index3(20, 20, 20));
  const Aabb box{Vec3(0.3, 0.25, 0.0), Vec3(1.0, 0.55, 2.5)};
  Index3 lo, hi;
  g.centreRange(box, lo, hi);
  for (int a = 0; a < 3; ++a) {
    for (int i = 0; i < g.dims()[a]; ++i) {
      Index3 idx = Index3::Zero();
      idx[a] = i;
      const double c = g.indexToCoord(idx)[a];
      const bool in = c >= box.min[a] - 1e-9 && c <= box.max[a] + 1e-9;
      EXPECT_EQ(in, i >= lo[a] && i < hi[a]) << "axis " << a << " index " << i;
    }
  }
}

namespace {

/// True when the segment [a, b] meets voxel idx of g (slab test on the voxel's box, widened by eps).
bool segmentMeetsVoxel(const GridGeometry& g, const Index3& idx, const Vec3& a, const Vec3& b, double eps) {
  const Vec3 lo = g.origin() + idx.cast<double>() * g.resolution() - Vec3::Constant(eps);
  const Vec3 hi = lo + Vec3::Constant(g.resolution() + 2 * eps);
  double t0 = 0.0, t1 = 1.0;
  const Vec3 d = b - a;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0.0) {
      if (a[i] < lo[i] || a[i] > hi[i]) return false;
      continue;
    }
    double ta = (lo[i] - a[i]) / d[i], tb = (hi[i] - a[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 <= t1;
}

std::vector<Index3> walk(const GridGeometry& g, const Vec3& a, const Vec3& b) {
  std::vector<Index3> cells;
  go_feap::common::traverse(g, a, b, [&](const Index3& c) {
    cells.push_back(c);
    return true;
  });
  return cells;
}

}  // namespace

TEST(Traverse, VisitsExactlyTheVoxelsTheSegmentCrossesInOrder) {
  const GridGeometry g(Vec3(-1.0, -2.0, 0.5), 0.1, Index3(40, 40, 30));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(-1.0, 3.0), uy(-2.0, 2.0), uz(0.5, 3.5);
  for (int trial = 0; trial < 500; ++trial) {
    const Vec3 a(ux(rng), uy(rng), uz(rng)), b(ux(rng), uy(rng), uz(rng));
    const std::vector<Index3> cells = walk(g, a, b);
    ASSERT_FALSE(cells.empty());
    EXPECT_EQ(cells.front(), g.coordToIndex(a)) << trial;
    EXPECT_EQ(cells.back(), g.coordToIndex(b)) << trial;
    EXPECT_EQ(static_cast<int>(cells.size()), (g.coordToIndex(b) - g.coordToIndex(a)).cwiseAbs().sum() + 1);
    for (std::size_t k = 0; k < cells.size(); ++k) {
      // Every visited voxel is one the segment meets ...
      EXPECT_TRUE(segmentMeetsVoxel(g, cells[k], a, b, 1e-9)) << trial << " voxel " << k;
      // ... reached from the last through one face.
      if (k > 0) {
        EXPECT_EQ((cells[k] - cells[k - 1]).cwiseAbs().sum(), 1) << trial << " voxel " << k;
      }
    }
    // ... and every voxel the segment passes through is visited.
    for (int s = 0; s <= 1000; ++s) {
      const Vec3 p = a + (b - a) * (s / 1000.0);
      const Vec3 q = (p - g.origin()) / g.resolution();
      if (((q.array() - q.array().round()).abs() < 1e-6).any()) continue;  // on a face: either side
      EXPECT_NE(std::find(cells.begin(), cells.end(), g.coordToIndex(p)), cells.end()) << trial << " at " << s;
    }
  }
}

TEST(Traverse, ExactTiesAndAxisAlignedSegmentsEndInTheEndVoxel) {
  const GridGeometry g(Vec3(0, 0, 0), 0.1, Index3(20, 20, 20));
  // Through voxel corners (all three boundaries at once) and along one axis.
  for (const auto& [a, b] : std::vector<std::pair<Vec3, Vec3>>{{Vec3(0.05, 0.05, 0.05), Vec3(1.05, 1.05, 1.05)},
                                                               {Vec3(0.0, 0.0, 0.0), Vec3(1.0, 1.0, 1.0)},
                                                               {Vec3(1.0, 0.2, 0.0), Vec3(0.0, 0.4, 0.0)},
                                                               {Vec3(0.35, 0.35, 0.35), Vec3(1.55, 0.35, 0.35)},
                                                               {Vec3(0.35, 0.35, 0.35), Vec3(0.35, 0.35, 0.35)}}) {
    const std::vector<Index3> cells = walk(g, a, b);
    EXPECT_EQ(cells.front(), g.coordToIndex(a));
    EXPECT_EQ(cells.back(), g.coordToIndex(b));
    for (std::size_t k = 1; k < cells.size(); ++k) EXPECT_EQ((cells[k] - cells[k - 1]).cwiseAbs().sum(), 1);
  }
  EXPECT_EQ(walk(g, Vec3(0.35, 0.35, 0.35), Vec3(1.55, 0.35, 0.35)).size(), 13u);
}

TEST(Traverse, StopsWhenTheVisitorSaysSo) {
  const GridGeometry g(Vec3(0, 0, 0), 0.1, Index3(20, 20, 20));
  int seen = 0;
  const bool done = go_feap::common::traverse(g, Vec3(0.05, 0.05, 0.05), Vec3(1.55, 0.85, 0.35), [&](const Index3&) {
    return ++seen < 4;
  });
  EXPECT_FALSE(done);
  EXPECT_EQ(seen, 4);
}

TEST(Traverse, InGridWalkGivesTheSameVoxelsAsLinearIndicesOrRefusesSegmentsLeavingTheGrid) {
  using go_feap::common::Walk;
  const GridGeometry g(Vec3(-1.0, -2.0, 0.5), 0.1, Index3(40, 30, 20));
  std::mt19937 rng(11);
  // Points from half a metre around the grid: some segments end outside it.
  std::uniform_real_distribution<double> ux(-1.5, 3.5), uy(-2.5, 1.5), uz(0.0, 3.0);
  int inside = 0, leaving = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vec3 a(ux(rng), uy(rng), uz(rng)), b(ux(rng), uy(rng), uz(rng));
    std::vector<std::size_t> linear;
    const Walk w = go_feap::common::traverseInGrid(g, a, b, [&](std::size_t l) {
      linear.push_back(l);
      return true;
    });
    const std::vector<Index3> cells = walk(g, a, b);
    if (!g.inside(g.coordToIndex(a)) || !g.inside(g.coordToIndex(b))) {
      EXPECT_EQ(w, Walk::kLeavesGrid) << trial;
      EXPECT_TRUE(linear.empty()) << trial;
      ++leaving;
      continue;
    }
    ++inside;
    EXPECT_EQ(w, Walk::kCompleted) << trial;
    ASSERT_EQ(linear.size(), cells.size()) << trial;
    for (std::size_t k = 0; k < cells.size(); ++k) {
      ASSERT_TRUE(g.inside(cells[k])) << trial;
      EXPECT_EQ(linear[k], g.linear(cells[k])) << trial << " voxel " << k;
    }
  }
  EXPECT_GT(inside, 100);
  EXPECT_GT(leaving, 100);
  // On the far face (its voxel is outside), far away, or not a number: refused, nothing visited.
  const GridGeometry h(Vec3(0, 0, 0), 0.1, Index3(20, 20, 20));
  int visits = 0;
  auto count = [&](std::size_t) { return ++visits > 0; };
  EXPECT_EQ(go_feap::common::traverseInGrid(h, Vec3(0.5, 0.5, 0.5), Vec3(2.0, 0.5, 0.5), count), Walk::kLeavesGrid);
  EXPECT_EQ(go_feap::common::traverseInGrid(h, Vec3(0.5, 0.5, 0.5), Vec3(1e300, 0.5, 0.5), count), Walk::kLeavesGrid);
  EXPECT_EQ(go_feap::common::traverseInGrid(h, Vec3(0.5, 0.5, 0.5), Vec3(std::nan(""), 0.5, 0.5), count),
            Walk::kLeavesGrid);
  EXPECT_EQ(visits, 0);
  // Up to the face's voxel, and stopped by the visitor.
  EXPECT_EQ(go_feap::common::traverseInGrid(h, Vec3(0.05, 0.05, 0.05), Vec3(1.95, 0.05, 0.05), count), Walk::kCompleted);
  EXPECT_EQ(visits, 20);
  visits = 0;
  EXPECT_EQ(go_feap::common::traverseInGrid(h, Vec3(0.05, 0.05, 0.05), Vec3(1.55, 0.85, 0.35),
                                            [&](std::size_t) { return ++visits < 4; }),
            Walk::kStopped);
  EXPECT_EQ(visits, 4);
}

// A source clock that goes back (a bag played again) pauses the monotonic clock for as long; it then goes
// on at the source's pace, and says each time by how much the source went back.
TEST(MonotonicClock, PausesForAsLongAsTheSourceWentBack) {
  go_feap::common::MonotonicClock clock;
  EXPECT_DOUBLE_EQ(clock.at(100.0), 100.0);
  EXPECT_DOUBLE_EQ(clock.wentBack(), 0.0);
  EXPECT_DOUBLE_EQ(clock.at(105.0), 105.0);
  EXPECT_DOUBLE_EQ(clock.at(25.0), 105.0);  // back 80 s
  EXPECT_DOUBLE_EQ(clock.wentBack(), 80.0);
  EXPECT_DOUBLE_EQ(clock.at(27.0), 107.0);
  EXPECT_DOUBLE_EQ(clock.wentBack(), 0.0);
  EXPECT_DOUBLE_EQ(clock.at(27.0), 107.0);  // standing still is not going back
  EXPECT_DOUBLE_EQ(clock.at(20.0), 107.0);  // back again: 7 s
  EXPECT_DOUBLE_EQ(clock.wentBack(), 7.0);
  EXPECT_DOUBLE_EQ(clock.at(21.5), 108.5);
}
