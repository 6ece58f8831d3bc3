// Voxel traversal along a segment (Amanatides & Woo 1987).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "go_feap/common/grid.h"

namespace go_feap::common {

namespace detail {

/// The walk of traverse(): calls `visit(x, y, z, l)` for each voxel, where l is the voxel's linear index when
/// kLinear (and the walk is then only valid with every voxel in the grid), else 0.
template <bool kLinear, typename Visit>
bool walk(const GridGeometry& geo, const Vec3& pa, const Vec3& pb, const Index3& cur, const Index3& last,
          Visit&& visit) {
  const Vec3 d = pb - pa;
  Index3 step;
  Vec3 t_max, t_delta;
  for (int i = 0; i < 3; ++i) {
    if (d[i] > 0.0) {
      step[i] = 1;
      t_delta[i] = 1.0 / d[i];
      t_max[i] = (std::floor(pa[i]) + 1.0 - pa[i]) * t_delta[i];
    } else if (d[i] < 0.0) {
      step[i] = -1;
      t_delta[i] = -1.0 / d[i];
      t_max[i] = (pa[i] - std::floor(pa[i])) * t_delta[i];
    } else {
      step[i] = 0;
      t_delta[i] = std::numeric_limits<double>::infinity();
      t_max[i] = std::numeric_limits<double>::infinity();
    }
  }
  // The number of steps is fixed by the end voxel, which guards against rounding.
  int steps = (last - cur).cwiseAbs().sum();
  // The walk runs on scalars and picks the axis without branching: which boundary comes
  // next is unpredictable, and a mispredicted branch per voxel costs more than the step.
  int x = cur[0], y = cur[1], z = cur[2];
  double tx = t_max[0], ty = t_max[1], tz = t_max[2];
  const std::ptrdiff_t sx = step[0], sy = kLinear ? step[1] * static_cast<std::ptrdiff_t>(geo.dims().x()) : 0,
                       sz = kLinear ? step[2] * static_cast<std::ptrdiff_t>(geo.dims().x()) * geo.dims().y() : 0;
  std::size_t l = kLinear ? geo.linear(cur) : 0;
  if (!visit(x, y, z, l)) return false;
  while (steps-- > 0) {
    const bool y_before_x = ty < tx;
    bool step_z = tz < std::min(tx, ty);
    bool step_y = !step_z && y_before_x;
    bool step_x = !step_z && !y_before_x;
    // Never step past the end voxel along an axis (can happen at exact ties).
    if ((step_x && x == last[0]) || (step_y && y == last[1]) || (step_z && z == last[2])) {
      step_x = x != last[0];
      step_y = !step_x && y != last[1];
      step_z = !step_x && !step_y;
    }
    x += step_x ? step[0] : 0;
    y += step_y ? step[1] : 0;
    z += step_z ? step[2] : 0;
    if constexpr (kLinear) l += step_x ? sx : (step_y ? sy : sz);
    tx += step_x ? t_delta[0] : 0.0;
    ty += step_y ? t_delta[1] : 0.0;
    tz += step_z ? t_delta[2] : 0.0;
    if (!visit(x, y, z, l)) return false;
  }
  return true;
}

}  // namespace detail

/// Visits, in order, every voxel of `geo`'s lattice that the segment from `a` to `b`
/// passes through, starting with the voxel of `a` and ending with the voxel of `b`.
/// `visit(const Index3&)` returns false to stop early; the function then returns false.
/// Voxels outside the grid are visited too (callers check `geo.inside`).
template <typename Visit>
bool traverse(const GridGeometry& geo, const Vec3& a, const Vec3& b, Visit&& visit) {
  const double res = geo.resolution();
  const Vec3 pa = (a - geo.origin()) / res, pb = (b - geo.origin()) / res;  // voxel units
  const Index3 cur = pa.array().floor().cast<int>(), last = pb.array().floor().cast<int>();
  return detail::walk<false>(geo, pa, pb, cur, last,
                             [&](int x, int y, int z, std::size_t) { return visit(Index3(x, y, z)); });
}

/// What traverseInGrid() did.
enum class Walk { kCompleted, kStopped, kLeavesGrid };

/// The walk of traverse() for a segment whose first and last voxels both lie in the grid (then so does
/// every voxel between them: the walk is monotone on each axis), with `visit(std::size_t)` given each
/// voxel's linear index: no bounds check per voxel. kLeavesGrid (nothing visited) when an end voxel lies
/// outside; else kStopped when `visit` returned false, kCompleted otherwise.
template <typename Visit>
Walk traverseInGrid(const GridGeometry& geo, const Vec3& a, const Vec3& b, Visit&& visit) {
  const double res = geo.resolution();
  const Vec3 pa = (a - geo.origin()) / res, pb = (b - geo.origin()) / res;  // voxel units
  // Compared as doubles first: a far-away point must not overflow the cast to int.
  const Vec3 hi = geo.dims().cast<double>();
  if (!((pa.array() >= 0.0).all() && (pa.array() < hi.array()).all() && (pb.array() >= 0.0).all() &&
        (pb.array() < hi.array()).all()))
    return Walk::kLeavesGrid;
  const Index3 cur = pa.array().floor().cast<int>(), last = pb.array().floor().cast<int>();
  return detail::walk<true>(geo, pa, pb, cur, last, [&](int, int, int, std::size_t l) { return visit(l); })
             ? Walk::kCompleted
             : Walk::kStopped;
}

}  // namespace go_feap::common
