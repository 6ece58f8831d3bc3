// Exploration metrics (DESIGN §3.9): coverage against the scene's observable set, collisions
// against ground truth, a time series, per-block compute times, and the files every run writes:
// summary.json, metrics.csv and coverage.png. Used by the MetricsRecorder nodelet and the bench.
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <functional>
#include <string>
#include <unordered_map>
#include <vector>

#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"
#include "go_feap/map/occupancy_map.h"
#include "go_feap/world/scene.h"

namespace go_feap::metrics {

/// A run's trail (the flown path sent to rviz, whole, at every sample) in at most `max` items for a run of any
/// length: every stride-th item added is kept, evenly spaced over the whole run, and the latest item added
/// always ends it. When full, every other kept item goes and the stride doubles. (Dropping every other item
/// of the trail as it stood, with each new one kept, halved the oldest part at every thinning: after a long
/// run the trail was its first pose and the last few thousand.)
template <typename T>
class BoundedTrail {
 public:
  explicit BoundedTrail(std::size_t max) : max_(std::max<std::size_t>(max, 3)) {}
  void add(T item) {
    if (latest_) items_.pop_back();  // the previous latest, not a stride item
    bool on_stride = count_ % stride_ == 0;
    if (on_stride && items_.size() + 1 >= max_) {
      // Full of stride items: every other one goes (the first stays), the stride doubles.
      std::size_t kept = 0;
      for (std::size_t i = 0; i < items_.size(); i += 2) items_[kept++] = std::move(items_[i]);
      items_.resize(kept);
      stride_ *= 2;
      on_stride = count_ % stride_ == 0;
    }
    ++count_;
    items_.push_back(std::move(item));
    latest_ = !on_stride;
  }
  const std::vector<T>& items() const { return items_; }

 private:
  std::size_t max_;
  std::vector<T> items_;
  std::size_t stride_ = 1, count_ = 0;
  bool latest_ = false;  ///< the last item is the latest added, not a stride item
};

/// Distance (m) from `p` to the nearest occupied ground-truth voxel cube, looking no farther than
/// `radius` (m): `radius` when none is that close; 0 inside an obstacle.
double obstacleDistance(const world::Scene& scene, const common::Vec3& p, double radius);

/// Whether a run can start at the scene's start: an error naming the start and its clearance when that is
/// under `collision_distance` (m; validDistance()), as every run from there would begin with a collision
/// (validateScene() refuses only a start inside an obstacle's voxel).
common::Status checkStartClearance(const world::Scene& scene, double collision_distance);

/// Collisions and the closest approach along a flown path (DESIGN §3.9: a collision is the UAV centre
/// closer than collision_distance to a ground-truth obstacle; one collision per entry into that zone).
class CollisionMonitor {
 public:
  /// m: clearances are looked up this far at most; a closest approach beyond it reads as this.
  static constexpr double kHorizon = 0.5;
  /// Whether `collision_distance` can be measured: in (0, kHorizon] m. At 0 nothing ever counted (a
  /// centre inside an obstacle is at 0, not below it); beyond kHorizon every position did.
  static bool validDistance(double collision_distance) {
    return collision_distance > 0.0 && collision_distance <= kHorizon;
  }
  /// A collision ends once the clearance is back to kReleaseFactor x collision_distance (at most
  /// kHorizon): a vehicle scraping along a wall, its clearance jittering round the distance, is one
  /// collision, not one per sample that dipped below it.
  static constexpr double kReleaseFactor = 1.5;
  CollisionMonitor(const world::Scene& scene, double collision_distance)
      : scene_(scene), collision_distance_(collision_distance),
        release_distance_(std::min(kHorizon, kReleaseFactor * collision_distance)) {}
  /// Checks the next position of the path; true when it starts a new collision.
  bool update(const common::Vec3& p);
  int collisions() const { return collisions_; }
  double closestApproach() const { return closest_; }  ///< m
  double lastClearance() const { return last_; }       ///< m, of the latest position

 private:
  const world::Scene& scene_;
  double collision_distance_, release_distance_;
  int collisions_ = 0;
  double closest_ = kHorizon, last_ = kHorizon;
  bool inside_ = false;
};

/// Counts how much of the scene's observable set a map has classified: in full (coverage()), or
/// incrementally from the voxels each integrated frame changed (reset(), then update() per frame, read
/// with current()), which costs the frame's changes instead of a pass over the observable set. A map
/// voxel never returns to unknown, so the two agree.
class CoverageTracker {
 public:
  /// Computes the observable set of `scene` and where its voxels fall in maps of geometry `map_geometry`
  /// (voxels the map does not cover stay unknown for ever).
  CoverageTracker(const world::Scene& scene, const common::GridGeometry& map_geometry);
  /// |known ∩ observable| / |observable| of `map` (same geometry as given to the constructor).
  double coverage(const map::OccupancyMap& map) const;
  /// Starts the incremental count from `map` (a full count).
  void reset(const map::OccupancyMap& map);
  /// Adds the observable voxels among `changed` (linear indices whose state changed in `map`, as
  /// FrameChange::changed gives them) that are now known.
  void update(const map::OccupancyMap& map, const std::vector<std::size_t>& changed);
  /// The incremental coverage: equals coverage(map) after reset(map) and update() with every frame since.
  double current() const;
  std::size_t observableCount() const { return observable_total_; }

