// QuadrotorSim: flies the simulated vehicle. position_cmd in; odom, TF world->body and
// /clock out, at a configurable real-time factor.
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <tf2_ros/transform_broadcaster.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <mutex>
#include <thread>

#include "go_feap/PositionCommand.h"
#include "go_feap/common/config_groups.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/message_checks.h"
#include "go_feap/ros/params.h"
#include "go_feap/sim/pacer.h"
#include "go_feap/sim/vehicle.h"
#include "go_feap/world/scene.h"

namespace go_feap {

class QuadrotorSim : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
 public:
  ~QuadrotorSim() override {
    running_ = false;
    if (thread_.joinable()) thread_.join();
  }

 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    const std::string me = getName();
    ros_params::ParamReader p(pnh);
    sim::QuadrotorParams q;
    config::readQuadrotor(p, q);
    sim::So3ControllerConfig c;
    config::readController(p, c);
    p.get("simulation/rate_factor", rate_factor_).get("simulation/odom_rate", odom_rate_);
    p.get("simulation/command_timeout", command_timeout_).get("simulation/publish_clock", publish_clock_);
    p.get("simulation/max_command_acceleration", max_cmd_acc_).get("simulation/max_command_outside", max_cmd_out_);
    p.get("simulation/max_command_speed", max_cmd_speed_).get("simulation/max_command_yaw_rate", max_cmd_yaw_rate_);
    p.getFrame("simulation/world_frame", world_frame_).getFrame("simulation/body_frame", body_frame_);
    bool use_scene_start = true;
    Eigen::Vector3d start;
    double start_yaw = 0.0;
    p.get("use_scene_start", use_scene_start).getVec3("start", start).get("start_yaw", start_yaw);
    ros_params::requireOrThrow(p.ok(), me, p.error());
    for (const common::Status& st : {q.validate(), c.validate()}) ros_params::requireOrThrow(st.ok(), me, st.message());
    ros_params::requireOrThrow(world_frame_ != body_frame_, me,
                               "parameter '" + p.fullName("simulation/body_frame") + "' must differ from '" +
                                   p.fullName("simulation/world_frame") + "' (a TF from a frame to itself)");
    // At least 0.01: at 1e-9 the first step would wait 1e7 s of wall time, the clock standing still.
    ros_params::requireOrThrow(rate_factor_ >= 0.01 && rate_factor_ <= 1000.0, me,
                               "parameter '" + p.fullName("simulation/rate_factor") + "' must be in [0.01, 1000]");
    // NaN would switch the command checks off (no norm is > NaN), and a limit of 1e308 would let through the
    // commands they guard against (the controller's gains times 1e308 m/s overflow, its thrust goes NaN).
    ros_params::requireOrThrow(max_cmd_acc_ > 0.0 && max_cmd_acc_ <= 1000.0, me,
                               "parameter '" + p.fullName("simulation/max_command_acceleration") + "' must be in (0, 1000]");
    ros_params::requireOrThrow(max_cmd_speed_ > 0.0 && max_cmd_speed_ <= 1000.0, me,
                               "parameter '" + p.fullName("simulation/max_command_speed") + "' must be in (0, 1000]");
    ros_params::requireOrThrow(max_cmd_yaw_rate_ > 0.0 && max_cmd_yaw_rate_ <= 100.0, me,
                               "parameter '" + p.fullName("simulation/max_command_yaw_rate") + "' must be in (0, 100]");
    ros_params::requireOrThrow(max_cmd_out_ >= 0.0 && max_cmd_out_ <= 1000.0, me,
                               "parameter '" + p.fullName("simulation/max_command_outside") + "' must be in [0, 1000]");
    ros_params::requireOrThrow(odom_rate_ >= 10.0 && odom_rate_ <= q.dynamics_rate, me,
                               "parameter '" + p.fullName("simulation/odom_rate") + "' must be in [10, dynamics_rate]");
    ros_params::requireOrThrow(std::isfinite(command_timeout_) && command_timeout_ > 0.0, me,
                               "parameter '" + p.fullName("simulation/command_timeout") + "' must be > 0");
    ros_params::requireOrThrow(publish_clock_ || rate_factor_ == 1.0, me,
                               "parameter '" + p.fullName("simulation/rate_factor") +
                                   "' must be 1 unless simulation/publish_clock is true");

    const world::Scene scene = ros_params::loadScene(pnh, me);
    bounds_ = scene.box;
    if (use_scene_start) {
      start = scene.start.position;
      start_yaw = scene.start.yaw;
    } else {  // a start of its own: finite, in the scene's box and not inside an obstacle
      ros_params::requireOrThrow(start.allFinite() && std::isfinite(start_yaw), me,
                                 "parameters '" + p.fullName("start") + "' and '" + p.fullName("start_yaw") +
                                     "' must be finite");
      ros_params::requireOrThrow(scene.box.contains(start) && !scene.isOccupied(start), me,
                                 "parameter '" + p.fullName("start") + "' must lie in the scene's box, in free space");
    }
    vehicle_ = std::make_unique<sim::SimulatedVehicle>(q, c);
    vehicle_->reset(start, start_yaw);
    hold_.position = start;
    hold_.yaw = start_yaw;
    command_ = hold_;

