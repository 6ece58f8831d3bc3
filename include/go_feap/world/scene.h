// Ground-truth worlds for simulation: a voxel grid, an exploration box, a start pose.
#pragma once

#include <cstdint>
#include <string>

#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"

namespace go_feap::world {

using common::Aabb;
using common::Index3;
using common::Vec3;

/// Where the vehicle starts: position in the world frame (m) and yaw (rad, about +z).
struct StartPose {
  Vec3 position = Vec3::Zero();
  double yaw = 0.0;
};

/// Ground-truth voxel world. The grid covers the exploration box plus a margin, so that
/// geometry just outside the box (ceilings, walls) is still seen by a simulated camera.
/// Occupancy: 1 = occupied, 0 = free. Everything outside the grid is free.
struct Scene {
  std::string name;
  std::uint64_t seed = 0;
  bool seeded = false;  ///< generated from `seed` (maze, powerplant); a scene read from a file takes none
  Aabb box;
  StartPose start;
  common::DenseGrid<std::uint8_t> occupied;

  double resolution() const { return occupied.geometry().resolution(); }
  const common::GridGeometry& geometry() const { return occupied.geometry(); }
  /// Occupancy of the voxel containing `p`; outside the grid counts as free.
  /// Any point: one however far outside the grid, or NaN, is free (clampedIndex).
  bool isOccupied(const Vec3& p) const { return isOccupied(geometry().clampedIndex(p)); }
  bool isOccupied(const Index3& idx) const {
    return geometry().inside(idx) && occupied.at(idx) != 0;
  }
  std::size_t occupiedCount() const;
};

/// Most voxels a scene's grid may have (one byte each): 2^30, a 1 GiB grid, as 0.1 m voxels over about
/// 1000 m x 1000 m x 107 m. A typo in a resolution must be refused, not allocated (or wrapped round).
inline constexpr double kMaxSceneVoxels = 1073741824.0;

/// Voxels (as a double: it may not fit an integer) of the grid covering `box` expanded by `margin` at
/// `resolution`.
double sceneVoxelCount(const Aabb& box, double resolution, double margin);

/// Empty scene whose grid covers `box` expanded by `margin` metres.
Scene makeEmptyScene(const std::string& name, const Aabb& box, double resolution, double margin);

/// Marks the voxel containing `p` occupied. Returns false when `p` lies outside the grid.
bool markOccupied(Scene& scene, const Vec3& p);

/// Checks a scene before use: valid box and resolution, start inside the box and outside every
/// obstacle's voxel (its clearance is metrics::checkStartClearance()'s). The message names what is wrong.
common::Status validateScene(const Scene& scene);

/// Coverage reference (DESIGN §3.1): free voxels inside the box reachable from the start
/// through ground-truth free space (6-connected, staying in the box), plus occupied
/// voxels inside the box that are face-adjacent to them.
struct ObservableSet {
  common::DenseGrid<std::uint8_t> mask;  ///< 1 where the voxel is observable
  std::size_t free_count = 0;
  std::size_t occupied_count = 0;
  std::size_t total() const { return free_count + occupied_count; }
};
ObservableSet computeObservableSet(const Scene& scene);

/// Coverage = |known ∩ observable| / |observable|. `is_known(centre)` reports whether the
/// map has classified (free or occupied) the voxel whose centre is given.
template <typename KnownFn>
double coverage(const ObservableSet& observable, KnownFn&& is_known) {
  if (observable.total() == 0) return 0.0;
  const auto& geo = observable.mask.geometry();
  std::size_t known = 0;
  for (std::size_t l = 0; l < observable.mask.size(); ++l) {
    if (observable.mask[l] && is_known(geo.indexToCoord(geo.unlinear(l)))) ++known;
  }
  return static_cast<double>(known) / static_cast<double>(observable.total());
}

}  // namespace go_feap::world
