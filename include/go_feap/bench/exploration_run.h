// The closed exploration loop in simulated lock-step time (DESIGN §1, §3.9): the same core
// classes the nodelets wrap, stepped deterministically as fast as the CPU allows: dynamics and
// controller, depth camera, mapping, frontiers, global tour, local viewpoint, trajectory,
// altitude-layer manager and metrics. Same scene, configuration and seed: same result.
#pragma once

#include <Eigen/Geometry>
#include <atomic>
#include <functional>
#include <memory>
#include <random>
#include <optional>
#include <string>

#include "go_feap/common/result.h"
#include "go_feap/frontier/frontier_finder.h"
#include "go_feap/map/voxel_map.h"
#include "go_feap/metrics/metrics.h"
#include "go_feap/planning/astar.h"
#include "go_feap/planning/global_planner.h"
#include "go_feap/planning/layer_manager.h"
#include "go_feap/planning/local_planner.h"
#include "go_feap/planning/tour_planner.h"
#include "go_feap/planning/viewpoints.h"
#include "go_feap/sim/depth_camera.h"
#include "go_feap/sim/vehicle.h"
#include "go_feap/trajectory/trajectory_planner.h"
#include "go_feap/world/scene.h"

namespace go_feap::bench {

/// Rates of the lock-step loop (config/bench.yaml) and the metrics' sample rate and collision criterion
/// (exploration.yaml metrics/).
struct LoopConfig {
  double control_rate = 100.0;      ///< Hz: position commands (the controller runs at the dynamics rate)
  double plan_rate = 5.0;           ///< Hz: global tour and local viewpoint (exploration.yaml global/rate)
  double sample_rate = 2.0;         ///< Hz: metrics.csv rows
  double collision_distance = 0.1;  ///< m: the UAV centre closer than this to ground truth is a collision
  common::Status validate() const;
};

/// Everything a run needs, read from config/*.yaml (the same keys the nodelets read).
struct ExplorationConfig {
  sim::QuadrotorParams quadrotor;
  sim::So3ControllerConfig controller;
  sim::DepthCameraConfig camera;
  double camera_rate = 15.0;  ///< Hz
  Eigen::Isometry3d T_B_C = Eigen::Isometry3d::Identity();
  map::MapConfig map;
  frontier::FrontierConfig frontier;
  planning::GlobalPlannerConfig global;
  planning::AstarConfig distance_astar;  ///< exploration.yaml distance_astar: path lengths for the tour
  planning::LayerManagerConfig layers;
  double layer_rate = 5.0;  ///< Hz
  planning::ViewpointConfig viewpoints;
  planning::LocalPlannerConfig local;
  trajectory::OptimizerConfig optimizer;
  trajectory::ReplanConfig replan;
  trajectory::TrajectoryPlannerConfig planner;
  double planner_rate = 10.0;          ///< Hz: replanning checks
  planning::AstarConfig flight_astar;  ///< trajectory.yaml astar: paths to fly
  planning::AstarConfig scout_astar;   ///< trajectory.yaml scout_astar: the way on through unseen space
  planning::AstarConfig coarse_astar;  ///< trajectory.yaml coarse_astar: the flight search on a coarse lattice
  LoopConfig loop;
  /// Every group's validate(), plus the rates and the extrinsic; names the bad key.
  common::Status validate() const;
};

/// Reads sim.yaml, mapping.yaml, exploration.yaml, trajectory.yaml and bench.yaml from `config_dir`,
/// with modes/<planner>.yaml laid over exploration.yaml and trajectory.yaml (planner modes are
/// parameter sets: go_feap, fuel, nearest). Errors name the file and key, or the unknown mode.
common::Result<ExplorationConfig> loadExplorationConfig(const std::string& config_dir, const std::string& planner);

/// What a progress callback sees.
struct Progress {
  double t = 0.0;  ///< simulated s
  double coverage = 0.0;
  double distance = 0.0;
  planning::ExplorationState state = planning::ExplorationState::kWaitTrigger;
  int band = 0;
  int frontiers = 0;
};

class ExplorationRun {
 public:
  /// The scene must pass world::validateScene; the config must validate (throws std::invalid_argument
  /// otherwise, with the message). The run starts hovering at the scene's start and is triggered at t = 0.
  /// max_sim_time (s) is the exploration's time limit: it replaces config.layers.time_limit.
  ExplorationRun(const world::Scene& scene, const ExplorationConfig& config, const std::string& planner,
                 double max_sim_time);
  ~ExplorationRun();

