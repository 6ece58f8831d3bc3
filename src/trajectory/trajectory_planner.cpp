#include "go_feap/trajectory/trajectory_planner.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace go_feap::trajectory {

TrajectorySample sampleTrajectory(const Trajectory& trajectory, double t) {
  TrajectorySample s;
  t = std::max(0.0, t);
  const double T = trajectory.position.duration();
  const double tc = std::min(t, T);
  s.position = trajectory.position.evaluate(tc, 0);
  s.completed = t > T;
  if (!s.completed) {
    s.velocity = trajectory.position.evaluate(tc, 1);
    s.acceleration = trajectory.position.evaluate(tc, 2);
  }
  const double Ty = trajectory.yaw.duration();
  const double ty = std::min(t, Ty);
  const double yaw = trajectory.yaw.evaluate(ty, 0)(0);
  s.yaw = std::atan2(std::sin(yaw), std::cos(yaw));
  if (t <= Ty) s.yaw_dot = trajectory.yaw.evaluate(ty, 1)(0);
  return s;
}

common::Status TrajectoryPlannerConfig::validate() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  // At least 5 cm, half the shipped voxel (a finer resampling of the voxel path adds nothing): the spline fit
  // is dense in the samples (8000 of them for an 8 m horizon at 1 mm: half a gigabyte per matrix).
  if (!(std::isfinite(path_spacing) && path_spacing >= 0.05))
    return common::Status::Error("planner: path_spacing must be finite and >= 0.05 m");
  if (!positive(collision_horizon))
    return common::Status::Error("planner: collision_horizon must be finite and > 0");
  if (!std::isfinite(min_time_between_plans) || min_time_between_plans < 0.0)
    return common::Status::Error("planner: min_time_between_plans must be finite and >= 0");
  if (!positive(cruise_fraction) || cruise_fraction > 1.0)
    return common::Status::Error("planner: cruise_fraction must be in (0, 1]");
  if (!std::isfinite(min_progress) || min_progress < 0.0)
    return common::Status::Error("planner: min_progress must be finite and >= 0");
  if (!std::isfinite(enclosed_turn) || enclosed_turn <= 0.0 || enclosed_turn > M_PI)
    return common::Status::Error("planner: enclosed_turn must be in (0, pi]");
  if (max_refits < 0) return common::Status::Error("planner: max_refits must be >= 0");
  if (!std::isfinite(horizon) || horizon < 0.0) return common::Status::Error("planner: horizon must be finite and >= 0");
  if (!std::isfinite(max_slowdown) || max_slowdown < 1.0)
    return common::Status::Error("planner: max_slowdown must be finite and >= 1");
  // At most 3 m: the search waives its checks of unseen space within it around the start, so a large radius
  // would let flights brush unseen space unchecked (and 5 km overflows its squared voxel count).
  if (!std::isfinite(snap_radius) || snap_radius < 0.0 || snap_radius > 3.0)
    return common::Status::Error("planner: snap_radius must be in [0, 3] m");
  if (!std::isfinite(goal_tolerance) || goal_tolerance < 0.0)
    return common::Status::Error("planner: goal_tolerance must be finite and >= 0");
  if (!std::isfinite(failed_search_memory) || failed_search_memory < 0.0)
    return common::Status::Error("planner: failed_search_memory must be finite and >= 0");
  if (!std::isfinite(scout_min_length) || scout_min_length < 0.0)
    return common::Status::Error("planner: scout_min_length must be finite and >= 0");
  if (!std::isfinite(brake_speed) || brake_speed < 0.0)
    return common::Status::Error("planner: brake_speed must be finite and >= 0");
  if (!std::isfinite(look_tolerance) || look_tolerance < 0.0 || look_tolerance > M_PI)
    return common::Status::Error("planner: look_tolerance must be in [0, pi]");
  if (max_scouts < 0) return common::Status::Error("planner: max_scouts must be >= 0");
  if (fine_spans < 0 || fine_spans > 1000) return common::Status::Error("planner: fine_spans must be in [0, 1000]");
  if (!std::isfinite(profile_acceleration) || profile_acceleration < 0.0 || profile_acceleration >= 1.0)
    return common::Status::Error("planner: profile_acceleration must be in [0, 1) (a share of a_max)");
  // At least 5 ms: the timed fit has a knot per span of the profile's duration (1e-9 s overflowed the count).
  if (!(profile_knot_span >= 0.005 && profile_knot_span <= 1.0))
    return common::Status::Error("planner: profile_knot_span must be in [0.005, 1] s");
  if (!std::isfinite(profile_ramp) || profile_ramp < 0.0 || profile_ramp > 2.0)
    return common::Status::Error("planner: profile_ramp must be in [0, 2] s");
  if (!std::isfinite(profile_corner_cut) || profile_corner_cut < 0.0)
    return common::Status::Error("planner: profile_corner_cut must be finite and >= 0");
  if (!std::isfinite(profile_max_cross_speed) || profile_max_cross_speed < 0.0)
    return common::Status::Error("planner: profile_max_cross_speed must be finite and >= 0");
  return common::Status::Ok();
}

