#include <algorithm>
#include <cmath>

#include "go_feap/world/scene_files.h"

namespace go_feap::world {

namespace {

// Separating-axis test between a triangle (vertices relative to the box centre) and an
// axis-aligned box of half extent h (Akenine-Möller's formulation of the 13 axes).
bool triangleOverlapsBox(const Vec3& v0, const Vec3& v1, const Vec3& v2, double h) {
  const Vec3 e[3] = {v1 - v0, v2 - v1, v0 - v2};
  const Vec3 v[3] = {v0, v1, v2};
  // Box face normals.
  for (int a = 0; a < 3; ++a) {
    const double mn = std::min({v0[a], v1[a], v2[a]}), mx = std::max({v0[a], v1[a], v2[a]});
    if (mn > h || mx < -h) return false;
  }
  // Triangle normal.
  const Vec3 n = e[0].cross(e[1]);
  const double r_n = h * n.cwiseAbs().sum();
  if (std::abs(n.dot(v0)) > r_n) return false;
  // Cross products of box axes and triangle edges.
  for (const Vec3& edge : e) {
    for (int a = 0; a < 3; ++a) {
      const Vec3 axis = Vec3::Unit(a).cross(edge);
      if (axis.squaredNorm() < 1e-24) continue;
      const double p0 = axis.dot(v[0]), p1 = axis.dot(v[1]), p2 = axis.dot(v[2]);
      const double r = h * axis.cwiseAbs().sum();
      if (std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r) return false;
    }
  }
  return true;
}

}  // namespace

void voxelizeTriangle(Scene& scene, const Vec3& a, const Vec3& b, const Vec3& c) {
  const auto& geo = scene.geometry();
  const double res = geo.resolution();
  // Voxels are half-open [lo, lo + res): test against a box nudged by -eps so that a
  // triangle lying exactly on a voxel face marks the voxel on its positive side only.
  const double eps = 1e-6 * res;
  const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
  const Index3 i0 = geo.clampedIndex(lo - Vec3::Constant(eps)).cwiseMax(Index3::Zero());
  const Index3 i1 = geo.clampedIndex(hi + Vec3::Constant(eps)).cwiseMin(geo.dims() - Index3::Ones());
  for (int z = i0.z(); z <= i1.z(); ++z)
    for (int y = i0.y(); y <= i1.y(); ++y)
      for (int x = i0.x(); x <= i1.x(); ++x) {
        const Index3 idx(x, y, z);
        const Vec3 centre = geo.indexToCoord(idx) - Vec3::Constant(eps);
        if (triangleOverlapsBox(a - centre, b - centre, c - centre, 0.5 * res)) scene.occupied.at(idx) = 1;
      }
}

}  // namespace go_feap::world