  /// Advances one control period. False once the run has ended (FINISHED or max_sim_time).
  bool step();
  /// Steps to the end; calls `progress` about once per simulated second. Fills the summary. When
  /// `interrupt` is given and becomes true (go_feap_bench sets it on SIGINT/SIGTERM), the run ends at
  /// its next step as it stands, finish reason "interrupted": what was explored so far is kept.
  void run(const std::function<void(const Progress&)>& progress = {}, const std::atomic<bool>* interrupt = nullptr);

  double time() const { return t_; }
  bool ended() const { return ended_; }
  Progress progress() const;
  const metrics::Recorder& recorder() const { return recorder_; }
  const map::VoxelMap& map() const { return *map_; }
  const sim::SimulatedVehicle& vehicle() const { return vehicle_; }
  /// What happened, one line each with the simulated time: state transitions, new targets, failed
  /// plans, collisions (the bench writes them to events.log).
  const std::vector<std::string>& events() const { return events_; }

 private:
  void frame();
  void layerStep();
  void planStep();
  void trajectoryStep();
  void sample();
  void finish(const std::string& reason);
  double yaw() const;
  void log(const std::string& what);

  const world::Scene& scene_;
  ExplorationConfig config_;
  double max_sim_time_;
  sim::SimulatedVehicle vehicle_;
  sim::DepthRenderer renderer_;
  std::mt19937_64 noise_rng_;  ///< the camera's noise and dropout (DepthRenderer::addNoise), seeded by the scene's seed
  map::DepthIntrinsics intrinsics_;
  std::unique_ptr<map::VoxelMap> map_;
  std::unique_ptr<frontier::FrontierFinder> finder_;
  std::unique_ptr<planning::Astar> distance_astar_, flight_astar_, scout_astar_, coarse_astar_;
  std::unique_ptr<planning::TourPlanner> tour_planner_;
  planning::ObstacleWindow window_;
  planning::ViewpointCache viewpoint_cache_;
  std::unique_ptr<planning::LayerManager> layers_;
  std::unique_ptr<metrics::CoverageTracker> coverage_;
  metrics::Recorder recorder_;
  metrics::CollisionMonitor collisions_;

  std::uint64_t tick_ = 0;
  double t_ = 0.0;
  double next_frame_ = 0.0, next_layer_ = 0.0, next_plan_ = 0.0, next_replan_ = 0.0, next_sample_ = 0.0;
  bool ended_ = false, triggered_ = false;
  planning::LayerOutputs layer_out_;
  std::uint64_t map_progress_ = 0;
  std::vector<std::uint32_t> failed_;

  struct Target {
    common::Vec3 position;
    double yaw;
    std::uint32_t frontier;
    double committed_at;
    bool quicker = false;  ///< won on cost (planning::CurrentTarget::quicker)
    trajectory::TargetAttempts attempts{};  ///< looks, widened plans and scouts for it (planForTarget())
  };
  std::optional<Target> target_;
  planning::VisitedViewpoints visited_;
  bool target_changed_ = false;
  std::optional<trajectory::Trajectory> trajectory_;
  trajectory::SearchMemory search_memory_;  ///< flight searches that found no path lately
  double trajectory_start_ = 0.0, last_plan_ = -1e9;
  double last_tour_time_ = -1e9;  ///< s, when planStep() last planned a tour (planning::planDue())
  common::Vec3 hold_position_;
  double hold_yaw_ = 0.0;
  cv::Mat depth_;

  common::Vec3 last_position_;
  double distance_ = 0.0;
  double coverage_now_ = 0.0;
  std::vector<std::string> events_;
};

}  // namespace go_feap::bench
