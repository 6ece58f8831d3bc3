// Altitude-stratified exploration (DESIGN §3.8, paper §III-B): the exploration state
// machine and the altitude bands it steps through. A pure class driven by step(); the
// nodelet only converts messages and logs the transitions it reports.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"

namespace go_feap::planning {

struct LayerManagerConfig {
  double layer_height = 1.0;      ///< m, most height of an altitude band (>= 0.5): the box is cut into equal ones
  double settle_time = 1.0;       ///< s a band must stay without frontiers before it counts as explored
  int max_retries = 3;            ///< failed attempts on a frontier before it is blacklisted
  double time_limit = 600.0;      ///< s after the trigger: FINISHED(time_limit)
  double stuck_timeout = 30.0;    ///< s without progress (map or flight) while exploring: FINISHED(stuck)
  /// m the vehicle must get from where progress was last seen for its flight to count as progress (a
  /// transit through mapped space changes no voxel); 0: the map's changes only
  double progress_travel = 1.0;
  common::Status validate() const;
};

enum class ExplorationState { kWaitTrigger, kExplore, kFinalPass, kFinished };
enum class FinishReason { kNone, kComplete, kTimeLimit, kStuck, kAborted };
const char* toString(ExplorationState s);
const char* toString(FinishReason r);

/// A band of altitudes [z_min, z_max] (m); index counts from the lowest band of the box.
struct Band {
  int index = 0;
  int count = 0;
  double z_min = 0.0, z_max = 0.0;
  bool final_pass = false;  ///< the whole box, during the final pass
  /// A frontier whose average lies at height `z` is in the band (bounds included).
  bool contains(double z) const { return z >= z_min && z <= z_max; }
};

/// What the chain reports at a step.
struct LayerInputs {
  bool trigger = false;                    ///< a start request arrived (repeats are ignored)
  bool abort = false;                      ///< a stop request arrived: FINISHED(aborted) at once, from any state
  std::vector<std::uint32_t> band_frontiers;  ///< ids of frontiers in the current band
  std::vector<std::uint32_t> all_frontiers;   ///< ids of every frontier in the box
  std::vector<std::uint32_t> failed;       ///< frontiers the planners failed to reach since the last step
  std::uint64_t map_progress = 0;          ///< any counter that grows while the map grows (e.g. frames that changed it)
  std::optional<double> yaw;               ///< rad, the vehicle's heading now (none while unknown)
  /// A frontier list has arrived at all: before the first, the empty lists above say nothing, and no band
  /// (nor the box) counts as explored (a finder that never started, or a camera that never sent a frame,
  /// ended the run "complete" after the look round)
  bool frontiers_known = true;
  std::optional<common::Vec3> position;    ///< m, the vehicle's position now (none while unknown)
  /// The position jumped since the last step (odometry relocalised, beyond metrics/max_odom_step): where it
  /// landed is where progress is measured from, not progress itself (a VIO that kept relocalising held the
  /// stuck check off for good).
  bool relocalised = false;
  /// Lists frontier `id`, its average at height `z`: in all_frontiers, and in band_frontiers if `band`
  /// holds it.
  void listFrontier(std::uint32_t id, double z, const Band& band) {
    all_frontiers.push_back(id);
    if (band.contains(z)) band_frontiers.push_back(id);
  }
};

struct Transition {
  ExplorationState from, to;
  int band_from, band_to;
  std::string why;
};

struct LayerOutputs {
  ExplorationState state = ExplorationState::kWaitTrigger;
  FinishReason reason = FinishReason::kNone;
  Band band;
  std::vector<Transition> transitions;  ///< what changed in this step, in order
  bool trigger_ignored = false;         ///< a trigger arrived while already exploring
  /// Nothing is left to explore where the camera has looked, but its heading has not yet been round
  /// every octant: the chain turns in place (nothing counts as explored before that).
  bool look_around = false;
  /// Blacklisted frontiers among the box's frontiers at this step: once FINISHED(complete), those left
  /// unexplored (a "complete" run that leaves some did not explore everything it could see).
  std::size_t blacklisted_left = 0;
};

class LayerManager {
 public:
  /// Bands cover box.min.z .. box.max.z in ceil(height / layer_height) equal bands, from the band holding
  /// start_z: that band first, then the bands above it (upwards), then those below it (downwards).
  LayerManager(const LayerManagerConfig& config, const common::Aabb& box, double start_z);

  LayerOutputs step(const LayerInputs& in, double t);

  const std::vector<int>& bandOrder() const { return order_; }
  Band band(int index) const;
  /// Frontiers given up on after max_retries failed attempts. Ids the frontier finder no longer lists
  /// (every id up to the highest any step's all_frontiers held that is missing from the latest) are
  /// forgotten, with their failure counts: ids are never reused, so a long run keeps only live ones.
  const std::set<std::uint32_t>& blacklist() const { return blacklist_; }
  /// Frontiers with a failed attempt on record (blacklisted ones included).
  std::size_t failureRecords() const { return failures_.size(); }
  bool isBlacklisted(std::uint32_t id) const { return blacklist_.count(id) > 0; }
  ExplorationState state() const { return state_; }
  FinishReason reason() const { return reason_; }
  /// The heading has been in every octant since the trigger (a start facing a wall has not).
  bool lookedAround() const { return headings_seen_ == 0xFFu; }

 private:
  std::size_t countUsable(const std::vector<std::uint32_t>& ids) const;
  void forgetGoneFrontiers(const std::vector<std::uint32_t>& present);
  LayerOutputs output() const;

  LayerManagerConfig config_;
  common::Aabb box_;
  int count_ = 1;
  double band_height_ = 1.0;  ///< m, the box's height over count_
  std::vector<int> order_;
  std::size_t position_ = 0;  ///< index into order_
  ExplorationState state_ = ExplorationState::kWaitTrigger;
  FinishReason reason_ = FinishReason::kNone;
  double t_trigger_ = 0.0;
  double empty_since_ = -1.0;  ///< when the current band (or box) last became free of usable frontiers
  double box_empty_since_ = -1.0;  ///< when the whole box last became free of usable frontiers
  std::uint64_t last_progress_ = 0;
  double progress_time_ = 0.0;
  std::optional<common::Vec3> progress_position_;  ///< where the vehicle was when progress was last seen
  std::map<std::uint32_t, int> failures_;
  std::set<std::uint32_t> blacklist_;
  std::uint32_t highest_seen_ = 0;  ///< the highest frontier id any step's all_frontiers held
  std::uint32_t headings_seen_ = 0;  ///< bit k: the heading has been in octant k since the trigger
};

}  // namespace go_feap::planning
