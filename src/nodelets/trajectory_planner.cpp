// TrajectoryPlanner: turns the local target into a smooth, feasible trajectory. A* in known
// free space to the target viewpoint, a cubic B-spline fitted to it and optimised with NLopt,
// a yaw spline; replans on a new target, little time left or a predicted collision, and
// stops safely when planning fails. In: local_target, odom, position_cmd (continuity),
// map_handle. Out: bspline (go_feap/Bspline), trajectory_marker, frontier_failed.
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <std_msgs/UInt32.h>
#include <visualization_msgs/Marker.h>

#include <mutex>
#include <optional>

#include "go_feap/PositionCommand.h"
#include "go_feap/ViewpointPath.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/bspline_conversion.h"
#include "go_feap/ros/exploration_params.h"
#include "go_feap/ros/shared_map.h"
#include "go_feap/trajectory/bspline_optimizer.h"
#include "go_feap/trajectory/replan.h"

namespace go_feap {

class TrajectoryPlanner : public nodelet::Nodelet {
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros_params::ParamReader p(getPrivateNodeHandle());
    auto& o = optimizer_;
    p.get("optimizer/lambda_smooth", o.lambda_smooth).get("optimizer/lambda_clearance", o.lambda_clearance);
    p.get("optimizer/lambda_feasibility", o.lambda_feasibility).get("optimizer/lambda_time", o.lambda_time);
    p.get("optimizer/clearance", o.clearance).get("optimizer/min_clearance", o.min_clearance);
    p.get("optimizer/v_max", o.v_max).get("optimizer/a_max", o.a_max).get("optimizer/yaw_rate_max", o.yaw_rate_max);
    p.get("optimizer/feasibility_margin", o.feasibility_margin).get("optimizer/limit_tolerance", o.limit_tolerance);
    p.get("optimizer/max_iterations", o.max_iterations).get("optimizer/relative_tolerance", o.relative_tolerance);
    p.get("optimizer/min_knot_span", o.min_knot_span).get("optimizer/max_knot_span", o.max_knot_span);
    p.get("replan/min_time_left", replan_.min_time_left).get("replan/target_tolerance", replan_.target_tolerance);
    p.get("planner/rate", rate_).get("planner/path_spacing", spacing_);
    p.get("planner/collision_horizon", horizon_).get("planner/min_time_between_plans", min_gap_);
    ros_params::readAstarConfig(p, astar_config_);
    p.get("world_frame", world_frame_);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    for (const common::Status& st : {o.validate(), replan_.validate(), astar_config_.validate()})
      ros_params::requireOrThrow(st.ok(), getName(), st.message());
    ros_params::requireOrThrow(rate_ > 0.0 && spacing_ > 0.0 && horizon_ > 0.0 && min_gap_ >= 0.0, getName(),
                               "parameters '" + p.fullName("planner") +
                                   "/{rate, path_spacing, collision_horizon}' must be > 0");
    bspline_pub_ = nh.advertise<Bspline>("bspline", 5);
    marker_pub_ = nh.advertise<visualization_msgs::Marker>("trajectory_marker", 2);
    failed_pub_ = nh.advertise<std_msgs::UInt32>("frontier_failed", 10);
    handle_sub_ = nh.subscribe("map_handle", 1, &TrajectoryPlanner::onHandle, this);
    odom_sub_ = nh.subscribe("odom", 5, &TrajectoryPlanner::onOdom, this);
    cmd_sub_ = nh.subscribe("position_cmd", 5, &TrajectoryPlanner::onCommand, this);
    target_sub_ = nh.subscribe("local_target", 2, &TrajectoryPlanner::onTarget, this);
    timer_ = nh.createTimer(ros::Duration(1.0 / rate_), &TrajectoryPlanner::onTimer, this);
  }

