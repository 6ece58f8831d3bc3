// Frontier detection and clustering (DESIGN §3.4, paper §III-A.1, Table I).
#pragma once

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

#include "go_feap/common/bits.h"
#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"
#include "go_feap/map/occupancy_map.h"

namespace go_feap::frontier {

using common::Aabb;
using common::Index3;
using common::Vec3;

struct FrontierConfig {
  int min_cluster_cells = 10;       ///< connected frontier regions with fewer cells are ignored
  double max_cluster_extent = 2.0;  ///< m: a cluster with a cell farther than this from its mean is split (PCA)
  double s_near = 5.0;              ///< m: radius for N_near (other frontiers' average positions)
  /// cells: an update regrows the whole connected regions of the clusters it touches while it has
  /// visited fewer cells than this (the result then equals recomputeAll()); beyond it, the clusters it
  /// did not touch are kept and the fill goes around them (bounded cost in large scenes; 0: untouched
  /// clusters are always kept and no region is regrown whole, the fuel mode's setting)
  int max_regrow_cells = 20000;
  /// Hysteresis on min_cluster_cells (1 = none): a region of a cluster that fell below
  /// min_cluster_cells is retired, and a region that is mostly (half or more) retired cells counts
  /// again only from revive_factor * min_cluster_cells cells, so that a remnant hovering at the size
  /// limit is not dropped beside the UAV and brought back when it is far away.
  double revive_factor = 1.0;

  common::Status validate() const;
};

/// A candidate place to observe a frontier from (filled by the local planner's sampler).
struct Viewpoint {
  Vec3 position = Vec3::Zero();
  double yaw = 0.0;
  int visible_cells = 0;  ///< N_view
};

/// One frontier cluster and its information (Table I).
struct Frontier {
  std::uint32_t id = 0;
  std::vector<Index3> cells;  ///< frontier voxels, in increasing linear-index order
  Vec3 average = Vec3::Zero();  ///< P_avg: mean of the cell centres (m)
  Aabb box;                     ///< B: bounding box of the cell cubes (m)
  double first_seen = 0.0;      ///< s: when it, or the oldest frontier it came from, appeared
  int n_near = 0;               ///< N_near: other frontiers whose average lies within s_near
  bool active = true;           ///< average inside the active altitude band
  std::vector<Viewpoint> viewpoints;  ///< VP

  /// T; never below 0 (a clock that went back, as a bag played again).
  double duration(double now) const { return std::max(0.0, now - first_seen); }
};

/// Frontiers removed and created by one update.
struct FrontierDelta {
  std::vector<std::uint32_t> removed;
  std::vector<std::uint32_t> added;
  std::size_t filled_cells = 0;  ///< frontier cells the update's flood fill visited: its cost
  bool empty() const { return removed.empty() && added.empty(); }
};

/// Keeps the frontier clusters of an occupancy map up to date. A frontier cell is a known-
/// free voxel of the exploration box with an unknown face neighbour inside the box. Cells
/// are grouped into 26-connected regions; regions below min_cluster_cells are dropped and
/// wide regions are split along their principal axis until every piece is narrow enough.
/// Updates are local (DESIGN §3.4): the clusters the change touches are removed and their connected
/// regions regrown. A region larger than max_regrow_cells (a sheet of frontier over a large hall can
/// hold 10^5 cells) is regrown only that far: past it, the clusters the change did not touch are kept
/// and the fill goes around them, as FUEL's does. Then clusters depend on the order the map was seen
/// in, and a piece that the kept clusters cut off and that is smaller than min_cluster_cells is left
/// out; every connected set of frontier cells that no cluster holds stays below that size, or below
/// revive_factor times it when half or more of its cells are retired (then the clusters depend on the
/// map's history, and recomputeAll() on a fresh finder is the oracle only with revive_factor 1).
class FrontierFinder {
 public:
  FrontierFinder(const FrontierConfig& config, const common::GridGeometry& geometry, const Aabb& box);

  /// Updates after the map changed in the voxel index box [changed_min, changed_max]
  /// (inclusive). Only clusters within reach of the change (a cell within 2 voxels of the box) are
  /// rebuilt; while no region exceeds max_regrow_cells the result equals recomputeAll() up to ids.
  FrontierDelta update(const map::OccupancyMap& map, const Index3& changed_min, const Index3& changed_max, double now);
  /// Updates after the voxels `changed` (linear indices) changed state; cheaper than the
  /// box form when the changes are sparse in a large box. Only clusters with a cell in or
  /// 26-adjacent to a changed voxel or its face neighbours are rebuilt; same result.
  FrontierDelta update(const map::OccupancyMap& map, const std::vector<std::size_t>& changed, double now);
  /// Rebuilds everything from the map (the oracle for update() when revive_factor is 1; retired cells
  /// are kept).
  FrontierDelta recomputeAll(const map::OccupancyMap& map, double now);

  /// Frontiers whose average lies in [z_min, z_max] are active; the others are kept.
  void setActiveBand(double z_min, double z_max);

