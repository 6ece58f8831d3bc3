#include "go_feap/bench/exploration_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "go_feap/common/config_groups.h"
#include "go_feap/common/machine.h"
#include "go_feap/common/transform.h"
#include "go_feap/common/yaml_reader.h"

namespace go_feap::bench {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

bool positiveFinite(double v) { return std::isfinite(v) && v > 0.0; }

// The rendered images' intrinsics, as the mapper takes them.
map::DepthIntrinsics depthIntrinsics(const sim::DepthCameraConfig& camera) {
  const auto K = camera.intrinsics();
  return {K.width, K.height, K.fx, K.fy, K.cx, K.cy};
}

}  // namespace

common::Status LoopConfig::validate() const {
  // Rates in (0, 1000] Hz, as the nodelets' timers: 1e12 Hz made steps of a picosecond, a run that never ends.
  auto rate = [](double r) { return positiveFinite(r) && r <= 1000.0; };
  // Named by the keys they are read from (bench.yaml, exploration.yaml).
  if (!rate(control_rate)) return common::Status::Error("loop: control_rate must be in (0, 1000] Hz");
  if (!rate(plan_rate)) return common::Status::Error("global: rate must be in (0, 1000] Hz");
  if (!rate(sample_rate)) return common::Status::Error("metrics: sample_rate must be in (0, 1000] Hz");
  if (!metrics::CollisionMonitor::validDistance(collision_distance))
    return common::Status::Error("metrics: collision_distance must be in (0, 0.5] m");
  return common::Status::Ok();
}

common::Status ExplorationConfig::validate() const {
  for (const common::Status& st :
       {quadrotor.validate(), controller.validate(), camera.validate(), map.validate(), frontier.validate(),
        global.validate(), distance_astar.validate(map.esdf), layers.validate(), viewpoints.validate(map.esdf),
        local.validate(), optimizer.validate(map.esdf), replan.validate(), planner.validate(map.occupancy),
        flight_astar.validate(map.esdf), scout_astar.validate(map.esdf), coarse_astar.validate(map.esdf),
        loop.validate()})
    if (!st.ok()) return st;
  if (!positiveFinite(camera_rate) || camera_rate > 100.0)
    return common::Status::Error("depth_camera: rate must be in (0, 100] Hz");
  // (0, 1000] Hz as the nodelets' timers: at 0.02 Hz the run's end guard, two layer steps past
  // max_sim_time, let a 2 s run fly 50 s.
  if (!positiveFinite(layer_rate) || layer_rate > 1000.0)
    return common::Status::Error("layers: rate must be in (0, 1000] Hz");
  if (!positiveFinite(planner_rate) || planner_rate > 1000.0)
    return common::Status::Error("planner: rate must be in (0, 1000] Hz");
  if (!common::isCameraMount(T_B_C.matrix()))
    return common::Status::Error("depth_camera: T_B_C must be a finite rigid transform with a translation of at most " +
                                 std::to_string(common::kMaxMountOffset) + " m (a camera on the vehicle; metres, not millimetres)");
  // The mapper takes rays within 85 degrees of the optical axis: a wider camera (an hfov_deg of 175) passed
  // the camera's own check and then had every frame refused, a run that mapped nothing without a word.
  if (const common::Status st = depthIntrinsics(camera).validate(); !st.ok())
    return common::Status::Error("depth_camera: hfov_deg and vfov_deg (or fx, fy, cx, cy) are too wide for the "
                                 "mapper: " + st.message());
  // The camera renders nothing in its range as +inf, which the mapper casts free up to its own range: a
  // mapper reaching farther would clear the walls between the two ranges.
  if (!(map.occupancy.max_range <= camera.max_range))
    return common::Status::Error("occupancy: max_range must not exceed depth_camera: max_range (" +
                                 std::to_string(camera.max_range) + " m): beyond it the camera's 'nothing in range' "
                                 "would be cast free through walls");
  // The viewpoints' sensor model must fit the camera and the mapper: a wider or longer one scores viewpoints on
  // frontier cells the map will not take from there, flights that clear nothing, retried until blacklisted.
  for (const common::Status& st : {viewpoints.fitsMapper(map.occupancy), viewpoints.fitsCamera(depthIntrinsics(camera))})
    if (!st.ok()) return st;
  // Each stage runs at most once a control step: a faster one ran at the control rate without a word.
  for (const auto& [key, r] : {std::make_pair("depth_camera: rate", camera_rate), std::make_pair("global: rate", loop.plan_rate),
                               std::make_pair("planner: rate", planner_rate), std::make_pair("layers: rate", layer_rate),
                               std::make_pair("metrics: sample_rate", loop.sample_rate)})
    if (r > loop.control_rate)
      return common::Status::Error(std::string(key) + " must be at most loop: control_rate (" +
                                   std::to_string(loop.control_rate) + " Hz) in go_feap_bench: each stage runs at most once a control step");
  return common::Status::Ok();
}