common::Status TrajectoryPlannerConfig::validate(const map::OccupancyConfig& occupancy) const {
  if (common::Status st = validate(); !st) return st;
  const double half_diagonal = 0.5 * std::sqrt(3.0) * occupancy.resolution;
  if (!(goal_tolerance >= half_diagonal))
    return common::Status::Error("planner: goal_tolerance must be at least half a voxel's diagonal (" +
                                 std::to_string(half_diagonal) + " m at the map's resolution of " +
                                 std::to_string(occupancy.resolution) +
                                 " m): a path ends at a voxel's centre, and targets off it were refused as blocked");
  return common::Status::Ok();
}

double flyableClearance(const OptimizerConfig& optimizer, double resolution) {
  return optimizer.min_clearance - 0.5 * std::sqrt(3.0) * resolution;
}

double refitSpacing(double spacing, double resolution) {
  return std::max(0.5 * spacing, std::min(spacing, 0.5 * resolution));
}

bool staysFlyable(const UniformBspline& spline, const planning::Astar& astar, double min_distance,
                  double exempt_radius, std::optional<Vec3>* unseen_at) {
  if (unseen_at) unseen_at->reset();
  const common::GridGeometry& geo = astar.geometry();
  // Samples at most a quarter voxel apart along the curve.
  const double step = std::max(1e-3, 0.25 * geo.resolution() / std::max(spline.maxVelocity(), 1e-3));
  const Vec3 start = spline.position(0.0);
  auto refused = [&](const Vec3& p, const common::Index3& idx) {
    bool unseen = false;
    if (astar.traversableWith(idx, min_distance, &unseen)) return false;
    if (unseen && unseen_at) *unseen_at = p;
    return true;
  };
  // Consecutive samples mostly share a voxel: each voxel is checked once in a row.
  std::optional<common::Index3> checked;
  for (double t = 0.0;; t = std::min(t + step, spline.duration())) {
    const Vec3 p = spline.position(t);
    const common::Index3 idx = geo.clampedIndex(p);
    if (t >= spline.duration()) return idx == checked || !refused(p, idx);
    if ((p - start).norm() > exempt_radius && idx != checked) {
      if (refused(p, idx)) return false;
      checked = idx;
    }
  }
}

void SearchMemory::remember(const Vec3& start, const Vec3& goal, planning::PathStatus status, int expansions,
                            double t) {
  entries_.push_back({start, goal, {status, expansions, t}});
}

std::optional<SearchMemory::Failure> SearchMemory::recall(const Vec3& start, const Vec3& goal, double t,
                                                          const TrajectoryPlannerConfig& config) {
  entries_.erase(std::remove_if(entries_.begin(), entries_.end(),
                                [&](const Entry& e) {
                                  return !(t - e.failure.t < config.failed_search_memory) || t < e.failure.t;
                                }),
                 entries_.end());
  for (const Entry& e : entries_)
    if (e.matches(start, goal, config)) return e.failure;
  return std::nullopt;
}

void SearchMemory::forget(const Vec3& start, const Vec3& goal, const TrajectoryPlannerConfig& config) {
  entries_.erase(std::remove_if(entries_.begin(), entries_.end(),
                                [&](const Entry& e) { return e.matches(start, goal, config); }),
                 entries_.end());
}

