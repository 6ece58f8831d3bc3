// TrajectoryPlanner: turns the local target into a smooth, feasible trajectory. A* in known
// free space to the target viewpoint, a cubic B-spline fitted to it and optimised with NLopt,
// a yaw spline; replans on a new target, little time left or a predicted collision, and
// stops safely when planning fails, and plans again when the server dropped the trajectory (its
// position_cmd names another or none) or when the odometry is far from the trajectory's reference (a jump:
// the next plan starts from the odometry). Once the status says FINISHED(aborted) (the layer manager's stop
// service) the target is dropped and the flight in progress brakes to rest. In: local_target, odom,
// position_cmd (continuity), map_handle, status. Out: bspline (go_feap/Bspline), trajectory_marker,
// frontier_failed.
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <std_msgs/UInt32.h>
#include <visualization_msgs/Marker.h>

#include <mutex>
#include <optional>

#include "go_feap/ExplorationStatus.h"
#include "go_feap/PositionCommand.h"
#include "go_feap/ViewpointPath.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/message_checks.h"
#include "go_feap/ros/bspline_conversion.h"
#include "go_feap/common/config_groups.h"
#include "go_feap/ros/compute_time.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/params.h"
#include "go_feap/ros/shared_map.h"
#include "go_feap/trajectory/trajectory_planner.h"

