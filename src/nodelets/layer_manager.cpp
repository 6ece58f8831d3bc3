// LayerManager: runs the exploration state machine and steers the chain band by band.
// In: frontiers, map_update (progress), frontier_failed (std_msgs/UInt32 from planners),
// trigger (std_srvs/Trigger service, or a goal on move_base_simple/goal from rviz's 2D Nav
// Goal with layers/goal_trigger, or layers/auto_start), stop (std_srvs/Trigger service: FINISHED(aborted) at once; the trajectory
// planner then brakes the flight in progress to rest). Out: layer (go_feap/LayerBounds), status
// (go_feap/ExplorationStatus), blacklist (std_msgs/UInt32MultiArray, latched: frontiers the
// planners must skip), layer_marker (the band as a translucent slab for rviz). Every
// transition is logged.
#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <std_msgs/UInt32.h>
#include <std_msgs/UInt32MultiArray.h>
#include <visualization_msgs/Marker.h>
#include <std_srvs/Trigger.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <optional>
#include <set>

#include "go_feap/ExplorationStatus.h"
#include "go_feap/FrontierArray.h"
#include "go_feap/LayerBounds.h"
#include "go_feap/MapUpdate.h"
#include "go_feap/planning/layer_manager.h"
#include "go_feap/common/config_groups.h"
#include "go_feap/common/monotonic_clock.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/message_checks.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/params.h"

namespace go_feap {

class LayerManager : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros_params::ParamReader p(getPrivateNodeHandle());
    config::readLayers(p, config_);
    p.get("layers/rate", rate_).get("metrics/max_odom_step", max_odom_step_);
    p.get("layers/auto_start", auto_start_).get("layers/goal_trigger", goal_trigger_).getFrame("world_frame", world_frame_);
    config::readBox(p, box_);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    ros_params::requireOrThrow(config_.validate().ok(), getName(), config_.validate().message());
    ros_params::requireBox(box_, p, getName());
    ros_params::requireOrThrow(rate_ > 0.0 && rate_ <= 1000.0, getName(),
                               "parameter '" + p.fullName("layers/rate") + "' must be in (0, 1000] Hz");
    ros_params::requireOrThrow(max_odom_step_ > 0.0 && std::isfinite(max_odom_step_), getName(),
                               "parameter '" + p.fullName("metrics/max_odom_step") + "' must be finite and > 0");