std::vector<Vec3> profileSamples(const std::vector<Vec3>& path, double v_start, double a_start,
                                 const SpeedProfile& profile, double* knot_span) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  if (!positive(profile.cruise) || !positive(profile.acceleration) || !positive(profile.knot_span) ||
      !(std::isfinite(profile.ramp) && profile.ramp >= 0.0) ||
      !(std::isfinite(profile.corner_cut) && profile.corner_cut >= 0.0) || !std::isfinite(v_start) ||
      !std::isfinite(a_start))
    throw std::invalid_argument("profileSamples: cruise, acceleration and knot_span must be finite and > 0, ramp "
                                "and corner_cut finite and >= 0, v_start and a_start finite");
  if (path.size() < 2) return {};
  std::vector<double> s(path.size(), 0.0);
  for (std::size_t i = 1; i < path.size(); ++i) s[i] = s[i - 1] + (path[i] - path[i - 1]).norm();
  const double length = s.back();
  const double acc = profile.acceleration;
  const double a0 = std::clamp(a_start, -acc, acc);
  // The profile is integrated in steps of h and its arc length averaged over the last m steps (the
  // ramp). Before t = 0 it is extended as a flight at constant acceleration a0, with the speed v0 that
  // makes the average leave at v_start: the averaged curve then starts with v_start and about a0, and
  // the averaging moves it back by `shift`, which the raw profile leaves out of its length.
  constexpr double h = 0.002;
  const int m = std::max(1, static_cast<int>(std::lround(profile.ramp / h)));
  const double v0 = std::clamp(v_start + 0.5 * a0 * m * h, 0.0, profile.cruise);
  auto before = [&](int j) { return v0 * j * h + 0.5 * a0 * (j * h) * (j * h); };  // j < 0
  double shift = 0.0;
  for (int q = -m; q < 0; ++q) shift -= before(q) / m;
  const double raw = length - shift;
  if (raw < 0.05) return {};
  // Corner speeds: a circular turn by theta at `acc` whose apex stays within corner_cut of the vertex.
  std::vector<std::pair<double, double>> corners;  // (raw arc length, speed)
  for (std::size_t i = 1; i + 1 < path.size(); ++i) {
    const Vec3 in = path[i] - path[i - 1], out = path[i + 1] - path[i];
    if (in.norm() < 1e-9 || out.norm() < 1e-9) continue;
    const double half = 0.5 * std::acos(std::clamp(in.dot(out) / (in.norm() * out.norm()), -1.0, 1.0));
    const double excess = 1.0 / std::cos(std::min(half, 1.5)) - 1.0;  // apex cut per metre of radius
    if (excess > 1e-9) corners.push_back({s[i] - shift, std::sqrt(acc * profile.corner_cut / excess)});
  }
  auto speed = [&](double x) {
    double v = std::min({profile.cruise, std::sqrt(v0 * v0 + 2.0 * acc * x), std::sqrt(2.0 * acc * std::max(0.0, raw - x))});
    for (const auto& [at, vc] : corners) v = std::min(v, std::sqrt(vc * vc + 2.0 * acc * std::abs(x - at)));
    return v;
  };
  // Arc length at t = j h (midpoint steps; the speed's floor only ends the last, braking step).
  std::vector<double> xs{0.0};
  for (double x = 0.0; x < raw - 1e-9;) {
    const double v = std::max(speed(x + 0.5 * h * speed(x)), 0.5 * acc * h);
    x = std::min(raw, x + h * v);
    xs.push_back(x);
  }
  const int n = static_cast<int>(xs.size());
  auto extended = [&](int j) { return j < 0 ? before(j) : j < n ? xs[j] : raw; };
  const int steps = n - 1 + m;
  std::vector<double> averaged(steps + 1);
  double sum = 0.0;
  for (int q = -m; q < 0; ++q) sum += extended(q);
  for (int j = 0; j <= steps; ++j) {
    averaged[j] = std::clamp(sum / m + shift, 0.0, length);
    sum += extended(j) - extended(j - m);
  }
  const double duration = steps * h;
  const int spans = std::max(6, static_cast<int>(std::ceil(duration / profile.knot_span - 1e-9)));
  if (knot_span) *knot_span = duration / spans;
  std::vector<Vec3> out;
  out.reserve(spans + 1);
  std::size_t seg = 1;
  for (int i = 0; i <= spans; ++i) {
    const double at = static_cast<double>(steps) * i / spans;
    const int j0 = std::min(steps, static_cast<int>(at));
    const int j1 = std::min(steps, j0 + 1);
    const double x = averaged[j0] + (at - j0) * (averaged[j1] - averaged[j0]);
    while (seg + 1 < path.size() && s[seg] < x) ++seg;
    const double seg_len = s[seg] - s[seg - 1];
    const double f = seg_len > 0.0 ? std::clamp((x - s[seg - 1]) / seg_len, 0.0, 1.0) : 1.0;
    out.push_back(path[seg - 1] + f * (path[seg] - path[seg - 1]));
  }
  out.front() = path.front();
  out.back() = path.back();
  return out;
}

namespace {

/// Brake to a stop where the reference is while turning to `yaw`, then hold still for as long as the turn
/// takes (the replanning rule goes by the position's duration: a stop over before the turn made the next
/// plan start the turn again). Partial, with the target as goal.
Trajectory turnTowards(const PlanRequest& request, double yaw, const OptimizerConfig& optimizer) {
  Trajectory out;
  out.position = safeStop(request.start, request.velocity, optimizer.a_max);
  auto turn = yawTurn(request.yaw, yaw, out.position.duration(), optimizer, request.yaw_rate);
  out.yaw = turn ? std::move(turn).value() : UniformBspline(Eigen::MatrixXd::Constant(1, 4, request.yaw), 3, 0.1);
  const double speed = request.velocity.norm();
  const double gap = out.yaw.duration() - out.position.duration();
  // A stop shorter than a tenth of a millimetre (an odometry's noise, the last moment of braking): held where it starts,
  // as its spans would be too short to fill the turn with. Else the stop's last point, repeated.
  if (speed * speed / (2.0 * optimizer.a_max) < 1e-4) {
    out.position = UniformBspline(request.start.replicate(1, 4), 3, out.yaw.duration());
  } else if (gap > 0.0) {
    const Eigen::MatrixXd& q = out.position.controlPoints();
    const double dt = out.position.knotSpan();
    const auto extra = static_cast<Eigen::Index>(std::min(std::ceil(gap / dt - 1e-9), 10000.0));
    Eigen::MatrixXd padded(q.rows(), q.cols() + extra);
    padded << q, q.rightCols<1>().replicate(1, extra);
    out.position = UniformBspline(padded, 3, dt);
  }
  out.goal = request.target;
  out.partial = true;
  return out;
}

}  // namespace

