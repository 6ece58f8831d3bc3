#include <algorithm>
#include <array>
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
  // Triangle normal. Skipped for a triangle thinner than a thousandth of a voxel (twice its area over its
  // longest edge): for a collinear one the computed normal is rounding noise, which cut away voxels the
  // triangle's own points lie in. The axes left are those of a segment, the shape such a triangle has,
  // so at most voxels within that thinness of it are marked besides. (A threshold on the sine of an
  // angle instead took a 0.8 m wide sliver 3e8 m long for a segment and marked a slab beside it.)
  const Vec3 n = e[0].cross(e[1]);
  const double longest2 = std::max({e[0].squaredNorm(), e[1].squaredNorm(), e[2].squaredNorm()});
  if (n.squaredNorm() > 4e-6 * h * h * longest2) {
    const double r_n = h * n.cwiseAbs().sum();
    if (std::abs(n.dot(v0)) > r_n) return false;
  }
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

// A triangle cut by up to four axis-aligned planes: 7 vertices at most in exact arithmetic (each cut of a
// convex polygon adds at most one). Rounding in the cut points can make the piece very slightly
// non-convex, so that a cut crosses it more than twice: room for 16 keeps every clip() in bounds (a
// 5-vertex strip gives at most 7 after one column cut and 10 after the other).
struct Polygon {
  std::array<Vec3, 16> p;
  int n = 0;
};

// The part of `in` on the kept side of the plane x[axis] = bound (Sutherland-Hodgman, one plane).
Polygon clip(const Polygon& in, int axis, double bound, bool keep_above) {
  Polygon out;
  for (int i = 0; i < in.n; ++i) {
    const Vec3& p = in.p[i];
    const Vec3& q = in.p[(i + 1) % in.n];
    const double dp = keep_above ? p[axis] - bound : bound - p[axis];
    const double dq = keep_above ? q[axis] - bound : bound - q[axis];
    if (dp >= 0.0) out.p[out.n++] = p;
    if ((dp >= 0.0) != (dq >= 0.0)) {
      Vec3& x = out.p[out.n++];
      x = p + (dp / (dp - dq)) * (q - p);
      x[axis] = bound;  // exact: with far vertices (1e30 m) the interpolation may miss the plane by metres
    }
  }
  return out;
}

// Extent of `poly` along `axis`.
void extent(const Polygon& poly, int axis, double& lo, double& hi) {
  lo = hi = poly.p[0][axis];
  for (int i = 1; i < poly.n; ++i) {
    lo = std::min(lo, poly.p[i][axis]);
    hi = std::max(hi, poly.p[i][axis]);
  }
}

}  // namespace

bool triangleMarksVoxel(const common::GridGeometry& geo, const Index3& idx, const Vec3& a, const Vec3& b,
                        const Vec3& c) {
  const double res = geo.resolution();
  // Voxels are half-open [lo, lo + res): test against a box nudged by -eps so that a
  // triangle lying exactly on a voxel face marks the voxel on its positive side only.
  const Vec3 centre = geo.indexToCoord(idx) - Vec3::Constant(1e-6 * res);
  return triangleOverlapsBox(a - centre, b - centre, c - centre, 0.5 * res);
}