common::Result<ExplorationConfig> loadExplorationConfig(const std::string& config_dir, const std::string& planner) {
  using R = common::Result<ExplorationConfig>;
  const std::string mode = config_dir + "/modes/" + planner + ".yaml";
  if (!std::filesystem::exists(mode))
    return R::Error("unknown planner '" + planner + "' (no " + mode + "; modes: go_feap, fuel, nearest)");
  ExplorationConfig c;
  common::YamlReader sim(config_dir + "/sim.yaml");
  config::readQuadrotor(sim, c.quadrotor);
  config::readController(sim, c.controller);
  config::readDepthCamera(sim, c.camera);
  Eigen::Matrix4d T_B_C = Eigen::Matrix4d::Identity();
  sim.get("depth_camera/rate", c.camera_rate).getMatrix4("depth_camera/T_B_C", T_B_C);
  if (!sim.ok()) return sim.status();
  if (!T_B_C.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1)))
    return R::Error(config_dir + "/sim.yaml: parameter 'depth_camera/T_B_C' must end with the row 0 0 0 1");
  c.T_B_C.matrix() = T_B_C;
  common::YamlReader mapping(config_dir + "/mapping.yaml");
  config::readMap(mapping, c.map);
  if (!mapping.ok()) return mapping.status();
  // The runs of every mode are measured alike: a mode file setting metrics/* would compare planners
  // under different collision or sampling rules in one table (and, through the ROS chain, its layer
  // manager would read a metrics/max_odom_step that the metrics recorder, which loads no mode, does not).
  if (common::YamlReader(mode).has("metrics"))
    return R::Error(mode + ": a planner mode must not set 'metrics/*' (every mode is measured alike)");
  common::YamlReader exploration({config_dir + "/exploration.yaml", mode});
  config::readFrontier(exploration, c.frontier);
  config::readGlobalPlanner(exploration, c.global);
  exploration.get("global/rate", c.loop.plan_rate);
  config::readAstar(exploration, c.distance_astar, "distance_astar");
  config::readLayers(exploration, c.layers);
  exploration.get("layers/rate", c.layer_rate);
  config::readViewpoints(exploration, c.viewpoints);
  config::readLocal(exploration, c.local);
  exploration.get("metrics/sample_rate", c.loop.sample_rate).get("metrics/collision_distance", c.loop.collision_distance);
  if (!exploration.ok()) return exploration.status();
  common::YamlReader traj({config_dir + "/trajectory.yaml", mode});
  config::readOptimizer(traj, c.optimizer);
  config::readReplan(traj, c.replan);
  config::readTrajectoryPlanner(traj, c.planner);
  traj.get("planner/rate", c.planner_rate);
  config::readAstar(traj, c.flight_astar);
  config::readAstar(traj, c.scout_astar, "scout_astar");
  config::readAstar(traj, c.coarse_astar, "coarse_astar");
  if (!traj.ok()) return traj.status();
  common::YamlReader bench(config_dir + "/bench.yaml");
  bench.get("loop/control_rate", c.loop.control_rate);
  if (!bench.ok()) return bench.status();
  const common::Status st = c.validate();
  if (!st.ok()) return st;
  return c;
}