    pending_trigger_ = auto_start_;  // before any callback can run (they read it under the mutex)
    layer_pub_ = nh.advertise<LayerBounds>("layer", 1, /*latch=*/true);
    status_pub_ = nh.advertise<ExplorationStatus>("status", 5, /*latch=*/true);
    blacklist_pub_ = nh.advertise<std_msgs::UInt32MultiArray>("blacklist", 1, /*latch=*/true);
    marker_pub_ = nh.advertise<visualization_msgs::Marker>("layer_marker", 1, /*latch=*/true);
    frontier_sub_ = ros_guard::subscribe(nh, getName(), "frontiers", 2, &LayerManager::onFrontiers, this);
    update_sub_ = ros_guard::subscribe(nh, getName(), "map_update", 20, &LayerManager::onMapUpdate, this);
    failed_sub_ = ros_guard::subscribe(nh, getName(), "frontier_failed", 100, &LayerManager::onFailed, this);
    odom_sub_ = ros_guard::subscribe(nh, getName(), "odom", 2, &LayerManager::onOdom, this);
    if (goal_trigger_)
      goal_sub_ = ros_guard::subscribe(nh, getName(), "move_base_simple/goal", 1, &LayerManager::onGoal, this);
    trigger_srv_ = ros_guard::service(nh, getName(), "trigger", &LayerManager::onTrigger, this);
    stop_srv_ = ros_guard::service(nh, getName(), "stop", &LayerManager::onStop, this);
    timer_ = ros_guard::timer(nh, getName(), ros::Duration(1.0 / rate_), &LayerManager::onTimer, this);
  }

  void onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
    const std::string bad = ros_conv::odometryPoseProblem(*msg, world_frame_);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": odometry refused: " << bad);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    const auto& q = msg->pose.pose.position;
    const common::Vec3 p(q.x, q.y, q.z);
    const double z = p.z();
    const bool flying = manager_ && (manager_->state() == planning::ExplorationState::kExplore ||
                                     manager_->state() == planning::ExplorationState::kFinalPass);
    if (flying) {
      if (const std::optional<double> step = ros_conv::flownStep(last_position_, p, max_odom_step_)) {
        distance_ += *step;
      } else {
        GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": " << ros_conv::odometryJump(*last_position_, p));
        relocalised_ = true;  // the next step measures progress from here
      }
    }
    last_position_ = p;
    yaw_ = ros_conv::yawOf(msg->pose.pose.orientation);
    if (!manager_) {
      manager_ = std::make_unique<planning::LayerManager>(config_, box_, z);
      step({});
    }
  }
  void onFrontiers(const FrontierArray::ConstPtr& msg) {
    const std::string bad = ros_check::frontierArrayProblem(*msg);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": frontiers refused: " << bad);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    frontiers_ = msg;
  }
  void onMapUpdate(const MapUpdate::ConstPtr& msg) {
    const std::string bad = ros_check::mapUpdateProblem(*msg);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": map_update " << msg->sequence << " refused: " << bad);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (msg->changed_voxels > 0) ++progress_;
  }
  void onFailed(const std_msgs::UInt32::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    failed_.push_back(msg->data);
  }
  void onGoal(const geometry_msgs::PoseStamped::ConstPtr&) {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_trigger_ = true;
  }
  bool onTrigger(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
    std::lock_guard<std::mutex> lock(mutex_);
    pending_trigger_ = true;
    if (!manager_) {
      res.success = true;
      res.message = "no odometry yet: the trigger is kept until it arrives";
    } else if (manager_->state() == planning::ExplorationState::kWaitTrigger) {
      res.success = true;
      res.message = "exploration starts";
    } else {
      res.success = false;
      res.message = "already started: trigger ignored";
    }
    return true;
  }

  bool onStop(std_srvs::Trigger::Request&, std_srvs::Trigger::Response& res) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (manager_ && manager_->state() == planning::ExplorationState::kFinished) {
      res.success = false;
      res.message = std::string("already finished (") + planning::toString(manager_->reason()) + ")";
      return true;
    }
    pending_stop_ = true;
    pending_trigger_ = false;  // a trigger kept for the first odometry is void
    res.success = true;
    res.message = manager_ ? "exploration stops: the flight in progress brakes to rest"
                           : "no odometry yet: the exploration finishes (aborted) when it arrives";
    return true;
  }

  void onTimer(const ros::TimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!manager_) return;
    // The band order starts where the vehicle is at the trigger, not where its first odometry put it (on
    // the ground, before the pilot took off): nothing the manager holds before the trigger is lost.
    if (pending_trigger_ && manager_->state() == planning::ExplorationState::kWaitTrigger && last_position_)
      manager_ = std::make_unique<planning::LayerManager>(config_, box_, last_position_->z());
    planning::LayerInputs in;
    in.trigger = pending_trigger_;
    pending_trigger_ = false;
    in.abort = pending_stop_;
    pending_stop_ = false;
    in.failed.swap(failed_);
    in.map_progress = progress_;
    in.yaw = yaw_;
    const planning::Band band = current_band_;
    in.frontiers_known = frontiers_ != nullptr;
    in.position = last_position_;
    in.relocalised = relocalised_;
    relocalised_ = false;
    if (!frontiers_ && (manager_->state() == planning::ExplorationState::kExplore ||
                        manager_->state() == planning::ExplorationState::kFinalPass))
      GO_FEAP_NODELET_THROTTLE(WARN, 5.0, getName() << ": no frontiers yet (from the frontier finder): no band counts as "
                                                     "explored until they come");
    if (frontiers_) {
      for (const auto& f : frontiers_->frontiers) in.listFrontier(f.id, f.average.z, band);
    }
    step(in);
  }

  // One step of the core at the exploration's clock, and what it says published (under mutex_).
  void step(const planning::LayerInputs& in) {
    const ros::Time now = ros::Time::now();
    const double t = coreTime(now);
    publish(now, t, manager_->step(in, t));
  }

  // The exploration's own clock, which never goes back: a ROS clock that does (a bag played again, a
  // simulator restarted) pauses it by as much. The core's settle, stuck and time-limit timers, and the
  // elapsed time, count from times before the jump: read against the clock itself they went negative
  // (a finished band could not settle, stuck detection was off and the time limit moved back for as long).
  double coreTime(const ros::Time& now) {
    const double t = clock_.at(now.toSec());
    if (clock_.wentBack() > 0.0)
      NODELET_WARN_STREAM(getName() << ": the clock went back " << clock_.wentBack()
                                    << " s: the exploration's timers pause for as long");
    return t;
  }

  // `t` is coreTime(now).
  void publish(const ros::Time& now, double t, const planning::LayerOutputs& out) {
    for (const planning::Transition& tr : out.transitions) {
      NODELET_INFO_STREAM(getName() << ": " << planning::toString(tr.from)
                                    << (tr.band_from >= 0 ? "(band " + std::to_string(tr.band_from) + ")" : "")
                                    << " -> " << planning::toString(tr.to)
                                    << (tr.band_to >= 0 ? "(band " + std::to_string(tr.band_to) + ")" : "") << ": "
                                    << tr.why
                                    << (tr.to == planning::ExplorationState::kFinished
                                            ? std::string(" [") + planning::toString(out.reason) + "]"
                                            : ""));
    }
    if (out.trigger_ignored) NODELET_INFO_STREAM(getName() << ": trigger received while exploring: ignored");
    if (!t_start_ && out.state != planning::ExplorationState::kWaitTrigger) t_start_ = t;
    current_band_ = out.band;
    LayerBounds layer;
    layer.header.stamp = now;
    layer.header.frame_id = world_frame_;
    layer.index = static_cast<std::uint32_t>(out.band.index);
    layer.count = static_cast<std::uint32_t>(out.band.count);
    layer.z_min = out.band.z_min;
    layer.z_max = out.band.z_max;
    layer.final_pass = out.band.final_pass;
    layer.look_around = out.look_around;
    if (out.look_around && !look_around_)
      NODELET_INFO_STREAM(getName() << ": no frontier in view before a look round: the vehicle turns in place");
    // Published on a transition, and at every step while a look round is wanted or when it stops (the
    // local planner turns again whenever it is idle).
    const bool transition = !out.transitions.empty() || !published_;
    if (transition || out.look_around || look_around_) layer_pub_.publish(layer);
    look_around_ = out.look_around;
    if (transition) {
      visualization_msgs::Marker slab;
      slab.header = layer.header;
      slab.ns = "altitude_band";
      slab.type = visualization_msgs::Marker::CUBE;
      slab.pose.position.x = 0.5 * (box_.min.x() + box_.max.x());
      slab.pose.position.y = 0.5 * (box_.min.y() + box_.max.y());
      slab.pose.position.z = 0.5 * (out.band.z_min + out.band.z_max);
      slab.pose.orientation.w = 1.0;
      slab.scale.x = box_.max.x() - box_.min.x();
      slab.scale.y = box_.max.y() - box_.min.y();
      slab.scale.z = std::max(0.01, out.band.z_max - out.band.z_min);
      slab.color.r = 0.3, slab.color.g = 0.6, slab.color.b = 1.0, slab.color.a = 0.08;
      marker_pub_.publish(slab);
    }
    // Sent whenever it changes: frontiers the finder no longer lists leave it as others join, so one
    // step can change it and keep its size.
    if (manager_ && manager_->blacklist() != blacklisted_) {
      std::string added;
      for (std::uint32_t id : manager_->blacklist())
        if (!blacklisted_.count(id)) added += (added.empty() ? "" : ", ") + std::to_string(id);
      blacklisted_ = manager_->blacklist();
      std_msgs::UInt32MultiArray list;
      list.data.assign(blacklisted_.begin(), blacklisted_.end());
      blacklist_pub_.publish(list);
      if (!added.empty())
        NODELET_WARN_STREAM(getName() << ": frontier(s) " << added << " blacklisted after " << config_.max_retries
                                      << " failed attempts (" << blacklisted_.size() << " on the blacklist)");
    }
    published_ = true;
    ExplorationStatus status;
    status.header = layer.header;
    status.state = static_cast<std::uint8_t>(out.state);
    status.state_name = planning::toString(out.state);
    status.layer = layer.index;
    // On the exploration's clock, which never goes back: against the ROS clock, a clock that went back (a
    // bag played again) made every status one that MetricsRecorder refuses, the finishing one too.
    status.elapsed = t_start_ ? t - *t_start_ : 0.0;
    status.distance = distance_;
    status.coverage = -1.0;  // unknown here: the metrics recorder compares with ground truth
    status.frontier_count = frontiers_ ? static_cast<std::uint32_t>(frontiers_->frontiers.size()) : 0;
    status.finish_reason = planning::toString(out.reason);
    status.blacklisted_frontiers = static_cast<std::uint32_t>(out.blacklisted_left);
    status_pub_.publish(status);
  }

  planning::LayerManagerConfig config_;
  common::Aabb box_;
  double rate_ = 5.0;
  double max_odom_step_ = 1.0;  ///< m, a longer step between odometry messages is a jump, not flight
  bool auto_start_ = false;
  bool goal_trigger_ = true;  ///< layers/goal_trigger: a 2D Nav Goal triggers too
  std::string world_frame_;
  std::mutex mutex_;
  std::unique_ptr<planning::LayerManager> manager_;
  planning::Band current_band_;
  FrontierArray::ConstPtr frontiers_;
  std::vector<std::uint32_t> failed_;
  std::uint64_t progress_ = 0;
  bool pending_trigger_ = false, pending_stop_ = false, published_ = false;
  std::optional<double> t_start_;     ///< coreTime() when the exploration started
  common::MonotonicClock clock_;     ///< the exploration's clock, from the ROS clock at each step
  std::optional<common::Vec3> last_position_;
  bool relocalised_ = false;  ///< the odometry jumped since the last step (LayerInputs::relocalised)
  std::optional<double> yaw_;
  bool look_around_ = false;
  double distance_ = 0.0;
  ros::Publisher layer_pub_, status_pub_, blacklist_pub_, marker_pub_;
  std::set<std::uint32_t> blacklisted_;  ///< as last published
  ros::Subscriber frontier_sub_, update_sub_, failed_sub_, odom_sub_, goal_sub_;
  ros::ServiceServer trigger_srv_, stop_srv_;
  ros::Timer timer_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::LayerManager, nodelet::Nodelet)
