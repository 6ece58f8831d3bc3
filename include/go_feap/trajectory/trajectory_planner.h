// From a start state and a target viewpoint to a flyable trajectory (DESIGN §3.7): A* in
// known free space, a cubic B-spline fitted to the path and optimised with NLopt (refitted
// slower when the optimum breaks a limit), and a yaw spline. Shared by the TrajectoryPlanner
// nodelet, the trajectory server and the lock-step bench, so both run the same code.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"
#include "go_feap/planning/astar.h"
#include "go_feap/trajectory/bspline_optimizer.h"
#include "go_feap/trajectory/replan.h"

namespace go_feap::trajectory {

/// A position spline (3-D) and a yaw spline (1-D) that start together at t = 0.
struct Trajectory {
  UniformBspline position;
  UniformBspline yaw;
  Vec3 goal = Vec3::Zero();  ///< m, the target it was planned for (its end, unless partial)
  bool partial = false;      ///< ends short of the goal, `horizon` along the path: replanned before its end
  double duration() const { return position.duration(); }
};

/// The reference a trajectory gives at a time: what the trajectory server sends.
struct TrajectorySample {
  Vec3 position = Vec3::Zero();      ///< m
  Vec3 velocity = Vec3::Zero();      ///< m/s (zero after the end)
  Vec3 acceleration = Vec3::Zero();  ///< m/s^2 (zero after the end)
  double yaw = 0.0;                  ///< rad, wrapped to (-pi, pi]
  double yaw_dot = 0.0;              ///< rad/s (zero after the yaw spline's end)
  bool completed = false;            ///< t is past the position spline's end: holding its last point
};

/// Samples `trajectory` at t (s since its start; negative counts as 0). Past the end it holds the
/// final position and yaw at rest.
TrajectorySample sampleTrajectory(const Trajectory& trajectory, double t);

struct TrajectoryPlannerConfig {
  double path_spacing = 0.3;            ///< m between the A* path samples the spline is fitted to
  double collision_horizon = 3.0;       ///< s of the current trajectory checked against new obstacles
  double min_time_between_plans = 0.3;  ///< s
  double cruise_fraction = 0.6;         ///< share of v_max the initial timing assumes
  int max_refits = 4;                   ///< slower refits tried when the optimum breaks a limit
  double max_slowdown = 3.0;            ///< no refit is slower than this many times the first timing
  /// m: a longer path is flown only this far (a partial trajectory, replanned on the way; 0 = whole path)
  double horizon = 8.0;
  /// rad: a vehicle that cannot leave its start region (startEnclosed()) and already faces its target
  /// turns this much to look around
  double enclosed_turn = 2.0944;
  /// m: when no path through known space is found, the search's nearest point to the target is flown to
  /// (partial) if it is at least this much closer to the target than the start (0 = never)
  double min_progress = 1.5;
  double snap_radius = 1.0;             ///< m: a blocked start (or goal) moves to free space this close
  /// m: a path may end at most this far from the target (a goal that had to snap farther is blocked)
  double goal_tolerance = 0.3;
  /// s a flight search that found no path is remembered (SearchMemory); 0 = never
  double failed_search_memory = 3.0;
  /// m: with no path through known space (and no min_progress towards the target), the part in known
  /// flyable space of a scout search's path (unknown space free) is flown when it is at least this
  /// long, facing along it: the way on comes into view (0 = never; needs a scout search)
  double scout_min_length = 0.5;
  /// rad: a plan refused where its spline touches unseen space (PlanReport::unseen_at) turns the camera
  /// there first, unless the heading is already this close to it (lookAtUnseen(); 0 = never)
  double look_tolerance = 0.5236;
  /// scouting flights towards one target before the next counts a failed attempt (scoutedTooOften(); 0 = no limit)
  int max_scouts = 5;
  /// A second optimisation with at least this many spline spans runs beside the usual one (at least 6
  /// spans, path_spacing apart) whenever the path is short enough to get more: finer knots let the
  /// acceleration switch faster, which on short hops a 6-span spline cannot; the quicker of the two
  /// valid results is flown (0 = off).
  int fine_spans = 12;
  /// m/s: when no flyable spline is found from a start moving faster than this, the vehicle brakes to
  /// rest, turning towards the target, and the plan is asked again from there (PlanReport::braked; the
  /// optimiser keeps the start velocity, which on a turn-around swings the curve out of known space)
  /// instead of failing the target (0 = never)
  double brake_speed = 0.3;
  /// A flight search over its budget is asked again with the coarse search given to planTrajectory()
  /// (false: the coarse search is never used)
  bool coarse_retry = true;
  /// Every spline along the path was refused for unseen space beside it (the flight search keeps unseen
  /// space away along the axes, and known_radius all round; the check looks all round, flyableClearance()):
  /// search again, once, keeping it flyableClearance() away all round, and fly that path when it has a
  /// flyable spline (false: the failure stands, and the vehicle may look there)
  bool unseen_retry = true;
  /// Timed fit (profileSamples()): before optimising, the path is timed with a speed profile that
  /// accelerates and brakes at this share of a_max (cruising at feasibility_margin * v_max, slower
  /// round corners), and the spline whose control points are its samples, profile_knot_span apart
  /// (UniformBspline::fromTimedSamples(): within the profile's speed and acceleration), is flown as it is when
  /// it passes the optimiser's checks (limits, clearance, staysFlyable). It is near the quickest
  /// possible flight along the path; corners and starts moving across the path fall back to the
  /// optimiser. 0 = off.
  double profile_acceleration = 0.95;
  double profile_knot_span = 0.05;  ///< s between the timed fit's knots
  double profile_ramp = 0.1;        ///< s over which the profile's acceleration rises and falls (finite jerk)
  /// m: round a corner turning by theta no faster than a circle with this much cut at its apex allows
  /// (speed^2 <= a * cut / (1 / cos(theta / 2) - 1))
  double profile_corner_cut = 0.1;
  /// m/s: a start velocity with more than this across the path's first leg is left to the optimiser
  double profile_max_cross_speed = 0.1;
  /// Checks every key; the message names the bad one, e.g. "planner: path_spacing must be > 0".
  common::Status validate() const;
  /// validate() plus goal_tolerance against the map's voxels: at least half a voxel's diagonal. A path ends
  /// at a voxel's centre, so a smaller tolerance refused targets off their voxel's centre as blocked.
  common::Status validate(const map::OccupancyConfig& occupancy) const;
};

/// Start state and goal of one plan.
struct PlanRequest {
  Vec3 start = Vec3::Zero();     ///< m, where the reference is now
  Vec3 velocity = Vec3::Zero();  ///< m/s, the reference's velocity (kept, for continuity)
  /// m/s^2, the reference's acceleration: kept too (up to feasibility_margin * a_max), so that a
  /// replan does not first drop the acceleration to zero and build it up again
  Vec3 acceleration = Vec3::Zero();
  double yaw = 0.0;              ///< rad, the reference's heading
  /// rad/s, the reference's yaw rate: a turn goes on from it (yawTurn's rate0) instead of from rest
  double yaw_rate = 0.0;
  Vec3 target = Vec3::Zero();    ///< m, viewpoint position
  double target_yaw = 0.0;       ///< rad, viewpoint heading
  double time = 0.0;             ///< s, when it is planned (for a SearchMemory)
  /// An earlier plan to this target was widened (PlanReport::widened): search keeping unseen space
  /// flyableClearance() away all round from the start (with config.unseen_retry), so that a replan on the
  /// way does not turn back to the refused way, whose pocket lies beyond the horizon it checks
  bool widen = false;
};

/// What plan() did, for logs and benchmarks.
struct PlanReport {
  int refits = 0;              ///< slower refits needed
  bool used_fit = false;       ///< the unoptimised (refitted) spline was kept: it passed the checks
  bool profiled = false;       ///< the timed fit (profileSamples()) was flown
  /// No flyable spline from a start faster than brake_speed: braking to rest (partial) is flown instead
  bool braked = false;
  /// The path flown was searched keeping unseen space flyableClearance() away all round
  /// (config.unseen_retry): the first path's splines were refused for unseen space beside it, or the
  /// request asked for it (PlanRequest::widen)
  bool widened = false;
  bool fine = false;           ///< the optimisation with fine_spans spans was the quicker
  planning::PathStatus path_status = planning::PathStatus::kNoPath;
  double path_length = 0.0;    ///< m
  int left_flyable = 0;        ///< optimised splines refused by staysFlyable()
  int path_expansions = 0;     ///< voxels the path search expanded
  bool toward = false;         ///< no path was found: the trajectory goes towards the target (PathResult::toward)
  bool remembered = false;     ///< failed without searching: the same search failed lately (SearchMemory)
  bool scouted = false;        ///< no known path, nor toward: the known start of the scout search's path is flown
  /// The flight search ran out of budget and the coarse search found the path that is flown
  bool coarse = false;
  /// A failed plan whose path was found but whose spline was refused where it touched unseen space
  /// (staysFlyable(), the last such refusal), or whose search found no way through known space (the
  /// target: the way there is through space not yet seen): a look there may mend it (lookAtUnseen()).
  std::optional<Vec3> unseen_at;
};

/// Flight searches that found no path (no path or budget exceeded, and nothing to fly towards either),
/// remembered for config.failed_search_memory seconds. A search that used the whole of
/// astar/max_expansions costs about 0.2 s in a large scene, and the local planner proposes the same
/// viewpoint again right after a failure (its frontier is blacklisted only after layers/max_retries
/// failed attempts), so planTrajectory() given a memory answers a request from within snap_radius of a
/// remembered start to within goal_tolerance of its goal with the same failure, at once.
class SearchMemory {
 public:
  void remember(const Vec3& start, const Vec3& goal, planning::PathStatus status, int expansions, double t);
  /// The remembered failure matching (start, goal) at time t, if any (older ones are forgotten here).
  struct Failure {
    planning::PathStatus status;
    int expansions;
    double t;
  };
  std::optional<Failure> recall(const Vec3& start, const Vec3& goal, double t, const TrajectoryPlannerConfig& config);
  /// Drops what is remembered for (start, goal) (matched as recall() does): the map around has changed
  /// (a look there), and the next request searches again.
  void forget(const Vec3& start, const Vec3& goal, const TrajectoryPlannerConfig& config);
  std::size_t size() const { return entries_.size(); }

