// TrajectoryServer: samples the current B-spline trajectory into position commands at a
// fixed rate. In: bspline, odom. Out: position_cmd (go_feap/PositionCommand). Holds the
// position where the last trajectory ended, or where the vehicle was, when none is active. Before the
// first trajectory it sends nothing (the flight stack hovers the vehicle where the pilot took it), or,
// with server/hold_before_trajectory, holds the first pose.
// When odometry stops for longer than server/odom_timeout the current trajectory is dropped and the
// reference holds where it was, flagged ABORT until odometry is back; when the odometry lies farther than
// server/max_start_offset from the reference (a jump, a VIO re-initialised, a controller that lost it), it
// is dropped too and the reference holds where the vehicle is; a trajectory that arrives before odometry is
// back is refused (its start was checked against nothing but a stale pose), and the next one after resumes
// (the planner replans once odometry is back). A trajectory whose reference, when it is taken (now, or at its start if that is
// later), lies farther than server/max_start_offset from the vehicle's odometry is refused: the
// controller would chase a step that large at once (a stale trajectory from a bag, another planner, a
// start time long past). So is one whose control polygon moves faster than server/max_speed or
// accelerates harder than server/max_acceleration (corrupt: control points of 1e308 m, or a knot span so
// short that the reference would leap to the end at once), and one whose heading turns faster than
// server/max_yaw_rate.
// A trajectory whose start time lies ahead waits: the running one is followed until then (not a hold
// in place at speed), and its start is checked again against the odometry when it is taken over. A
// later trajectory replaces a waiting one; one that starts at once replaces both.
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>

#include <algorithm>
#include <mutex>
#include <optional>
#include <sstream>

#include "go_feap/PositionCommand.h"
#include "go_feap/common/config_groups.h"
#include "go_feap/ros/bspline_conversion.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/params.h"

