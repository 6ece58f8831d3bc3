// Voxel traversal along a segment (Amanatides & Woo 1987).
#pragma once

#include <cmath>
#include <limits>

#include "go_feap/common/grid.h"

namespace go_feap::common {

/// Visits, in order, every voxel of `geo`'s lattice that the segment from `a` to `b`
/// passes through, starting with the voxel of `a` and ending with the voxel of `b`.
/// `visit(const Index3&)` returns false to stop early; the function then returns false.
/// Voxels outside the grid are visited too (callers check `geo.inside`).
template <typename Visit>
bool traverse(const GridGeometry& geo, const Vec3& a, const Vec3& b, Visit&& visit) {
  const double res = geo.resolution();
  const Vec3 pa = (a - geo.origin()) / res, pb = (b - geo.origin()) / res;  // voxel units
  Index3 cur = pa.array().floor().cast<int>(), last = pb.array().floor().cast<int>();
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
  if (!visit(static_cast<const Index3&>(cur))) return false;
  while (steps-- > 0) {
    int axis = 0;
    if (t_max[1] < t_max[axis]) axis = 1;
    if (t_max[2] < t_max[axis]) axis = 2;
    // Never step past the end voxel along an axis (can happen at exact ties).
    if (cur[axis] == last[axis]) {
      for (int i = 0; i < 3; ++i)
        if (cur[i] != last[i]) {
          axis = i;
          break;
        }
    }
    cur[axis] += step[axis];
    t_max[axis] += t_delta[axis];
    if (!visit(static_cast<const Index3&>(cur))) return false;
  }
  return true;
}

}  // namespace go_feap::common