ExplorationRun::ExplorationRun(const world::Scene& scene, const ExplorationConfig& config, const std::string& planner,
                               double max_sim_time)
    : scene_(scene),
      config_(config),
      max_sim_time_(max_sim_time),
      vehicle_(config.quadrotor, config.controller),
      renderer_(config.camera, scene),
      noise_rng_(scene.seed),
      window_(config.local),
      collisions_(scene, config.loop.collision_distance) {
  for (const common::Status& st : {config.validate(), world::validateScene(scene),
                                   metrics::checkStartClearance(scene, config.loop.collision_distance)})
    if (!st.ok()) throw std::invalid_argument(st.message());
  if (!positiveFinite(max_sim_time)) throw std::invalid_argument("max_sim_time must be finite and > 0");
  intrinsics_ = depthIntrinsics(config.camera);
  if (const common::Status fits = config.map.checkFits(scene.box, common::physicalMemoryBytes()); !fits.ok())
    throw std::invalid_argument(fits.message());
  map_ = std::make_unique<map::VoxelMap>(config.map, scene.box);
  finder_ = std::make_unique<frontier::FrontierFinder>(config.frontier, map_->geometry(), scene.box);
  distance_astar_ = std::make_unique<planning::Astar>(map_->occupancy(), map_->esdf(), config.distance_astar);
  flight_astar_ = std::make_unique<planning::Astar>(map_->occupancy(), map_->esdf(), config.flight_astar);
  scout_astar_ = std::make_unique<planning::Astar>(map_->occupancy(), map_->esdf(), config.scout_astar);
  coarse_astar_ = std::make_unique<planning::Astar>(map_->occupancy(), map_->esdf(), config.coarse_astar);
  tour_planner_ = std::make_unique<planning::TourPlanner>(config.global, *distance_astar_);
  // The run's simulated-time budget is the exploration's time limit (layers/time_limit is the ROS chain's).
  planning::LayerManagerConfig layers = config.layers;
  layers.time_limit = max_sim_time;
  layers_ = std::make_unique<planning::LayerManager>(layers, scene.box, scene.start.position.z());
  coverage_ = std::make_unique<metrics::CoverageTracker>(scene, map_->geometry());
  coverage_->reset(map_->occupancy());
  vehicle_.reset(scene.start.position, scene.start.yaw);
  hold_position_ = last_position_ = scene.start.position;
  hold_yaw_ = scene.start.yaw;
  metrics::Summary& s = recorder_.summary();
  s.scene = scene.name;
  s.seed = scene.seed;
  s.planner = planner;
  collisions_.update(scene.start.position);
  s.min_obstacle_distance_m = collisions_.closestApproach();
}

ExplorationRun::~ExplorationRun() = default;

double ExplorationRun::yaw() const { return vehicle_.state().heading(); }

void ExplorationRun::log(const std::string& what) {
  std::ostringstream line;
  line << std::fixed << std::setprecision(2) << t_ << " " << what;
  events_.push_back(line.str());
}

Progress ExplorationRun::progress() const {
  Progress p;
  p.t = t_;
  p.coverage = coverage_now_;
  p.distance = distance_;
  p.state = layer_out_.state;
  p.band = layer_out_.band.index;
  p.frontiers = static_cast<int>(finder_->frontiers().size());
  return p;
}