void voxelizeTriangle(Scene& scene, const Vec3& a, const Vec3& b, const Vec3& c) {
  const auto& geo = scene.geometry();
  const double res = geo.resolution();
  // Candidates are found column by column rather than over the triangle's whole bounding box (a long
  // diagonal triangle's box holds far more voxels than the triangle touches): the triangle is cut to
  // each strip along u, then to each column of that strip along v, and only the voxels of the column
  // within the cut piece's extent along d are tested. Strips and extents are widened by `pad`, more than
  // the -eps nudge of triangleMarksVoxel, so every voxel it would mark is tested; the test decides.
  const double pad = 2e-6 * res;
  const Vec3 n = (b - a).cross(c - a);
  int d = 0;  // the normal's largest component: each column then crosses the plane over at most ~2 voxels
  n.cwiseAbs().maxCoeff(&d);
  const int u = (d + 1) % 3, v = (d + 2) % 3;
  // Index of the voxel holding `x` along `axis`, clamped to the grid.
  auto index = [&](double x, int axis) {
    const double f = std::floor((x - geo.origin()[axis]) / res);
    return static_cast<int>(std::clamp(f, 0.0, static_cast<double>(geo.dims()[axis] - 1)));
  };
  // Nothing to do for a triangle wholly outside the grid (the clamped ranges would still hold one voxel),
  // nor for one with a vertex that is not finite (the loaders refuse those).
  if (!(a.allFinite() && b.allFinite() && c.allFinite())) return;
  const Vec3 lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
  const common::Aabb bounds = geo.bounds();
  for (int k = 0; k < 3; ++k)
    if (!(hi[k] >= bounds.min[k] - pad && lo[k] <= bounds.max[k] + pad)) return;
  Polygon tri;
  tri.p[0] = a, tri.p[1] = b, tri.p[2] = c, tri.n = 3;
  for (int iu = index(lo[u] - pad, u), iu1 = index(hi[u] + pad, u); iu <= iu1; ++iu) {
    const double u0 = geo.origin()[u] + iu * res;
    const Polygon strip = clip(clip(tri, u, u0 - pad, true), u, u0 + res + pad, false);
    if (strip.n == 0) continue;
    double v_lo, v_hi;
    extent(strip, v, v_lo, v_hi);
    if (!(std::isfinite(v_lo) && std::isfinite(v_hi))) continue;  // cut points overflowed (vertices ~1e300 m)
    for (int iv = index(v_lo - pad, v), iv1 = index(v_hi + pad, v); iv <= iv1; ++iv) {
      const double v0 = geo.origin()[v] + iv * res;
      const Polygon column = clip(clip(strip, v, v0 - pad, true), v, v0 + res + pad, false);
      if (column.n == 0) continue;
      double d_lo, d_hi;
      extent(column, d, d_lo, d_hi);
      if (!(std::isfinite(d_lo) && std::isfinite(d_hi))) continue;
      Index3 idx;
      idx[u] = iu, idx[v] = iv;
      for (int id = index(d_lo - pad, d), id1 = index(d_hi + pad, d); id <= id1; ++id) {
        idx[d] = id;
        if (triangleMarksVoxel(geo, idx, a, b, c)) scene.occupied.at(idx) = 1;
      }
    }
  }
}

void voxelizeParallelepiped(Scene& scene, const Vec3& centre, const Eigen::Matrix3d& half) {
  const auto& geo = scene.geometry();
  const double res = geo.resolution();
  if (!(centre.allFinite() && half.allFinite())) return;
  const double shortest = 2.0 * half.colwise().norm().minCoeff();
  const double tol = 1e-6 * std::min(res, shortest);
  // Candidates: the voxels that the solid's bounds overlap by more than tol on every axis, clamped to the grid
  // as doubles (a solid far outside must not overflow the cast to int).
  const Vec3 reach = half.cwiseAbs().rowwise().sum();
  Index3 lo, hi;
  for (int a = 0; a < 3; ++a) {
    const double from = (centre[a] - reach[a] + tol - geo.origin()[a]) / res;
    const double to = (centre[a] + reach[a] - tol - geo.origin()[a]) / res;
    const double dim = static_cast<double>(geo.dims()[a]);
    lo[a] = static_cast<int>(std::clamp(std::floor(from), 0.0, dim));
    hi[a] = static_cast<int>(std::clamp(std::ceil(to), 0.0, dim));
  }
  // Separating axes of a voxel and the solid: the grid's axes, the solid's face normals and the cross products
  // of their edges (the grid's alone for an axis-aligned box). Along each the two must overlap by more than
  // tol; the solid's half width along an axis does not depend on the voxel.
  std::array<Vec3, 15> axes;
  std::array<double, 15> solid_half;
  int n = 0;
  const bool aligned = ((half.array() != 0.0).cast<int>().colwise().sum() == 1).all();
  auto add = [&](const Vec3& u, const Vec3& v) {
    const Vec3 axis = u.cross(v);
    const double length = axis.norm();
    if (!(length > 1e-9 * u.norm() * v.norm())) return;  // parallel edges: the other axes decide
    axes[n] = axis / length;
    solid_half[n] = (half.transpose() * axes[n]).cwiseAbs().sum();
    ++n;
  };
  for (int a = 0; a < 3; ++a) add(Vec3::Unit((a + 1) % 3), Vec3::Unit((a + 2) % 3));
  if (!aligned) {
    for (int i = 0; i < 3; ++i) {
      add(half.col((i + 1) % 3), half.col((i + 2) % 3));
      for (int a = 0; a < 3; ++a) add(Vec3::Unit(a), half.col(i));
    }
  }
  for (int z = lo.z(); z < hi.z(); ++z)
    for (int y = lo.y(); y < hi.y(); ++y)
      for (int x = lo.x(); x < hi.x(); ++x) {
        const Index3 idx(x, y, z);
        const Vec3 d = centre - geo.indexToCoord(idx);
        bool overlaps = true;
        for (int k = 0; k < n && overlaps; ++k)
          overlaps = 0.5 * res * axes[k].cwiseAbs().sum() + solid_half[k] - std::abs(axes[k].dot(d)) > tol;
        if (overlaps) scene.occupied.at(idx) = 1;
      }
}

}  // namespace go_feap::world