namespace go_feap {

class TrajectoryServer : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros_params::ParamReader p(getPrivateNodeHandle());
    p.get("server/rate", rate_).get("server/odom_timeout", odom_timeout_).getFrame("world_frame", world_frame_);
    p.get("server/max_start_offset", max_start_offset_).get("server/max_start_yaw_offset", max_start_yaw_offset_);
    p.get("server/max_speed", max_speed_).get("server/max_acceleration", max_acceleration_);
    p.get("server/max_yaw_rate", max_yaw_rate_).get("server/hold_before_trajectory", hold_before_trajectory_);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    ros_params::requireOrThrow(std::isfinite(max_speed_) && max_speed_ > 0.0, getName(),
                               "parameter '" + p.fullName("server/max_speed") + "' must be > 0");
    ros_params::requireOrThrow(std::isfinite(max_acceleration_) && max_acceleration_ > 0.0, getName(),
                               "parameter '" + p.fullName("server/max_acceleration") + "' must be > 0");
    ros_params::requireOrThrow(std::isfinite(max_yaw_rate_) && max_yaw_rate_ > 0.0, getName(),
                               "parameter '" + p.fullName("server/max_yaw_rate") + "' must be > 0");
    ros_params::requireOrThrow(std::isfinite(max_start_offset_) && max_start_offset_ > 0.0, getName(),
                               "parameter '" + p.fullName("server/max_start_offset") + "' must be > 0");
    ros_params::requireOrThrow(max_start_yaw_offset_ > 0.0 && max_start_yaw_offset_ <= M_PI, getName(),
                               "parameter '" + p.fullName("server/max_start_yaw_offset") + "' must be in (0, pi] rad");
    ros_params::requireOrThrow(rate_ >= 10.0 && rate_ <= 1000.0, getName(),
                               "parameter '" + p.fullName("server/rate") + "' must be in [10, 1000] Hz");
    ros_params::requireOrThrow(std::isfinite(odom_timeout_) && odom_timeout_ > 0.0, getName(),
                               "parameter '" + p.fullName("server/odom_timeout") + "' must be > 0");
    // The planner's own limits, from the same trajectory.yaml: a server limit below one of them would
    // refuse every plan that uses it, and the vehicle would hold for good.
    trajectory::OptimizerConfig planner;
    config::readOptimizer(p, planner);
    double max_tracking_error = 0.0;
    p.get("planner/max_tracking_error", max_tracking_error);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    // The planner plans from its reference while the odometry is within max_tracking_error of it: a server
    // refusing starts nearer than that would refuse those plans, and the planner would plan them again for good.
    ros_params::requireOrThrow(max_start_offset_ > max_tracking_error, getName(),
                               "parameter '" + p.fullName("server/max_start_offset") + "' (" +
                                   std::to_string(max_start_offset_) + ") must be above '" +
                                   p.fullName("planner/max_tracking_error") + "' (" +
                                   std::to_string(max_tracking_error) + ")");
    const common::Status planner_ok = planner.validate();
    ros_params::requireOrThrow(planner_ok.ok(), getName(), planner_ok.message());
    // The server checks control polygons, the planner samples: a stop from a reference at the planner's
    // speed (trajectory::safeStop) has a polygon up to 4/3 faster than its start (m / (m - 1/2), m >= 2 spans).
    const double scale = 1.0 + planner.limit_tolerance;
    constexpr double kStopPolygon = 4.0 / 3.0;
    const struct {
      double limit, planner_limit, factor;
      const char *key, *planner_key;
    } pairs[] = {{max_speed_, planner.v_max, kStopPolygon, "server/max_speed", "optimizer/v_max"},
                 {max_acceleration_, planner.a_max, 1.0, "server/max_acceleration", "optimizer/a_max"},
                 {max_yaw_rate_, planner.yaw_rate_max, 1.0, "server/max_yaw_rate", "optimizer/yaw_rate_max"}};
    for (const auto& pair : pairs) {
      const double least = pair.planner_limit * scale * pair.factor;
      std::ostringstream why;
      why << "parameter '" << p.fullName(pair.key) << "' (" << pair.limit << ") is below " << least << ", the planner's '"
          << p.fullName(pair.planner_key) << "' (" << pair.planner_limit << ") with optimizer/limit_tolerance"
          << (pair.factor > 1.0 ? " and the 4/3 a braking plan's control polygon may reach" : "")
          << ": plans that reach it would be refused";
      ros_params::requireOrThrow(pair.limit >= least, getName(), why.str());
    }
    cmd_pub_ = nh.advertise<PositionCommand>("position_cmd", 10);
    bspline_sub_ = ros_guard::subscribe(nh, getName(), "bspline", 5, &TrajectoryServer::onBspline, this);
    odom_sub_ = ros_guard::subscribe(nh, getName(), "odom", 5, &TrajectoryServer::onOdom, this);
    timer_ = ros_guard::timer(nh, getName(), ros::Duration(1.0 / rate_), &TrajectoryServer::onTimer, this);
  }

  void onBspline(const Bspline::ConstPtr& msg) {
    auto t = ros_traj::fromMsg(*msg);
    std::lock_guard<std::mutex> lock(mutex_);
    if (!t) return refuse(msg->traj_id, t.message());
    std::string bad = ros_traj::motionProblem(*t, max_speed_, max_acceleration_, max_yaw_rate_);
    if (!bad.empty()) bad += " (server/max_speed, server/max_acceleration, server/max_yaw_rate)";
    const ros::Time now = ros::Time::now();
    const bool later = t->start_time > now;
    // One starting later is checked for where it starts when it is taken over (the vehicle goes on
    // along the running one until then: 1 s ahead at 2 m/s is 2 m from where it is now).
    if (bad.empty()) bad = startProblem(*t, now, /*where=*/!later);
    if (!bad.empty()) return refuse(msg->traj_id, bad);
    if (later) {
      pending_ = std::move(t).value();  // the running one goes on until it starts
    } else {
      current_ = std::move(t).value();
      pending_.reset();
    }
  }

  // The waiting trajectory, once its start time has come: it becomes the running one if its start still
  // lies near the odometry (the vehicle went on along the running one meanwhile).
  void takeOverPending(const ros::Time& now) {
    if (!pending_ || now < pending_->start_time) return;
    const std::string bad = startProblem(*pending_, now);
    if (bad.empty()) {
      current_ = std::move(pending_);
    } else {
      refuse(pending_->id, "at its start, " + bad);
    }
    pending_.reset();
  }

  // A trajectory refused: said, and the reference stays as it was. Once there is a hold, commands flow from
  // then on (a refused first trajectory is held where the vehicle is: its EMPTY flag tells the planner to plan
  // again).
  void refuse(std::int64_t id, const std::string& why) {
    GO_FEAP_NODELET_THROTTLE(WARN, 1.0, getName() << ": trajectory " << id << " refused: " << why
                                                << "; the reference stays as it was");
    commanding_ = commanding_ || hold_;
  }

  // Why a trajectory cannot be taken over at time `now` (s), or "" when it can: the odometry silent, or
  // (with `where`) its reference then too far from the odometry. In seconds as doubles: a start time is
  // the sender's, and ros::Time arithmetic throws beyond 2^31 s.
  std::string startProblem(const ros_traj::Trajectory& t, const ros::Time& now, bool where = true) const {
    if (!odom_position_) return "no odometry yet to check where it starts";
    // The gap is judged here too, not only by the timer: a trajectory planned just before the odometry
    // stopped may arrive after the timer dropped the last one, and would be flown blind to its end.
    const double odom_age = (now - last_odom_).toSec();
    if (odom_gap_ || odom_age > odom_timeout_) {
      std::ostringstream why;
      why << "no odometry for " << odom_age << " s (server/odom_timeout " << odom_timeout_ << " s)";
      return why.str();
    }
    if (!where) return "";
    const double from = std::max(0.0, now.toSec() - t.start_time.toSec());
    const trajectory::TrajectorySample sample = trajectory::sampleTrajectory(t, from);
    const double offset = (sample.position - *odom_position_).norm();
    if (!(offset <= max_start_offset_)) {
      std::ostringstream why;
      why << "its reference " << from << " s after its start is " << offset << " m from the odometry (more than "
          << "server/max_start_offset " << max_start_offset_ << " m)";
      return why.str();
    }
    // Likewise its heading: the controller would spin the vehicle round at once.
    const double turn = std::abs(std::remainder(sample.yaw - odom_yaw_, 2.0 * M_PI));
    if (!(turn <= max_start_yaw_offset_)) {
      std::ostringstream why;
      why << "its heading " << from << " s after its start is " << turn << " rad from the odometry's (more than "
          << "server/max_start_yaw_offset " << max_start_yaw_offset_ << " rad)";
      return why.str();
    }
    return "";
  }

  void onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
    const std::string bad = ros_conv::odometryPoseProblem(*msg, world_frame_);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": odometry refused: " << bad);
      return;
    }
    const auto& p = msg->pose.pose.position;
    const auto& q = msg->pose.pose.orientation;
    std::lock_guard<std::mutex> lock(mutex_);
    last_odom_ = ros::Time::now();
    odom_position_ = Eigen::Vector3d(p.x, p.y, p.z);
    odom_yaw_ = ros_conv::yawOf(q);
    if (odom_gap_) {
      // Held where the odometry is now, not where the reference was before the gap: the vehicle flew
      // blind meanwhile, or its odometry came back in another place (a VIO re-initialised), and the old
      // reference would pull it there at once (the planner's next plans start from the held command).
      odom_gap_ = false;
      hold_ = false;
      NODELET_WARN_STREAM(getName() << ": odometry is back, " << (*odom_position_ - hold_position_).norm()
                                    << " m from the held reference; holding there, following the next trajectory");
    }
    if (!hold_ || (!commanding_ && !hold_before_trajectory_)) {
      // The first pose, or the first after a gap: held until a trajectory arrives. Before any command is
      // sent (server/hold_before_trajectory false) the hold follows the vehicle, wherever the pilot takes
      // it, so that a hold sent after a refused first trajectory is where the vehicle is.
      hold_position_ = Eigen::Vector3d(p.x, p.y, p.z);
      hold_yaw_ = ros_conv::yawOf(q);
      hold_ = true;
    } else if (const double off = (*odom_position_ - hold_position_).norm(); off > max_start_offset_) {
      // The vehicle is farther than server/max_start_offset from the reference last sent (its odometry
      // jumped, a VIO re-initialised, it was moved by hand, or the controller lost the trajectory): held
      // where it is now, the trajectory dropped, running or ended. The old reference pulled it the whole way
      // at once, into space nothing had checked, and every plan starting from that command was refused as
      // starting too far from the odometry. An ended trajectory stays the current one (its end is held,
      // COMPLETED): this was only checked with none, so a jump after the first flight, or while hovering
      // after a stop, was chased.
      std::ostringstream what;
      if (current_) what << " of trajectory " << current_->id;
      NODELET_WARN_STREAM(getName() << ": the vehicle is " << off << " m from the reference" << what.str()
                                    << " (more than server/max_start_offset " << max_start_offset_ << " m): "
                                    << (current_ ? "trajectory dropped, " : "") << "holding where it is");
      current_.reset();
      hold_position_ = *odom_position_;
      hold_yaw_ = ros_conv::yawOf(q);
    }
  }

  void onTimer(const ros::TimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    const ros::Time now = ros::Time::now();
    // A clock that went back (a bag played again, a simulator restarted): the trajectories' times are void.
    // Kept, one started over once the clock came back to its start, from where the vehicle had been, with
    // none of the checks a trajectory taken over gets.
    if (!last_tick_.isZero() && now < last_tick_ && (current_ || pending_)) {
      current_.reset();
      pending_.reset();
      NODELET_WARN_STREAM(getName() << ": the clock went back " << (last_tick_ - now).toSec()
                                    << " s: trajectory dropped, holding the last reference");
    }
    last_tick_ = now;
    if (!last_odom_.isZero() && !odom_gap_ && (now - last_odom_).toSec() > odom_timeout_) {
      odom_gap_ = true;
      current_.reset();  // hold_position_ is where the reference was
      pending_.reset();
      NODELET_WARN_STREAM(getName() << ": no odometry for " << (now - last_odom_).toSec()
                                    << " s: trajectory dropped, holding position");
    }
    takeOverPending(now);
    PositionCommand cmd;
    cmd.header.stamp = now;
    cmd.header.frame_id = world_frame_;
    Eigen::Vector3d p, v = Eigen::Vector3d::Zero(), a = Eigen::Vector3d::Zero();
    double yaw = hold_yaw_, yaw_dot = 0.0;
    if (current_ && now >= current_->start_time) {
      const trajectory::TrajectorySample sample =
          trajectory::sampleTrajectory(*current_, now.toSec() - current_->start_time.toSec());
      p = sample.position, v = sample.velocity, a = sample.acceleration;
      yaw = sample.yaw, yaw_dot = sample.yaw_dot;
      cmd.trajectory_flag = sample.completed ? PositionCommand::TRAJECTORY_STATUS_COMPLETED
                                             : PositionCommand::TRAJECTORY_STATUS_READY;
      cmd.trajectory_id = static_cast<std::uint32_t>(current_->id);
      hold_position_ = p;  // where to hold if the trajectory is dropped
      hold_yaw_ = yaw;
      commanding_ = true;
    } else if (hold_ && (commanding_ || hold_before_trajectory_)) {
      p = hold_position_;
      // Through an odometry gap the hold is ABORT: the vehicle is held blind, and a bridge can tell that from
      // a hold at rest (EMPTY) and act on it (its own position hold, a landing); as EMPTY it could not.
      cmd.trajectory_flag =
          odom_gap_ ? PositionCommand::TRAJECTORY_STATUS_ABORT : PositionCommand::TRAJECTORY_STATUS_EMPTY;
    } else {
      // Nothing known yet, or no trajectory flown yet: a hold of the pose at launch, on the ground, would
      // pull a vehicle the pilot then took off by hand back down when the bridge took the commands, and the
      // first plan would start from it.
      return;
    }
    cmd.position.x = p.x(), cmd.position.y = p.y(), cmd.position.z = p.z();
    cmd.velocity.x = v.x(), cmd.velocity.y = v.y(), cmd.velocity.z = v.z();
    cmd.acceleration.x = a.x(), cmd.acceleration.y = a.y(), cmd.acceleration.z = a.z();
    cmd.yaw = std::atan2(std::sin(yaw), std::cos(yaw));
    cmd.yaw_dot = yaw_dot;
    cmd_pub_.publish(cmd);
  }

  double rate_ = 100.0, odom_timeout_ = 0.5, max_start_offset_ = 1.5, max_speed_ = 30.0, max_acceleration_ = 50.0,
         max_yaw_rate_ = 20.0;
  ros::Time last_odom_;
  ros::Time last_tick_;  ///< the clock at the last timer call
  std::optional<Eigen::Vector3d> odom_position_;  ///< m, of the latest usable odometry
  double odom_yaw_ = 0.0;                         ///< rad, its heading
  double max_start_yaw_offset_ = 1.0;
  bool odom_gap_ = false;
  std::string world_frame_;
  std::mutex mutex_;
  std::optional<ros_traj::Trajectory> current_;
  std::optional<ros_traj::Trajectory> pending_;  ///< received, its start time still ahead
  bool hold_ = false;
  bool hold_before_trajectory_ = false;
  /// A trajectory has been followed, or refused: commands flow from then on (a planner whose first
  /// trajectory was refused learns it from the hold's EMPTY flag, and plans again)
  bool commanding_ = false;
  Eigen::Vector3d hold_position_ = Eigen::Vector3d::Zero();
  double hold_yaw_ = 0.0;
  ros::Publisher cmd_pub_;
  ros::Subscriber bspline_sub_, odom_sub_;
  ros::Timer timer_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::TrajectoryServer, nodelet::Nodelet)
