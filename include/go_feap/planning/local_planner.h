// Local planner (DESIGN §3.6, paper §III-A.3): types the frontiers ahead from how cluttered the recent
// depth frames were, filters their viewpoints accordingly, and picks one viewpoint per frontier for
// the first K frontiers of the global tour by a shortest path through a layered DAG.
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <deque>
#include <functional>
#include <opencv2/core.hpp>
#include <unordered_map>
#include <vector>

#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"
#include "go_feap/frontier/frontier_finder.h"
#include "go_feap/planning/astar.h"
#include "go_feap/planning/viewpoints.h"

namespace go_feap::planning {

struct LocalPlannerConfig {
  int k_frontiers = 3;             ///< layers of the DAG: the first frontiers of the tour (with viewpoints)
  int top_k = 5;                   ///< viewpoints kept per frontier after filtering
  double d_near = 2.0;             ///< m, a frontier at a smaller path distance is near
  double v_max = 2.0;              ///< m/s
  double yaw_rate_max = 1.0;       ///< rad/s
  int window_size = 10;            ///< depth frames in the obstacle-ratio window (flag_que)
  double clutter_threshold = 0.5;  ///< window mean above this: cluttered / corner
  double max_range = 4.5;          ///< m, depth returns closer than this count as obstacles
  /// m; distances below count as this in the steering rate, so viewpoints at the current position
  /// get a finite rate ranked by how far they turn.
  double min_dist = 0.1;
  /// s a chosen viewpoint is kept before a different proposal may replace it (unless nothing is left
  /// to see from it, or it has been reached): stops the target from flickering between near-equal
  /// viewpoints as the map grows frame by frame.
  double commit_time = 1.5;
  /// s: FUEL's replan cadence (planDue()): no planning while the target is held (committed or won on
  /// cost, not reached, not seen out), and past commit_time at most this often; FUEL replans every 1.5 s
  /// (replan_thresh3). 0 = plan at every planning tick, whatever the target's state.
  double replan_period = 0.0;
  /// Near or cluttered frontiers: only viewpoints seeing at least this share of the frontier's best
  /// N_view are ranked by steering rate, so turning in place never settles for a poor view (0: all).
  double min_view_fraction = 0.0;
  /// m and rad: a proposal this close to the current target (position and yaw) is the same target.
  double same_target_distance = 0.3;
  double same_target_yaw = 0.3;
  /// m/s: a vehicle this slow within same_target_distance and same_target_yaw of its target has reached
  /// it (it is braking the last centimetres: the view from there is the view from the target)
  double reached_speed = 0.8;
  /// rad and m/s: a reached viewpoint is judged in vain (decideTarget()) only with the camera settled,
  /// tilted less than settled_tilt from level or slower than settled_speed. Braking into a viewpoint
  /// tilts the camera up to 0.2 rad, away from the level view the viewpoint model counts, and a frontier
  /// that a level camera would clear from there was booked as a failed attempt; a vehicle hovering
  /// tilted (in wind) is settled by its speed.
  double settled_tilt = 0.05;
  double settled_speed = 0.1;
  /// a viewpoint pose reached this many times (VisitedViewpoints) is no longer proposed: its frontier
  /// is not being cleared from there
  int max_visits = 3;
  /// A place chosen to replace the target this many times within choice_window s (VisitedViewpoints::choose())
  /// is exhausted, reached or not: two viewpoints whose frontiers regrow with new ids on every pass take
  /// turns without either being reached or its frontier failing (0 = off)
  int max_choices = 3;
  double choice_window = 60.0;  ///< s
  /// m: choices within this distance of each other (and same_target_yaw) are of the same place; the
  /// viewpoint sampler offers a place at several heights
  double choice_radius = 1.0;
  /// rad: when no viewpoint can be planned (at the start, facing a wall, nothing known around), the
  /// vehicle turns in place by this much to look around (scanTarget()).
  double scan_step = 2.0943951023931953;
  /// m/s^2, the vehicle's acceleration: a leg from the vehicle adds the time to cancel the part of
  /// its velocity that does not lead to the leg's end, (|v| - v . dir) / a_max (startCost()): going on
  /// is free, a right angle costs |v| / a_max, turning back 2 |v| / a_max (0 = the velocity is ignored).
  double a_max = 0.0;

