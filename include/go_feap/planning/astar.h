// Grid path search for the planners (DESIGN §3.4 path distances between frontiers, §3.7 paths to
// fly): A* over the 26-connected lattice of voxel centres of the mapper's grid, where a voxel is
// blocked when it is occupied, closer than a clearance to the nearest obstacle (ESDF), or, on
// request, unknown.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"
#include "go_feap/map/esdf.h"
#include "go_feap/map/occupancy_map.h"

namespace go_feap::planning {

using common::Index3;
using common::Vec3;

struct AstarConfig {
  /// m: voxels whose ESDF distance is below this are blocked (inflation = UAV radius).
  double clearance = 0.2;
  /// true: unknown voxels are traversable (optimistic distance estimates between frontiers); false: only
  /// known-free voxels (safe paths to fly).
  bool unknown_is_free = true;
  /// true: a voxel is traversable only when the voxels `clearance` away along each axis are known too, so
  /// a flight path never hugs space it has not seen (a wall seen edge-on is not in the ESDF yet). Only
  /// meaningful with unknown_is_free false.
  bool known_clearance = false;
  /// m, with known_clearance: every voxel whose centre lies this close to the voxel's centre must be known
  /// as well. The six along the axes alone let a path pass one voxel from an unseen pocket, which a
  /// trajectory along it then fails (traversableWith() checks the ball round each voxel). 0 to clearance.
  double known_radius = 0.0;
  /// Search budget: voxels expanded before giving up, at most 5e7.
  int max_expansions = 200000;
  /// Expansions after which a search that has not finished looks from the goal's side: a search from the
  /// goal back to the start, with the same budget, that runs out of voxels proves the goal is cut off
  /// (kNoPath at once, instead of flooding the start's side up to max_expansions); one that reaches the
  /// start gives the path. Only when neither settles it does the search go on to max_expansions
  /// (starting over). 0 = off. Paths are as short either way.
  int probe_expansions = 0;
  /// Weight on the heuristic. 1 gives shortest paths; w > 1 may return a path up to w times longer than
  /// the shortest in exchange for fewer expansions in cluttered maps. Not needed for speed in open space:
  /// ties between equal-cost candidates are already broken towards the goal.
  double tie_breaker = 1.0;
  /// Lattice step in voxels, 1 to 8: the search runs over the voxels `stride` apart along each axis from
  /// the start's voxel (the goal is snapped onto that lattice), and a move between two of them needs its
  /// straight segment to pass segmentTraversable() (or, with unknown_is_free and no known_clearance, the
  /// ESDF at its two ends to prove it clear). 1 = every voxel, moves checked by the swept-voxel rule.
  /// A coarse lattice costs about stride^3 times fewer expansions in open space: FUEL's remedy (a 0.4 m
  /// search grid) for path distances between many frontiers in large scenes. Meant for distance
  /// estimates: the known-surroundings waiver near the start only covers the start's own voxel there.
  int stride = 1;
  /// Section name used in validate()'s messages ("astar", "distance_astar", "scout_astar").
  std::string name = "astar";

  /// Checks every key; the message names the bad one, e.g. "astar: clearance must be finite and >= 0".
  common::Status validate() const;
  /// validate() plus clearance <= esdf.max_distance (distances are truncated there, so a larger
  /// clearance would block every voxel).
  common::Status validate(const map::EsdfConfig& esdf) const;
};

enum class PathStatus { kFound, kStartBlocked, kGoalBlocked, kNoPath, kBudgetExceeded };

/// "found", "start_blocked", "goal_blocked", "no_path", "budget_exceeded".
const char* toString(PathStatus s);

struct PathResult {
  PathStatus status = PathStatus::kNoPath;
  /// Voxel centres from the start voxel to the goal voxel (the start and goal points themselves are
  /// replaced by their, possibly snapped, voxel centres), after Astar::shorten(); empty unless found.
  std::vector<Vec3> path;
  double length = 0.0;  ///< m, sum of the segment lengths of `path`
  /// The 26-connected voxel path the search found (consecutive centres are neighbours on the search's
  /// lattice, config.stride voxels apart along each axis), before shortening.
  std::vector<Vec3> raw_path;
  /// m, sum of the segment lengths of `raw_path`: the shortest-path cost when tie_breaker is 1.
  double raw_length = 0.0;
  int expansions = 0;  ///< voxels expanded (closed) by the search
  /// When the search ran out (no path, budget exceeded): the shortened path from the start voxel to the
  /// expanded voxel nearest the goal (by the heuristic's lattice distance); empty when that is the start
  /// voxel itself, or after any other outcome. Where to go to see what lies between.
  std::vector<Vec3> toward;
};

/// A* on the grid of an occupancy map and its ESDF. Holds references to both (they must outlive it and
/// share one geometry) and reusable search scratch sized by the largest search so far, never by the grid;
/// search() is const but uses that scratch, so one instance must not be searched from two threads at once.
class Astar {
 public:
  /// Throws std::invalid_argument when config.validate(esdf.config()) fails or the two maps' geometries
  /// differ (callers validate first).
  Astar(const map::OccupancyMap& occupancy, const map::Esdf& esdf, const AstarConfig& config);