common::Result<Trajectory> planTrajectory(const PlanRequest& request, const planning::Astar& astar,
                                          const map::Esdf& esdf, const OptimizerConfig& optimizer,
                                          const TrajectoryPlannerConfig& config, PlanReport* report,
                                          SearchMemory* memory, const planning::Astar* scout,
                                          const planning::Astar* coarse) {
  using R = common::Result<Trajectory>;
  PlanReport local;
  PlanReport& rep = report ? *report : local;
  rep = PlanReport();
  if (!request.start.allFinite() || !request.velocity.allFinite() || !request.target.allFinite() ||
      !std::isfinite(request.yaw) || !std::isfinite(request.yaw_rate) || !std::isfinite(request.target_yaw))
    return R::Error("plan request is not finite");
  // A target where the reference already is: turn in place (braking first if moving).
  auto turnInPlace = [&]() -> R {
    Trajectory out;
    out.position = safeStop(request.start, request.velocity, optimizer.a_max);
    // Braking from speed comes to rest past the target (v^2 / 2 a_max, a metre at 2 m/s), and is taken as
    // ending there all the same: not replanned back to the target. Marked partial (replanned before its end),
    // it flew the vehicle back to views it had taken in passing, +96 and +118 s on powerplant seeds 2 and 4
    // (docs/benchmark-history.md, twenty-ninth session: 8cb9aa4, reverted); the frontier is seen in passing.
    out.goal = request.target;
    rep.path_status = planning::PathStatus::kFound;
    auto yaw = yawTurn(request.yaw, request.target_yaw, 0.0, optimizer, request.yaw_rate);
    if (!yaw) return R::Error("yaw spline failed: " + yaw.message());
    out.yaw = std::move(yaw).value();
    return out;
  };
  if ((request.target - request.start).norm() < 0.5 * astar.geometry().resolution()) return turnInPlace();
  // How near unseen space and obstacles the spline's voxels may come (staysFlyable() below). A search
  // keeping unseen space nearer than that all round may be widened to it (config.unseen_retry).
  const double voxel_clearance = flyableClearance(optimizer, astar.geometry().resolution());
  planning::AstarConfig wide = astar.config();
  wide.known_radius = std::min(voxel_clearance, wide.clearance);
  // Only a search that does look farther: with a flight clearance below the check's radius the wide search
  // would be this one again, failing the same way, and each retry would start another (without end).
  const bool widenable = config.unseen_retry && wide.known_clearance && !wide.unknown_is_free &&
                         wide.known_radius > astar.config().known_radius;
  if (request.widen && widenable) {
    PlanRequest plain = request;
    plain.widen = false;
    const planning::Astar wide_search(astar.occupancy(), astar.esdf(), wide);
    auto planned = planTrajectory(plain, wide_search, esdf, optimizer, config, &rep, memory, scout, coarse);
    rep.widened = true;
    return planned;
  }
  if (memory) {
    if (const auto failure = memory->recall(request.start, request.target, request.time, config)) {
      rep.path_status = failure->status;
      rep.path_expansions = failure->expansions;
      rep.remembered = true;
      return R::Error(std::string("no path: ") + planning::toString(failure->status) + " (the same search failed " +
                      std::to_string(request.time - failure->t) + " s ago)");
    }
  }
  planning::PathResult path = astar.search(request.start, request.target, config.snap_radius);
  rep.path_status = path.status;
  rep.path_expansions = path.expansions;
  // The fine search ran out of budget: a long way round (a concave structure between) floods more voxels
  // than it may expand. The same question on a coarse lattice covers stride^3 times the volume.
  std::string coarse_failure;  // what the coarse search said, for the error message
  if (path.status == planning::PathStatus::kBudgetExceeded && coarse && config.coarse_retry) {
    planning::PathResult way = coarse->search(request.start, request.target, config.snap_radius);
    rep.path_expansions += way.expansions;
    coarse_failure = std::string(" (coarse search: ") + planning::toString(way.status) + ")";
    if (way.status == planning::PathStatus::kFound) {
      // The lattice voxel nearest the target may be a little off it: join the target's own voxel when the
      // segment there is flyable; otherwise the way is flown as a partial path and replanned near its end.
      const common::GridGeometry& geo = astar.geometry();
      const Vec3 goal_voxel = geo.indexToCoord(geo.clampedIndex(request.target));
      const double last_leg = (goal_voxel - way.path.back()).norm();
      if (last_leg > 1e-9 && astar.segmentTraversable(way.path.back(), goal_voxel)) {
        way.path.push_back(goal_voxel);
        way.length += last_leg;
      }
      rep.coarse = true;
      rep.path_status = planning::PathStatus::kFound;
      path = std::move(way);
    }
  }
  // No path through known space (yet): when the search got min_progress closer to the target, fly
  // there (a partial trajectory, replanned on the way, as the space between comes into view);
  // otherwise the plan fails.
  const bool toward = path.status != planning::PathStatus::kFound && !path.toward.empty() &&
                      config.min_progress > 0.0 &&
                      (request.target - request.start).norm() - (request.target - path.toward.back()).norm() >=
                          config.min_progress;
  const bool no_path =
      path.status == planning::PathStatus::kNoPath || path.status == planning::PathStatus::kBudgetExceeded;
  // Known space does not lead there (yet), but space nobody has seen may: fly the known start of that way.
  std::vector<Vec3> scouted;
  if (no_path && !toward && scout && config.scout_min_length > 0.0) {
    const planning::PathResult way = scout->search(request.start, request.target, config.snap_radius);
    if (way.status == planning::PathStatus::kFound) {
      std::vector<Vec3> prefix = flyablePrefix(way.path, astar);
      double along = 0.0;
      for (std::size_t i = 1; i < prefix.size(); ++i) along += (prefix[i] - prefix[i - 1]).norm();
      if (along >= config.scout_min_length) scouted = std::move(prefix);
    }
  }
  if (path.status != planning::PathStatus::kFound && !toward && scouted.empty()) {
    if (memory && no_path) memory->remember(request.start, request.target, path.status, path.expansions, request.time);
    // Known space does not lead there, and no known start of a way does: the way is through space not yet
    // seen, which a look towards the target may show.
    if (path.status == planning::PathStatus::kNoPath) rep.unseen_at = request.target;
    return R::Error(std::string("no path: ") + planning::toString(path.status) + coarse_failure);
  }
  rep.toward = toward;
  rep.scouted = !scouted.empty();
  const bool partial_way = toward || rep.scouted;  // no path to the target: a part of the way there
  const std::vector<Vec3>& found = rep.scouted ? scouted : toward ? path.toward : path.path;
  rep.path_length = partial_way ? 0.0 : path.length;
  // The start may snap out of a blocked voxel; the goal may not wander off the viewpoint.
  // A coarse path ending short of the target (its last leg not flyable) is flown as a partial one instead.
  const bool short_of_goal = !partial_way && (path.path.back() - request.target).norm() > config.goal_tolerance;
  const bool coarse_short = short_of_goal && rep.coarse;
  if (short_of_goal && !rep.coarse) {
    rep.path_status = planning::PathStatus::kGoalBlocked;
    return R::Error("no path: goal_blocked (the nearest flyable voxel is " +
                    std::to_string((path.path.back() - request.target).norm()) + " m from the target)");
  }
  std::vector<Vec3> points = found;
  points.front() = request.start;  // start exactly at the current reference
  double length = 0.0;
  for (std::size_t i = 1; i < points.size(); ++i) length += (points[i] - points[i - 1]).norm();
  // Start and goal in one voxel: the path is that voxel; hop straight to the target inside it.
  if (length < 1e-3) {
    if (!astar.segmentTraversable(request.start, request.target)) return turnInPlace();
    points = {request.start, request.target};
    length = (request.target - request.start).norm();
  }
  bool partial = partial_way || coarse_short;
  if (config.horizon > 0.0 && length > config.horizon) {
    // Keep the first `horizon` metres of the polyline.
    std::vector<Vec3> kept{points.front()};
    double along = 0.0;
    for (std::size_t i = 1; i < points.size(); ++i) {
      const double seg = (points[i] - points[i - 1]).norm();
      if (along + seg >= config.horizon) {
        kept.push_back(points[i - 1] + (points[i] - points[i - 1]) * ((config.horizon - along) / seg));
        break;
      }
      kept.push_back(points[i]);
      along += seg;
    }
    points = std::move(kept);
    length = config.horizon;
    partial = true;
  }
  // At least 6 segments, however short the hop: the optimiser needs 7 control points.
  double spacing = std::min(config.path_spacing, length / 6.0);
  // Initial timing within the limits: cruise at a share of v_max, but short hops from (or to) rest
  // need the time an a_max-limited accelerate/brake takes.
  const double v0 = request.velocity.norm();
  const double total = std::max({length / (config.cruise_fraction * optimizer.v_max),
                                 2.5 * std::sqrt(length / optimizer.a_max), v0 / optimizer.a_max + 0.5});
  double duration = total;
  // The reference's acceleration is kept as well (within the limits the optimiser aims at).
  const double a_limit = optimizer.feasibility_margin * optimizer.a_max;
  Vec3 start_acc = request.acceleration.allFinite() ? request.acceleration : Vec3::Zero();
  if (start_acc.norm() > a_limit) start_acc *= a_limit / start_acc.norm();
  common::Result<UniformBspline> spline = common::Result<UniformBspline>::Error("not planned");
  auto flyable = [&](const UniformBspline& candidate) {
    return checkTrajectory(candidate, esdf, optimizer).ok() &&
           staysFlyable(candidate, astar, voxel_clearance, config.snap_radius);
  };
  // The timed fit: the quickest flight along the path (within the profile), flown as it is if flyable.
  const Vec3 first_leg = (points[1] - points[0]).normalized();
  const double v_along = request.velocity.dot(first_leg);
  const Vec3 v_cross = request.velocity - v_along * first_leg;
  if (config.profile_acceleration > 0.0 && v_along >= 0.0 && v_cross.norm() <= config.profile_max_cross_speed) {
    SpeedProfile profile;
    profile.cruise = optimizer.feasibility_margin * optimizer.v_max;
    profile.acceleration = config.profile_acceleration * optimizer.a_max;
    profile.ramp = config.profile_ramp;
    profile.corner_cut = config.profile_corner_cut;
    profile.knot_span = config.profile_knot_span;
    double dt = 0.0;
    std::vector<Vec3> samples = profileSamples(points, v_along, start_acc.dot(first_leg), profile, &dt);
    if (!samples.empty()) {
      // The start velocity's part across the path decays on the way: an offset v_cross g(t), g(t) =
      // t (1 - t / Te)^2 (g'(0) = 1, g(Te) = g'(Te) = 0, |g''| <= 4 / Te) with the acceleration the
      // profile leaves: Te = 4 |v_cross| / a_cross.
      const double a_cross = std::sqrt(std::max(0.0, a_limit * a_limit - profile.acceleration * profile.acceleration));
      const double Te = a_cross > 0.0 ? 4.0 * v_cross.norm() / a_cross : 0.0;
      // Likewise the reference's acceleration across the path (the profile starts with the part along it)
      // fades out over Ta: a t^2 / 2 (1 - t / Ta)^3 has acceleration a at 0 and nothing left (nor speed) at
      // Ta; along the path it also corrects what the profile's start is off by.
      const double Ta = std::max(2.0 * profile.ramp, 4.0 * profile.knot_span);
      const Vec3 a_fix = start_acc - (samples[2] - 2.0 * samples[1] + samples[0]).dot(first_leg) / (dt * dt) * first_leg;
      const Vec3 end = samples.back();
      for (std::size_t i = 0; i < samples.size(); ++i) {
        const double t = dt * static_cast<double>(i);
        if (t < Te) samples[i] += v_cross * (t * (1.0 - t / Te) * (1.0 - t / Te));
        if (t < Ta) samples[i] += a_fix * (0.5 * t * t * std::pow(1.0 - t / Ta, 3));
      }
      // A fade that outlasts the flight moves its end off the path's: a 1 m/s start across a 2 m hop (Te
      // 6.6 s) ended a metre beside the goal, flown as if there. Such a flight is optimised instead.
      if ((samples.back() - end).norm() <= 1e-3) {
        UniformBspline fit = UniformBspline::fromTimedSamples(samples, dt, request.velocity, start_acc);
        if (flyable(fit)) {
          spline = std::move(fit);
          rep.profiled = true;
        }
      }
    }
  }
  // A finer optimisation beside the usual one (short paths only: long ones have their spans already).
  std::optional<UniformBspline> fine;
  if (!spline && config.fine_spans > 0 && length / config.fine_spans < spacing - 1e-9) {
    const auto samples = UniformBspline::resamplePolyline(points, length / config.fine_spans);
    const double dt = duration / static_cast<double>(samples.size() - 1);
    auto optimum = optimize(UniformBspline::fitPath(samples, dt, request.velocity, Vec3::Zero(), start_acc), esdf,
                            optimizer);
    if (optimum && staysFlyable(*optimum, astar, voxel_clearance, config.snap_radius)) fine = std::move(optimum).value();
  }
  // Optimise; when the result breaks a limit or a clearance, refit slower and closer to the path (half
  // the sample spacing, down to half a voxel: the fit then hugs the searched path, which keeps
  // astar.clearance) and try again; the start velocity is kept, so the reference stays continuous. A
  // refit that passes the same checks as an optimised spline is accepted as it is.
  for (int attempt = 0; !rep.profiled && attempt <= config.max_refits; ++attempt) {
    rep.refits = attempt;
    const auto samples = UniformBspline::resamplePolyline(points, spacing);
    const double dt = duration / static_cast<double>(std::max<std::size_t>(1, samples.size() - 1));
    const UniformBspline init = UniformBspline::fitPath(samples, dt, request.velocity, Vec3::Zero(), start_acc);
    spline = optimize(init, esdf, optimizer);
    // The optimum must also stay where the path search may go: the ESDF knows only mapped obstacles,
    // and a smoothed corner can cut through space nobody has seen (or over the box's clearance).
    std::optional<Vec3> optimum_unseen;
    if (spline && !staysFlyable(*spline, astar, voxel_clearance, config.snap_radius, &optimum_unseen)) {
      spline = common::Result<UniformBspline>::Error("the optimised trajectory leaves known flyable space");
      ++rep.left_flyable;
      if (optimum_unseen) rep.unseen_at = optimum_unseen;
    }
    if (spline) break;
    std::optional<Vec3> fit_unseen;
    const bool fit_ok = checkTrajectory(init, esdf, optimizer).ok();
    if (fit_ok && staysFlyable(init, astar, voxel_clearance, config.snap_radius, &fit_unseen)) {
      spline = init;
      rep.used_fit = true;
      break;
    }
    if (fit_unseen) rep.unseen_at = fit_unseen;
    const double f = std::max({1.5, init.maxVelocity() / (0.9 * optimizer.v_max),
                               std::sqrt(init.maxAcceleration() / (0.9 * optimizer.a_max))});
    // Slowing down mends broken limits, not clearance: a crawl (a 26 m path in 145 s was seen) is a
    // failure, so that the frontier counts a failed attempt instead of holding the vehicle for minutes.
    if (duration >= total * config.max_slowdown) break;
    duration = std::min(duration * std::min(f, 4.0), total * config.max_slowdown);
    spacing = refitSpacing(spacing, astar.geometry().resolution());
  }
  if (fine && (!spline || fine->duration() < spline->duration())) {
    spline = std::move(*fine);
    rep.fine = true;
    rep.refits = 0;
    rep.used_fit = false;
  }
  if (!spline && rep.unseen_at && widenable) {
    // Refused for unseen space beside the path: the search vouched for voxels one voxel from an unseen
    // pocket (it looks along the axes), which the check refuses (it looks all round). Search again keeping
    // unseen space as far away all round as the check does; without a coarse or scouting search (a path
    // through known space is what this mends), nor the memory (the first search did find a path).
    PlanReport again;
    const planning::Astar wide_search(astar.occupancy(), astar.esdf(), wide);
    auto retried = planTrajectory(request, wide_search, esdf, optimizer, config, &again);
    if (retried) {
      again.widened = true;
      again.left_flyable += rep.left_flyable;
      rep = again;
      return retried;
    }
  }
  if (!spline) {
    // From a start moving faster than brake_speed (most often a turn-around: a new target behind or beside
    // the vehicle) the optimiser keeps the start velocity, and its curve swings out of the space the
    // search vouched for. Brake to rest, turning towards the target, and ask again from there (a partial
    // trajectory, replanned as it ends) rather than fail the target.
    if (config.brake_speed > 0.0 && v0 > config.brake_speed) {
      rep.braked = true;
      rep.unseen_at.reset();  // not a failure: nothing to look at
      return turnTowards(request, request.target_yaw, optimizer);
    }
    return R::Error("optimisation failed: " + spline.message());
  }
  rep.unseen_at.reset();
  Trajectory out;
  out.position = std::move(spline).value();
  out.goal = request.target;
  out.partial = partial;
  // Turn at once: facing the viewpoint's way early, the camera may see its frontier (and the target be
  // dropped) before the vehicle has to stop there.
  // A scouting flight looks where it goes: along the way's last known piece.
  double target_yaw = request.target_yaw;
  if (rep.scouted && points.size() >= 2) {
    const Vec3 last = points.back() - points[points.size() - 2];
    if (last.head<2>().norm() > 1e-6) target_yaw = std::atan2(last.y(), last.x());
  }
  auto yaw = yawTurn(request.yaw, target_yaw, 0.0, optimizer, request.yaw_rate);
  if (!yaw) return R::Error("yaw spline failed: " + yaw.message());
  out.yaw = std::move(yaw).value();
  return out;
}