  /// Checks every key; the message names the bad one, e.g. "local: top_k must be >= 1".
  common::Status validate() const;
};

/// flag_i of a depth frame: the share of all its pixels that hold a valid return (finite, > 0) closer
/// than max_range (m), or -inf (REP 117: a surface too near to measure). CV_32FC1 in metres or CV_16UC1
/// in millimetres. Errors: an empty image, another type, or max_range not > 0.
common::Result<double> obstacleRatio(const cv::Mat& depth, double max_range);

/// The sliding window flag_que of the last window_size obstacle ratios.
class ObstacleWindow {
 public:
  /// window_size >= 1 (smaller counts as 1).
  ObstacleWindow(int window_size, double clutter_threshold);
  explicit ObstacleWindow(const LocalPlannerConfig& config)
      : ObstacleWindow(config.window_size, config.clutter_threshold) {}

  /// Appends a ratio, dropping the oldest when the window is full. Values outside [0, 1] (NaN
  /// included) are ignored and give false.
  bool push(double ratio);
  /// Mean of the ratios in the window; 0 when empty.
  double mean() const;
  /// True when the window holds a ratio and its mean is above the threshold.
  bool cluttered() const;
  std::size_t size() const { return ratios_.size(); }
  void clear() { ratios_.clear(); }