 private:
  /// Observable voxels in map voxel l (1 unless the scene's grid is finer than the map's).
  std::size_t weight(std::size_t l) const;
  /// Calls visit(l) for every map voxel l that holds an observable voxel and is known in `map`.
  template <typename Visit>
  void forEachKnownObservable(const map::OccupancyMap& map, Visit&& visit) const;

  std::vector<std::uint64_t> observable_;  ///< one bit per map voxel: holds an observable voxel
  std::vector<std::uint64_t> pending_;     ///< observable map voxels not yet counted known (incremental)
  std::unordered_map<std::size_t, std::size_t> extra_weight_;  ///< map voxels holding more than one
  std::size_t observable_total_ = 0;
  std::size_t known_ = 0;  ///< incremental count of known observable voxels
};

/// Mean and max of a block's compute times (ms).
/// The planning blocks, whose means summed make Table IV's "total".
bool isPlanningBlock(const std::string& block);
/// The chain's compute blocks: "mapping" and the planning blocks (frontier, global, local, trajectory).
bool isComputeBlock(const std::string& block);

struct BlockTime {
  double total_ms = 0.0, max_ms = 0.0;
  std::size_t count = 0;
  void add(double ms) {
    total_ms += ms;
    max_ms = std::max(max_ms, ms);
    ++count;
  }
  double mean() const { return count ? total_ms / static_cast<double>(count) : 0.0; }
};

/// One row of metrics.csv.
struct Sample {
  double t = 0.0;              ///< s since the trigger
  double coverage = 0.0;       ///< share of the observable set, [0, 1] (negative: unknown, e.g. onboard)
  double explored_m3 = 0.0;    ///< known volume
  double distance = 0.0;       ///< m flown
  int layer = 0;               ///< current band index
  int frontiers = 0;           ///< frontier count
  common::Vec3 position = common::Vec3::Zero();  ///< m, UAV position (the flown path)
};

/// What summary.json holds.
struct Summary {
  std::string scene, planner, finish_reason;
  std::uint64_t seed = 0;
  double exploration_time_s = 0.0;
  double flight_distance_m = 0.0;
  double coverage = 0.0;
  int collisions = 0;
  int blacklisted_frontiers = 0;  ///< frontiers left blacklisted (after failed attempts) at the finish
  double min_obstacle_distance_m = 0.0;  ///< closest approach of the UAV centre to ground truth
  /// false with no scene to compare with (onboard, replay): coverage, collisions and
  /// min_obstacle_distance_m were never measured, and summary.json says null for them.
  bool ground_truth = true;
  double wall_time_s = 0.0;
  std::map<std::string, BlockTime> compute;  ///< per block: mapping, frontier, global, local, trajectory
  std::map<std::string, double> extra;       ///< other figures (memory, speed-up, ...)
};

/// Collects the time series and timings of a run and writes its files.
class Recorder {
 public:
  void addSample(const Sample& s) { samples_.push_back(s); }
  void addTime(const std::string& block, double ms) { summary_.compute[block].add(ms); }
  Summary& summary() { return summary_; }
  const Summary& summary() const { return summary_; }
  const std::vector<Sample>& samples() const { return samples_; }

  /// summary.json: scene, seed, planner, finish_reason, exploration_time_s, flight_distance_m,
  /// coverage, collisions, blacklisted_frontiers, min_obstacle_distance_m, wall_time_s, compute_ms {block: {mean, max, count}}
  /// with "total" = the sum of the planning blocks' means (frontier, global, local, trajectory), and
  /// the extra figures. Without ground truth, coverage, collisions and min_obstacle_distance_m are null.
  common::Status writeSummary(const std::string& path) const;
  /// metrics.csv: t,coverage,explored_m3,distance,layer,frontiers,x,y,z.
  common::Status writeCsv(const std::string& path) const;
  /// coverage.png: coverage (%) against time (s), the paper's Fig. 9 style.
  common::Status writePlot(const std::string& path, const std::string& title) const;
  /// The three files into `dir` (created if missing): metrics.csv, coverage.png and summary.json last,
  /// each written under a temporary name (.partial-NAME) and renamed into place, so that a file seen is
  /// whole, and summary.json seen means all three are there. The first failure stops it, naming the file.
  common::Status writeAll(const std::string& dir) const;

 private:
  Summary summary_;
  std::vector<Sample> samples_;
};

/// Writes `path` whole or not at all: `write` fills a temporary file beside it (.partial-NAME, keeping
/// the extension, which tells OpenCV the format), which is then renamed into place. A reader sees the
/// old file or the whole new one; on failure the message names `path`.
common::Status writeWhole(const std::string& path, const std::function<common::Status(const std::string&)>& write);
/// writeWhole() of `text` (checked: a full disk is an error, not a short file).
common::Status writeTextWhole(const std::string& path, const std::string& text);

/// Plots coverage (%) against time (s) for one or more named series into a PNG (OpenCV).
common::Status plotCoverage(const std::vector<std::pair<std::string, std::vector<Sample>>>& series,
                            const std::string& title, const std::string& path);

/// summary.json as written by Recorder::writeSummary, as a string.
std::string summaryJson(const Summary& summary);

}  // namespace go_feap::metrics
