// Probabilistic occupancy from depth images (DESIGN §3.3): log-odds per voxel, one
// byte each, over a dense grid sized from the exploration box.
#pragma once

#include <opencv2/core.hpp>

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"

namespace go_feap::map {

using common::Aabb;
using common::Index3;
using common::Vec3;

enum class VoxelState : std::uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

struct OccupancyConfig {
  double resolution = 0.1;   ///< m
  double margin = 0.5;       ///< m of map kept around the exploration box
  double p_hit = 0.65;       ///< probability update for a voxel holding a return
  double p_miss = 0.35;      ///< probability update for a voxel a ray passes through
  double p_min = 0.12;       ///< clamp
  double p_max = 0.90;       ///< clamp
  double p_occupied = 0.80;  ///< occupied above this probability
  double min_range = 0.1;    ///< m, depth below (and -inf): a surface too near to measure, skipped
  double max_range = 4.5;    ///< m, depth beyond (and +inf): free up to max_range, no return
  int skip_pixel = 2;        ///< integrate every skip_pixel-th pixel in u and v
  /// m: a 32FC1 frame whose finite depths are mostly beyond this is refused (millimetres sent as metres,
  /// against REP 118: every pixel read past max_range and was cast free through the walls). > max_range.
  double max_plausible_depth = 100.0;
  bool invalid_as_free = false;  ///< 0/NaN pixels: skipped (REP 117: no measurement), or free up to max_range (a 16UC1 source whose 0 also means nothing in range)

  common::Status validate() const;
};

/// Pinhole camera model of the depth image.
struct DepthIntrinsics {
  int width = 0, height = 0;             ///< pixels
  double fx = 0, fy = 0, cx = 0, cy = 0;  ///< pixels

  /// Error naming what is wrong unless width and height are > 0, fx and fy finite and > 0, cx and cy finite.
  common::Status validate() const;
  bool operator==(const DepthIntrinsics& o) const {
    return width == o.width && height == o.height && fx == o.fx && fy == o.fy && cx == o.cx && cy == o.cy;
  }
  bool operator!=(const DepthIntrinsics& o) const { return !(*this == o); }
};

/// What one integrated frame changed.
struct FrameChange {
  std::size_t rays = 0;              ///< rays cast (after merging pixels that end in the same voxel)
  std::size_t pixels_used = 0;       ///< sampled pixels that were integrated
  std::size_t pixels_invalid = 0;    ///< sampled pixels that were 0, NaN, negative, -inf or below min_range
  std::size_t changed_voxels = 0;    ///< voxels whose state (unknown/free/occupied) changed
  bool any_change = false;
  Index3 changed_min = Index3::Zero(), changed_max = Index3::Zero();  ///< inclusive, when any_change
  std::vector<std::size_t> changed;          ///< linear indices of the voxels whose state changed
  std::vector<std::size_t> became_occupied;  ///< linear indices
  std::vector<std::size_t> stopped_occupied; ///< linear indices
};

/// The voxels' states at one moment, one byte each: what a slow reader (a .bt export) copies under the
/// map's lock, to work on without holding it.
struct OccupancySnapshot {
  common::GridGeometry geometry;
  std::vector<VoxelState> states;  ///< by linear index
};

class OccupancyMap {
 public:
  /// Map covering `box` expanded by config.margin. The config must pass validate().
  OccupancyMap(const OccupancyConfig& config, const Aabb& box);

  const OccupancyConfig& config() const { return config_; }
  const common::GridGeometry& geometry() const { return geo_; }
  const Aabb& box() const { return box_; }

  VoxelState state(const Index3& idx) const {
    if (!geo_.inside(idx)) return VoxelState::kUnknown;
    return stateOf(logodds_[geo_.linear(idx)]);
  }
  /// Of the voxel holding `p`: unknown outside the grid, for any point (NaN, 1e30: clampedIndex()).
  VoxelState state(const Vec3& p) const { return state(geo_.clampedIndex(p)); }
  VoxelState stateAt(std::size_t linear) const { return stateOf(logodds_[linear]); }
  OccupancySnapshot snapshot() const;
  /// Occupancy probability of a known voxel; 0.5 for unknown.
  double probability(const Index3& idx) const;

  /// Checks a depth image before integration: CV_32FC1 (m) or CV_16UC1 (mm), size equal to
  /// the intrinsics', finite positive focal lengths; a 32FC1 one whose finite positive depths (sampled
  /// every 8th pixel each way) are more than half beyond max_plausible_depth is refused.
  common::Status checkFrame(const cv::Mat& depth, const DepthIntrinsics& K) const;

  /// Integrates one depth image taken from T_W_C (camera optical frame to world). Returns
  /// an error (and changes nothing) when checkFrame fails.
  common::Result<FrameChange> integrate(const cv::Mat& depth, const DepthIntrinsics& K, const Eigen::Isometry3d& T_W_C);

  /// Sets a voxel's state directly (used when loading maps): occupied or free at the
  /// clamp value, or unknown.
  void setState(const Index3& idx, VoxelState s);

  /// True when no voxel on the segment from a to b is occupied (and, with
  /// `unknown_blocks`, none is unknown). Points outside the map block.
  bool isLineFree(const Vec3& a, const Vec3& b, bool unknown_blocks) const;

  std::size_t memoryBytes() const;
  /// Voxels that are free or occupied (kept up to date by integrate() and setState(), not counted).
  std::size_t knownCount() const { return known_; }

 private:
  static constexpr std::int8_t kUnknown = -128;
  static constexpr double kScale = 50.0;  // stored value = log-odds * kScale

 public:
  static constexpr double kScaleLimit() { return kScale; }

 private:
  VoxelState stateOf(std::int8_t v) const {
    return v == kUnknown ? VoxelState::kUnknown : (v > occupied_ ? VoxelState::kOccupied : VoxelState::kFree);
  }

  OccupancyConfig config_;
  Aabb box_;
  common::GridGeometry geo_;
  std::vector<std::int8_t> logodds_;
  std::size_t known_ = 0;  ///< voxels whose logodds_ is not kUnknown
  std::int8_t hit_, miss_, min_, max_, occupied_;
  // Per-frame scratch, cleared where set. marks_ holds two bits per voxel, the return
  // (kHitMark) and the free-space (kFreeMark) mark side by side, so that one load tells
  // whether a voxel was touched this frame; end_bits_ holds one bit per voxel.
  std::vector<std::uint64_t> marks_, end_bits_;
  std::vector<std::size_t> touched_;
  // Per sampled pixel (row-major, every skip_pixel-th), the push of a return behind its measured point in
  // depth units, kept while the intrinsics and skip_pixel stay (a square root and a division per pixel).
  std::vector<double> behind_;
  DepthIntrinsics behind_for_;
};

}  // namespace go_feap::map