std::vector<Vec3> flyablePrefix(const std::vector<Vec3>& path, const planning::Astar& astar) {
  std::vector<Vec3> out;
  if (path.empty()) return out;
  out.push_back(path.front());
  const double step = 0.5 * astar.geometry().resolution();
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Vec3 a = path[i - 1], d = path[i] - a;
    const int n = std::max(1, static_cast<int>(std::ceil(d.norm() / step)));
    Vec3 last_ok = a;
    for (int k = 1; k <= n; ++k) {
      const Vec3 p = a + d * (static_cast<double>(k) / n);
      if (!astar.segmentTraversable(last_ok, p)) {
        if (last_ok != out.back()) out.push_back(last_ok);
        return out;
      }
      last_ok = p;
    }
    out.push_back(path[i]);
  }
  return out;
}

bool scoutedTooOften(const PlanReport& report, const TrajectoryPlannerConfig& config, int* scouts) {
  if (!report.scouted) return false;
  ++*scouts;
  return config.max_scouts > 0 && *scouts > config.max_scouts;
}

Trajectory stopTrajectory(const Vec3& p, const Vec3& v, double yaw, const OptimizerConfig& optimizer,
                          double yaw_rate) {
  Trajectory out;
  out.position = safeStop(p, v, optimizer.a_max);
  out.goal = out.position.position(out.position.duration());
  // yawTurn's rate profile from w0 over a turn of w0 times its shortest span: w0, w0, then 0 (within
  // yaw_acc_max, as that span reaches yaw_rate_max at it). Not spread over the brake: a longer span would
  // ask for a longer turn, up to half a turn and more for a long brake.
  const double w0 = std::isfinite(yaw_rate) ? std::clamp(yaw_rate, -optimizer.yaw_rate_max, optimizer.yaw_rate_max) : 0.0;
  auto y = yawTurn(yaw, yaw + w0 * optimizer.yaw_rate_max / optimizer.yaw_acc_max, 0.0, optimizer, w0);
  // yawTurn fails only on a non-finite yaw or an invalid config: keep a valid spline even then.
  out.yaw = y ? std::move(y).value() : UniformBspline(Eigen::MatrixXd::Constant(1, 4, yaw), 3, 0.1);
  return out;
}

