// Incremental Euclidean distance field (the mapper's ESDF, DESIGN §3.3) over a dense voxel grid: the
// distance from every voxel centre to the nearest obstacle voxel centre, kept up to date as obstacles
// appear and disappear, in 3 bytes + 1 bit per voxel.
#pragma once

#include <cstdint>
#include <vector>

#include "go_feap/common/bits.h"
#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"

namespace go_feap::map {

struct EsdfConfig {
  double max_distance = 2.0;  ///< m; distances are truncated here (cost of an update is bounded by it)

  /// Checks every key; the message names the bad one, e.g. "esdf: max_distance must be > 0".
  common::Status validate() const;
  /// validate() plus the limits that depend on the grid: max_distance / resolution <= 127 voxels
  /// (offsets to the nearest obstacle are stored in int8) and fewer than 2^32 voxels.
  common::Status validate(const common::GridGeometry& geometry) const;
};

/// Distance from each voxel centre to the nearest obstacle voxel centre (metres), 0 at obstacle
/// voxels, truncated at max_distance. Obstacles are set and cleared incrementally; only voxels whose
/// nearest obstacle changes are touched, by raise and lower waves in the manner of Lau, Sprunk &
/// Burgard (2013) and FIESTA: a raise wave first clears the voxels that pointed to removed obstacles,
/// then a lower wave, ordered by squared voxel distance (bucket queue), offers the new obstacles and
/// those bordering the cleared region to their 26-neighbours. An update thus costs in proportion to
/// the region within max_distance of the changed obstacles, never the whole grid.
///
/// Storage: per voxel the offset (int8 x, y, z, in voxels) to its nearest obstacle, or "none" when no
/// obstacle lies within max_distance; distances are computed from it on demand. One bit per voxel
/// marks the voxels touched by the running update. Propagating obstacles between 26-neighbours is
/// exact except where the discrete Voronoi region of a voxel's nearest obstacle does not reach it
/// through neighbours; such (very rare) voxels get the distance to a slightly farther obstacle.
class Esdf {
 public:
  using Config = EsdfConfig;
  /// Largest max_distance / resolution that can be stored.
  static constexpr int kMaxRangeVoxels = 127;

  /// An empty map (no obstacles: max_distance everywhere). Throws std::invalid_argument when
  /// `config.validate(geometry)` fails (callers validate first).
  Esdf(const common::GridGeometry& geometry, const EsdfConfig& config);

  const common::GridGeometry& geometry() const { return geometry_; }
  const EsdfConfig& config() const { return config_; }

  /// Marks the obstacle voxels added and removed since the last update (linear indices of
  /// geometry()) and propagates the change. Removals are applied first, so an index in both lists
  /// ends up an obstacle; indices outside the grid, inserting an obstacle that is already there and
  /// removing one that is not are ignored. Returns the number of voxels whose distance changed.
  std::size_t update(const std::vector<std::size_t>& inserted, const std::vector<std::size_t>& removed);

  /// Voxel index range [lo, hi) holding every voxel whose distance changed in the last update;
  /// false (and lo, hi untouched) when none changed.
  bool lastChangedRange(common::Index3& lo, common::Index3& hi) const;

  /// False outside the grid.
  bool isObstacle(const common::Index3& idx) const;
  /// Distance at a voxel centre (m); voxels outside the grid: max_distance.
  double distance(const common::Index3& idx) const;
  /// The nearest obstacle voxel of `idx`; false when none lies within max_distance or idx is outside
  /// the grid.
  bool nearestObstacle(const common::Index3& idx, common::Index3& obstacle) const;
  /// Trilinear interpolation of the voxel-centre distances at a point (m); centres outside the grid
  /// count as max_distance.
  double distance(const common::Vec3& p) const;
  /// distance(p), and in `gradient` the exact gradient of that trilinear interpolant (a one-sided
  /// derivative where p lies on a face between interpolation cells).
  double distanceAndGradient(const common::Vec3& p, common::Vec3& gradient) const;

  /// Bytes held by this map, scratch included (for benchmarks).
  std::size_t memoryBytes() const;

 private:
  /// Offset from a voxel to its nearest obstacle (voxels); x == kNone: no obstacle within range.
  struct Offset {
    std::int8_t x, y, z;
  };
  static_assert(sizeof(Offset) == 3, "3 bytes per voxel");
  static constexpr std::int8_t kNone = -128;

  static int squaredNorm(const Offset& o) { return o.x * o.x + o.y * o.y + o.z * o.z; }
  static bool hasSite(const Offset& o) { return o.x != kNone; }
  static bool isZero(const Offset& o) { return o.x == 0 && o.y == 0 && o.z == 0; }
  /// Squared voxel distance of a stored voxel; -1 when it has none.
  int key(std::size_t v) const { return hasSite(offsets_[v]) ? squaredNorm(offsets_[v]) : -1; }
  /// True when the obstacle that voxel v points to (o = offsets_[v], a site) is still an obstacle.
  bool siteValid(std::size_t v, const Offset& o) const {
    return isZero(offsets_[static_cast<std::int64_t>(v) + o.x + o.y * stride_y_ + o.z * stride_z_]);
  }
  bool touched(std::size_t v) const { return common::testBit(touched_, v); }
  double distanceOfKey(int key) const;
  /// Distances at the 8 voxel centres around p, and p's fractional position among them.
  void corners(const common::Vec3& p, double c[8], common::Vec3& t) const;

  void touch(std::size_t v);
  void push(std::size_t v, int key);
  bool pop(std::size_t& v, int& key);
  /// Visits the in-grid 26-neighbours n of v as f(n, neighbour offset index).
  template <typename F>
  void forNeighbours(std::size_t v, F&& f) const;
  void raise(bool first);
  void lower(std::size_t v, const Offset& o, bool check_sites);
  void releaseLargeScratch();

  common::GridGeometry geometry_;
  EsdfConfig config_;
  std::int64_t stride_y_ = 0, stride_z_ = 0;
  int max_key_ = 0;  // largest stored squared voxel distance
  std::vector<double> metres_of_key_;  // resolution * sqrt(key) for keys 0..max_key_ (a lookup: no sqrt per query)
  std::vector<Offset> offsets_;

  std::int8_t nb_[26][3];       // neighbour offsets
  std::int64_t nb_linear_[26];  // and their linear steps

  // Per-update scratch, sized by the affected region (the bitset has 1 bit per voxel, all clear
  // between updates).
  struct Change {
    std::uint32_t voxel;
    std::int32_t old_key;
  };
  std::vector<std::uint64_t> touched_;  // voxel is in changes_
  std::vector<std::uint32_t> raise_stack_;
  std::vector<Change> changes_;
  std::vector<std::vector<std::uint32_t>> buckets_;  // by squared voxel distance
  int lowest_bucket_ = 0;
  std::size_t queued_ = 0;

  common::Index3 changed_lo_ = common::Index3::Zero(), changed_hi_ = common::Index3::Zero();
  bool changed_any_ = false;
};

}  // namespace go_feap::map