  const AstarConfig& config() const { return config_; }
  const map::OccupancyMap& occupancy() const { return occupancy_; }
  const map::Esdf& esdf() const { return esdf_; }
  const common::GridGeometry& geometry() const { return geo_; }

  /// Shortest 26-connected path between the voxels of `start` and `goal` (move costs 1, sqrt 2, sqrt 3
  /// times the resolution) over traversable voxels, never leaving the grid. A diagonal move must not cut
  /// a blocked voxel: every voxel around the edge or corner it passes through must be traversable too,
  /// so every segment of the raw path passes segmentTraversable(). A start or goal that is blocked
  /// or outside the grid is first moved to the nearest traversable voxel whose centre lies within
  /// `snap_radius` metres of it (status kStartBlocked / kGoalBlocked when there is none). Within snap_radius
/// of the start the known-surroundings rule (config.known_clearance) is waived, as staysFlyable() waives
/// it for trajectories: the camera has not seen beside or below a vehicle hovering there, and a vehicle
/// that has only looked ahead (at the start, or after turning) could otherwise not leave at all; the
/// voxels themselves must still be known free with the ESDF clearance. The heuristic is
  /// the exact obstacle-free cost on this lattice (the 3D octile distance, >= the Euclidean distance and
  /// still admissible), so open space costs few expansions. Stops with kBudgetExceeded after
  /// config.max_expansions expansions, and earlier with kNoPath when config.probe_expansions proves the
  /// goal cut off (see there; `expansions` then counts both directions, and `toward` is from the probe).
  PathResult search(const Vec3& start, const Vec3& goal, double snap_radius = 0.5) const;

  /// Greedily removes intermediate points: from each kept point, the path continues to a following point
  /// reachable by a straight segment that passes segmentTraversable(), found by galloping ahead and
  /// bisecting (the farthest such point when visibility along the path does not come back after it is
  /// lost). Consecutive input points are always joined, so the result keeps the first and last points,
  /// is never longer than the input, and never shorter than the straight line between its ends.
  std::vector<Vec3> shorten(const std::vector<Vec3>& path) const;

  /// Inside the grid with its centre inside the map's exploration box shrunk by config.clearance (the UAV
  /// never leaves the box nor touches its faces, and distances never cut through the map's margin), not occupied, unknown only when config.unknown_is_free,
  /// and ESDF distance at least config.clearance.
  bool traversable(const Index3& idx) const;
  /// traversable() with `min_distance` (m) in place of config.clearance, from mapped obstacles (ESDF) and
  /// from the box's faces, and with a nearer known-surroundings rule: the voxel itself must be free (or
  /// unknown when config.unknown_is_free), and with config.known_clearance every voxel whose centre lies
  /// within min_distance of its centre must be known, since an unseen obstacle there would be that close.
  /// The test for a trajectory that the optimiser bent away from the path: it may graze the edge of the
  /// known region the path hugs (config.clearance away), never cross or touch unseen space. A voxel
  /// traversable() passes it for every min_distance up to min(config.clearance, config.known_radius).
  /// `unseen`, when given, is set when the voxel fails for unseen space alone (it is inside the box,
  /// min_distance from mapped obstacles and the box's faces): a look there may clear it.
  bool traversableWith(const Index3& idx, double min_distance, bool* unseen = nullptr) const;
  /// True when every voxel the segment from a to b touches is traversable (see shorten()).
  bool segmentTraversable(const Vec3& a, const Vec3& b) const;

 private:
  static constexpr int kBrickBits = 3;
  static constexpr int kBrickEdge = 1 << kBrickBits;
  static constexpr std::size_t kBrickCells = std::size_t{1} << (3 * kBrickBits);
  // Cell values besides the index (>= 0) of an open node.
  static constexpr std::int32_t kCellUnseen = -1, kCellBlocked = -2, kCellFree = -3, kCellClosed = -4;

  /// One voxel the search reached: its cost from the start as counts of axis, face-diagonal and
  /// space-diagonal moves (exact, so equal costs compare equal), and its parent node.
  struct Node {
    Index3 idx;
    std::int32_t parent;
    std::int32_t moves[3];
    std::int32_t heap_pos;  ///< index of its entry in open_, -1 when not open
  };
  /// A brick (8^3 voxels) touched by the current search: slot valid when stamp equals search_stamp_.
  struct BrickSlot {
    std::uint32_t stamp;
    std::uint32_t key;    ///< linear index of the brick in the grid of bricks
    std::uint32_t brick;  ///< its cells are cells_[brick * kBrickCells, ...)
  };
  struct OpenEntry {
    double f;  ///< cost + heuristic (voxels)
    float h;   ///< heuristic, breaks ties in f
    std::int32_t node;
  };