bool startEnclosed(const PlanReport& report, const TrajectoryPlannerConfig& config, double resolution) {
  if (report.path_status == planning::PathStatus::kStartBlocked) return true;
  if (report.path_status != planning::PathStatus::kNoPath) return false;
  const double r = config.snap_radius / resolution;
  return report.path_expansions < 4.0 / 3.0 * M_PI * r * r * r;
}

Trajectory lookAroundTrajectory(const PlanRequest& request, const TrajectoryPlannerConfig& config,
                                const OptimizerConfig& optimizer) {
  const Vec3 to = request.target - request.start;
  double yaw = std::atan2(to.y(), to.x());
  if (to.head<2>().norm() < 1e-6 || std::abs(std::remainder(yaw - request.yaw, 2.0 * M_PI)) <= 0.25 * config.enclosed_turn)
    yaw = request.yaw + config.enclosed_turn;
  return turnTowards(request, yaw, optimizer);
}

std::optional<Trajectory> lookAtUnseen(const PlanRequest& request, const PlanReport& report,
                                       const TrajectoryPlannerConfig& config, const OptimizerConfig& optimizer) {
  if (!report.unseen_at || config.look_tolerance <= 0.0) return std::nullopt;
  const Vec3 to = *report.unseen_at - request.start;
  // Turning does not bring a point above or below the vehicle into view.
  if (to.head<2>().norm() < std::abs(to.z())) return std::nullopt;
  const double yaw = std::atan2(to.y(), to.x());
  if (std::abs(std::remainder(yaw - request.yaw, 2.0 * M_PI)) <= config.look_tolerance) return std::nullopt;
  return turnTowards(request, yaw, optimizer);
}

