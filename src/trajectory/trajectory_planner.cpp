#include "go_feap/trajectory/trajectory_planner.h"

#include <algorithm>
#include <cmath>

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
  if (!positive(path_spacing)) return common::Status::Error("planner: path_spacing must be finite and > 0");
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
  if (!std::isfinite(snap_radius) || snap_radius < 0.0)
    return common::Status::Error("planner: snap_radius must be finite and >= 0");
  if (!std::isfinite(goal_tolerance) || goal_tolerance < 0.0)
    return common::Status::Error("planner: goal_tolerance must be finite and >= 0");
  if (!std::isfinite(failed_search_memory) || failed_search_memory < 0.0)
    return common::Status::Error("planner: failed_search_memory must be finite and >= 0");
  if (!std::isfinite(scout_min_length) || scout_min_length < 0.0)
    return common::Status::Error("planner: scout_min_length must be finite and >= 0");
  if (!std::isfinite(look_tolerance) || look_tolerance < 0.0 || look_tolerance > M_PI)
    return common::Status::Error("planner: look_tolerance must be in [0, pi]");
  if (max_scouts < 0) return common::Status::Error("planner: max_scouts must be >= 0");
  return common::Status::Ok();
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
    const common::Index3 idx = geo.coordToIndex(p);
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
    if ((e.start - start).norm() <= config.snap_radius && (e.goal - goal).norm() <= config.goal_tolerance)
      return e.failure;
  return std::nullopt;
}