void ExplorationRun::frame() {
  const sim::QuadrotorState& s = vehicle_.state();
  Eigen::Isometry3d T_W_B = Eigen::Isometry3d::Identity();
  T_W_B.linear() = s.attitude.toRotationMatrix();
  T_W_B.translation() = s.position;
  const Eigen::Isometry3d T_W_C = T_W_B * config_.T_B_C;
  renderer_.render(T_W_C, depth_);
  if (config_.camera.noise_stddev_per_m > 0.0 || config_.camera.dropout_probability > 0.0)
    renderer_.addNoise(depth_, noise_rng_);  // as the DepthCamera nodelet does
  if (const auto ratio = planning::obstacleRatio(depth_, config_.local.max_range)) window_.push(*ratio);
  auto t0 = Clock::now();
  auto update = map_->integrate(depth_, intrinsics_, T_W_C);
  recorder_.addTime("mapping", msSince(t0));
  if (!update) return;  // cannot happen with the renderer's own images; skipped like the nodelet would
  if (update->frame.any_change) {
    ++map_progress_;
    coverage_->update(map_->occupancy(), update->frame.changed);
    t0 = Clock::now();
    finder_->update(map_->occupancy(), update->frame.changed, t_);
    // The viewpoints cached for frontiers the change reaches go too (timed with the frontier block: it is
    // done per map update, as the frontiers are; a "local" sample per frame would dilute that block's mean).
    viewpoint_cache_.forgetChanged(map_->occupancy().geometry(), update->frame.changed);
    recorder_.addTime("frontier", msSince(t0));
  }
}

void ExplorationRun::layerStep() {
  planning::LayerInputs in;
  in.trigger = !triggered_;
  triggered_ = true;
  in.failed.swap(failed_);
  in.map_progress = map_progress_;
  in.yaw = yaw();
  in.position = vehicle_.state().position;
  for (const frontier::Frontier& f : finder_->frontiers()) in.listFrontier(f.id, f.average.z(), layer_out_.band);
  const planning::Band before = layer_out_.band;
  layer_out_ = layers_->step(in, t_);
  for (const planning::Transition& tr : layer_out_.transitions)
    log(std::string(planning::toString(tr.from)) + "(" + std::to_string(tr.band_from) + ") -> " +
        planning::toString(tr.to) + "(" + std::to_string(tr.band_to) + "): " + tr.why);
  if (layer_out_.band.z_min != before.z_min || layer_out_.band.z_max != before.z_max || !layer_out_.transitions.empty())
    finder_->setActiveBand(layer_out_.band.z_min, layer_out_.band.z_max);
  if (layer_out_.state == planning::ExplorationState::kFinished) finish(planning::toString(layer_out_.reason));
}