 private:
  std::size_t window_size_;
  double threshold_;
  std::deque<double> ratios_;
};

enum class FrontierType { kNearOrCluttered, kOpen };

/// kNearOrCluttered when path_distance < d_near or the window is cluttered, else kOpen.
FrontierType classifyFrontier(double path_distance, const ObstacleWindow& window,
                              const LocalPlannerConfig& config);

/// Expected steering rate phi = cost_yaw / cost_dist of flying from (position, yaw) to `viewpoint`:
/// cost_yaw = |wrapped yaw difference| / yaw_rate_max, cost_dist = max(distance, min_dist) / v_max.
double steeringRate(const common::Vec3& position, double yaw, const frontier::Viewpoint& viewpoint,
                    const LocalPlannerConfig& config);

/// The top_k viewpoints for a frontier of the given type. kNearOrCluttered: among the viewpoints seeing at
/// least min_view_fraction of the best visible_cells, the highest steering rate first (turning in place
/// rather than flying, paper Fig. 6), ties by visible_cells; kOpen: the most
/// visible_cells first. Further ties keep the input order.
std::vector<frontier::Viewpoint> filterViewpoints(const std::vector<frontier::Viewpoint>& viewpoints,
                                                  FrontierType type, const common::Vec3& position, double yaw,
                                                  const LocalPlannerConfig& config);

/// Distance (m) between two points for the edge costs; a non-finite value means "no edge".
using DistanceFn = std::function<double(const common::Vec3& a, const common::Vec3& b)>;

/// Time lower bound (s) between two poses: max(dist / v_max, |wrapped dyaw| / yaw_rate_max).
double edgeCost(double dist, double yaw_a, double yaw_b, const LocalPlannerConfig& config);

/// Time (s) of a leg from the moving vehicle at `position` (velocity, yaw) to `target` over a path of
/// `dist` metres: max(dist / v_max + (|v| - v . dir) / a_max, |wrapped dyaw| / yaw_rate_max), where dir
/// is the straight direction to the target (a target at the position: the whole speed is cancelled).
/// With a_max 0, edgeCost().
double startCost(const common::Vec3& position, const common::Vec3& velocity, double yaw,
                 const frontier::Viewpoint& target, double dist, const LocalPlannerConfig& config);

struct LocalPlan {
  std::vector<frontier::Viewpoint> path;  ///< one viewpoint per layer; path[0] is the next to fly to
  std::vector<unsigned> frontier_ids;     ///< the frontier of each path entry
  double cost = 0.0;                      ///< s, sum of the edge costs from the start
  std::vector<std::vector<frontier::Viewpoint>> layers;  ///< the filtered viewpoints (for rviz)
};

/// Shortest path from the start pose through the layered DAG: layer i holds the filtered viewpoints
/// (filterViewpoints() with types[j]) of the i-th frontier of `tour` that has any, for the first
/// k_frontiers such frontiers; edges lead from the start to layer 0 and from layer i to layer i + 1,
/// with edgeCost(distance(a, b), ...), from the start with startCost() (`velocity` in the world frame).
/// The DAG is relaxed layer by layer in topological order, which gives Dijkstra's result in O(edges);
/// ties keep the earlier viewpoint. `distance` defaults to the
/// Euclidean distance. Errors: invalid config, types.size() != tour.size(), no frontier with
/// viewpoints, or no finite path.
common::Result<LocalPlan> planLocal(const common::Vec3& position, const common::Vec3& velocity, double yaw,
                                    const std::vector<frontier::Frontier>& tour,
                                    const std::vector<FrontierType>& types, const LocalPlannerConfig& config,
                                    const DistanceFn& distance = DistanceFn());

/// The viewpoint being flown to, as the target hysteresis sees it.
struct CurrentTarget {
  frontier::Viewpoint viewpoint;
  double committed_at = 0.0;  ///< s, when it was chosen
  int remaining_visible = 0;  ///< frontier cells still visible from it now (remainingVisible(): counted up to min_visible)
  bool reached = false;       ///< the vehicle got there (targetReached())
  bool settled = true;        ///< the camera is level or the vehicle at rest (settled_tilt, settled_speed)
  /// it replaced a target for being quicker to reach (kSwitchQuicker): it is not replaced that way in
  /// turn, so that two targets whose estimated costs cross as the vehicle moves cannot take turns
  bool quicker = false;
};

/// rad, the angle between the body's z axis under `attitude` (body -> world, normalised first) and the
/// world's: the camera's tilt from level (0 hovering, 0.19 rad braking at 2 m/s^2); NaN for a zero or
/// non-finite quaternion.
double tiltOf(const Eigen::Quaterniond& attitude);

/// The current target as decideTarget() needs it, assessed from the vehicle's pose, speed and tilt
/// (rad, the body's z axis from the world's): reached (targetReached()), settled (tilt < settled_tilt or
/// speed < settled_speed) and the frontier cells still visible
/// from it (remainingVisible() over `frontiers`), counted while it is not reached (min_visible once it is,
/// as the count decides nothing then). It is counted after commit_time too: a target whose frontier has
/// been seen on the way is dropped at once, instead of being flown to and stopped at.
CurrentTarget assessTarget(const frontier::Viewpoint& target, double committed_at,
                           const common::Vec3& position, double yaw, double speed, double tilt,
                           const std::vector<frontier::Frontier>& frontiers, const map::OccupancyMap& map,
                           const ViewpointConfig& viewpoint_config, double cluster_extent,
                           const LocalPlannerConfig& config);

/// Where to look when no viewpoint can be planned: here, turned by scan_step.
frontier::Viewpoint scanTarget(const common::Vec3& position, double yaw, const LocalPlannerConfig& config);

/// The vehicle is at the target: within same_target_distance and same_target_yaw of it, and slower than
/// reached_speed (braking the last centimetres; waiting for a full stop there cost about a second per
/// viewpoint).
bool targetReached(const common::Vec3& position, double yaw, double speed, const frontier::Viewpoint& target,
                   const LocalPlannerConfig& config);

/// kReachedInVain: the current target was reached and is proposed again, so its frontier is not being
/// cleared from there; the caller reports that frontier as failed (blacklisted after bounded retries)
/// and drops the target.
/// kSwitchQuicker: switched for the commitment rule (the proposal is quicker to reach); the caller
/// marks the new target CurrentTarget::quicker.
enum class TargetDecision { kKeep, kSwitch, kSwitchQuicker, kReachedInVain };
/// The time to reach a viewpoint from the vehicle's state, for comparing targets: startCost() over the
/// path distance (pathDistance() on `astar`), not the straight line, which through a wall makes a
/// target far round it look as near as one in front.
double pathCost(const Astar& astar, const common::Vec3& position, const common::Vec3& velocity, double yaw,
                const frontier::Viewpoint& target, const LocalPlannerConfig& config);

/// Whether `proposal` (the planner's newest first viewpoint) replaces `current` at time t: always when
/// there is no current target; when the proposal is the same target (within same_target_distance and
/// same_target_yaw), keep it unless it was reached with the camera settled (kReachedInVain: still
/// braking, the tilted camera has not had the view the viewpoint was chosen for); otherwise switch when
/// nothing is left to see from the current one (remaining_visible < min_visible), when it was reached, or
/// (kSwitchQuicker) when it has been kept for commit_time, did not itself win that way
/// (CurrentTarget::quicker) and the proposal is quicker to reach (cost(proposal) < cost(current
/// viewpoint); `cost` is called only then: the callers pass pathCost()). Path estimates through unknown
/// space can make two targets' costs cross and cross back as the vehicle flies: a target won on cost is
/// flown to until it is reached, seen or failed, so no two targets take turns for ever.
TargetDecision decideTarget(const CurrentTarget* current, const frontier::Viewpoint& proposal,
                            const std::function<double(const frontier::Viewpoint&)>& cost, double t,
                            int min_visible, const LocalPlannerConfig& config);

/// Whether to plan (global tour, then local viewpoint) at time t. With replan_period 0 always (go_feap:
/// the planners' caches then see every tick, as the shipped figures were measured). Otherwise FUEL's
/// cadence: always with no current target, or one reached or seen out (remaining_visible <
/// min_visible); never while decideTarget() would keep it whatever was proposed (committed for less
/// than commit_time, or won on cost); past that, when replan_period has passed since the last plan at
/// `last_plan` (s). The callers skip both planners when it is false.
bool planDue(const CurrentTarget* current, double t, double last_plan, int min_visible,
             const LocalPlannerConfig& config);

/// Frontier cells of `frontiers` (those whose average lies within sensor_range + max_cluster_extent of the
/// viewpoint) that the viewpoint sees: its remaining value, counted up to min_visible (the only
/// threshold it is compared with; the count stops there).
int remainingVisible(const frontier::Viewpoint& viewpoint, const std::vector<frontier::Frontier>& frontiers,
                     const map::OccupancyMap& map, const ViewpointConfig& config, double cluster_extent);

/// The viewpoint poses the vehicle has reached, and how often. Frontier ids do not identify a place for
/// long (a cluster gets a new id whenever it is regrown, which a voxel flickering at a grazing angle
/// does every frame), so the blacklist of failed frontiers cannot stop two viewpoints whose frontiers
/// are never cleared from taking turns for ever (seen in the powerplant: 1700 s between two poses 4 m
/// apart). A pose reached max_visits times (within same_target_distance and same_target_yaw) is
/// exhausted: chooseLocalTarget() no longer proposes it. Some such pairs are never reached either: each
/// pass shows a few voxels of the frontier, which regrows with a new id whose best viewpoint is the
/// other one (seen in the powerplant: 137 s between two poses 3.9 m apart, at a frontier along the box's
/// face). So a place chosen max_choices times within choice_window s (choose()) is exhausted too.
class VisitedViewpoints {
 public:
  /// Counts a visit to the pose `reached`.
  void add(const frontier::Viewpoint& reached, const LocalPlannerConfig& config);
  /// Counts `chosen` as the target chosen at time t (s) to replace another (the callers leave out a target
  /// chosen anew after a failed plan: failed attempts on its frontier count those); the choice that makes max_choices of one place
  /// (within choice_radius and same_target_yaw) in the last choice_window s exhausts that place for good.
  /// Returns true when this choice exhausted it.
  bool choose(const frontier::Viewpoint& chosen, double t, const LocalPlannerConfig& config);
  bool exhausted(const frontier::Viewpoint& viewpoint, const LocalPlannerConfig& config) const;
  std::size_t size() const { return visits_.size(); }

