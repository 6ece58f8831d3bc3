// Voxel traversal along a segment (Amanatides & Woo 1987).
#pragma once

#include <algorithm>
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
  // The walk runs on scalars and picks the axis without branching: which boundary comes
  // next is unpredictable, and a mispredicted branch per voxel costs more than the step.
  int x = cur[0], y = cur[1], z = cur[2];
  double tx = t_max[0], ty = t_max[1], tz = t_max[2];
  if (!visit(Index3(x, y, z))) return false;
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
    tx += step_x ? t_delta[0] : 0.0;
    ty += step_y ? t_delta[1] : 0.0;
    tz += step_z ? t_delta[2] : 0.0;
    if (!visit(Index3(x, y, z))) return false;
  }
  return true;
}

}  // namespace go_feap::common