    // A second of odometry per subscriber link: a subscriber in another process that reads late on a loaded
    // machine gets every message instead of losing all but the last 10 (0.1 s at 100 Hz).
    odom_pub_ = nh.advertise<nav_msgs::Odometry>("odom", 100);
    if (publish_clock_) clock_pub_ = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
    cmd_sub_ = ros_guard::subscribe(nh, getName(), "position_cmd", 10, &QuadrotorSim::onCommand, this, ros::TransportHints().tcpNoDelay());
    NODELET_INFO_STREAM(me << ": vehicle at (" << start.transpose() << "), yaw " << start_yaw << ", scene '"
                           << scene.name << "', rate factor " << rate_factor_);
    running_ = true;
    // An exception escaping a thread ends the process: here it ends the simulation, logged, and the
    // nodelets in the manager keep what they have (the odometry timeouts then hold the chain).
    thread_ = std::thread([this] { ros_guard::run(getName(), "the simulation thread", log_throttle_, [this] { loop(); }); });
  }

  void onCommand(const PositionCommand::ConstPtr& msg) {
    sim::PositionReference ref;
    ref.position = Eigen::Vector3d(msg->position.x, msg->position.y, msg->position.z);
    ref.velocity = Eigen::Vector3d(msg->velocity.x, msg->velocity.y, msg->velocity.z);
    ref.acceleration = Eigen::Vector3d(msg->acceleration.x, msg->acceleration.y, msg->acceleration.z);
    ref.yaw = msg->yaw;
    ref.yaw_dot = msg->yaw_dot;
    // A command in another frame (a planner on 'map' or 'odom') used to be flown as if in the world frame.
    std::string bad = ros_check::positionCommandProblem(*msg, world_frame_);
    if (bad.empty())
      bad = sim::checkReference(ref, bounds_, max_cmd_acc_, max_cmd_out_, max_cmd_speed_, max_cmd_yaw_rate_).message();
    std::lock_guard<std::mutex> lock(mutex_);
    if (!bad.empty()) {
      ++refused_;
      GO_FEAP_NODELET_THROTTLE(WARN, 1.0, getName() << ": refused " << refused_ << " position_cmd so far (latest: "
                                                  << bad << "); holding the last valid command");
      return;
    }
    command_ = ref;
    last_command_time_ = sim_time_;
    have_command_ = true;
    timed_out_ = false;
  }

  // Simulation thread: advances in odom periods, then waits for wall time to catch up (driving /clock), or
  // for the ROS clock (without publish_clock: wall time, or another simulator's /clock).
  void loop() {
    const double period = 1.0 / odom_rate_;
    if (!publish_clock_)  // under use_sim_time the clock reads 0 until its first /clock
      while (ros::Time::now().isZero() && running_ && ros::ok()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const ros::Time origin = publish_clock_ ? ros::Time(1.0) : ros::Time::now();
    const auto wall_start = std::chrono::steady_clock::now();
    auto wall_at = [&](double wall) {
      return wall_start +
             std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(wall));
    };
    sim::WallPacer pacer(rate_factor_, kMaxLag);
    double t = 0.0, report_t = 0.0;
    auto report_wall = wall_start;
    publishClock(origin);
    bool diverged = false;
    while (running_ && ros::ok()) {
      if (diverged) {  // the clock only: every timeout of the chain runs on it
        t += period;
        publishClock(origin + ros::Duration(t));
        waitFor(origin + ros::Duration(t), wall_at(pacer.due(t)));
        continue;
      }
      sim::PositionReference ref;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (have_command_ && t - last_command_time_ > command_timeout_ && !timed_out_) {
          timed_out_ = true;
          hold_ = sim::PositionReference();
          hold_.position = vehicle_->state().position;
          hold_.yaw = vehicle_->state().heading();
          NODELET_WARN_STREAM(getName() << ": no position_cmd for " << command_timeout_
                                        << " s; hovering in place until one arrives");
        }
        ref = (!have_command_ || timed_out_) ? hold_ : command_;
      }
      vehicle_->advance(period, ref);
      if (!vehicle_->state().finite()) {
        // Nothing to publish from: the odometry stops and the chain holds what it has. /clock goes on (when
        // this nodelet drives it), or every timeout on simulated time (the odometry's, the run's time limit)
        // would wait for ever and the run would hang instead of ending.
        NODELET_ERROR_STREAM(getName() << ": the simulated vehicle's state is not finite after " << t
                                       << " s: the dynamics diverged (quadrotor/inertia, controller gains and "
                                          "quadrotor/dynamics_rate); the simulation stops"
                                       << (publish_clock_ ? " (the clock goes on)" : ""));
        diverged = true;
        continue;
      }
      t += period;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        sim_time_ = t;
      }
      const ros::Time stamp = origin + ros::Duration(t);
      publishClock(stamp);
      publishState(stamp);

      waitFor(stamp, wall_at(pacer.due(t)));
      const auto now = std::chrono::steady_clock::now();
      if (const double dropped = pacer.settle(t, std::chrono::duration<double>(now - wall_start).count());
          publish_clock_ && dropped > 0.0)
        GO_FEAP_NODELET_THROTTLE(WARN, 10.0, getName() << ": the simulation fell " << dropped << " s behind wall time"
                                                       << " at " << t << " s (a loaded machine); going on from there"
                                                       << " at the rate factor, not faster to catch up");
      const double wall = std::chrono::duration<double>(now - report_wall).count();
      if (wall >= 10.0) {
        NODELET_INFO_STREAM(getName() << ": achieved real-time factor " << (t - report_t) / wall << " (wanted "
                                      << rate_factor_ << ")");
        report_t = t;
        report_wall = now;
      }
    }
  }

  // Sleeps until `target` in slices, so that unloading (running_ false) or shutdown never waits out a long
  // step (a rate factor of 1e-3 made each 0.01 s step 10 s of wall time).
  // s of wall time the simulation may fall behind before the lag is dropped rather than caught up (a fifth of
  // a second: planners compute on wall time, and the commands time out after simulation/command_timeout).
  static constexpr double kMaxLag = 0.2;

  // Until the simulation's next step is due: at `wall` when this simulator drives the clock, else when the ROS
  // clock reaches `stamp` (stamps from a wall-paced origin drifted off another simulator's /clock: at its rate
  // factor 2, half as fast).
  void waitFor(const ros::Time& stamp, std::chrono::steady_clock::time_point wall) const {
    if (publish_clock_) return waitUntil(wall);
    while (ros::Time::now() < stamp && running_ && ros::ok()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }

  template <typename TimePoint>
  void waitUntil(TimePoint target) const {
    constexpr auto kSlice = std::chrono::milliseconds(50);
    for (auto now = std::chrono::steady_clock::now(); now < target && running_ && ros::ok();
         now = std::chrono::steady_clock::now())
      std::this_thread::sleep_for(
          std::min(std::chrono::duration_cast<std::chrono::steady_clock::duration>(target - now) +
                       std::chrono::steady_clock::duration(1),
                   std::chrono::duration_cast<std::chrono::steady_clock::duration>(kSlice)));
  }

  void publishClock(const ros::Time& stamp) {
    if (!publish_clock_) return;
    rosgraph_msgs::Clock clock;
    clock.clock = stamp;
    clock_pub_.publish(clock);
  }

  void publishState(const ros::Time& stamp) {
    const sim::QuadrotorState& s = vehicle_->state();
    nav_msgs::Odometry odom;
    odom.header.stamp = stamp;
    odom.header.frame_id = world_frame_;
    odom.child_frame_id = body_frame_;
    odom.pose.pose.position.x = s.position.x();
    odom.pose.pose.position.y = s.position.y();
    odom.pose.pose.position.z = s.position.z();
    odom.pose.pose.orientation.w = s.attitude.w();
    odom.pose.pose.orientation.x = s.attitude.x();
    odom.pose.pose.orientation.y = s.attitude.y();
    odom.pose.pose.orientation.z = s.attitude.z();
    // nav_msgs/Odometry: twist in the child (body) frame.
    const Eigen::Vector3d v_body = s.attitude.inverse() * s.velocity;
    odom.twist.twist.linear.x = v_body.x();
    odom.twist.twist.linear.y = v_body.y();
    odom.twist.twist.linear.z = v_body.z();
    odom.twist.twist.angular.x = s.angular_velocity.x();
    odom.twist.twist.angular.y = s.angular_velocity.y();
    odom.twist.twist.angular.z = s.angular_velocity.z();
    odom_pub_.publish(odom);

    geometry_msgs::TransformStamped tf;
    tf.header = odom.header;
    tf.child_frame_id = body_frame_;
    tf.transform.translation.x = s.position.x();
    tf.transform.translation.y = s.position.y();
    tf.transform.translation.z = s.position.z();
    tf.transform.rotation = odom.pose.pose.orientation;
    tf_broadcaster_.sendTransform(tf);
  }

  // Configuration.
  double rate_factor_ = 1.0, odom_rate_ = 100.0, command_timeout_ = 0.5;
  double max_cmd_acc_ = 50.0, max_cmd_out_ = 10.0, max_cmd_speed_ = 20.0, max_cmd_yaw_rate_ = 20.0;
  bool publish_clock_ = true;
  std::string world_frame_, body_frame_;
  common::Aabb bounds_;
  // State shared between the command callback and the simulation thread.
  std::mutex mutex_;
  sim::PositionReference command_, hold_;
  bool have_command_ = false, timed_out_ = false;
  double last_command_time_ = 0.0, sim_time_ = 0.0;
  std::size_t refused_ = 0;
  // Simulation thread only.
  std::unique_ptr<sim::SimulatedVehicle> vehicle_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  ros::Publisher odom_pub_, clock_pub_;
  ros::Subscriber cmd_sub_;
  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::QuadrotorSim, nodelet::Nodelet)