 private:
  struct Visit {
    common::Vec3 position;
    double yaw;
    int count;
  };
  struct Choice {
    common::Vec3 position;
    double yaw;
    double t;
  };
  std::vector<Visit> visits_;
  std::vector<Choice> choices_;            ///< within the last choice_window s
  std::vector<Choice> exhausted_places_;  ///< chosen max_choices times within choice_window
};

/// A local planning step's target rule, as the LocalPlanner nodelet and go_feap_bench both take it:
/// decideTarget() on `proposal`; unless the current target is kept, its visit is counted in `visited` when it
/// was reached, and a proposal that replaces it (not a reached-in-vain one) counts as a choice of its place
/// (VisitedViewpoints::choose()). `exhausted` says that choice exhausted the place.
struct TargetStep {
  TargetDecision decision = TargetDecision::kKeep;
  bool exhausted = false;
};
TargetStep stepTarget(const CurrentTarget* current, const frontier::Viewpoint& proposal,
                      const std::function<double(const frontier::Viewpoint&)>& cost, double t, int min_visible,
                      const LocalPlannerConfig& config, VisitedViewpoints& visited);

/// Candidate viewpoints kept per frontier between planning steps (FUEL keeps them in the frontier
/// the same way): a frontier keeps its id only while its cells are unchanged, so its viewpoints stay
/// what sampleViewpoints() gave, except where the map has since filled in; get() re-checks each
/// cached position (still known free, ESDF clearance) and drops those that fail. Entries of frontiers
/// that no longer exist, or sampled for another band, are replaced.
class ViewpointCache {
 public:
  /// The viewpoints of `frontier` in the band [z_min, z_max]: cached and re-checked (those no longer free
  /// or clear dropped), or sampled now. Call forgetChanged() with every change of the map: an entry is
  /// kept only while the map within its reach stays as it was.
  const std::vector<frontier::Viewpoint>& get(const frontier::Frontier& frontier, const map::OccupancyMap& map,
                                              const map::Esdf& esdf, double z_min, double z_max,
                                              const ViewpointConfig& config);
  /// Forgets every frontier not in `ids` (call with the current frontier ids).
  void retain(const std::vector<std::uint32_t>& ids);
  /// Forgets the frontiers whose viewpoints a change of the map could alter: those with a changed voxel
  /// (linear indices of `geometry`) within reach of their sampling (the frontier's box grown by the
  /// farthest ring position, the clearance and a voxel; the lines of sight lie inside it too). A frontier
  /// keeps its id while its cells stay the same, however the map round it changes.
  void forgetChanged(const common::GridGeometry& geometry, const std::vector<std::size_t>& changed);
  /// As above for a change known only by its bounding box (m).
  void forgetChanged(const common::Aabb& changed);
  /// Forgets what the mapper's update `note` may have changed, after the updates up to `last_sequence`
  /// (0: none yet) with the map now at frame `map_sequence`, whose changed voxels are `map_changed`, the
  /// frontier::updatePath() way: every entry after a gap, else by the frame's list or the note's box.
  void forgetFor(const frontier::MapUpdateNote& note, std::uint64_t last_sequence, std::uint64_t map_sequence,
                 const common::GridGeometry& geometry, const std::vector<std::size_t>& map_changed);
  std::size_t size() const { return entries_.size(); }
  std::size_t hits() const { return hits_; }
  std::size_t misses() const { return misses_; }