  bool traversable(const Index3& idx, std::size_t linear) const;
  /// traversable() without the known-surroundings rule: what a voxel near the search's start needs.
  bool traversableNearStart(const Index3& idx, std::size_t linear) const;
  /// traversableNearStart() within sqrt(exempt2) voxels of voxel `start` (squared voxel distance at most
  /// exempt2), traversable() beyond: what a search from `start` needs of a voxel.
  bool traversableFrom(const Index3& idx, std::size_t linear, const Index3& start, int exempt2) const;
  /// Not occupied, unknown only when config.unknown_is_free, and (with `surroundings` and
  /// config.known_clearance) the voxels config.clearance away along each axis and those within
  /// config.known_radius known (known_offsets_).
  bool freeAndKnown(const Index3& idx, std::size_t linear, bool surroundings) const;
  /// Nearest traversable voxel to p whose centre is within `radius` of it; false when none. With
  /// `lattice` only voxels whose index differs from it by multiples of config.stride count.
  bool snap(const Vec3& p, double radius, Index3& out, bool near_start = false,
            const Index3* lattice = nullptr) const;
  /// A move between the traversable lattice voxels a and b (config.stride > 1): true when the ESDF at both
  /// ends proves the segment clear (unknown_is_free without known_clearance only), else segmentTraversable()
  /// of their centres with each touched voxel judged by traversableFrom(start, exempt2), as the search judges
  /// its voxels.
  bool moveClear(const Index3& a, const Index3& b, double esdf_a, const Index3& start, int exempt2) const;
  /// True when pass(v) holds for every voxel v the segment from a to b touches (both ends inside the
  /// grid's bounds); where the segment crosses an edge or corner, every voxel around it.
  template <typename Pass>
  bool segmentPasses(const Vec3& a, const Vec3& b, const Pass& pass) const;
  /// One A* run from voxel `from` to voxel `to` with at most `budget` expansions; the known-surroundings
  /// rule is waived within snap_radius of voxel `start` (the vehicle's, whichever way the run goes).
  /// Sets result.status and result.expansions; returns the node that reached `to` (-1 when none) and
  /// the expanded node nearest to it in `nearest`.
  std::int32_t run(const Index3& from, const Index3& to, const Index3& start, double snap_radius, int budget,
                   PathResult& result, std::int32_t& nearest) const;
  /// Voxel centres from node n back to the run's first node.
  std::vector<Vec3> chain(std::int32_t n) const;
  void resetScratch() const;
  void heapUp(std::size_t i, const OpenEntry& e) const;
  /// Adds node e.node to the open list, or moves its entry to the (lower) f of e.
  void heapPush(const OpenEntry& e) const;
  /// Removes the first entry of the open list and returns its node.
  std::int32_t heapPop() const;
  /// Slot of brick `key` in brick_slots_, or the empty slot where it would go.
  std::size_t brickSlot(std::uint32_t key) const;
  /// First cell of brick `key`, allocated (every cell kCellUnseen) on first use in this search.
  std::size_t brick(std::uint32_t key) const;

  const map::OccupancyMap& occupancy_;
  const map::Esdf& esdf_;
  AstarConfig config_;
  common::GridGeometry geo_;
  double blocked_below_ = 0.0;  // clearance less a rounding margin
  Index3 brick_dims_ = Index3::Zero();
  Index3 box_lo_ = Index3::Zero(), box_hi_ = Index3::Zero();  ///< voxels whose centres lie in the box, [lo, hi]
  /// known_clearance: offsets (voxels) of the neighbours that must be known, farthest first.
  std::vector<Index3> known_offsets_;

  // Search scratch: the voxels a search touches, in bricks of 8^3 cells (locality: a voxel's neighbours
  // mostly share its brick) found through an open-addressing table; each cell holds kCellUnseen,
  // kCellBlocked, kCellFree (traversable, not reached), kCellClosed or the index of the voxel's open node.
  // Kept between searches, sized by the largest one.
  mutable std::vector<BrickSlot> brick_slots_;
  mutable std::uint32_t search_stamp_ = 0;
  mutable std::uint32_t bricks_used_ = 0;
  mutable std::vector<std::int32_t> cells_;
  mutable std::vector<Node> nodes_;
  mutable std::vector<OpenEntry> open_;
};

/// Path length between two points, or their Euclidean distance flagged as a fallback.
struct PathDistance {
  double metres;
  bool euclidean_fallback;
};

/// With a coarse lattice (config.stride > 1), |a - b| when the segment between them passes
/// Astar::segmentTraversable() (no path is shorter, so no search is run). Otherwise the length of the
/// (shortened) A* path between a and b plus the two snaps from a and b to its end voxel centres (so never
/// below |a - b|); when the search fails for any reason (blocked ends, no path, budget exceeded) |a - b|
/// with euclidean_fallback set.
PathDistance pathDistance(const Astar& astar, const Vec3& a, const Vec3& b);

}  // namespace go_feap::planning
