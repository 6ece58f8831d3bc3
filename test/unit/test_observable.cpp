// Observable set and coverage on a hand-built room with a sealed cavity.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <random>

#include "go_feap/world/scene.h"
#include "go_feap/world/shapes.h"

using namespace go_feap::world;
using go_feap::common::Index3;

namespace {

// Box [0, 2]^3 at 0.1 m (20^3 voxels); its outermost voxel layer is wall, floor and
// ceiling; inside, a hollow 6^3-voxel cube (voxels 5..10) seals a 4^3 cavity.
Scene sealedCavityRoom() {
  Scene s = makeEmptyScene("room", {Vec3::Zero(), Vec3::Constant(2.0)}, 0.1, 0.0);
  const auto& g = s.geometry();
  for (std::size_t l = 0; l < g.size(); ++l) {
    const Index3 i = g.unlinear(l);
    const bool shell = (i.array() == 0).any() || (i.array() == 19).any();
    const bool cube = (i.array() >= 5).all() && (i.array() <= 10).all();
    const bool cavity = (i.array() >= 6).all() && (i.array() <= 9).all();
    s.occupied[l] = shell || (cube && !cavity);
  }
  s.start.position = Vec3(0.35, 0.35, 1.55);
  return s;
}

}  // namespace

TEST(ObservableSet, SealedCavityIsExcluded) {
  const Scene s = sealedCavityRoom();
  ASSERT_TRUE(validateScene(s)) << validateScene(s).message();
  const ObservableSet o = computeObservableSet(s);
  // Free: 18^3 interior minus the 6^3 cube. Occupied: the 6 inner faces of the shell
  // (18 x 18 each; shell edges touch no interior voxel) plus the cube's whole surface.
  EXPECT_EQ(o.free_count, 18u * 18 * 18 - 6 * 6 * 6);
  EXPECT_EQ(o.occupied_count, 6u * 18 * 18 + (6 * 6 * 6 - 4 * 4 * 4));
  EXPECT_EQ(o.total(), o.free_count + o.occupied_count);
  // The cavity's inside is free but not observable.
  EXPECT_FALSE(o.mask.at(Index3(7, 7, 7)));
  EXPECT_FALSE(s.occupied.at(Index3(7, 7, 7)));
  // Shell corners touch no free voxel through a face.
  EXPECT_FALSE(o.mask.at(Index3(0, 0, 0)));
  EXPECT_TRUE(o.mask.at(Index3(0, 5, 5)));
}

TEST(ObservableSet, FloodFillStaysInsideTheBox) {
  // An open-sided room: with the grid margin, free space outside the box is not counted.
  Scene s = makeEmptyScene("open", {Vec3::Zero(), Vec3(1.0, 1.0, 1.0)}, 0.1, 0.5);
  s.start.position = Vec3(0.55, 0.55, 0.55);
  const ObservableSet o = computeObservableSet(s);
  EXPECT_EQ(o.free_count, 1000u);
  EXPECT_EQ(o.occupied_count, 0u);
  // A start in the margin, outside the box, reaches nothing of it (the fill must not seed from there and
  // spill into the box).
  s.start.position = Vec3(-0.05, 0.55, 0.55);
  const ObservableSet outside = computeObservableSet(s);
  EXPECT_EQ(outside.total(), 0u);
  for (std::size_t l = 0; l < outside.mask.size(); ++l) ASSERT_FALSE(outside.mask[l]) << l;
}

TEST(Coverage, CountsKnownObservableVoxels) {
  const Scene s = sealedCavityRoom();
  const ObservableSet o = computeObservableSet(s);
  EXPECT_DOUBLE_EQ(coverage(o, [](const Vec3&) { return true; }), 1.0);
  EXPECT_DOUBLE_EQ(coverage(o, [](const Vec3&) { return false; }), 0.0);
  // Knowing only the lower half (z < 1 m) of the room.
  std::size_t expect = 0;
  for (std::size_t l = 0; l < o.mask.size(); ++l)
    expect += o.mask[l] && s.geometry().unlinear(l).z() < 10;
  EXPECT_DOUBLE_EQ(coverage(o, [](const Vec3& p) { return p.z() < 1.0; }),
                   static_cast<double>(expect) / o.total());
}

TEST(ValidateScene, RejectsStartInObstacleOrOutsideBox) {
  Scene s = sealedCavityRoom();
  s.start.position = Vec3(0.55, 0.55, 0.55);  // in the cube's shell (voxel 5)
  auto st = validateScene(s);
  ASSERT_FALSE(st);
  EXPECT_NE(st.message().find("inside an obstacle"), std::string::npos) << st.message();
  s.start.position = Vec3(3.0, 0.5, 0.5);
  st = validateScene(s);
  ASSERT_FALSE(st);
  EXPECT_NE(st.message().find("outside the exploration box"), std::string::npos) << st.message();
}