namespace go_feap {

class TrajectoryPlanner : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
  ros_map::EmptyHandles empty_handles_{10.0};  ///< map_handles without a map, said only when they last
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros_params::ParamReader p(getPrivateNodeHandle());
    auto& o = optimizer_;
    config::readOptimizer(p, o);
    config::readReplan(p, replan_);
    config::readTrajectoryPlanner(p, planner_);
    p.get("planner/rate", rate_).get("planner/odom_timeout", odom_timeout_).get("planner/drop_grace", drop_grace_);
    p.get("planner/max_tracking_error", max_tracking_error_).get("planner/max_input_speed", max_input_speed_);
    p.get("planner/command_timeout", command_timeout_);
    config::readAstar(p, astar_config_);
    config::readAstar(p, scout_config_, "scout_astar");
    config::readAstar(p, coarse_config_, "coarse_astar");
    p.getFrame("world_frame", world_frame_);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    for (const common::Status& st :
         {o.validate(), replan_.validate(), astar_config_.validate(), scout_config_.validate(), coarse_config_.validate(),
          planner_.validate()})
      ros_params::requireOrThrow(st.ok(), getName(), st.message());
    ros_params::requireOrThrow(rate_ > 0.0 && rate_ <= 1000.0, getName(),
                               "parameter '" + p.fullName("planner/rate") + "' must be in (0, 1000] Hz");
    ros_params::requireOrThrow(std::isfinite(odom_timeout_) && odom_timeout_ > 0.0, getName(),
                               "parameter '" + p.fullName("planner/odom_timeout") + "' must be > 0");
    ros_params::requireOrThrow(std::isfinite(drop_grace_) && drop_grace_ > 0.0, getName(),
                               "parameter '" + p.fullName("planner/drop_grace") + "' must be > 0");
    ros_params::requireOrThrow(std::isfinite(max_tracking_error_) && max_tracking_error_ > 0.0, getName(),
                               "parameter '" + p.fullName("planner/max_tracking_error") + "' must be > 0");
    ros_params::requireOrThrow(std::isfinite(max_input_speed_) && max_input_speed_ > 0.0, getName(),
                               "parameter '" + p.fullName("planner/max_input_speed") + "' must be > 0");
    ros_params::requireOrThrow(std::isfinite(command_timeout_) && command_timeout_ > 0.0, getName(),
                               "parameter '" + p.fullName("planner/command_timeout") + "' must be > 0");
    speed_limit_name_ = p.fullName("planner/max_input_speed");
    compute_pub_ = nh.advertise<ComputeTime>("compute_time", 20);
    bspline_pub_ = nh.advertise<Bspline>("bspline", 5);
    marker_pub_ = nh.advertise<visualization_msgs::Marker>("trajectory_marker", 2);
    failed_pub_ = nh.advertise<std_msgs::UInt32>("frontier_failed", 10);
    handle_sub_ = ros_guard::subscribe(nh, getName(), "map_handle", 1, &TrajectoryPlanner::onHandle, this);
    odom_sub_ = ros_guard::subscribe(nh, getName(), "odom", 5, &TrajectoryPlanner::onOdom, this);
    cmd_sub_ = ros_guard::subscribe(nh, getName(), "position_cmd", 5, &TrajectoryPlanner::onCommand, this);
    target_sub_ = ros_guard::subscribe(nh, getName(), "local_target", 2, &TrajectoryPlanner::onTarget, this);
    status_sub_ = ros_guard::subscribe(nh, getName(), "status", 2, &TrajectoryPlanner::onStatus, this);
    timer_ = ros_guard::timer(nh, getName(), ros::Duration(1.0 / rate_), &TrajectoryPlanner::onTimer, this);
  }

  void onHandle(const boost::shared_ptr<const ros_map::MapHandle>& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (shared_) {
      if (const std::string other = ros_map::otherMapProblem(*msg, shared_); !other.empty())
        GO_FEAP_NODELET_THROTTLE(ERROR, 10.0, getName() << ": " << other);
      return;
    }
    auto map = ros_map::acceptHandle(*msg);
    if (!map) {
      if (empty_handles_.due(ros::Time::now().toSec()))
        NODELET_ERROR_STREAM(getName() << ": for " << empty_handles_.patience() << " s: " << map.message());
      return;
    }
    const map::EsdfConfig& esdf = (*map)->map->config().esdf;
    for (const common::Status& st : {optimizer_.validate(esdf), astar_config_.validate(esdf), scout_config_.validate(esdf),
                                     coarse_config_.validate(esdf), planner_.validate((*map)->map->config().occupancy)})
      if (!st) {
        ros_params::stopManager(getName(), st.message());
        return;
      }
    // Built before the map is kept: a constructor that threw would leave the map taken and a search
    // missing (the next plan would reach a null one, and the handle would never be taken again).
    const map::OccupancyMap& occupancy = (*map)->map->occupancy();
    auto astar = std::make_unique<planning::Astar>(occupancy, (*map)->map->esdf(), astar_config_);
    auto scout = std::make_unique<planning::Astar>(occupancy, (*map)->map->esdf(), scout_config_);
    auto coarse = std::make_unique<planning::Astar>(occupancy, (*map)->map->esdf(), coarse_config_);
    shared_ = *map;
    astar_ = std::move(astar);
    scout_ = std::move(scout);
    coarse_ = std::move(coarse);
  }
  void onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
    // The velocity is the start of every plan from the odometry: one not finite (it used to be taken as
    // rest) or faster than planner/max_input_speed refuses the message whole.
    common::Vec3 v;
    const std::string bad =
        ros_conv::odometryProblem(*msg, world_frame_, max_input_speed_, speed_limit_name_, v);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": odometry refused: " << bad);
      return;
    }
    const auto& p = msg->pose.pose.position;
    const auto& q = msg->pose.pose.orientation;
    std::lock_guard<std::mutex> lock(mutex_);
    odom_position_ = common::Vec3(p.x, p.y, p.z);
    odom_time_ = ros::Time::now();
    // When the pose held: a plan from it starts then (a VIO's latency behind its arrival). A stamp after
    // the arrival or older than planner/odom_timeout (another clock, a bag's) says nothing: the arrival.
    const double age = (odom_time_ - msg->header.stamp).toSec();
    odom_stamp_ = age >= 0.0 && age <= odom_timeout_ ? msg->header.stamp : odom_time_;
    odom_yaw_ = ros_conv::yawOf(q);
    odom_velocity_ = v;
  }
  void onCommand(const PositionCommand::ConstPtr& msg) {
    // The command is the next plan's start: one that is not finite is refused (the last usable one goes
    // stale, and the plan then starts from the odometry).
    std::string bad = ros_check::positionCommandProblem(*msg, world_frame_);
    if (bad.empty())
      bad = ros_conv::velocityProblem(common::Vec3(msg->velocity.x, msg->velocity.y, msg->velocity.z), max_input_speed_,
                                      speed_limit_name_);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": position_cmd refused: " << bad);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    command_ = msg;
  }
  // FINISHED(aborted), once: the flight in progress brakes (the next timer call). Other endings fly the
  // flight in progress to its end, at rest at its viewpoint.
  void onStatus(const ExplorationStatus::ConstPtr& msg) {
    if (const std::string bad = ros_check::explorationStatusProblem(*msg); !bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": status refused: " << bad);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (msg->state == ExplorationStatus::FINISHED && msg->finish_reason == "aborted" && !aborted_) {
      aborted_ = true;
      brake_pending_ = true;
    }
  }
  void onTarget(const ViewpointPath::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (aborted_) return;  // stopped: nothing is flown to any more
    if (msg->positions.empty()) return;
    if (msg->yaws.size() != msg->positions.size()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": local_target refused: " << msg->positions.size()
                                                  << " positions but " << msg->yaws.size() << " yaws");
      return;
    }
    const auto& p = msg->positions.front();
    const common::Vec3 target(p.x, p.y, p.z);
    if (!target.allFinite() || !std::isfinite(msg->yaws.front())) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": local_target refused: its first viewpoint (" << p.x << ", "
                                                  << p.y << ", " << p.z << ", yaw " << msg->yaws.front()
                                                  << ") is not finite");
      return;
    }
    // A newly numbered target is flown to exactly, however near the last one: the local planner judges
    // it reached by its own pose, and after dropping a target it may choose a viewpoint next to it (kept
    // within the tolerances, the vehicle hovered short of it for good). A repeat keeps its number.
    const bool renumbered = msg->target_seq != 0 && msg->target_seq != target_seq_;
    const bool new_target =
        !target_ || renumbered || trajectory::targetMoved(*target_, target_yaw_, target, msg->yaws.front(), replan_);
    if (new_target) attempts_ = trajectory::TargetAttempts();
    target_changed_ = target_changed_ || new_target;
    target_seq_ = msg->target_seq;
    target_ = target;
    target_yaw_ = msg->yaws.front();
    target_frontier_ = msg->frontier_ids.empty() ? 0 : msg->frontier_ids.front();
  }

  void onTimer(const ros::TimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (brake_pending_) {
      brake_pending_ = false;
      target_.reset();
      if (current_ && odom_position_) {
        trajectory::PlanRequest stop;
        const ros::Time start_time = startState(ros::Time::now(), stop);
        publish(ros::Time::now(), start_time, trajectory::stopTrajectory(stop.start, stop.velocity, stop.yaw, optimizer_, stop.yaw_rate));
        NODELET_WARN_STREAM(getName() << ": exploration stopped: braking to rest from " << stop.velocity.norm()
                                      << " m/s");
      }
      return;
    }
    if (target_ && (!shared_ || !odom_position_)) {  // a target to fly to, and nothing to plan it on: said
      GO_FEAP_NODELET_THROTTLE(WARN, 5.0, getName() << ": a target but no " << (shared_ ? "odometry" : "map_handle")
                                                  << " yet: not planning");
      return;
    }
    if (!shared_ || !target_ || !odom_position_) return;
    const ros::Time now = ros::Time::now();
    // An odometry gap: the server holds position; plan nothing until odometry is back, then start
    // from scratch (the old trajectory was dropped).
    if ((now - odom_time_).toSec() > odom_timeout_) {
      if (!odom_gap_) NODELET_WARN_STREAM(getName() << ": no odometry for " << (now - odom_time_).toSec() << " s: not planning");
      odom_gap_ = true;
      current_.reset();
      return;
    }
    if (odom_gap_) {
      NODELET_WARN_STREAM(getName() << ": odometry is back: replanning");
      odom_gap_ = false;
      target_changed_ = true;
    }
    // The server dropped the trajectory (an odometry gap it saw and this timer missed): the vehicle holds
    // position, so plan again; counted on, a trajectory ending at its target was never replanned.
    if (current_ && command_ &&
        trajectory::serverDropped(static_cast<std::uint32_t>(current_->id), sent_time_.toSec(),
                                  command_->trajectory_flag != PositionCommand::TRAJECTORY_STATUS_EMPTY,
                                  command_->trajectory_id, command_->header.stamp.toSec(), drop_grace_)) {
      NODELET_WARN_STREAM(getName() << ": the trajectory server is not following trajectory " << current_->id
                                    << " (it follows " << command_->trajectory_id << "): replanning");
      current_.reset();
      target_changed_ = true;
    }
    // The vehicle is far from the reference of this planner's trajectory (the odometry jumped, or the
    // controller lost the trajectory): the reference is no start for the next plan, and following it on
    // would have the controller close the whole gap at once. Plan again from the odometry.
    if (current_ && commandRecent(now) &&
        command_->trajectory_flag != PositionCommand::TRAJECTORY_STATUS_EMPTY &&
        command_->trajectory_id == static_cast<std::uint32_t>(current_->id)) {
      const common::Vec3 reference(command_->position.x, command_->position.y, command_->position.z);
      const double off = (reference - *odom_position_).norm();
      if (off > max_tracking_error_) {
        NODELET_WARN_STREAM(getName() << ": the vehicle is " << off << " m from the reference of trajectory "
                                      << current_->id << " (an odometry jump?): replanning from the odometry");
        current_.reset();
        target_changed_ = true;
        from_odometry_ = true;
      }
    }
    if (now < last_plan_) {  // a clock that went back (a bag played again): the trajectory's times are void
      NODELET_WARN_STREAM(getName() << ": the clock went back " << last_plan_.toSec() - now.toSec()
                                    << " s: replanning from the odometry");
      last_plan_ = ros::Time();
      current_.reset();
      target_changed_ = true;
      from_odometry_ = true;
    }
    if (!last_plan_.isZero() && (now - last_plan_).toSec() < planner_.min_time_between_plans) return;
    trajectory::ReplanReason reason;
    {
      std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
      reason = trajectory::replanReason(current_ ? &*current_ : nullptr,
                                        current_ ? (now - current_->start_time).toSec() : 0.0, *target_,
                                        target_changed_, shared_->map->esdf(), replan_, optimizer_, planner_);
    }
    if (reason == trajectory::ReplanReason::kNone) return;
    target_changed_ = false;
    last_plan_ = now;
    try {
      plan(now, reason);
    } catch (const std::exception& e) {  // a core precondition broken by odd input: never crash the manager
      GO_FEAP_NODELET_THROTTLE(ERROR, 1.0, getName() << ": planning aborted: " << e.what() << "; stopping");
      target_.reset();
      // The trajectory flown may be the one just found to collide: brake to a stop instead of flying it on.
      try {
        trajectory::PlanRequest stop;
        const ros::Time start_time = startState(now, stop);
        publish(now, start_time, trajectory::stopTrajectory(stop.start, stop.velocity, stop.yaw, optimizer_, stop.yaw_rate));
      } catch (const std::exception& e2) {
        GO_FEAP_NODELET_THROTTLE(ERROR, 1.0, getName() << ": no stop trajectory either: " << e2.what());
      }
    }
  }

  // A position_cmd from the last planner/command_timeout s: the reference the server is sending now (in seconds as doubles:
  // its stamp is the sender's).
  bool commandRecent(const ros::Time& now) const {
    return command_ && now.toSec() - command_->header.stamp.toSec() < command_timeout_;
  }

  // Start state: the commanded state when recent (continuity of the reference), else odometry (also
  // right after the vehicle was found far from the reference). Returns when that state held (the
  // command's stamp, the odometry's): the trajectory starts then, so that the server, which takes it
  // over later, samples it where the reference is by then instead of a command period or an odometry
  // age behind.
  ros::Time startState(const ros::Time& now, trajectory::PlanRequest& request) const {
    if (!from_odometry_ && commandRecent(now)) {
      request.start = common::Vec3(command_->position.x, command_->position.y, command_->position.z);
      request.velocity = common::Vec3(command_->velocity.x, command_->velocity.y, command_->velocity.z);
      request.acceleration =
          common::Vec3(command_->acceleration.x, command_->acceleration.y, command_->acceleration.z);
      request.yaw = command_->yaw;
      request.yaw_rate = command_->yaw_dot;
      return std::min(now, command_->header.stamp);
    }
    request.start = *odom_position_;
    request.velocity = odom_velocity_;
    request.acceleration.setZero();
    request.yaw = odom_yaw_;
    return std::min(now, odom_stamp_);
  }

  void plan(const ros::Time& now, trajectory::ReplanReason reason) {
    trajectory::PlanRequest request;
    const ros::Time start_time = startState(now, request);
    request.target = *target_;
    request.target_yaw = target_yaw_;
    request.time = now.toSec();
    from_odometry_ = false;
    const auto t_compute = ros_conv::WallClock::now();
    trajectory::FlightStep step;
    {
      std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
      step = trajectory::planForTarget(request, &attempts_, *astar_, shared_->map->esdf(), optimizer_, planner_,
                                       &search_memory_, scout_.get(), coarse_.get());
    }
    ros_conv::publishComputeTime(compute_pub_, "trajectory", t_compute);
    const trajectory::PlanReport& report = step.report;
    switch (step.outcome) {
      case trajectory::FlightOutcome::kFly:
        if (report.coarse)
          NODELET_DEBUG_STREAM(getName() << ": flight search to frontier " << target_frontier_
                                         << " over budget: flying the coarse search's path (" << report.path_length
                                         << " m)");
        if (step.newly_widened)
          NODELET_INFO_STREAM(getName() << ": every trajectory along the way to frontier " << target_frontier_
                                        << " came too near unseen space: flying a way that keeps it away all round");
        if (report.braked)
          NODELET_INFO_STREAM(getName() << ": no flyable trajectory to frontier " << target_frontier_ << " from "
                                        << request.velocity.norm() << " m/s: braking to plan again from rest");
        if (report.scouted)
          NODELET_INFO_STREAM(getName() << ": no known path to frontier " << target_frontier_
                                        << ": scouting along a way through unseen space");
        break;
      case trajectory::FlightOutcome::kScoutedTooOften:
        NODELET_WARN_STREAM(getName() << ": frontier " << target_frontier_ << " scouted " << attempts_.scouts
                                      << " times without a known path: stopping; it counts a failed attempt");
        break;
      case trajectory::FlightOutcome::kLookAround:
      case trajectory::FlightOutcome::kLookAtUnseen:
      case trajectory::FlightOutcome::kFail:
        NODELET_WARN_STREAM(getName() << ": planning to frontier " << target_frontier_ << " failed ("
                                      << trajectory::toString(reason) << "): " << step.failure);
        if (step.outcome == trajectory::FlightOutcome::kLookAround)
          NODELET_WARN_STREAM(getName() << ": the start region cannot be left (" << report.path_expansions
                                        << " voxels reachable): looking around");
        else if (step.outcome == trajectory::FlightOutcome::kLookAtUnseen)
          NODELET_WARN_STREAM(getName() << ": the way to frontier " << target_frontier_
                                        << " leads through unseen space at (" << report.unseen_at->transpose()
                                        << "): looking there");
        else
          NODELET_WARN_STREAM(getName() << ": stopping; frontier " << target_frontier_ << " counts a failed attempt");
        break;
    }
    if (step.failsTarget()) failFrontier();
    publish(now, start_time, std::move(step.trajectory));
  }

  // The target's frontier counts a failed attempt (frontier_failed); wait for a new target.
  void failFrontier() {
    std_msgs::UInt32 failed;
    failed.data = target_frontier_;
    failed_pub_.publish(failed);
    target_.reset();
  }

  void publish(const ros::Time& now, const ros::Time& start_time, trajectory::Trajectory planned) {
    ros_traj::Trajectory t;
    static_cast<trajectory::Trajectory&>(t) = std::move(planned);
    t.id = ++trajectory_id_;
    t.start_time = start_time;
    current_ = t;
    bspline_pub_.publish(ros_traj::toMsg(t));
    sent_time_ = ros::Time::now();  // after planning: the server's reports are judged from here
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
  planning::AstarConfig astar_config_, scout_config_, coarse_config_;
  trajectory::TrajectoryPlannerConfig planner_;
  double rate_ = 10.0, odom_timeout_ = 0.5, drop_grace_ = 0.5, max_tracking_error_ = 1.0, max_input_speed_ = 20.0;
  double command_timeout_ = 0.1;  ///< s, planner/command_timeout
  std::string speed_limit_name_;  ///< planner/max_input_speed's full name, for the messages
  bool aborted_ = false;        ///< the status said FINISHED(aborted): no target is taken any more
  bool brake_pending_ = false;  ///< and the flight in progress is to brake at the next timer call
  bool from_odometry_ = false;  ///< the next plan starts from the odometry: it was far from the reference
  common::Vec3 odom_velocity_ = common::Vec3::Zero();  ///< world frame
  ros::Time odom_time_;   ///< when the last odometry arrived
  ros::Time odom_stamp_;  ///< when its pose held (its stamp, when plausible)
  bool odom_gap_ = false;
  std::string world_frame_;
  std::mutex mutex_;
  std::shared_ptr<ros_map::SharedMap> shared_;
  std::unique_ptr<planning::Astar> astar_, scout_, coarse_;
  std::optional<common::Vec3> odom_position_, target_;
  double odom_yaw_ = 0.0, target_yaw_ = 0.0;
  unsigned target_frontier_ = 0;
  std::uint32_t target_seq_ = 0;  ///< ViewpointPath::target_seq of the target
  bool target_changed_ = false;
  trajectory::TargetAttempts attempts_;  ///< looks, widened plans and scouts for this target (planForTarget())
  PositionCommand::ConstPtr command_;
  std::optional<ros_traj::Trajectory> current_;
  trajectory::SearchMemory search_memory_;  // flight searches that found no path lately
  std::int64_t trajectory_id_ = 0;
  ros::Time last_plan_;
  ros::Time sent_time_;  ///< when current_ was published
  ros::Publisher compute_pub_;
  ros::Publisher bspline_pub_, marker_pub_, failed_pub_;
  ros::Subscriber handle_sub_, odom_sub_, cmd_sub_, target_sub_, status_sub_;
  ros::Timer timer_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::TrajectoryPlanner, nodelet::Nodelet)
