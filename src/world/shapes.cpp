#include "go_feap/world/shapes.h"

#include <cmath>

namespace go_feap::world {
namespace {

// Calls fn(index, centre) for every grid voxel whose centre lies in `box`.
template <typename Fn>
void forEachVoxelIn(const Scene& scene, const Aabb& box, Fn&& fn) {
  const auto& geo = scene.geometry();
  Index3 lo, hi;
  geo.centreRange(box, lo, hi);
  for (int z = lo.z(); z < hi.z(); ++z)
    for (int y = lo.y(); y < hi.y(); ++y)
      for (int x = lo.x(); x < hi.x(); ++x) {
        const Index3 idx(x, y, z);
        fn(idx, geo.indexToCoord(idx));
      }
}

}  // namespace

void fillBox(Scene& scene, const Aabb& box) {
  forEachVoxelIn(scene, box, [&](const Index3& idx, const Vec3&) { scene.occupied.at(idx) = 1; });
}

void clearBox(Scene& scene, const Aabb& box) {
  forEachVoxelIn(scene, box, [&](const Index3& idx, const Vec3&) { scene.occupied.at(idx) = 0; });
}

void fillVerticalCylinder(Scene& scene, double cx, double cy, double radius, double z0, double z1,
                          double wall) {
  const Aabb bounds{Vec3(cx - radius, cy - radius, z0), Vec3(cx + radius, cy + radius, z1)};
  const double inner = wall > 0.0 ? std::max(0.0, radius - wall) : -1.0;
  forEachVoxelIn(scene, bounds, [&](const Index3& idx, const Vec3& c) {
    const double d = std::hypot(c.x() - cx, c.y() - cy);
    if (d <= radius && d >= inner) scene.occupied.at(idx) = 1;
  });
}

void fillPipe(Scene& scene, const Vec3& a, const Vec3& b, double radius) {
  Aabb bounds{a.cwiseMin(b), a.cwiseMax(b)};
  bounds = bounds.expanded(radius);
  const Vec3 axis = (b - a).normalized();
  forEachVoxelIn(scene, bounds, [&](const Index3& idx, const Vec3& c) {
    const Vec3 rel = c - a;
    const double along = rel.dot(axis);
    if (along < 0.0 || along > (b - a).norm()) return;
    if ((rel - along * axis).norm() <= radius) scene.occupied.at(idx) = 1;
  });
}

void fillSphere(Scene& scene, const Vec3& centre, double radius) {
  const Aabb bounds = Aabb{centre, centre}.expanded(radius);
  forEachVoxelIn(scene, bounds, [&](const Index3& idx, const Vec3& c) {
    if ((c - centre).norm() <= radius) scene.occupied.at(idx) = 1;
  });
}

}  // namespace go_feap::world
