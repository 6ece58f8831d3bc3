// The keys of every parameter group in config/*.yaml, in one place. Each function reads one group
// through any reader with the ParamReader interface: `get(key, T&)`, `getVec3(key, Vector3d&)` and
// `getMatrix4(key, Matrix4d&)`, recording the first missing or mistyped key. The nodelets read with
// ros_params::ParamReader (ROS parameter server), go_feap_bench with common::YamlReader (the same
// YAML files), so both run with the same values and the same names in their messages.
#pragma once

#include <string>

#include "go_feap/frontier/frontier_finder.h"
#include "go_feap/map/voxel_map.h"
#include "go_feap/planning/astar.h"
#include "go_feap/planning/global_planner.h"
#include "go_feap/planning/layer_manager.h"
#include "go_feap/planning/local_planner.h"
#include "go_feap/planning/viewpoints.h"
#include "go_feap/sim/depth_camera.h"
#include "go_feap/sim/quadrotor.h"
#include "go_feap/sim/so3_controller.h"
#include "go_feap/trajectory/trajectory_planner.h"

namespace go_feap::config {

/// exploration_box/min and exploration_box/max (m, world frame).
template <class R>
void readBox(R& p, common::Aabb& box) {
  p.getVec3("exploration_box/min", box.min).getVec3("exploration_box/max", box.max);
}

template <class R>
void readOccupancy(R& p, map::OccupancyConfig& o) {
  p.get("occupancy/resolution", o.resolution).get("occupancy/margin", o.margin);
  p.get("occupancy/p_hit", o.p_hit).get("occupancy/p_miss", o.p_miss).get("occupancy/p_min", o.p_min);
  p.get("occupancy/p_max", o.p_max).get("occupancy/p_occupied", o.p_occupied);
  p.get("occupancy/min_range", o.min_range).get("occupancy/max_range", o.max_range);
  p.get("occupancy/skip_pixel", o.skip_pixel).get("occupancy/invalid_as_free", o.invalid_as_free);
  p.get("occupancy/max_plausible_depth", o.max_plausible_depth);
}

template <class R>
void readMap(R& p, map::MapConfig& c) {
  readOccupancy(p, c.occupancy);
  p.get("esdf/max_distance", c.esdf.max_distance);
}

template <class R>
void readFrontier(R& p, frontier::FrontierConfig& c) {
  p.get("frontier/min_cluster_cells", c.min_cluster_cells).get("frontier/max_cluster_extent", c.max_cluster_extent);
  p.get("frontier/max_regrow_cells", c.max_regrow_cells).get("frontier/revive_factor", c.revive_factor);
  p.get("frontier/s_near", c.s_near);
}

template <class R>
void readOmission(R& p, planning::OmissionConfig& c) {
  p.get("omission/alpha_max", c.alpha_max).get("omission/c_small", c.c_small).get("omission/w_t", c.w_t);
  p.get("omission/t_max", c.t_max).get("omission/n_t", c.n_t).get("omission/n_max", c.n_max);
}

template <class R>
void readGlobalPlanner(R& p, planning::GlobalPlannerConfig& c) {
  p.get("global/s_near", c.s_near).get("global/n_min_tsp", c.n_min_tsp).get("global/n_max_tsp", c.n_max_tsp);
  p.get("global/lambda", c.lambda).get("global/v_max", c.v_max).get("global/max_exact", c.max_exact);
  p.get("global/reuse_cell", c.reuse_cell).get("global/reuse_time", c.reuse_time);
  p.get("global/rest_weight", c.rest_weight).get("global/rest_frontiers", c.rest_frontiers);
  readOmission(p, c.omission);
}

template <class R>
void readAstar(R& p, planning::AstarConfig& c, const std::string& ns = "astar") {
  p.get(ns + "/clearance", c.clearance).get(ns + "/unknown_is_free", c.unknown_is_free);
  p.get(ns + "/known_clearance", c.known_clearance).get(ns + "/known_radius", c.known_radius);
  p.get(ns + "/max_expansions", c.max_expansions).get(ns + "/probe_expansions", c.probe_expansions);
  p.get(ns + "/tie_breaker", c.tie_breaker).get(ns + "/stride", c.stride);
  c.name = ns;
}

template <class R>
void readLayers(R& p, planning::LayerManagerConfig& c) {
  p.get("layers/layer_height", c.layer_height).get("layers/settle_time", c.settle_time);
  p.get("layers/max_retries", c.max_retries).get("layers/time_limit", c.time_limit);
  p.get("layers/stuck_timeout", c.stuck_timeout).get("layers/progress_travel", c.progress_travel);
}

template <class R>
void readViewpoints(R& p, planning::ViewpointConfig& v) {
  p.get("viewpoints/ring_radii", v.ring_radii).get("viewpoints/angular_step", v.angular_step);
  p.get("viewpoints/height_offsets", v.height_offsets).get("viewpoints/clearance", v.clearance);
  p.get("viewpoints/sensor_range", v.sensor_range).get("viewpoints/hfov", v.hfov).get("viewpoints/vfov", v.vfov);
  p.get("viewpoints/min_visible", v.min_visible).get("viewpoints/yaw_samples", v.yaw_samples);
  p.get("viewpoints/max_evaluated_cells", v.max_evaluated_cells).get("viewpoints/known_clearance", v.known_clearance);
}

template <class R>
void readLocal(R& p, planning::LocalPlannerConfig& l) {
  p.get("local/k_frontiers", l.k_frontiers).get("local/top_k", l.top_k).get("local/d_near", l.d_near);
  p.get("local/v_max", l.v_max).get("local/yaw_rate_max", l.yaw_rate_max).get("local/window_size", l.window_size);
  p.get("local/clutter_threshold", l.clutter_threshold).get("local/max_range", l.max_range);
  p.get("local/min_dist", l.min_dist).get("local/commit_time", l.commit_time);
  p.get("local/replan_period", l.replan_period);
  p.get("local/min_view_fraction", l.min_view_fraction).get("local/scan_step", l.scan_step);
  p.get("local/same_target_distance", l.same_target_distance).get("local/same_target_yaw", l.same_target_yaw);
  p.get("local/reached_speed", l.reached_speed).get("local/max_visits", l.max_visits);
  p.get("local/settled_tilt", l.settled_tilt).get("local/settled_speed", l.settled_speed);
  p.get("local/max_choices", l.max_choices).get("local/choice_window", l.choice_window);
  p.get("local/choice_radius", l.choice_radius).get("local/a_max", l.a_max);
}

template <class R>
void readOptimizer(R& p, trajectory::OptimizerConfig& o) {
  p.get("optimizer/lambda_smooth", o.lambda_smooth).get("optimizer/lambda_clearance", o.lambda_clearance);
  p.get("optimizer/lambda_feasibility", o.lambda_feasibility).get("optimizer/lambda_time", o.lambda_time);
  p.get("optimizer/clearance", o.clearance).get("optimizer/min_clearance", o.min_clearance);
  p.get("optimizer/leave_distance", o.leave_distance);
  p.get("optimizer/v_max", o.v_max).get("optimizer/a_max", o.a_max).get("optimizer/yaw_rate_max", o.yaw_rate_max);
  p.get("optimizer/yaw_acc_max", o.yaw_acc_max);
  p.get("optimizer/feasibility_margin", o.feasibility_margin).get("optimizer/limit_tolerance", o.limit_tolerance);
  p.get("optimizer/max_iterations", o.max_iterations).get("optimizer/relative_tolerance", o.relative_tolerance);
  p.get("optimizer/min_knot_span", o.min_knot_span).get("optimizer/max_knot_span", o.max_knot_span);
}

template <class R>
void readReplan(R& p, trajectory::ReplanConfig& c) {
  p.get("replan/min_time_left", c.min_time_left).get("replan/target_tolerance", c.target_tolerance);
  p.get("replan/yaw_tolerance", c.yaw_tolerance);
}

template <class R>
void readTrajectoryPlanner(R& p, trajectory::TrajectoryPlannerConfig& c) {
  p.get("planner/path_spacing", c.path_spacing).get("planner/collision_horizon", c.collision_horizon);
  p.get("planner/min_time_between_plans", c.min_time_between_plans);
  p.get("planner/cruise_fraction", c.cruise_fraction).get("planner/max_refits", c.max_refits);
  p.get("planner/max_slowdown", c.max_slowdown).get("planner/horizon", c.horizon);
  p.get("planner/enclosed_turn", c.enclosed_turn).get("planner/min_progress", c.min_progress);
  p.get("planner/snap_radius", c.snap_radius).get("planner/goal_tolerance", c.goal_tolerance);
  p.get("planner/failed_search_memory", c.failed_search_memory).get("planner/scout_min_length", c.scout_min_length);
  p.get("planner/look_tolerance", c.look_tolerance).get("planner/max_scouts", c.max_scouts);
  p.get("planner/fine_spans", c.fine_spans).get("planner/profile_acceleration", c.profile_acceleration);
  p.get("planner/unseen_retry", c.unseen_retry);
  p.get("planner/coarse_retry", c.coarse_retry).get("planner/brake_speed", c.brake_speed);
  p.get("planner/profile_knot_span", c.profile_knot_span).get("planner/profile_ramp", c.profile_ramp);
  p.get("planner/profile_corner_cut", c.profile_corner_cut);
  p.get("planner/profile_max_cross_speed", c.profile_max_cross_speed);
}

template <class R>
void readQuadrotor(R& p, sim::QuadrotorParams& q) {
  p.get("quadrotor/mass", q.mass).getVec3("quadrotor/inertia", q.inertia);
  p.get("quadrotor/arm_length", q.arm_length).get("quadrotor/torque_coefficient", q.torque_coefficient);
  p.get("quadrotor/motor_min_thrust", q.motor_min_thrust).get("quadrotor/motor_max_thrust", q.motor_max_thrust);
  p.get("quadrotor/linear_drag", q.linear_drag).get("quadrotor/gravity", q.gravity);
  p.get("quadrotor/dynamics_rate", q.dynamics_rate);
}

template <class R>
void readController(R& p, sim::So3ControllerConfig& c) {
  p.getVec3("controller/kx", c.kx).getVec3("controller/kv", c.kv).getVec3("controller/kR", c.kR);
  p.getVec3("controller/kw", c.kw).get("controller/max_tilt", c.max_tilt);
}

/// The camera model keys (not its rate, frames or extrinsic, which the caller reads).
template <class R>
void readDepthCamera(R& p, sim::DepthCameraConfig& c) {
  p.get("depth_camera/width", c.width).get("depth_camera/height", c.height);
  p.get("depth_camera/hfov_deg", c.hfov_deg).get("depth_camera/vfov_deg", c.vfov_deg);
  p.get("depth_camera/fx", c.fx).get("depth_camera/fy", c.fy).get("depth_camera/cx", c.cx).get("depth_camera/cy", c.cy);
  p.get("depth_camera/min_range", c.min_range).get("depth_camera/max_range", c.max_range);
  p.get("depth_camera/noise_stddev_per_m", c.noise_stddev_per_m);
  p.get("depth_camera/dropout_probability", c.dropout_probability);
}

}  // namespace go_feap::config