void ExplorationRun::planStep() {
  if (layer_out_.state != planning::ExplorationState::kExplore &&
      layer_out_.state != planning::ExplorationState::kFinalPass)
    return;
  const common::Vec3 position = vehicle_.state().position;
  auto idle = [&] {
    return !target_ || planning::targetReached(position, yaw(), vehicle_.state().velocity.norm(),
                                               {target_->position, target_->yaw, 0}, config_.local);
  };
  auto turnInPlace = [&](const std::string& why) {
    const frontier::Viewpoint scan = planning::scanTarget(position, yaw(), config_.local);
    log(why);
    target_ = Target{scan.position, scan.yaw, 0, t_};
    target_changed_ = true;
  };
  if (layer_out_.look_around) {
    // No frontier where the camera has looked, and it has not looked round yet.
    if (idle()) turnInPlace("no frontier in view before a look round: turning in place");
    return;
  }
  std::optional<planning::CurrentTarget> current;
  if (target_)
    current = planning::assessTarget(
        {target_->position, target_->yaw, 0}, target_->committed_at, position, yaw(),
        vehicle_.state().velocity.norm(), planning::tiltOf(vehicle_.state().attitude), finder_->frontiers(),
        map_->occupancy(), config_.viewpoints, config_.frontier.max_cluster_extent, config_.local);
  if (current) current->quicker = target_->quicker;
  if (!planning::planDue(current ? &*current : nullptr, t_, last_tour_time_, config_.viewpoints.min_visible,
                         config_.local))
    return;
  last_tour_time_ = t_;
  std::vector<planning::FrontierSummary> summaries;
  for (const frontier::Frontier& f : finder_->frontiers())
    if (!layers_->isBlacklisted(f.id)) summaries.push_back(planning::summarize(f, t_));
  auto t0 = Clock::now();
  auto tour = tour_planner_->plan(summaries, position, t_);
  recorder_.addTime("global", msSince(t0));
  if (!tour || tour->frontier_ids.empty()) {
    if (!tour) log("no tour: " + tour.message());
    return;
  }
  std::vector<std::uint32_t> ids;
  for (const frontier::Frontier& f : finder_->frontiers()) ids.push_back(f.id);
  viewpoint_cache_.retain(ids);
  std::vector<frontier::Frontier> ordered;
  for (unsigned id : tour->frontier_ids)
    if (const frontier::Frontier* f = finder_->find(id)) ordered.push_back(*f);
  t0 = Clock::now();
  const common::Vec3 velocity = vehicle_.state().velocity;
  auto plan = planning::chooseLocalTarget(position, velocity, yaw(), std::move(ordered), layer_out_.band.z_min,
                                          layer_out_.band.z_max, map_->occupancy(), map_->esdf(), *distance_astar_,
                                          window_, config_.viewpoints, config_.local, &viewpoint_cache_, &visited_);
  recorder_.addTime("local", msSince(t0));
  if (!plan) {
    // Nothing to fly to: look around, unless already flying somewhere or turning.
    if (idle()) {
      // Each look around is a failed attempt for the tour's frontiers (none had a viewpoint): a frontier
      // that stays unchanged through max_retries of them is blacklisted instead of scanned for ever.
      failed_.insert(failed_.end(), tour->frontier_ids.begin(), tour->frontier_ids.end());
      turnInPlace("no local plan (" + plan.message() + "): turning in place to look around");
    }
    return;
  }
  const frontier::Viewpoint& vp = plan->path.front();
  const double heading = yaw();
  const planning::TargetStep step = planning::stepTarget(
      current ? &*current : nullptr, vp,
      [&](const frontier::Viewpoint& v) { return planning::pathCost(*distance_astar_, position, velocity, heading, v, config_.local); },
      t_, config_.viewpoints.min_visible, config_.local, visited_);
  const planning::TargetDecision decision = step.decision;
  if (decision == planning::TargetDecision::kKeep) return;
  if (decision == planning::TargetDecision::kReachedInVain) {
    // The frontier the same target is proposed for now (the target's own may have been regrown under a new id).
    const std::uint32_t frontier = plan->frontier_ids.front();
    log("frontier " + std::to_string(frontier) + " not cleared from its reached viewpoint: failed attempt");
    failed_.push_back(frontier);
    target_.reset();
    return;
  }
  // A new target, however near the last one, is flown to exactly (the nodelets number their targets
  // alike): the local planner judges it reached by its own pose.
  target_changed_ = true;
  std::ostringstream what;
  what << "target frontier " << plan->frontier_ids.front() << " viewpoint " << vp.position.transpose() << " yaw "
       << vp.yaw << " (tour of " << tour->frontier_ids.size() << ", " << summaries.size() << " frontiers)";
  log(what.str());
  if (step.exhausted) {
    std::ostringstream exhausted;
    exhausted << "this target's place was chosen " << config_.local.max_choices << " times within "
              << config_.local.choice_window << " s: it is not proposed again";
    log(exhausted.str());
  }
  target_ = Target{vp.position, vp.yaw, plan->frontier_ids.front(), t_,
                   decision == planning::TargetDecision::kSwitchQuicker};
}