// A hollow cylinder is the ring between radius - wall and radius, a solid one (wall 0) the disc: every voxel
// centre against the closed form.
TEST(Shapes, HollowCylinderLeavesTheAxisFree) {
  for (const double wall : {0.3, 0.0}) {
    SCOPED_TRACE("wall " + std::to_string(wall));
    Scene s = makeEmptyScene("tube", {Vec3(-2, -2, 0), Vec3(2, 2, 2)}, 0.1, 0.0);
    const double cx = 0.03, cy = -0.02, radius = 1.0;
    fillVerticalCylinder(s, cx, cy, radius, 0.0, 2.0, wall);
    EXPECT_EQ(s.isOccupied(Vec3(0.05, 0.05, 1.0)), wall == 0.0);
    const auto& g = s.geometry();
    std::size_t mismatches = 0, inside = 0;
    for (std::size_t l = 0; l < g.size(); ++l) {
      const Vec3 c = g.indexToCoord(g.unlinear(l));
      const double d = std::hypot(c.x() - cx, c.y() - cy);
      const bool expect = d <= radius && (wall == 0.0 || d >= radius - wall);
      inside += expect;
      mismatches += expect != (s.occupied.at(g.unlinear(l)) != 0);
    }
    EXPECT_GT(inside, 0u);
    EXPECT_EQ(mismatches, 0u);
  }
}

// A pipe is the solid cylinder between its end points, capped flat there: every voxel centre against the
// closed form (within the radius of the axis, between the ends along it), for pipes along x, along y (as the
// powerplant's first rack) and askew.
TEST(Shapes, APipeFillsItsCylinderBetweenItsEnds) {
  const double radius = 0.27;
  for (const auto& [a, b] : {std::pair{Vec3(-0.98, 0.02, 1.03), Vec3(0.98, 0.02, 1.03)},
                             std::pair{Vec3(0.02, -0.87, 1.03), Vec3(0.02, 0.91, 1.03)},
                             std::pair{Vec3(-0.9, -0.6, 0.5), Vec3(0.8, 0.7, 1.4)}}) {
    SCOPED_TRACE("from " + std::to_string(a.x()) + " " + std::to_string(a.y()) + " to " + std::to_string(b.x()) + " " +
                 std::to_string(b.y()));
    Scene s = makeEmptyScene("pipe", {Vec3(-2, -2, 0), Vec3(2, 2, 2)}, 0.1, 0.0);
    fillPipe(s, a, b, radius);
    const auto& g = s.geometry();
    const Vec3 u = (b - a) / (b - a).norm();
    std::size_t mismatches = 0, inside = 0;
    for (std::size_t l = 0; l < g.size(); ++l) {
      const Vec3 c = g.indexToCoord(g.unlinear(l));
      const double t = (c - a).dot(u);
      const bool expect = t >= 0.0 && t <= (b - a).norm() && (c - a).cross(u).norm() <= radius;
      inside += expect;
      mismatches += expect != (s.occupied.at(g.unlinear(l)) != 0);
    }
    EXPECT_GT(inside, 100u);
    EXPECT_EQ(mismatches, 0u);
  }
}

// The scan-line fill against a plain breadth-first fill over face neighbours (the oracle), on random
// boxes of random clutter, with margins outside the box that must stay out of the set.
TEST(ObservableSet, ScanLineFillMatchesABreadthFirstFill) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int compared = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const Vec3 size(0.5 + 2.0 * unit(rng), 0.5 + 2.0 * unit(rng), 0.3 + 1.5 * unit(rng));
    Scene s = makeEmptyScene("clutter", {Vec3::Zero(), size}, 0.1, trial % 3 == 0 ? 0.0 : 0.3);
    const double density = 0.1 + 0.5 * unit(rng);
    for (std::size_t l = 0; l < s.occupied.size(); ++l) s.occupied[l] = unit(rng) < density;
    const auto& g = s.geometry();
    Index3 lo, hi;
    g.centreRange(s.box, lo, hi);
    Index3 start;  // a voxel of the box (a start outside it has an empty set)
    for (int k = 0; k < 3; ++k) start[k] = lo[k] + static_cast<int>(unit(rng) * (hi[k] - lo[k]) * 0.999);
    s.start.position = g.indexToCoord(start);
    s.occupied.at(start) = 0;
    const ObservableSet o = computeObservableSet(s);
    // Oracle.
    auto in_box = [&](const Index3& i) { return (i.array() >= lo.array()).all() && (i.array() < hi.array()).all(); };
    std::vector<char> seen(g.size(), 0);
    std::vector<Index3> queue{g.coordToIndex(s.start.position)};
    seen[g.linear(queue[0])] = 1;
    std::size_t free_count = 1, occupied_count = 0;
    for (std::size_t head = 0; head < queue.size(); ++head)
      for (const Index3& off : go_feap::common::faceNeighbours()) {
        const Index3 nb = queue[head] + off;
        if (!in_box(nb) || seen[g.linear(nb)]) continue;
        seen[g.linear(nb)] = 1;
        if (s.occupied.at(nb)) {
          ++occupied_count;
        } else {
          ++free_count;
          queue.push_back(nb);
        }
      }
    EXPECT_EQ(o.free_count, free_count) << "trial " << trial;
    EXPECT_EQ(o.occupied_count, occupied_count) << "trial " << trial;
    for (std::size_t l = 0; l < g.size(); ++l) ASSERT_EQ(o.mask[l] != 0, seen[l] != 0) << "trial " << trial << " voxel " << l;
    compared += free_count > 10;
  }
  EXPECT_GT(compared, 20);  // most starts reach more than their own neighbourhood
}