 private:
  struct Entry {
    double z_min, z_max;
    common::Vec3 average;  ///< of the frontier sampled: the same id elsewhere (a bag, a tool) is sampled again
    common::Aabb reach;  ///< where a change of the map could alter the viewpoints
    std::vector<frontier::Viewpoint> viewpoints;
  };
  std::unordered_map<std::uint32_t, Entry> entries_;
  std::size_t hits_ = 0, misses_ = 0;
};

/// The local planning step on a map: for the frontiers of the tour, in tour order, samples viewpoints
/// (sampleViewpoints() in the band [z_min, z_max]) until k_frontiers have some, types each by its A*
/// path distance from `position` (pathDistance() on `astar`, searched only when the straight line is
/// shorter than d_near: a path is never shorter) and the obstacle window, and runs
/// planLocal(). `tour` holds the frontiers' cells and averages; their viewpoints are ignored and
/// replaced. Errors as planLocal(), or "no viewpoint" when no tour frontier has one. With a `cache`,
/// viewpoints come from it (ViewpointCache::get()) instead of being sampled every time. With `visited`,
/// exhausted poses (VisitedViewpoints::exhausted()) are left out.
common::Result<LocalPlan> chooseLocalTarget(const common::Vec3& position, const common::Vec3& velocity, double yaw,
                                            std::vector<frontier::Frontier> tour, double z_min, double z_max,
                                            const map::OccupancyMap& map, const map::Esdf& esdf, const Astar& astar,
                                            const ObstacleWindow& window, const ViewpointConfig& viewpoint_config,
                                            const LocalPlannerConfig& config, ViewpointCache* cache = nullptr,
                                            const VisitedViewpoints* visited = nullptr);

}  // namespace go_feap::planning