void ExplorationRun::trajectoryStep() {
  if (!target_ || t_ - last_plan_ < config_.planner.min_time_between_plans) return;
  const trajectory::Trajectory* current = trajectory_ ? &*trajectory_ : nullptr;
  const trajectory::ReplanReason reason =
      trajectory::replanReason(current, t_ - trajectory_start_, target_->position, target_changed_, map_->esdf(),
                               config_.replan, config_.optimizer, config_.planner);
  if (reason == trajectory::ReplanReason::kNone) return;
  target_changed_ = false;
  last_plan_ = t_;
  // Start from the reference being flown (continuity), as the nodelet starts from the last command.
  trajectory::PlanRequest request;
  if (trajectory_) {
    const trajectory::TrajectorySample s = trajectory::sampleTrajectory(*trajectory_, t_ - trajectory_start_);
    request.start = s.position, request.velocity = s.velocity, request.yaw = s.yaw, request.yaw_rate = s.yaw_dot;
    request.acceleration = s.acceleration;
  } else {
    request.start = hold_position_, request.yaw = hold_yaw_;
  }
  request.target = target_->position;
  request.target_yaw = target_->yaw;
  request.time = t_;
  const auto t0 = Clock::now();
  trajectory::FlightStep step =
      trajectory::planForTarget(request, &target_->attempts, *flight_astar_, map_->esdf(), config_.optimizer,
                                config_.planner, &search_memory_, scout_astar_.get(), coarse_astar_.get());
  recorder_.addTime("trajectory", msSince(t0));
  trajectory_start_ = t_;
  const trajectory::PlanReport& report = step.report;
  const std::string frontier = std::to_string(target_->frontier);
  switch (step.outcome) {
    case trajectory::FlightOutcome::kFly:
      if (step.newly_widened)
        log("every trajectory along the way to frontier " + frontier +
            " came too near unseen space: flying a way that keeps it away all round");
      if (report.braked)
        log("no flyable trajectory to frontier " + frontier + " from " + std::to_string(request.velocity.norm()) +
            " m/s: braking to plan again from rest");
      if (report.coarse)
        log("flight search to frontier " + frontier + " over budget: coarse path of " +
            std::to_string(report.path_length) + " m");
      if (report.scouted)
        log("no known path to frontier " + frontier + ": scouting " +
            std::to_string((step.trajectory.position.position(step.trajectory.duration()) - request.start).norm()) +
            " m along a way through unseen space");
      break;
    case trajectory::FlightOutcome::kScoutedTooOften:
      log("frontier " + frontier + " scouted " + std::to_string(target_->attempts.scouts) +
          " times without a known path: stopping, a failed attempt");
      break;
    case trajectory::FlightOutcome::kLookAround:
    case trajectory::FlightOutcome::kLookAtUnseen:
    case trajectory::FlightOutcome::kFail:
      log(std::string("plan to frontier ") + frontier + " failed (" + trajectory::toString(reason) +
          "): " + step.failure);
      if (step.outcome == trajectory::FlightOutcome::kLookAround) {
        log("the start region cannot be left (" + std::to_string(report.path_expansions) +
            " voxels reachable): looking around");
      } else if (step.outcome == trajectory::FlightOutcome::kLookAtUnseen) {
        std::ostringstream what;
        what << "the way to frontier " << frontier << " leads through unseen space at ("
             << report.unseen_at->transpose() << "): looking there";
        log(what.str());
      }
      break;
  }
  if (step.failsTarget()) {
    failed_.push_back(target_->frontier);
    target_.reset();
  }
  trajectory_ = std::move(step.trajectory);
}

void ExplorationRun::sample() {
  coverage_now_ = coverage_->current();
  if (!vehicle_.state().finite()) return;  // diverged: the series ends at the last state that was
  metrics::Sample s;
  s.t = t_;
  s.coverage = coverage_now_;
  const double res = map_->geometry().resolution();
  s.explored_m3 = static_cast<double>(map_->occupancy().knownCount()) * res * res * res;
  s.distance = distance_;
  s.layer = layer_out_.band.index;
  s.frontiers = static_cast<int>(finder_->frontiers().size());
  s.position = vehicle_.state().position;
  recorder_.addSample(s);
}