  void onHandle(const boost::shared_ptr<const ros_map::MapHandle>& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (shared_) return;
    auto map = ros_map::acceptHandle(*msg, [&](const map::EsdfConfig& esdf) {
      const common::Status st = optimizer_.validate(esdf);
      return st.ok() ? astar_config_.validate(esdf) : st;
    });
    if (!map) {
      NODELET_ERROR_STREAM_THROTTLE(10.0, getName() << ": " << map.message());
      return;
    }
    shared_ = *map;
    astar_ = std::make_unique<planning::Astar>(shared_->map->occupancy(), shared_->map->esdf(), astar_config_);
  }
  void onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
    const auto& p = msg->pose.pose.position;
    const auto& q = msg->pose.pose.orientation;
    std::lock_guard<std::mutex> lock(mutex_);
    const common::Vec3 pos(p.x, p.y, p.z);
    if (!pos.allFinite()) return;
    odom_position_ = pos;
    odom_yaw_ = ros_conv::yawOf(q);
  }
  void onCommand(const PositionCommand::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    command_ = msg;
  }
  void onTarget(const ViewpointPath::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (msg->positions.empty()) return;
    const auto& p = msg->positions.front();
    const common::Vec3 target(p.x, p.y, p.z);
    if (!target.allFinite() || !std::isfinite(msg->yaws.front())) return;
    target_changed_ = !target_ || (target - *target_).norm() > replan_.target_tolerance;
    target_ = target;
    target_yaw_ = msg->yaws.front();
    target_frontier_ = msg->frontier_ids.empty() ? 0 : msg->frontier_ids.front();
  }

  void onTimer(const ros::TimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!shared_ || !target_ || !odom_position_) return;
    const ros::Time now = ros::Time::now();
    if (!last_plan_.isZero() && (now - last_plan_).toSec() < min_gap_) return;
    trajectory::ReplanInputs in;
    {
      std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
      if (current_) {
        const double t = (now - current_->start_time).toSec();
        in.has_trajectory = true;
        in.time_left = current_->duration() - t;
        in.target_distance_to_end = (current_->position.position(current_->duration()) - *target_).norm();
        in.collision_time = trajectory::firstCollisionTime(current_->position, std::max(0.0, t),
                                                           shared_->map->esdf(), optimizer_.min_clearance, horizon_);
      }
    }
    in.target_changed = target_changed_;
    // A trajectory that ended at its target needs no replanning until the target moves.
    const bool arrived = current_ && in.time_left <= 0.0 && in.target_distance_to_end <= replan_.target_tolerance;
    const trajectory::ReplanReason reason = trajectory::shouldReplan(in, replan_);
    if (reason == trajectory::ReplanReason::kNone || (arrived && reason == trajectory::ReplanReason::kShortTimeLeft))
      return;
    target_changed_ = false;
    last_plan_ = now;
    try {
      plan(now, reason);
    } catch (const std::exception& e) {  // a core precondition broken by odd input: never crash the manager
      NODELET_ERROR_STREAM_THROTTLE(1.0, getName() << ": planning aborted: " << e.what());
      target_.reset();
    }
  }

  // Start state: the commanded state when recent (continuity of the reference), else odometry.
  void startState(const ros::Time& now, common::Vec3& p, common::Vec3& v, double& yaw) const {
    if (command_ && (now - command_->header.stamp).toSec() < 0.1) {
      p = common::Vec3(command_->position.x, command_->position.y, command_->position.z);
      v = common::Vec3(command_->velocity.x, command_->velocity.y, command_->velocity.z);
      yaw = command_->yaw;
    } else {
      p = *odom_position_;
      v.setZero();
      yaw = odom_yaw_;
    }
  }

  void plan(const ros::Time& now, trajectory::ReplanReason reason) {
    common::Vec3 p0, v0;
    double yaw0 = 0.0;
    startState(now, p0, v0, yaw0);
    std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
    const map::Esdf& esdf = shared_->map->esdf();
    const planning::PathResult path = astar_->search(p0, *target_);
    common::Result<trajectory::UniformBspline> spline = common::Result<trajectory::UniformBspline>::Error("");
    if (path.status != planning::PathStatus::kFound) {
      spline = common::Result<trajectory::UniformBspline>::Error(std::string("no path: ") + planning::toString(path.status));
    } else {
      std::vector<common::Vec3> pts = path.path;
      pts.front() = p0;  // start exactly at the current reference
      const double length = path.length;
      const double spacing = std::max(0.05, std::min(spacing_, length / 6.0));
      const auto samples = trajectory::UniformBspline::resamplePolyline(pts, spacing);
      // Initial timing within the limits: cruise at 60 % of v_max, but short hops from
      // (or to) rest need the time an a_max-limited accelerate/brake takes.
      const double total = std::max({length / (0.6 * optimizer_.v_max), 2.5 * std::sqrt(length / optimizer_.a_max),
                                     v0.norm() / optimizer_.a_max + 0.5});
      double dt = total / std::max<std::size_t>(1, samples.size() - 1);
      // Optimise; when the result breaks a limit, refit slower (the start velocity is kept,
      // so the reference stays continuous) and try again, then accept a slower fit that
      // passes the same checks as an optimised one.
      for (int attempt = 0; attempt < 4; ++attempt) {
        const auto init = trajectory::UniformBspline::fitPath(samples, dt, v0, common::Vec3::Zero());
        spline = trajectory::optimize(init, esdf, optimizer_);
        if (spline) break;
        if (trajectory::checkTrajectory(init, esdf, optimizer_).ok()) {
          spline = init;
          break;
        }
        const double f = std::max({1.5, init.maxVelocity() / (0.9 * optimizer_.v_max),
                                   std::sqrt(init.maxAcceleration() / (0.9 * optimizer_.a_max))});
        dt *= std::min(f, 4.0);
      }
    }
    map_lock.unlock();
    if (!spline) {
      NODELET_WARN_STREAM(getName() << ": planning to frontier " << target_frontier_ << " failed ("
                                    << trajectory::toString(reason) << "): " << spline.message() << "; stopping");
      std_msgs::UInt32 failed;
      failed.data = target_frontier_;
      failed_pub_.publish(failed);
      publish(now, trajectory::safeStop(p0, v0, optimizer_.a_max), {yaw0, yaw0});
      target_.reset();  // wait for a new target
      return;
    }
    publish(now, std::move(spline).value(), {yaw0, target_yaw_});
  }

  void publish(const ros::Time& now, trajectory::UniformBspline position, const std::vector<double>& yaws) {
    ros_traj::Trajectory t;
    t.id = ++trajectory_id_;
    t.start_time = now;
    t.position = std::move(position);
    auto yaw = trajectory::optimizeYaw(yaws, std::max(0.1, t.position.duration()), 0.0, optimizer_);
    if (!yaw) {
      NODELET_WARN_STREAM(getName() << ": yaw spline failed (" << yaw.message() << "); keeping the heading");
      yaw = trajectory::optimizeYaw({yaws.front(), yaws.front()}, std::max(0.1, t.position.duration()), 0.0,
                                    optimizer_);
      if (!yaw) return;
    }
    t.yaw = std::move(yaw).value();
    current_ = t;
    bspline_pub_.publish(ros_traj::toMsg(t));
    visualization_msgs::Marker line;
    line.header.stamp = now;
    line.header.frame_id = world_frame_;
    line.ns = "trajectory";
    line.type = visualization_msgs::Marker::LINE_STRIP;
    line.pose.orientation.w = 1.0;
    line.scale.x = 0.05;
    line.color.r = 0.2, line.color.g = 0.4, line.color.b = 1.0, line.color.a = 1.0;
    for (double s = 0.0; s <= t.position.duration(); s += 0.05) {
      const common::Vec3 q = t.position.position(s);
      line.points.push_back(ros_conv::toPoint(q));
    }
    marker_pub_.publish(line);
  }

  trajectory::OptimizerConfig optimizer_;
  trajectory::ReplanConfig replan_;
  planning::AstarConfig astar_config_;
  double rate_ = 10.0, spacing_ = 0.3, horizon_ = 3.0, min_gap_ = 0.3;
  std::string world_frame_;
  std::mutex mutex_;
  std::shared_ptr<ros_map::SharedMap> shared_;
  std::unique_ptr<planning::Astar> astar_;
  std::optional<common::Vec3> odom_position_, target_;
  double odom_yaw_ = 0.0, target_yaw_ = 0.0;
  unsigned target_frontier_ = 0;
  bool target_changed_ = false;
  PositionCommand::ConstPtr command_;
  std::optional<ros_traj::Trajectory> current_;
  std::int64_t trajectory_id_ = 0;
  ros::Time last_plan_;
  ros::Publisher bspline_pub_, marker_pub_, failed_pub_;
  ros::Subscriber handle_sub_, odom_sub_, cmd_sub_, target_sub_;
  ros::Timer timer_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::TrajectoryPlanner, nodelet::Nodelet)