RecoveryPlan recoverFromFailedPlan(const PlanRequest& request, const PlanReport& report,
                                   const TrajectoryPlannerConfig& config, const OptimizerConfig& optimizer,
                                   double resolution, bool* looked_at_unseen, SearchMemory* memory) {
  RecoveryPlan out;
  if (startEnclosed(report, config, resolution)) {
    out.kind = Recovery::kLookAround;
    out.trajectory = lookAroundTrajectory(request, config, optimizer);
    return out;
  }
  if (!*looked_at_unseen) {
    if (auto look = lookAtUnseen(request, report, config, optimizer)) {
      *looked_at_unseen = true;
      if (memory) memory->forget(request.start, request.target, config);
      out.kind = Recovery::kLookAtUnseen;
      out.trajectory = std::move(*look);
      return out;
    }
  }
  out.kind = Recovery::kFail;
  out.trajectory = stopTrajectory(request.start, request.velocity, request.yaw, optimizer, request.yaw_rate);
  return out;
}

FlightStep planForTarget(const PlanRequest& request, TargetAttempts* attempts, const planning::Astar& astar,
                         const map::Esdf& esdf, const OptimizerConfig& optimizer,
                         const TrajectoryPlannerConfig& config, SearchMemory* memory, const planning::Astar* scout,
                         const planning::Astar* coarse) {
  FlightStep out;
  PlanRequest asked = request;
  asked.widen = attempts->widened;
  auto planned = planTrajectory(asked, astar, esdf, optimizer, config, &out.report, memory, scout, coarse);
  if (planned && scoutedTooOften(out.report, config, &attempts->scouts)) {
    out.outcome = FlightOutcome::kScoutedTooOften;
    out.trajectory = stopTrajectory(asked.start, asked.velocity, asked.yaw, optimizer, asked.yaw_rate);
    return out;
  }
  if (planned) {
    out.outcome = FlightOutcome::kFly;
    out.newly_widened = out.report.widened && !attempts->widened;
    attempts->widened = attempts->widened || out.report.widened;
    out.trajectory = std::move(planned).value();
    return out;
  }
  out.failure = planned.message();
  RecoveryPlan recovery = recoverFromFailedPlan(asked, out.report, config, optimizer, astar.geometry().resolution(),
                                                &attempts->looked_at_unseen, memory);
  switch (recovery.kind) {
    case Recovery::kLookAround:
      out.outcome = FlightOutcome::kLookAround;
      break;
    case Recovery::kLookAtUnseen:
      out.outcome = FlightOutcome::kLookAtUnseen;
      break;
    case Recovery::kFail:
      out.outcome = FlightOutcome::kFail;
      break;
  }
  out.trajectory = std::move(recovery.trajectory);
  return out;
}

ReplanReason replanReason(const Trajectory* current, double t, const Vec3& target, bool target_changed,
                          const map::Esdf& esdf, const ReplanConfig& replan, const OptimizerConfig& optimizer,
                          const TrajectoryPlannerConfig& config) {
  ReplanInputs in;
  in.target_changed = target_changed;
  if (current) {
    in.has_trajectory = true;
    in.time_left = current->duration() - t;
    in.target_distance_to_end = (current->goal - target).norm();
    in.collision_time =
        firstCollisionTime(current->position, std::max(0.0, t), esdf, optimizer.min_clearance,
                           optimizer.leave_distance, config.collision_horizon);
  }
  const ReplanReason reason = shouldReplan(in, replan);
  // A trajectory that ends at its target needs no replanning for running out: it arrives.
  const bool ends_at_target = current && !current->partial && in.target_distance_to_end <= replan.target_tolerance;
  if (ends_at_target && reason == ReplanReason::kShortTimeLeft) return ReplanReason::kNone;
  return reason;
}

}  // namespace go_feap::trajectory