void ExplorationRun::finish(const std::string& reason) {
  if (ended_) return;
  ended_ = true;
  sample();
  metrics::Summary& s = recorder_.summary();
  s.finish_reason = reason;
  s.blacklisted_frontiers = static_cast<int>(layer_out_.blacklisted_left);
  s.exploration_time_s = t_;
  s.flight_distance_m = distance_;
  s.coverage = coverage_now_;
  s.extra["map_memory_mb"] = static_cast<double>(map_->memoryBytes()) / (1024.0 * 1024.0);
}

bool ExplorationRun::step() {
  if (ended_) return false;
  const double dt = 1.0 / config_.loop.control_rate;
  if (t_ >= next_layer_) {
    layerStep();
    next_layer_ += 1.0 / config_.layer_rate;
    if (ended_) return false;
  }
  if (t_ >= next_frame_) {
    frame();
    next_frame_ += 1.0 / config_.camera_rate;
  }
  if (t_ >= next_plan_) {
    planStep();
    next_plan_ += 1.0 / config_.loop.plan_rate;
  }
  if (t_ >= next_replan_) {
    trajectoryStep();
    next_replan_ += 1.0 / config_.planner_rate;
  }
  if (t_ >= next_sample_) {
    sample();
    next_sample_ += 1.0 / config_.loop.sample_rate;
  }
  sim::PositionReference ref;
  if (trajectory_) {
    const trajectory::TrajectorySample s = trajectory::sampleTrajectory(*trajectory_, t_ - trajectory_start_);
    ref.position = s.position, ref.velocity = s.velocity, ref.acceleration = s.acceleration;
    ref.yaw = s.yaw, ref.yaw_dot = s.yaw_dot;
    hold_position_ = s.position, hold_yaw_ = s.yaw;
  } else {
    ref.position = hold_position_, ref.yaw = hold_yaw_;
  }
  vehicle_.advance(dt, ref);
  ++tick_;
  t_ = static_cast<double>(tick_) * dt;
  if (!vehicle_.state().finite()) {  // the run ends here, not the process (it rendered from a NaN pose)
    log("the simulated vehicle's state is not finite: the dynamics diverged");
    finish("diverged");
    return false;
  }
  const common::Vec3 p = vehicle_.state().position;
  distance_ += (p - last_position_).norm();
  last_position_ = p;
  if (collisions_.update(p)) {
    std::ostringstream what;
    what << "collision at " << p.transpose() << " (" << collisions_.lastClearance() << " m from ground truth)";
    log(what.str());
  }
  metrics::Summary& s = recorder_.summary();
  s.collisions = collisions_.collisions();
  s.min_obstacle_distance_m = collisions_.closestApproach();
  // The layer manager ends the run at its time limit (max_sim_time) on its next step; this only guards
  // against a state machine that would not, or one stepped so seldom that its next step is far off
  // (at layers/rate 0.02 Hz a 2 s run flew 50 s).
  if (t_ >= max_sim_time_ + std::min(1.0, 2.0 / config_.layer_rate)) finish("max_sim_time");
  return !ended_;
}

void ExplorationRun::run(const std::function<void(const Progress&)>& progress, const std::atomic<bool>* interrupt) {
  const auto t0 = Clock::now();
  double next_report = 0.0;
  while (step()) {
    if (interrupt && interrupt->load(std::memory_order_relaxed)) {
      log("interrupted");
      finish("interrupted");
      break;
    }
    if (progress && t_ >= next_report) {
      progress(this->progress());
      next_report += 1.0;
    }
  }
  if (progress) progress(this->progress());
  recorder_.summary().wall_time_s = msSince(t0) / 1000.0;
}

}  // namespace go_feap::bench
