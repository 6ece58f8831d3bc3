// Camera paths through a scene's free space for the perf tools.
#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <vector>

#include "go_feap/world/scene.h"

namespace go_feap::tools {

using common::Index3;
using common::Vec3;

// True when no occupied voxel lies within `clearance` of p (a camera a vehicle could carry).
inline bool isClear(const world::Scene& scene, const Vec3& p, double clearance) {
  const auto& geo = scene.geometry();
  const Index3 lo = geo.coordToIndex(p - Vec3::Constant(clearance));
  const Index3 hi = geo.coordToIndex(p + Vec3::Constant(clearance));
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x)
        if (scene.isOccupied(Index3(x, y, z))) return false;
  return true;
}

// Camera poses along a Lissajous curve (one loop = `samples` steps) through the box at 1-2 m height, looking
// horizontally with a turning yaw; points too close to obstacles are skipped.
inline std::vector<Eigen::Isometry3d> cameraPath(const world::Scene& scene, int frames, int samples) {
  const Vec3 c = scene.box.center();
  const Vec3 half = 0.5 * scene.box.size() - Vec3::Constant(1.0);
  // Optical frame (z forward, x right, y down) in a body frame (x forward, z up).
  Eigen::Matrix3d R_B_C;
  R_B_C << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; poses.size() < static_cast<std::size_t>(frames) && i < 100 * samples; ++i) {
    const double s = 2.0 * M_PI * i / samples;
    const Vec3 p(c.x() + half.x() * std::sin(3.0 * s + 0.3), c.y() + half.y() * std::sin(2.0 * s),
                 1.5 + 0.5 * std::sin(7.0 * s));
    if (!isClear(scene, p, 0.3)) continue;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(6.0 * s, Vec3::UnitZ()).toRotationMatrix() * R_B_C;
    T.translation() = p;
    poses.push_back(T);
  }
  return poses;
}

}  // namespace go_feap::tools
