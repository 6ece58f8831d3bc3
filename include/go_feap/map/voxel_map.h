// The mapper's map: occupancy from depth plus the incremental ESDF kept in step with it.
#pragma once

#include <string>

#include "go_feap/map/esdf.h"
#include "go_feap/map/occupancy_map.h"

namespace go_feap::map {

struct MapConfig {
  OccupancyConfig occupancy;
  EsdfConfig esdf;
  common::Status validate() const;
  /// validate(), and a box that is finite with min < max whose map (box and margin at the resolution)
  /// has at most 2^32 - 1 voxels (the ESDF indexes them in 32 bits).
  common::Status validate(const Aabb& box) const;
  /// Bytes the map of `box` (and margin) takes, about: kBytesPerVoxel a voxel (the occupancy's byte and
  /// frame bits, the ESDF's 3-byte offset and its bit). Known before it is allocated.
  double estimatedBytes(const Aabb& box) const;
  static constexpr double kBytesPerVoxel = 1.0 + 0.25 + 0.125 + 3.0 + 0.125;
  /// Error naming the keys when estimatedBytes(box) exceeds `memory_bytes` (the machine's: allocating it
  /// would end in the OOM killer taking the whole process, without a word of why).
  common::Status checkFits(const Aabb& box, double memory_bytes) const;
};

/// What one integrated frame changed, in world terms.
struct MapUpdateInfo {
  FrameChange frame;
  std::size_t esdf_changed = 0;  ///< voxels whose distance changed
  Aabb changed_box;              ///< world box of the voxels whose state changed (valid when frame.any_change)
};

/// Writes the known voxels (occupied and free) of `map` as an OctoMap .bt at its resolution, written beside
/// and renamed over `path`; fails, writing nothing, on a voxel beyond OctoMap's reach.
common::Status saveBt(const OccupancySnapshot& map, const std::string& path);

class VoxelMap {
 public:
  /// Map sized from the exploration box (plus the occupancy margin). Config must validate.
  VoxelMap(const MapConfig& config, const Aabb& box);

  /// Integrates a depth image and updates the ESDF where occupancy flipped.
  common::Result<MapUpdateInfo> integrate(const cv::Mat& depth, const DepthIntrinsics& K,
                                          const Eigen::Isometry3d& T_W_C);

  const OccupancyMap& occupancy() const { return occupancy_; }
  const Esdf& esdf() const { return esdf_; }
  const common::GridGeometry& geometry() const { return occupancy_.geometry(); }
  const MapConfig& config() const { return config_; }

  /// Writes known voxels (occupied and free) as an OctoMap .bt at the map resolution (map::saveBt() of a
  /// snapshot).
  common::Status saveBt(const std::string& path) const;
  /// Reads an OctoMap .bt into this map (voxels outside it are dropped; voxels the file
  /// does not mention stay as they are) and brings the ESDF up to date.
  common::Status loadBt(const std::string& path);

  std::size_t memoryBytes() const { return occupancy_.memoryBytes() + esdf_.memoryBytes(); }

 private:
  MapConfig config_;
  OccupancyMap occupancy_;
  Esdf esdf_;
};

}  // namespace go_feap::map