  const std::vector<Frontier>& frontiers() const { return frontiers_; }
  const Frontier* find(std::uint32_t id) const;
  /// New frontiers get ids from `first` on (never lower than any handed out before): a finder that
  /// replaces another in a running system goes on from the ids the other handed out, so that records
  /// the planners keep of those ids (failures, the blacklist) name none of its frontiers.
  void continueIdsFrom(std::uint32_t first) { next_id_ = std::max(next_id_, first); }
  /// The id the next new frontier gets.
  std::uint32_t nextId() const { return next_id_; }
  bool isFrontierCell(const Index3& idx) const {
    if (!geo_.inside(idx)) return false;
    const std::size_t l = geo_.linear(idx);
    return common::testBit(is_frontier_, l);
  }
  const FrontierConfig& config() const { return config_; }

 private:
  /// Whether `region` (linear indices) becomes clusters; retires the cells of a cluster's region
  /// that fell below the size limit (called while owner_ still names the removed clusters).
  bool keepRegion(const std::vector<std::size_t>& region);
  bool computeFrontierCell(const map::OccupancyMap& map, const Index3& idx) const;
  FrontierDelta rebuild(const map::OccupancyMap& map, const Index3& lo, const Index3& hi, double now);
  /// Removes the `affected` clusters and regrows from `seeds` and their cells (and the cells of every
  /// cluster the fill takes in before max_regrow_cells).
  FrontierDelta regrow(std::unordered_set<std::uint32_t> affected, std::vector<std::size_t> seeds, double now);
  struct Cell {
    Index3 index;
    Vec3 centre;
  };
  /// Splits cells[begin, end) in place into pieces no wider than max_cluster_extent (PCA halves, each
  /// kept in its order) and appends their ranges to `out`; `buffer` is scratch space.
  void splitRange(std::vector<Cell>& cells, std::size_t begin, std::size_t end, std::vector<Cell>& buffer,
                  std::vector<std::pair<std::size_t, std::size_t>>& out) const;
  void refreshNeighbourCounts();
  bool inBox(const Index3& idx) const {
    return (idx.array() >= box_lo_.array()).all() && (idx.array() < box_hi_.array()).all();
  }

  FrontierConfig config_;
  common::GridGeometry geo_;
  Aabb box_;
  Index3 box_lo_, box_hi_;  ///< voxel range of the box, [lo, hi)
  std::vector<std::uint64_t> is_frontier_;                   ///< one bit per voxel
  std::vector<std::uint64_t> scratch_;                       ///< per-update marks, cleared after use
  std::vector<std::uint64_t> retired_;                       ///< cells of regions retired below the size limit
  /// Slot of voxel `idx` in owner_: the grid in bricks of 4 x 4 x 4 voxels, each brick's 64 slots
  /// together, so a cell's 26 neighbours lie in a few cache lines (in the x-fastest order they span
  /// nine rows in three planes: in a large box the flood fill's lookups were mostly cache misses).
  std::size_t ownerSlot(const Index3& idx) const {
    const auto bx = static_cast<std::size_t>(idx.x() >> 2), by = static_cast<std::size_t>(idx.y() >> 2),
               bz = static_cast<std::size_t>(idx.z() >> 2);
    return (((bz * bricks_.y() + by) * bricks_.x() + bx) << 6) |
           static_cast<std::size_t>(((idx.z() & 3) << 4) | ((idx.y() & 3) << 2) | (idx.x() & 3));
  }

  /// Per voxel (at ownerSlot()): the id of the kept cluster holding it, 0 for none (ids start at 1).
  /// Dense, 4 bytes per voxel: the flood fill looks up every cell of every rebuilt region, a hash map
  /// made that the finder's main cost in large scenes.
  Index3 bricks_;  ///< bricks along each axis
  std::vector<std::uint32_t> owner_;
  std::vector<Frontier> frontiers_;                          ///< sorted by id
  std::uint32_t next_id_ = 1;
  double band_min_ = -1e18, band_max_ = 1e18;
};

/// One map update as the mapper announces it (go_feap/MapUpdate): its frame's sequence number, how many
/// voxels changed state, and the world box (m) of those voxels' cubes.
struct MapUpdateNote {
  std::uint64_t sequence = 0;
  std::size_t changed_voxels = 0;
  Vec3 changed_min = Vec3::Zero(), changed_max = Vec3::Zero();
};

/// How a map user catches up with the map for an update (applyMapUpdate(), ViewpointCache::forgetFor()).
enum class UpdatePath { kRecomputed, kListed, kBoxed, kUnchanged };

/// The way for `note`, after the updates up to `last_sequence` (0: none yet) with the map now at frame
/// `map_sequence`: everything again after a gap in the sequence (updates missed or refused); nothing when no
/// voxel changed; the frame's exact list of changed voxels while the map is still at it; the note's box once
/// the map has moved past it (the list is then a later frame's).
UpdatePath updatePath(const MapUpdateNote& note, std::uint64_t last_sequence, std::uint64_t map_sequence);

/// Brings `finder`, which has taken every update up to `last_sequence`, up to the map for `note` (the map at
/// frame `map_sequence`, whose changed voxels are `map_changed`) the updatePath() way: recomputeAll() after a
/// gap (the incremental path needs every change), update() by the list or by the box clamped to the map.
UpdatePath applyMapUpdate(FrontierFinder& finder, const map::OccupancyMap& map, std::uint64_t map_sequence,
                          const std::vector<std::size_t>& map_changed, std::uint64_t last_sequence,
                          const MapUpdateNote& note, double now);

}  // namespace go_feap::frontier