common::Result<Trajectory> planTrajectory(const PlanRequest& request, const planning::Astar& astar,
                                          const map::Esdf& esdf, const OptimizerConfig& optimizer,
                                          const TrajectoryPlannerConfig& config, PlanReport* report,
                                          SearchMemory* memory, const planning::Astar* scout) {
  using R = common::Result<Trajectory>;
  PlanReport local;
  PlanReport& rep = report ? *report : local;
  rep = PlanReport();
  if (!request.start.allFinite() || !request.velocity.allFinite() || !request.target.allFinite() ||
      !std::isfinite(request.yaw) || !std::isfinite(request.target_yaw))
    return R::Error("plan request is not finite");
  // A target where the reference already is: turn in place (braking first if moving).
  auto turnInPlace = [&]() -> R {
    Trajectory out;
    out.position = safeStop(request.start, request.velocity, optimizer.a_max);
    out.goal = request.target;
    rep.path_status = planning::PathStatus::kFound;
    auto yaw = yawTurn(request.yaw, request.target_yaw, 0.0, optimizer);
    if (!yaw) return R::Error("yaw spline failed: " + yaw.message());
    out.yaw = std::move(yaw).value();
    return out;
  };
  if ((request.target - request.start).norm() < 0.5 * astar.geometry().resolution()) return turnInPlace();
  if (memory) {
    if (const auto failure = memory->recall(request.start, request.target, request.time, config)) {
      rep.path_status = failure->status;
      rep.path_expansions = failure->expansions;
      rep.remembered = true;
      return R::Error(std::string("no path: ") + planning::toString(failure->status) + " (the same search failed " +
                      std::to_string(request.time - failure->t) + " s ago)");
    }
  }
  const planning::PathResult path = astar.search(request.start, request.target, config.snap_radius);
  rep.path_status = path.status;
  rep.path_expansions = path.expansions;
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
    return R::Error(std::string("no path: ") + planning::toString(path.status));
  }
  rep.toward = toward;
  rep.scouted = !scouted.empty();
  const bool partial_way = toward || rep.scouted;  // no path to the target: a part of the way there
  const std::vector<Vec3>& found = rep.scouted ? scouted : toward ? path.toward : path.path;
  rep.path_length = partial_way ? 0.0 : path.length;
  // The start may snap out of a blocked voxel; the goal may not wander off the viewpoint.
  if (!partial_way && (path.path.back() - request.target).norm() > config.goal_tolerance) {
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
  bool partial = partial_way;
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
  common::Result<UniformBspline> spline = common::Result<UniformBspline>::Error("not planned");
  // The optimiser checks min_clearance along the curve; a voxel's centre may be half a diagonal farther.
  const double voxel_clearance = optimizer.min_clearance - 0.5 * std::sqrt(3.0) * astar.geometry().resolution();
  // Optimise; when the result breaks a limit or a clearance, refit slower and closer to the path (half
  // the sample spacing, down to half a voxel: the fit then hugs the searched path, which keeps
  // astar.clearance) and try again; the start velocity is kept, so the reference stays continuous. A
  // refit that passes the same checks as an optimised spline is accepted as it is.
  for (int attempt = 0; attempt <= config.max_refits; ++attempt) {
    rep.refits = attempt;
    const auto samples = UniformBspline::resamplePolyline(points, spacing);
    const double dt = duration / static_cast<double>(std::max<std::size_t>(1, samples.size() - 1));
    const UniformBspline init = UniformBspline::fitPath(samples, dt, request.velocity, Vec3::Zero());
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
    spacing = std::max(0.5 * astar.geometry().resolution(), 0.5 * spacing);
  }
  if (!spline) return R::Error("optimisation failed: " + spline.message());
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
  auto yaw = yawTurn(request.yaw, target_yaw, 0.0, optimizer);
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

Trajectory stopTrajectory(const Vec3& p, const Vec3& v, double yaw, const OptimizerConfig& optimizer) {
  Trajectory out;
  out.position = safeStop(p, v, optimizer.a_max);
  out.goal = out.position.position(out.position.duration());
  auto y = yawTurn(yaw, yaw, out.position.duration(), optimizer);
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

namespace {

/// Brake to a stop where the reference is while turning to `yaw`; at rest, hold still for as long as
/// the turn takes (the replanning rule goes by the position's duration). Moving: the next plan comes
/// from wherever the braking has got to. Partial, with the target as goal.
Trajectory turnTowards(const PlanRequest& request, double yaw, const OptimizerConfig& optimizer) {
  Trajectory out;
  out.position = safeStop(request.start, request.velocity, optimizer.a_max);
  auto turn = yawTurn(request.yaw, yaw, out.position.duration(), optimizer);
  out.yaw = turn ? std::move(turn).value() : UniformBspline(Eigen::MatrixXd::Constant(1, 4, request.yaw), 3, 0.1);
  if (request.velocity.norm() < 1e-9) out.position = UniformBspline(request.start.replicate(1, 4), 3, out.yaw.duration());
  out.goal = request.target;
  out.partial = true;
  return out;
}

}  // namespace

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
                                   double resolution, bool* looked_at_unseen) {
  RecoveryPlan out;
  if (startEnclosed(report, config, resolution)) {
    out.kind = Recovery::kLookAround;
    out.trajectory = lookAroundTrajectory(request, config, optimizer);
    return out;
  }
  if (!*looked_at_unseen) {
    if (auto look = lookAtUnseen(request, report, config, optimizer)) {
      *looked_at_unseen = true;
      out.kind = Recovery::kLookAtUnseen;
      out.trajectory = std::move(*look);
      return out;
    }
  }
  out.kind = Recovery::kFail;
  out.trajectory = stopTrajectory(request.start, request.velocity, request.yaw, optimizer);
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
        firstCollisionTime(current->position, std::max(0.0, t), esdf, optimizer.min_clearance, config.collision_horizon);
  }
  const ReplanReason reason = shouldReplan(in, replan);
  // A trajectory that ends at its target needs no replanning for running out: it arrives.
  const bool ends_at_target = current && !current->partial && in.target_distance_to_end <= replan.target_tolerance;
  if (ends_at_target && reason == ReplanReason::kShortTimeLeft) return ReplanReason::kNone;
  return reason;
}

}  // namespace go_feap::trajectory