 private:
  struct Entry {
    Vec3 start, goal;
    Failure failure;
    /// The same request: start within snap_radius, goal within goal_tolerance.
    bool matches(const Vec3& s, const Vec3& g, const TrajectoryPlannerConfig& config) const {
      return (start - s).norm() <= config.snap_radius && (goal - g).norm() <= config.goal_tolerance;
    }
  };
  std::vector<Entry> entries_;
};

/// m: how near unseen space and mapped obstacles planTrajectory() lets a spline's voxels come (the
/// min_distance of its staysFlyable() checks): optimizer.min_clearance less half a voxel diagonal, since
/// a voxel's centre may lie that far from the curve.
double flyableClearance(const OptimizerConfig& optimizer, double resolution);

/// m: the path sample spacing of planTrajectory()'s next refit after `spacing` failed: half of it, so that
/// the fit hugs the searched path more closely, but not below half a voxel, and never coarser than
/// `spacing` (a hop shorter than 0.6 m starts finer than half a voxel, to have its 7 control points).
double refitSpacing(double spacing, double resolution);

/// True when `spline`, sampled at most a quarter voxel apart, stays in voxels astar.traversableWith(.,
/// min_distance) accepts (known free, at least min_distance from mapped obstacles and from the box's
/// faces) wherever it is farther than exempt_radius from its start, and ends in one. Near the start the
/// camera has not seen everything around the vehicle (and the path search may snap its start that far:
/// pass snap_radius).
/// With `unseen_at`: set to the refused sample when the spline fails for unseen space alone
/// (Astar::traversableWith's `unseen`), reset otherwise.
bool staysFlyable(const UniformBspline& spline, const planning::Astar& astar, double min_distance,
                  double exempt_radius, std::optional<Vec3>* unseen_at = nullptr);

/// Speed profile of profileSamples().
struct SpeedProfile {
  double cruise = 1.9;        ///< m/s, top speed
  double acceleration = 1.8;  ///< m/s^2, along the path when speeding up and braking
  double ramp = 0.1;          ///< s, the acceleration changes linearly over this long (box-smoothed speed)
  double corner_cut = 0.1;    ///< m, see TrajectoryPlannerConfig::profile_corner_cut
  double knot_span = 0.05;    ///< s, the samples' time step (at most; at least 6 steps)
};

/// The polyline `path` timed for flying it from speed `v_start` and acceleration `a_start` (along its
/// first leg; a_start clamped to +-acceleration) to rest at its end: the fastest speed profile over arc
/// length that accelerates and brakes at `acceleration`, stays under `cruise` and under each corner's
/// speed, with its arc length then averaged over `ramp` seconds (the acceleration then changes linearly
/// over `ramp`, as a cubic spline can follow, and never exceeds `acceleration`), the start extended
/// backwards at a_start so that the result leaves with v_start (exactly, when it is within [0, cruise])
/// and about a_start. Returns the positions at equal time steps (the path's first and last points
/// included, at least 7) and sets `knot_span` to the step. Empty when the path has fewer than 2 points or
/// is too short for the start's averaging (shorter than about v_start * ramp / 2 plus 5 cm). Throws
/// std::invalid_argument for a non-finite or non-positive cruise, acceleration, knot_span, a negative
/// ramp or corner_cut, or a non-finite v_start or a_start.
std::vector<Vec3> profileSamples(const std::vector<Vec3>& path, double v_start, double a_start,
                                 const SpeedProfile& profile, double* knot_span);

/// Plans a trajectory for `request`. A target within half a voxel of the start is a turn in place: the
/// position brakes to rest there (safeStop) and the yaw spline turns to target_yaw. Otherwise: A* (known
/// free space, the astar's clearance), spline fit through
/// the path starting exactly at request.start with request.velocity and request.acceleration and ending
/// at rest: first the timed fit (profileSamples(), when profile_acceleration > 0 and the start velocity
/// runs along the path's first leg within profile_max_cross_speed; its crossing part decays on the way),
/// flown as it is when it passes checkTrajectory() and staysFlyable() (PlanReport::profiled); otherwise
/// optimize() of the resampled path (refitted slower up to max_refits times, and to at most max_slowdown
/// times the first timing, while the optimum or the fit breaks a limit or leaves flyable space,
/// staysFlyable()), and beside it one optimisation with fine_spans spans, the quicker valid one kept,
/// then yawTurn() from request.yaw to target_yaw, as fast as the limits allow (the camera faces the
/// viewpoint's way early, so its frontier may be seen, and the target dropped, before the vehicle stops there). A target in the start's
/// voxel (a one-voxel path) is flown to straight; a hop of any length gets at least 6 path segments. A path
/// longer than `horizon` is flown only that far along (Trajectory::partial; yaw still turns to target_yaw):
/// long paths are replanned on the way, with what has been mapped since, and each optimisation stays small.
/// When the search finds no path (no path, budget exceeded) but its nearest point to the target
/// (PathResult::toward) is at least min_progress closer to it than the start, the trajectory goes there,
/// partial (PlanReport::toward): the space between comes into view on the way, as FUEL flies on
/// optimistically and replans.
/// Errors name the
/// reason: no path (with the A* status), optimisation failure (with the last check's message).
/// `astar` and `esdf` must describe the same map; the caller holds the map still while this runs.
/// With `memory`: a search failure remembered for this request (SearchMemory::recall at request.time)
/// fails at once (PlanReport::remembered, with the remembered status and expansions), and a new one is
/// remembered.
///
/// With a `scout` search (unknown space free) and config.scout_min_length > 0, a request that finds no
/// path through known space, and cannot fly min_progress towards the target either, searches again
/// with `scout`; the longest start of that path that `astar` could fly (segmentTraversable) is flown
/// when it is scout_min_length long or more: a partial trajectory facing along the path
/// (PlanReport::scouted), replanned on the way as the space beyond comes into view.
///
/// With a `coarse` search and config.coarse_retry (the flight search's rules on a lattice of stride > 1 voxels, whose moves pass
/// `astar`'s segmentTraversable()), a request whose flight search runs out of budget is searched again
/// with it before anything else is tried: a way round a large structure floods more voxels than the
/// fine budget, and the coarse lattice covers stride^3 times the volume for the same count. Its path is
/// flown (PlanReport::coarse), joined to the target's voxel when that segment is flyable too; when not,
/// the path is flown as a partial one (it ends within about a lattice step of the target).
common::Result<Trajectory> planTrajectory(const PlanRequest& request, const planning::Astar& astar,
                                          const map::Esdf& esdf, const OptimizerConfig& optimizer,
                                          const TrajectoryPlannerConfig& config, PlanReport* report = nullptr,
                                          SearchMemory* memory = nullptr, const planning::Astar* scout = nullptr,
                                          const planning::Astar* coarse = nullptr);

/// The longest start of `path` (from path.front()) whose every piece passes astar.segmentTraversable(),
/// checked in steps of half a voxel: the path's vertices up to the last such point, and that point.
std::vector<Vec3> flyablePrefix(const std::vector<Vec3>& path, const planning::Astar& astar);

/// A trajectory that brakes from (p, v) at a_max to a stop and brings the heading from `yaw`, turning at
/// `yaw_rate`, to rest within yaw_acc_max (the rate falls to 0 over one span, without turning back): what is
/// flown when planning fails. (The heading held where the stop began stepped the commanded yaw rate to 0.)
Trajectory stopTrajectory(const Vec3& p, const Vec3& v, double yaw, const OptimizerConfig& optimizer,
                          double yaw_rate = 0.0);

/// True when a failed plan is the vehicle's predicament, not its target's fault: the search could not
/// start (start blocked), or found no path after expanding fewer voxels than the ball of snap_radius
/// around the start holds, i.e. the vehicle has seen too little around itself to leave (at the start, or
/// stopped in the middle of a turn, it has looked one way only). Such a failure is not counted against
/// the frontier; the vehicle looks around instead (lookAroundTrajectory()).
bool startEnclosed(const PlanReport& report, const TrajectoryPlannerConfig& config, double resolution);

/// What to fly when the start is enclosed: brake to a stop where the reference is and turn towards the
/// target (the space towards it is what the search lacked), or, when already facing it (within
/// enclosed_turn / 4), by enclosed_turn further. `goal` is the target and the trajectory is partial, so
/// the replanning rule tries the target again shortly before the turn ends.
Trajectory lookAroundTrajectory(const PlanRequest& request, const TrajectoryPlannerConfig& config,
                                const OptimizerConfig& optimizer);

/// What to fly when a plan failed only for unseen space beside its way (PlanReport::unseen_at set): the
/// vehicle stopped mid-turn, say, has not looked where the way goes. Brakes to a stop where the reference
/// is and turns to face that point, as lookAroundTrajectory() does (goal = target, partial: the target is
/// tried again when the turn is nearly done). nullopt when there is no such point, when config.look_tolerance
/// is 0, when the point is more than 45 deg above or below the vehicle, or when the heading is already within
/// look_tolerance of it: a look cannot mend that, and the failure counts. Callers look once per target.
std::optional<Trajectory> lookAtUnseen(const PlanRequest& request, const PlanReport& report,
                                       const TrajectoryPlannerConfig& config, const OptimizerConfig& optimizer);

/// What follows a failed plan (recoverFromFailedPlan()).
enum class Recovery {
  kLookAround,    ///< the start region cannot be left: lookAroundTrajectory(), the target is kept
  kLookAtUnseen,  ///< the way touches unseen space off the heading: lookAtUnseen(), the target is kept
  kFail,          ///< neither: stopTrajectory(), the frontier counts a failed attempt
};

struct RecoveryPlan {
  Recovery kind = Recovery::kFail;
  Trajectory trajectory;
};

/// Counts a scouting flight (report.scouted) towards the caller's current target in `*scouts`, the caller's
/// count for that target (reset with it), and is true once the target has had more than config.max_scouts
/// of them (never with max_scouts 0). Flying the known start of a way through unseen space normally brings
/// the rest into view, and a path through known space follows within a scout or two; a way flown back and
/// forth without that (seen in a large scene: one target scouted every 7 s for 270 s while the map grew by
/// 0.1 m^3, which the layer manager's stuck timeout does not catch) then counts a failed attempt against
/// the frontier, as a failed plan does: the callers brake instead of flying it.
bool scoutedTooOften(const PlanReport& report, const TrajectoryPlannerConfig& config, int* scouts);

/// The one order both the bench and the trajectory_planner nodelet follow after planTrajectory() failed:
/// an enclosed start (startEnclosed()) looks around; otherwise a way refused for unseen space (or not
/// found through known space) looks there once per target (`*looked_at_unseen`, the caller's flag for its
/// current target, is read and set; the request's failed search is dropped from `memory`, so that the plan
/// after the look searches again); otherwise the vehicle brakes and the failure counts against the frontier.
RecoveryPlan recoverFromFailedPlan(const PlanRequest& request, const PlanReport& report,
                                   const TrajectoryPlannerConfig& config, const OptimizerConfig& optimizer,
                                   double resolution, bool* looked_at_unseen, SearchMemory* memory = nullptr);

/// What a caller keeps about its current target across the plans to it: a fresh one with each new target.
struct TargetAttempts {
  bool looked_at_unseen = false;  ///< lookAtUnseen() was flown for it (recoverFromFailedPlan())
  bool widened = false;           ///< a plan to it was widened (PlanReport::widened): later ones ask for it
  int scouts = 0;                 ///< scouting flights towards it (scoutedTooOften())
};

/// What planForTarget() decided.
enum class FlightOutcome {
  kFly,              ///< the plan is flown
  kScoutedTooOften,  ///< the plan was one scout too many (scoutedTooOften()): brake; a failed attempt
  kLookAround,       ///< the plan failed, the start region cannot be left (Recovery::kLookAround)
  kLookAtUnseen,     ///< the plan failed for unseen space off the heading (Recovery::kLookAtUnseen)
  kFail,             ///< the plan failed otherwise: brake; a failed attempt (Recovery::kFail)
};

struct FlightStep {
  FlightOutcome outcome = FlightOutcome::kFail;
  Trajectory trajectory;  ///< what to fly now, whatever the outcome
  PlanReport report;      ///< planTrajectory()'s report
  std::string failure;    ///< planTrajectory()'s message when the plan failed
  bool newly_widened = false;  ///< the first plan to this target that was widened
  /// The target's frontier counts a failed attempt and the caller drops the target.
  bool failsTarget() const { return outcome == FlightOutcome::kScoutedTooOften || outcome == FlightOutcome::kFail; }
};

/// One plan towards the caller's current target, in the one order the bench and the trajectory_planner
/// nodelet both follow: planTrajectory() (asked to widen once a plan to this target was widened, so that a
/// replan on the way does not turn back to the refused way); a scout beyond max_scouts brakes instead of
/// flying (scoutedTooOften()); a failed plan recovers (recoverFromFailedPlan()). `attempts` is the caller's
/// record for this target, read and updated; request.widen is taken from it.
FlightStep planForTarget(const PlanRequest& request, TargetAttempts* attempts, const planning::Astar& astar,
                         const map::Esdf& esdf, const OptimizerConfig& optimizer,
                         const TrajectoryPlannerConfig& config, SearchMemory* memory = nullptr,
                         const planning::Astar* scout = nullptr, const planning::Astar* coarse = nullptr);

/// The replanning decision for a trajectory being flown (DESIGN §3.7). `current` is null when none is
/// flown; t is the time since its start; target_changed is the caller's own notion of a new target.
/// A new target is one farther than target_tolerance from the trajectory's goal. A trajectory that ends
/// at its target needs no replanning for running out of time: short time left is a reason only for a
/// partial one.
ReplanReason replanReason(const Trajectory* current, double t, const Vec3& target, bool target_changed,
                          const map::Esdf& esdf, const ReplanConfig& replan, const OptimizerConfig& optimizer,
                          const TrajectoryPlannerConfig& config);

}  // namespace go_feap::trajectory
