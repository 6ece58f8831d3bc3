// rostest: the TrajectoryPlanner nodelet's rule for a new target. The local planner numbers the
// targets it commits to (ViewpointPath::target_seq) and judges one reached by its own pose, so a
// newly numbered target is flown to exactly, even 0.2 m from the last one (inside the distance
// tolerance). A repeat of the same number, or an unnumbered target inside the tolerances, is not
// a new target: no new trajectory.
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Log.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "go_feap/Bspline.h"
#include "go_feap/ExplorationStatus.h"
#include "go_feap/PositionCommand.h"
#include "go_feap/ViewpointPath.h"
#include "go_feap/ros/bspline_conversion.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/world/scene_files.h"
#include "flight_util.h"
#include "ros_test_util.h"

namespace {

using go_feap::common::Vec3;
using go_feap::test::latticeClearance;
using go_feap::test::Every;
using go_feap::test::spinSimUntil;
using go_feap::test::spinUntil;

class TrajectoryTargetTest : public ::testing::Test {
 protected:
  void SetUp() override {
    auto scene = go_feap::test::sceneFromParams();
    ASSERT_TRUE(scene) << scene.message();
    start_ = scene->start.position;
    yaw_ = scene->start.yaw;
    forward_ = Vec3(std::cos(yaw_), std::sin(yaw_), 0.0);
    // The fixture's precondition: open space ahead of the start, in the camera's first view.
    for (double s = 0.0; s <= 2.0; s += 0.1)
      ASSERT_GT(latticeClearance(*scene, start_ + s * forward_, 0.5), 0.45) << "no open space ahead at " << s << " m";
    target_pub_ = nh_.advertise<go_feap::ViewpointPath>("local_target", 5);
    odom_sub_ = nh_.subscribe("odom", 20, &TrajectoryTargetTest::onOdom, this);
    bspline_sub_ = nh_.subscribe("bspline", 20, &TrajectoryTargetTest::onBspline, this);
    foreign_pub_ = nh_.advertise<go_feap::Bspline>("bspline", 5);
  }
  void onOdom(const nav_msgs::Odometry::ConstPtr& m) {
    const auto& p = m->pose.pose.position;
    const auto& v = m->twist.twist.linear;
    position_ = Vec3(p.x, p.y, p.z);
    speed_ = Vec3(v.x, v.y, v.z).norm();
  }
  void onBspline(const go_feap::Bspline::ConstPtr& m) {
    if (m->traj_id >= kForeignIds) return;  // this test's own
    auto t = go_feap::ros_traj::fromMsg(*m);
    ASSERT_TRUE(t) << t.message();
    ++trajectories_;
    last_ = m;
    end_ = t->position.position(t->position.duration());
  }
  go_feap::ViewpointPath target(const Vec3& p, std::uint32_t seq) const {
    go_feap::ViewpointPath m;
    m.header.stamp = ros::Time::now();
    m.header.frame_id = "world";
    geometry_msgs::Point q;
    q.x = p.x(), q.y = p.y(), q.z = p.z();
    m.positions.push_back(q);
    m.yaws.push_back(yaw_);
    m.frontier_ids.push_back(7);
    m.target_seq = seq;
    return m;
  }
  // Publishes the target at 5 Hz (the local planner repeats a kept one) while spinning for
  // `sim_seconds` of simulated time, or until `until()` holds; returns until().
  template <typename Until>
  bool publishWhile(const go_feap::ViewpointPath& m, double sim_seconds, Until until) {
    Every target(0.2);
    return spinSimUntil(
        sim_seconds, [&] { if (target.due()) target_pub_.publish(m); }, until);
  }
  bool atRestNear(const Vec3& p) const { return (position_ - p).norm() < 0.08 && speed_ < 0.1; }

  static constexpr std::int64_t kForeignIds = 1000000;  ///< trajectory ids from here on are this test's
  ros::NodeHandle nh_;
  ros::Publisher target_pub_, foreign_pub_;
  go_feap::Bspline::ConstPtr last_;  ///< the planner's last trajectory
  ros::Subscriber odom_sub_, bspline_sub_;
  Vec3 start_, forward_, position_ = Vec3::Constant(1e9), end_ = Vec3::Constant(1e9);
  double yaw_ = 0.0, speed_ = 0.0;
  int trajectories_ = 0;
};

TEST_F(TrajectoryTargetTest, ANewlyNumberedTargetIsFlownToExactlyEvenNearTheLastOne) {
  // Connected both ways before the first target: a trajectory published before the bspline subscription
  // is connected would be flown but never seen here (a loaded machine can take that long).
  ASSERT_TRUE(spinUntil(
      [&] {
        return position_.x() < 1e8 && ros::Time::now().toSec() > 3.0 && bspline_sub_.getNumPublishers() > 0 &&
               target_pub_.getNumSubscribers() > 0;
      },
      60.0))
      << "no odometry, or the trajectory planner is not connected";
  // Targets at voxel centres (the planner's goal is its voxel's centre), 0.2 m apart.
  double resolution = 0.0;
  ASSERT_TRUE(ros::param::get("/esdf_mapper/occupancy/resolution", resolution) && resolution > 0.0);
  const auto centre = [&](const Vec3& p) { return Vec3(((p / resolution).array().floor() + 0.5) * resolution); };
  const Vec3 t1 = centre(start_ + 1.0 * forward_), t2 = centre(t1 + 0.2 * forward_), t3 = centre(t2 + 0.2 * forward_);

  // Malformed targets (no heading for the viewpoint; a position not finite; no viewpoint at all, a default
  // message) are refused: nothing is planned, and the planner stays up for the next (a missing heading was
  // read past the end of its array).
  go_feap::ViewpointPath no_yaw = target(t1, 1);
  no_yaw.yaws.clear();
  go_feap::ViewpointPath not_finite = target(t1, 1);
  not_finite.positions.front().y = std::numeric_limits<double>::quiet_NaN();
  go_feap::ViewpointPath empty = target(t1, 1);
  empty.positions.clear(), empty.yaws.clear(), empty.frontier_ids.clear();
  publishWhile(no_yaw, 1.0, [] { return false; });
  publishWhile(not_finite, 1.0, [] { return false; });
  publishWhile(empty, 1.0, [] { return false; });
  EXPECT_EQ(trajectories_, 0);

  // Target 1, repeated as a kept target is: one trajectory there, and the vehicle arrives.
  ASSERT_TRUE(publishWhile(target(t1, 1), 20.0, [&] { return atRestNear(t1); }))
      << "not at target 1; vehicle at " << position_.transpose() << ", " << trajectories_ << " trajectories";
  EXPECT_LT((end_ - t1).norm(), 0.01);
  const int after_t1 = trajectories_;

  // Target 2, numbered anew, 0.2 m on: inside the 0.3 m tolerance, yet a new trajectory ends there.
  ASSERT_TRUE(publishWhile(target(t2, 2), 20.0, [&] { return atRestNear(t2); }))
      << "not at target 2; vehicle at " << position_.transpose() << ", trajectory ends at " << end_.transpose();
  EXPECT_GT(trajectories_, after_t1);
  EXPECT_LT((end_ - t2).norm(), 0.01);

  // A repeat of number 2, then an unnumbered target 0.2 m on: neither is a new target.
  const int after_t2 = trajectories_;
  publishWhile(target(t2, 2), 2.0, [] { return false; });
  publishWhile(target(t3, 0), 2.0, [] { return false; });
  EXPECT_EQ(trajectories_, after_t2);
  EXPECT_LT((end_ - t2).norm(), 0.01);

  // Numbered, the same point is a new target.
  ASSERT_TRUE(publishWhile(target(t3, 3), 20.0, [&] { return atRestNear(t3); }))
      << "not at target 3; vehicle at " << position_.transpose();
  EXPECT_LT((end_ - t3).norm(), 0.01);
}

// The server follows a trajectory the planner did not send (as after an odometry gap only the server saw,
// when it drops the planner's and holds): the planner, whose trajectory ends at the target and so would
// never be replanned, sees that in position_cmd and plans again; the vehicle arrives. Runs after the test
// above (gtest keeps the order): the vehicle starts where that one left it.
TEST_F(TrajectoryTargetTest, ATrajectoryTheServerDroppedIsPlannedAgain) {
  ASSERT_TRUE(spinUntil(
      [&] {
        return position_.x() < 1e8 && ros::Time::now().toSec() > 3.0 && bspline_sub_.getNumPublishers() > 0 &&
               target_pub_.getNumSubscribers() > 0 && foreign_pub_.getNumSubscribers() >= 2 && speed_ < 0.1;
      },
      60.0))
      << "no odometry, or the trajectory planner or server is not connected";
  double resolution = 0.0;
  ASSERT_TRUE(ros::param::get("/esdf_mapper/occupancy/resolution", resolution) && resolution > 0.0);
  // Target 1 of the test above, 0.4 m behind the vehicle: flown to exactly there.
  const Vec3 goal = Vec3((((start_ + 1.0 * forward_) / resolution).array().floor() + 0.5) * resolution);
  ASSERT_GT((position_ - goal).norm(), 0.3);
  const int before = trajectories_;
  ASSERT_TRUE(publishWhile(target(goal, 40), 5.0, [&] { return trajectories_ > before; })) << "no trajectory planned";
  // The planner's trajectory is replaced at the server by one holding where the vehicle is.
  go_feap::Bspline hold = *last_;
  hold.traj_id = kForeignIds + last_->traj_id;
  hold.start_time = ros::Time::now();
  for (auto& q : hold.pos_pts) q.x = position_.x(), q.y = position_.y(), q.z = position_.z();
  for (double& y : hold.yaw_pts) y = last_->yaw_pts.front();
  foreign_pub_.publish(hold);
  const Vec3 held = position_;
  // The target repeated as a kept one is: only a new plan brings the vehicle there.
  ASSERT_TRUE(publishWhile(target(goal, 40), 20.0, [&] { return atRestNear(goal); }))
      << "not at the target; vehicle at " << position_.transpose() << " at " << speed_ << " m/s (held at " << held.transpose() << "), "
      << trajectories_ - before << " trajectories planned, the last ending at " << end_.transpose() << "; target " << goal.transpose();
  EXPECT_GE(trajectories_ - before, 2);
}

// A second trajectory planner (probe/jump/...) fed only by this test, which plays both the vehicle
// (odometry) and the server (position_cmd following the planner's trajectory). While the odometry stays
// on the reference nothing is replanned; when the odometry jumps 1.5 m away (a relocalisation) the
// planner drops its trajectory and plans the next from the odometry's pose and velocity, not from the
// reference (which the controller would otherwise chase across the whole gap at once).
TEST_F(TrajectoryTargetTest, AnOdometryJumpAwayFromTheReferenceIsPlannedFromTheOdometry) {
  auto odom_pub = nh_.advertise<nav_msgs::Odometry>("probe/jump/odom", 10);
  auto cmd_pub = nh_.advertise<go_feap::PositionCommand>("probe/jump/position_cmd", 10);
  auto target_pub = nh_.advertise<go_feap::ViewpointPath>("probe/jump/local_target", 5);
  std::vector<go_feap::ros_traj::Trajectory> planned;
  std::vector<double> received;  // when each arrived (simulated time)
  auto bspline_sub = nh_.subscribe<go_feap::Bspline>("probe/jump/bspline", 20, [&](const go_feap::Bspline::ConstPtr& m) {
    auto t = go_feap::ros_traj::fromMsg(*m);
    ASSERT_TRUE(t) << t.message();
    planned.push_back(*t);
    received.push_back(ros::Time::now().toSec());
  });
  // The probe planner saying it has had no odometry (this test held up past the timeout).
  bool gap = false;
  std::vector<std::string> refusals;  // the probe planner's
  auto log_sub = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    gap = gap || (m->msg.find("probe_jump_planner: no odometry for") != std::string::npos);
    if (m->msg.find("probe_jump_planner:") != std::string::npos && m->msg.find(" refused: ") != std::string::npos)
      refusals.push_back(m->msg);
  });
  ASSERT_TRUE(spinUntil(
      [&] {
        return position_.x() < 1e8 && odom_pub.getNumSubscribers() > 0 && cmd_pub.getNumSubscribers() > 0 &&
               target_pub.getNumSubscribers() > 0 && bspline_sub.getNumPublishers() > 0 && speed_ < 0.1;
      },
      60.0))
      << "the probe planner is not connected";
  // Where the real vehicle is: seen all round by the tests above, so the probe plans in known space.
  const Vec3 here = position_;
  // The probe vehicle's odometry: level, heading 0.9 rad, its velocity (0.4, 0, 0) in the world given in the
  // body frame (child_frame_id), as nav_msgs/Odometry defines it: a plan from the odometry starts at the
  // world velocity, the body's turned by the heading.
  Vec3 pose = here, velocity = Vec3(0.4, 0.0, 0.0);
  const double heading = 0.9;
  double odometry_age = 0.0;        // s, how old each odometry message is stamped when sent (a VIO's latency)
  std::vector<double> odom_stamps;  // every odometry stamp sent
  auto odometry = [&] {
    nav_msgs::Odometry m;
    m.header.stamp = ros::Time::now() - ros::Duration(odometry_age);
    odom_stamps.push_back(m.header.stamp.toSec());
    m.header.frame_id = "world";
    m.child_frame_id = "probe_body";
    m.pose.pose.position.x = pose.x(), m.pose.pose.position.y = pose.y(), m.pose.pose.position.z = pose.z();
    m.pose.pose.orientation.w = std::cos(0.5 * heading), m.pose.pose.orientation.z = std::sin(0.5 * heading);
    const Vec3 body = Eigen::AngleAxisd(-heading, Vec3::UnitZ()) * velocity;
    m.twist.twist.linear.x = body.x(), m.twist.twist.linear.y = body.y(), m.twist.twist.linear.z = body.z();
    return m;
  };
  // The server's command: the reference of the planner's last trajectory, at rest at its start.
  auto command = [&] {
    go_feap::PositionCommand m;
    m.header.stamp = ros::Time::now();
    m.header.frame_id = "world";
    const Vec3 p = go_feap::trajectory::sampleTrajectory(planned.back(), 0.0).position;
    m.position.x = p.x(), m.position.y = p.y(), m.position.z = p.z();
    m.yaw = yaw_;
    m.trajectory_flag = go_feap::PositionCommand::TRAJECTORY_STATUS_READY;
    m.trajectory_id = static_cast<std::uint32_t>(planned.back().id);
    return m;
  };
  // Odometry and (once a trajectory is out) commands at 20 Hz, the target at 5 Hz, for `seconds`.
  go_feap::ViewpointPath goal = target(here, 1);
  goal.yaws.front() = yaw_ + 1.0;  // a turn where the vehicle is: a trajectory is planned from anywhere
  auto play = [&](double seconds, const std::function<bool()>& until) {
    Every send(0.05), target(0.2);
    return spinSimUntil(
        seconds,
        [&] {
          if (send.due()) {
            odom_pub.publish(odometry());
            if (!planned.empty()) cmd_pub.publish(command());
          }
          if (target.due()) target_pub.publish(goal);
        },
        until);
  };
  // Odometry and a command in a VIO's own frame, not the map's, are refused by name before anything is
  // planned (a pose there would be a plan's start in the wrong frame).
  {
    nav_msgs::Odometry elsewhere = odometry();
    elsewhere.header.frame_id = "odom";
    go_feap::PositionCommand command_elsewhere;
    command_elsewhere.header.frame_id = "odom";
    command_elsewhere.header.stamp = ros::Time::now();
    command_elsewhere.position.x = pose.x(), command_elsewhere.position.y = pose.y(), command_elsewhere.position.z = pose.z();
    auto heard = [&](const std::string& what) {
      return std::any_of(refusals.begin(), refusals.end(), [&](const std::string& m) { return m.find(what) != std::string::npos; });
    };
    EXPECT_TRUE(spinUntil([&] {
      odom_pub.publish(elsewhere);
      cmd_pub.publish(command_elsewhere);
      return spinUntil([&] { return heard("odometry refused: odometry is in frame 'odom'") &&
                                    heard("position_cmd refused: the command is in frame 'odom'"); }, 0.5);
    }, 20.0)) << "odometry or a command in frame 'odom' was not refused by name";
  }
  ASSERT_TRUE(play(10.0, [&] { return !planned.empty(); })) << "the probe planned no trajectory";
  // On the reference: nothing new. A window in which this test was held up past the planner's odometry
  // timeout (it then replans when the odometry is back, rightly) says nothing, and is played again.
  pose = go_feap::trajectory::sampleTrajectory(planned.back(), 0.0).position;
  std::size_t before = planned.size();
  for (int window = 0; window < 3; ++window) {
    gap = false;
    before = planned.size();
    play(1.5, [] { return false; });
    spinUntil([] { return false; }, 0.2);  // the log of the window's end
    if (!gap) break;
  }
  EXPECT_FALSE(gap) << "three windows held up past the odometry timeout";
  EXPECT_EQ(planned.size(), before) << "replanned with the odometry on the reference";
  // The odometry jumps 1.5 m (more than planner/max_tracking_error) while the server goes on. It comes
  // 0.12 s after its pose held (within planner/odom_timeout, 0.5 s): the plan from it starts at its stamp,
  // where the vehicle was, not when it arrived.
  const std::int64_t old_id = planned.back().id;
  const Vec3 reference = pose;
  pose = reference + 1.5 * forward_;
  odometry_age = 0.12;
  ASSERT_TRUE(play(5.0, [&] { return planned.back().id != old_id; })) << "no new trajectory after the odometry jumped";
  const double jump_start = planned.back().start_time.toSec();
  EXPECT_NE(std::find(odom_stamps.begin(), odom_stamps.end(), jump_start), odom_stamps.end())
      << "the plan from the odometry starts at " << jump_start << " (arrived " << received.back()
      << "), not at the stamp of an odometry message";
  const go_feap::trajectory::TrajectorySample next = go_feap::trajectory::sampleTrajectory(planned.back(), 0.0);
  EXPECT_LT((next.position - pose).norm(), 0.02) << "the new trajectory starts at " << next.position.transpose()
                                                 << ", the odometry is at " << pose.transpose()
                                                 << ", the reference was at " << reference.transpose();
  EXPECT_LT((next.velocity - velocity).norm(), 0.02) << "not from the odometry's velocity " << velocity.transpose()
                                                     << " (in the world) but " << next.velocity.transpose();

  // Commands that are not finite (a broken bridge) are no start for a plan: a new target while only such
  // commands come is planned from the odometry. Its stamps are 5 s old now (another clock): no time the
  // pose held, so the plan starts when the odometry arrived (within planner/odom_timeout of the plan).
  odometry_age = 5.0;
  auto broken = [&] {
    go_feap::PositionCommand m = command();
    m.velocity.y = std::numeric_limits<double>::quiet_NaN();
    return m;
  };
  const Vec3 odometry_pose = pose;
  goal = target(odometry_pose, 2);
  goal.yaws.front() = yaw_ - 1.0;
  const std::int64_t jumped_id = planned.back().id;
  Every send(0.05), target(0.2, ros::Time::now() + ros::Duration(0.5));  // the last usable command stale by then
  ASSERT_TRUE(spinSimUntil(
      5.5,
      [&] {
        if (send.due()) {
          odom_pub.publish(odometry());
          cmd_pub.publish(broken());
        }
        if (target.due()) target_pub.publish(goal);
      },
      [&] { return planned.back().id != jumped_id; }))
      << "no trajectory to the new target while the commands were not finite";
  const go_feap::trajectory::TrajectorySample from = go_feap::trajectory::sampleTrajectory(planned.back(), 0.0);
  ASSERT_TRUE(from.position.allFinite() && from.velocity.allFinite());
  EXPECT_LT((from.position - odometry_pose).norm(), 0.02) << "starts at " << from.position.transpose();
  const double stale_start = planned.back().start_time.toSec();
  EXPECT_GT(stale_start, received.back() - 0.5) << "starts at " << stale_start << ", arrived " << received.back()
                                                << ": at an odometry stamp 5 s old?";
  EXPECT_LE(stale_start, received.back());
  odometry_age = 0.0;

  // Velocities no vehicle flies (1e7 m/s: finite, corrupt) in every command and in every other odometry
  // message: refused (planner/max_input_speed), so a new target is planned from the good odometry. Taken,
  // they made a braking plan of 1e8 spans, gigabytes.
  auto absurd_command = [&] {
    go_feap::PositionCommand m = command();
    m.velocity.x = 1e7;
    return m;
  };
  goal = this->target(odometry_pose, 3);  // the fixture's: `target` above is the Every
  goal.yaws.front() = yaw_ + 1.0;
  const std::int64_t broken_id = planned.back().id;
  Every again(0.05), target_again(0.2, ros::Time::now() + ros::Duration(0.5));
  bool odd = false;
  ASSERT_TRUE(spinSimUntil(
      5.5,
      [&] {
        if (again.due()) {
          nav_msgs::Odometry m = odometry();
          if ((odd = !odd)) m.twist.twist.linear.x = 1e7;
          odom_pub.publish(m);
          cmd_pub.publish(absurd_command());
        }
        if (target_again.due()) target_pub.publish(goal);
      },
      [&] { return planned.back().id != broken_id; }))
      << "no trajectory to the new target while commands and every other odometry moved at 1e7 m/s";
  const go_feap::trajectory::TrajectorySample sane = go_feap::trajectory::sampleTrajectory(planned.back(), 0.0);
  EXPECT_LT((sane.position - odometry_pose).norm(), 0.02) << "starts at " << sane.position.transpose();
  EXPECT_LT((sane.velocity - velocity).norm(), 0.02) << "starts at " << sane.velocity.transpose() << " m/s";

  // A plan from the commanded state starts when that state held: at the stamp of the command it was
  // planned from (sent here 0.06 s old, at 100 Hz: within planner/command_timeout, 0.1 s), not
  // when the planner got to it, so that the server takes it over where the reference is by then. A
  // loaded machine can hold the commands up past the 0.1 s (the plan then rightly starts from the
  // odometry): up to five new targets are sent until one is planned from a command.
  std::string tries;
  bool from_command = false;
  const Vec3 commanded_acceleration(0.3, -0.2, 0.0);
  for (int attempt = 0; attempt < 5 && !from_command; ++attempt) {
    std::vector<double> stamps;
    goal = this->target(odometry_pose, 4 + attempt);
    goal.yaws.front() = yaw_ + (attempt % 2 ? 1.0 : -1.0);
    const std::int64_t before = planned.back().id;
    Every late(0.01), odometry_rate(0.05), target_late(0.2, ros::Time::now() + ros::Duration(0.3));
    ASSERT_TRUE(spinSimUntil(
        5.5,
        [&] {
          if (odometry_rate.due()) odom_pub.publish(odometry());
          if (late.due()) {
            go_feap::PositionCommand m = command();
            m.header.stamp = ros::Time::now() - ros::Duration(0.06);
            // The reference 0.3 m short of the target, accelerating and turning: a plan from it keeps all of it.
            m.position = go_feap::ros_conv::toPoint(odometry_pose - 0.3 * forward_);
            m.acceleration.x = commanded_acceleration.x(), m.acceleration.y = commanded_acceleration.y();
            m.yaw_dot = 0.4;
            stamps.push_back(m.header.stamp.toSec());
            cmd_pub.publish(m);
          }
          if (target_late.due()) target_pub.publish(goal);
        },
        [&] { return planned.back().id != before; }))
        << "no trajectory to the target planned from late commands";
    const double start = planned.back().start_time.toSec();
    from_command = std::find(stamps.begin(), stamps.end(), start) != stamps.end();
    tries += " " + std::to_string(start) + " (arrived " + std::to_string(received.back()) + ")";
    if (from_command) {
      EXPECT_LE(start, received.back() - 0.05) << "starts when it was planned, not when its start state held";
      const go_feap::trajectory::TrajectorySample first = go_feap::trajectory::sampleTrajectory(planned.back(), 0.0);
      EXPECT_LT((first.position - (odometry_pose - 0.3 * forward_)).norm(), 0.02) << first.position.transpose();
      EXPECT_LT((first.acceleration - commanded_acceleration).norm(), 1e-6)
          << "starts at acceleration " << first.acceleration.transpose() << ", not the command's";
      EXPECT_NEAR(first.yaw_dot, 0.4, 1e-6) << "starts at yaw rate " << first.yaw_dot << ", not the command's";
    }
  }
  EXPECT_TRUE(from_command) << "no plan of five started at the stamp of a command:" << tries;

  // Stopped (FINISHED(aborted), the stop service): the planner brakes, then takes no target any more, a
  // new one included.
  ros::Publisher status_pub = nh_.advertise<go_feap::ExplorationStatus>("probe/jump/status", 1, /*latch=*/true);
  go_feap::ExplorationStatus stopped;
  stopped.state = go_feap::ExplorationStatus::FINISHED;
  stopped.state_name = "FINISHED";
  stopped.finish_reason = "aborted";
  status_pub.publish(stopped);
  ASSERT_TRUE(spinUntil([&] { return status_pub.getNumSubscribers() > 0; }, 10.0));
  play(1.0, [] { return false; });  // the last target repeated; a braking plan may come
  const std::size_t stopped_at = planned.size();
  goal = this->target(odometry_pose, 99);
  goal.yaws.front() = yaw_ + 2.0;
  play(3.0, [] { return false; });
  EXPECT_EQ(planned.size(), stopped_at) << "a target taken after FINISHED(aborted)";
}

// A second trajectory server (probe/...) fed only by this test. It holds the first usable odometry pose
// until a trajectory comes. Odometry it cannot use is refused whole: a finite position with a NaN or
// unset orientation once became a hold with a NaN heading, sent on to the controller; a pose in another
// frame than the world's would be held as a world position.
TEST(TrajectoryServerOdometry, UnusableOdometryIsRefusedAndTheFirstGoodPoseIsHeld) {
  ros::NodeHandle nh;
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("probe/odom", 10);
  std::vector<go_feap::PositionCommand::ConstPtr> commands;
  auto cmd_sub = nh.subscribe<go_feap::PositionCommand>(
      "probe/position_cmd", 200, [&](const go_feap::PositionCommand::ConstPtr& m) { commands.push_back(m); });
  ASSERT_TRUE(spinUntil([&] { return odom_pub.getNumSubscribers() > 0 && cmd_sub.getNumPublishers() > 0; }, 60.0))
      << "the probe trajectory server is not connected";
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double yaw = 0.7;
  auto odometry = [&](const Vec3& p, double w, double x, double y, double z) {
    nav_msgs::Odometry m;
    m.header.stamp = ros::Time::now();
    m.header.frame_id = "world";
    m.pose.pose.position.x = p.x(), m.pose.pose.position.y = p.y(), m.pose.pose.position.z = p.z();
    m.pose.pose.orientation.w = w, m.pose.pose.orientation.x = x;
    m.pose.pose.orientation.y = y, m.pose.pose.orientation.z = z;
    return m;
  };
  const Vec3 held(1.0, -0.5, 1.2);
  nav_msgs::Odometry elsewhere = odometry(held, 1.0, 0.0, 0.0, 0.0);
  elsewhere.header.frame_id = "odom";  // a VIO's own frame, not the map's: no pose to hold in the world
  const nav_msgs::Odometry bad[] = {
      odometry(held, nan, 0.0, 0.0, nan),                  // orientation not finite
      odometry(held, 0.0, 0.0, 0.0, 0.0),                  // orientation left unset
      odometry(Vec3(nan, 0.0, 1.0), 1.0, 0.0, 0.0, 0.0),  // position not finite
      elsewhere};
  // Each unusable kind for 0.5 s of simulated time at 20 Hz: no command follows any.
  for (const nav_msgs::Odometry& m : bad) {
    Every send(0.05);
    spinSimUntil(
        0.5, [&] { if (send.due()) odom_pub.publish(m); }, [] { return false; }, 30.0);
  }
  spinUntil([] { return false; }, 0.3);  // anything still in flight
  EXPECT_TRUE(commands.empty()) << commands.size() << " commands after unusable odometry, the first with yaw "
                                << commands.front()->yaw;
  commands.clear();
  // Then a usable pose: held, heading included.
  const nav_msgs::Odometry good = odometry(held, std::cos(0.5 * yaw), 0.0, 0.0, std::sin(0.5 * yaw));
  Every send(0.05);
  ASSERT_TRUE(spinSimUntil(
      60.0, [&] { if (send.due()) odom_pub.publish(good); }, [&] { return commands.size() >= 20; }, 30.0))
      << "no hold command after usable odometry";
  for (const auto& c : commands) {
    ASSERT_TRUE(std::isfinite(c->yaw));
    EXPECT_NEAR(c->yaw, yaw, 1e-9);
    EXPECT_LT((Vec3(c->position.x, c->position.y, c->position.z) - held).norm(), 1e-9);
    EXPECT_EQ(c->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_EMPTY);
  }
  // With no trajectory running, odometry within server/max_start_offset of the held pose leaves it held;
  // farther (a jump, a VIO re-initialised, the vehicle moved by hand) the pose is held where the vehicle is.
  // The old hold pulled the vehicle the whole way back, and every plan from that command was refused.
  double max_start_offset = 0.0;
  ASSERT_TRUE(ros::param::get("/probe_trajectory_server/server/max_start_offset", max_start_offset));
  // The odometry `m` at 20 Hz for 1 s of the clock (no gap: after one the server holds wherever the odometry
  // comes back), and the last command of its second half.
  auto holdAfter = [&](const nav_msgs::Odometry& m) {
    Every again(0.05);
    spinSimUntil(0.5, [&] { if (again.due()) odom_pub.publish(m); }, [] { return false; }, 30.0);
    commands.clear();
    spinSimUntil(0.5, [&] { if (again.due()) odom_pub.publish(m); }, [] { return false; }, 30.0);
    return commands.empty() ? Vec3(nan, nan, nan)
                            : Vec3(commands.back()->position.x, commands.back()->position.y, commands.back()->position.z);
  };
  const Vec3 near = held + Vec3(0.0, 0.9 * max_start_offset, 0.0);
  EXPECT_LT((holdAfter(odometry(near, 1.0, 0.0, 0.0, 0.0)) - held).norm(), 1e-9) << "a drift moved the hold";
  const Vec3 jumped = held + Vec3(1.2 * max_start_offset, 0.0, 0.0);
  EXPECT_LT((holdAfter(odometry(jumped, 1.0, 0.0, 0.0, 0.0)) - jumped).norm(), 1e-9) << "the hold stayed after a jump";
  EXPECT_NEAR(commands.back()->yaw, 0.0, 1e-9);
}

// The probe server (probe/...) as the tests below drive it: odometry at `vehicle` at 20 Hz while it hovers,
// straight-line trajectories, and the latest command it sent.
class ProbeServer {
 public:
  explicit ProbeServer(const std::string& prefix = "probe/") {
    odom_pub_ = nh_.advertise<nav_msgs::Odometry>(prefix + "odom", 10);
    bspline_pub_ = nh_.advertise<go_feap::Bspline>(prefix + "bspline", 10);
    cmd_sub_ = nh_.subscribe<go_feap::PositionCommand>(prefix + "position_cmd", 200, [this](const go_feap::PositionCommand::ConstPtr& m) {
      command = m;
      history.push_back(m);
      if (history.size() > 1000) history.pop_front();
    });
  }
  bool connected() {
    return spinUntil(
        [&] {
          return odom_pub_.getNumSubscribers() > 0 && bspline_pub_.getNumSubscribers() > 0 &&
                 cmd_sub_.getNumPublishers() > 0;
        },
        60.0);
  }
  // Spins for `seconds` of simulated time, with the odometry at `vehicle` at 20 Hz unless `silent`; the
  // latest command then.
  go_feap::PositionCommand::ConstPtr hover(double seconds, bool silent = false) {
    const auto publish_odometry = [&] {
      nav_msgs::Odometry m;
      m.header.stamp = ros::Time::now();
      m.header.frame_id = "world";
      m.pose.pose.position.x = vehicle.x(), m.pose.pose.position.y = vehicle.y(), m.pose.pose.position.z = vehicle.z();
      m.pose.pose.orientation.w = 1.0;
      odom_pub_.publish(m);
    };
    spinSimUntil(
        seconds, [&] { if (send_.due() && !silent) publish_odometry(); }, [] { return false; }, 30.0);
    return command;
  }
  // A straight flight from a to b over 4 knot spans of `span` s (3 s by default), heading `yaw`.
  void fly(const Vec3& a, const Vec3& b, std::int64_t id, const ros::Time& start, double yaw = 0.0, double span = 0.75) {
    send(go_feap::test::straightFlight(a, b, id, start, yaw, span));
  }
  void send(const go_feap::ros_traj::Trajectory& t) { bspline_pub_.publish(go_feap::ros_traj::toMsg(t)); }
  Vec3 commanded() const { return Vec3(command->position.x, command->position.y, command->position.z); }

  Vec3 vehicle = Vec3(0.5, 0.5, 1.5);  ///< where the odometry puts it (a test may move it)
  go_feap::PositionCommand::ConstPtr command;
  std::deque<go_feap::PositionCommand::ConstPtr> history;  ///< the last 1000 commands

 private:
  ros::NodeHandle nh_;
  ros::Publisher odom_pub_, bspline_pub_;
  ros::Subscriber cmd_sub_;
  Every send_{0.05};
};

// The server as shipped (server/hold_before_trajectory false: quiet/...) sends nothing before its first
// trajectory, however long the odometry comes: a hold of the pose at launch, on the ground, pulled a vehicle
// the pilot then took off by hand back down once the bridge took the commands. A refused first trajectory
// starts the commands, holding where the vehicle is then (the planner learns of the refusal from the
// hold's EMPTY flag; with no command it never did). The next is followed; after its end, and through an
// odometry gap, the server holds as before, at the trajectory's end and heading.
TEST(TrajectoryServerFirstCommand, NothingIsSentBeforeTheFirstTrajectoryThenItIsFollowedAndHeld) {
  ProbeServer quiet("quiet/");
  quiet.vehicle = Vec3(0.5, 0.5, 0.1);  // on the ground
  ASSERT_TRUE(quiet.connected()) << "the quiet trajectory server is not connected";
  quiet.hover(2.0);
  quiet.vehicle = Vec3(0.5, 0.5, 1.2);  // taken off by hand
  quiet.hover(1.0);
  EXPECT_TRUE(quiet.history.empty()) << quiet.history.size() << " commands before the first trajectory, the first at z "
                                     << quiet.history.front()->position.z;
  quiet.fly(quiet.vehicle + Vec3(3.0, 0.0, 0.0), quiet.vehicle + Vec3(4.0, 0.0, 0.0), 76, ros::Time::now());  // refused
  ASSERT_TRUE(spinUntil([&] { return quiet.hover(0.05) != nullptr; }, 20.0)) << "no command after a refused trajectory";
  EXPECT_EQ(quiet.command->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_EMPTY);
  EXPECT_LT((quiet.commanded() - quiet.vehicle).norm(), 1e-9) << "not held where the vehicle is";
  const Vec3 end = quiet.vehicle + Vec3(1.0, 0.0, 0.0);
  const double heading = 0.8;  // the odometry's is 0: the hold keeps the trajectory's, not the odometry's
  quiet.fly(quiet.vehicle, end, 77, ros::Time::now(), heading);
  ASSERT_TRUE(spinUntil([&] { return quiet.hover(0.05) && quiet.command->trajectory_id == 77u; }, 20.0))
      << "the first trajectory was not followed";
  EXPECT_GT(quiet.command->position.z, 1.0) << "it started from the ground";
  quiet.vehicle = end;
  quiet.hover(4.0);  // past its 3 s
  EXPECT_EQ(quiet.command->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_COMPLETED);
  const Vec3 held = quiet.commanded();  // its end (fly()'s spline ends short of `end` by a few cm)
  EXPECT_LT((held - end).norm(), 0.1) << "not held at the trajectory's end";
  EXPECT_NEAR(quiet.command->yaw, heading, 1e-6);
  double odom_timeout = 0.0;
  ASSERT_TRUE(ros::param::get("/quiet_trajectory_server/server/odom_timeout", odom_timeout));
  quiet.hover(2.0 * odom_timeout, true);
  EXPECT_EQ(quiet.command->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_ABORT);
  EXPECT_LT((quiet.commanded() - held).norm(), 1e-9) << "not holding through the odometry gap";
  EXPECT_NEAR(quiet.command->yaw, heading, 1e-6) << "the hold through the gap turned the vehicle";
  EXPECT_EQ(quiet.command->yaw_dot, 0.0);
}

// Each test below starts with the probe server connected and holding the vehicle's pose.
class ProbeServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(probe.connected()) << "the probe trajectory server is not connected";
    ASSERT_TRUE(probe.hover(0.5)) << "no command";
  }
  double param(const std::string& key) const {
    double value = 0.0;
    EXPECT_TRUE(ros::param::get("/probe_trajectory_server/" + key, value)) << key;
    return value;
  }
  ProbeServer probe;
};

// The probe server takes over a trajectory only where its reference, when taken (now, or at its start if
// later), lies within server/max_start_offset of the odometry: one starting 3 m away, and one planned
// from the vehicle's pose but started at 0 s (its reference now is its end, 3 m away), are refused and
// the server goes on holding; one starting 0.5 m away (a tracking error) is followed from there.
TEST_F(ProbeServerTest, TrajectoriesStartingFarFromTheOdometryAreRefused) {
  const double max_offset = param("server/max_start_offset");
  const Vec3 vehicle = probe.vehicle;
  const Vec3 ahead = vehicle + Vec3(3.0, 0.0, 0.0);
  ASSERT_GT(3.0, max_offset);
  probe.fly(ahead, ahead + Vec3(1.0, 0.0, 0.0), 901, ros::Time::now());
  probe.hover(1.0);
  EXPECT_NE(probe.command->trajectory_id, 901u) << "a trajectory starting 3 m away was taken";
  EXPECT_GT((probe.commanded() - ahead).norm(), max_offset) << "the reference went towards it";
  const Vec3 before = probe.commanded();
  while (ros::ok() && ros::Time::now().toSec() < 5.0) probe.hover(0.5);
  probe.fly(vehicle, ahead, 902, ros::Time(1e-3));  // long over: now its end
  probe.hover(1.0);
  EXPECT_NE(probe.command->trajectory_id, 902u) << "a trajectory started at 0 s was taken";
  EXPECT_LT((probe.commanded() - before).norm(), 1e-9) << "the held reference moved";
  ASSERT_GT(max_offset, 0.5);
  const Vec3 near = vehicle + Vec3(0.0, 0.5, 0.0);
  probe.fly(near, near + Vec3(1.0, 0.0, 0.0), 903, ros::Time::now());
  ASSERT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 903u; }, 20.0))
      << "a trajectory 0.5 m away was refused";
  EXPECT_LT((probe.commanded() - near).norm(), 0.15) << "not followed from its start";
  EXPECT_EQ(probe.command->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_READY);
}

// Likewise for the heading (server/max_start_yaw_offset): one starting where the vehicle is but facing
// 2 rad from its heading (odometry yaw 0) is refused, one 0.3 rad off is followed.
TEST_F(ProbeServerTest, TrajectoriesStartingAtAnotherHeadingAreRefused) {
  const double max_turn = param("server/max_start_yaw_offset");
  ASSERT_LT(max_turn, 2.0);
  ASSERT_GT(max_turn, 0.3);
  const Vec3 vehicle = probe.vehicle;
  probe.fly(vehicle, vehicle + Vec3(1.0, 0.0, 0.0), 921, ros::Time::now(), -2.0);
  probe.hover(1.0);
  EXPECT_NE(probe.command->trajectory_id, 921u) << "a trajectory facing 2 rad off was taken";
  probe.fly(vehicle, vehicle + Vec3(1.0, 0.0, 0.0), 922, ros::Time::now(), 0.3);
  EXPECT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 922u; }, 20.0))
      << "a trajectory facing 0.3 rad off was refused";
}

// A trajectory whose control polygon moves faster than server/max_speed (0.5 m in 4 ms: 125 m/s, corrupt
// or not this planner's) is refused though it starts and ends within server/max_start_offset of the
// odometry: the controller would have been handed a step. The same line over 3 s is followed.
TEST_F(ProbeServerTest, ATrajectoryFasterThanTheServerTakesIsRefused) {
  const double max_speed = param("server/max_speed");
  ASSERT_LT(max_speed, 0.125 / 0.001);
  ASSERT_GT(param("server/max_start_offset"), 0.5);
  const Vec3 vehicle = probe.vehicle;
  probe.hover(3.5);  // whatever an earlier test left running (3 s at most) has ended: the reference is held
  const Vec3 held = probe.commanded();
  probe.fly(vehicle, vehicle + Vec3(0.5, 0.0, 0.0), 951, ros::Time::now(), 0.0, 0.001);
  probe.hover(1.0);
  EXPECT_NE(probe.command->trajectory_id, 951u) << "a trajectory at 125 m/s was taken";
  EXPECT_LT((probe.commanded() - held).norm(), 1e-9) << "the held reference moved";
  probe.fly(vehicle, vehicle + Vec3(0.5, 0.0, 0.0), 952, ros::Time::now());
  EXPECT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 952u; }, 20.0))
      << "the same line over 3 s was refused";
}

// Each of the server's motion limits refuses on its own (the trajectory above breaks speed and acceleration
// at once): a straight line at 1.5 x server/max_speed with no acceleration, a jitter of 1 cm whose polygon
// accelerates at twice server/max_acceleration at a walking pace, and a slow line whose heading turns at
// twice server/max_yaw_rate; each refused by name, the reference held.
TEST_F(ProbeServerTest, EachMotionLimitRefusesOnItsOwn) {
  const double max_speed = param("server/max_speed"), max_acceleration = param("server/max_acceleration"),
               max_yaw_rate = param("server/max_yaw_rate");
  std::vector<std::string> said;
  ros::NodeHandle nh;
  auto log_sub = nh.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->msg.find("/probe_trajectory_server: trajectory") != std::string::npos) said.push_back(m->msg);
  });
  ASSERT_TRUE(spinUntil([&] { return log_sub.getNumPublishers() > 0; }, 20.0));
  probe.hover(3.5);  // whatever an earlier test left running has ended: the reference is held
  const Vec3 a = probe.vehicle;
  auto trajectory = [&](std::int64_t id, const Eigen::MatrixXd& q, double span, const Eigen::MatrixXd& yaw, double yaw_span) {
    go_feap::ros_traj::Trajectory t;
    t.position = go_feap::trajectory::UniformBspline(q, 3, span);
    t.yaw = go_feap::trajectory::UniformBspline(yaw, 3, yaw_span);
    t.id = id;
    t.start_time = ros::Time::now();
    return t;
  };
  const Eigen::MatrixXd level = Eigen::MatrixXd::Zero(1, 4);
  // Speed: control points evenly along x (the polygon's acceleration 0), 1.5 x max_speed, starting 2 cm ahead.
  const double span = 0.002, step = 1.5 * max_speed * span;
  Eigen::MatrixXd fast(3, 7), jitter(3, 7), slow(3, 7);
  for (int i = 0; i < 7; ++i) {
    fast.col(i) = a + Vec3(0.02 + (i - 1) * step, 0.0, 0.0);
    jitter.col(i) = a + Vec3(i % 2 ? 0.01 : 0.0, 0.0, 0.0);
    slow.col(i) = a + Vec3(0.05 * i / 6.0, 0.0, 0.0);
  }
  // Acceleration: 1 cm back and forth every `dt`, (0.02 / dt^2) = 2 x max_acceleration; speed 0.01 / dt.
  const double dt = std::sqrt(0.02 / (2.0 * max_acceleration));
  ASSERT_LT(0.01 / dt, max_speed);
  // Heading: 0 to 3 x max_yaw_rate x yaw_span over three spans: twice the limit on one of them at least.
  const double yaw_span = 0.5;
  Eigen::MatrixXd turn(1, 4);
  turn << 0.0, 0.0, 2.0 * max_yaw_rate * yaw_span, 2.0 * max_yaw_rate * yaw_span;
  const struct {
    go_feap::ros_traj::Trajectory t;
    std::string why;
  } cases[] = {{trajectory(971, fast, span, level, 1.0), "m/s, above"},
               {trajectory(972, jitter, dt, level, 1.0), "m/s^2, above"},
               {trajectory(973, slow, 0.5, turn, yaw_span), "rad/s, above"}};
  for (const auto& c : cases) {
    const Vec3 held = probe.commanded();
    said.clear();
    probe.send(c.t);
    probe.hover(1.5);  // more than the refusal's 1 s throttle: the next one is said too
    EXPECT_NE(probe.command->trajectory_id, static_cast<std::uint32_t>(c.t.id)) << "trajectory " << c.t.id << " was taken";
    EXPECT_LT((probe.commanded() - held).norm(), 1e-9) << "the held reference moved";
    EXPECT_TRUE(spinUntil([&] {
      return std::any_of(said.begin(), said.end(), [&](const std::string& m) {
        return m.find("trajectory " + std::to_string(c.t.id) + " refused") != std::string::npos &&
               m.find(c.why) != std::string::npos;
      });
    }, 5.0)) << "trajectory " << c.t.id << " not refused for '" << c.why << "'";
  }
  // Within every limit, the slow line with a level heading is followed.
  probe.send(trajectory(974, slow, 0.5, level, 1.0));
  EXPECT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 974u; }, 20.0)) << "the slow line was refused";
}

// A trajectory that reaches the server while its odometry is silent (one planned just before the odometry
// stopped) is refused: it was checked against nothing but the last, stale pose, and the server had
// already dropped the one before to hold position. It used to be taken and followed to its end, blind.
// Once odometry is back, the next trajectory is followed.
TEST_F(ProbeServerTest, ATrajectoryArrivingWhileTheOdometryIsSilentIsRefused) {
  const double odom_timeout = param("server/odom_timeout");
  ASSERT_GT(odom_timeout, 0.0);
  const Vec3 vehicle = probe.vehicle;
  // Silent for twice the timeout, then a trajectory from where the vehicle was last seen.
  probe.hover(2.0 * odom_timeout, true);
  const Vec3 held = probe.commanded();
  probe.fly(vehicle, vehicle + Vec3(1.0, 0.0, 0.0), 911, ros::Time::now());
  probe.hover(1.0, true);
  EXPECT_NE(probe.command->trajectory_id, 911u) << "a trajectory was taken with the odometry silent";
  EXPECT_EQ(probe.command->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_ABORT);
  EXPECT_LT((probe.commanded() - held).norm(), 1e-9) << "the held reference moved";
  // Odometry back: the next one is followed.
  probe.hover(0.3);
  probe.fly(vehicle, vehicle + Vec3(1.0, 0.0, 0.0), 912, ros::Time::now());
  ASSERT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 912u; }, 20.0))
      << "the trajectory after the odometry came back was refused";
  EXPECT_EQ(probe.command->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_READY);
}

// A trajectory whose start time lies ahead waits while the running one is followed (the server used to
// replace the running one at once and hold the reference still, at speed, until the new one started); it
// is taken over at its start time.
TEST_F(ProbeServerTest, ATrajectoryStartingLaterWaitsWhileTheRunningOneIsFollowed) {
  const Vec3 vehicle = probe.vehicle;
  probe.fly(vehicle, vehicle + Vec3(1.0, 0.0, 0.0), 921, ros::Time::now());
  ASSERT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 921u; }, 20.0))
      << "the first trajectory was refused";
  const ros::Time later = ros::Time::now() + ros::Duration(1.0);
  const Vec3 side = vehicle + Vec3(0.0, 0.3, 0.0);
  probe.fly(side, side + Vec3(0.0, 1.0, 0.0), 922, later);
  // Until it starts: the first one, moving on.
  Vec3 last = probe.commanded();
  int moved = 0;
  while (ros::ok() && ros::Time::now() + ros::Duration(0.15) < later) {
    probe.hover(0.05);
    ASSERT_EQ(probe.command->trajectory_id, 921u) << "the running trajectory was left before the next one started";
    ASSERT_EQ(probe.command->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_READY);
    moved += (probe.commanded() - last).norm() > 1e-6;
    last = probe.commanded();
  }
  EXPECT_GT(moved, 5) << "the reference did not move along the running trajectory";
  // From its start: the second one, from its start point.
  ASSERT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 922u; }, 20.0))
      << "the trajectory starting later was never taken over";
  EXPECT_GE(probe.command->header.stamp, later);
  EXPECT_LT((probe.commanded() - side).norm(), 0.15) << "not followed from its start";
  // One starting later 2 m from the vehicle (more than server/max_start_offset) is judged where it starts
  // when it is taken over, not on arrival: the vehicle goes on meanwhile. Taken once the vehicle is there;
  // one whose start the vehicle did not reach is refused then, and the running one goes on.
  const double max_offset = param("server/max_start_offset");
  const Vec3 far = probe.vehicle + Vec3(2.0, 0.0, 0.0);
  ASSERT_GT(2.0, max_offset);
  probe.fly(far, far + Vec3(1.0, 0.0, 0.0), 923, ros::Time::now() + ros::Duration(1.0));
  EXPECT_EQ(probe.hover(0.3)->trajectory_id, 922u);
  probe.vehicle = far;  // it got there
  ASSERT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 923u; }, 20.0))
      << "a trajectory starting later where the vehicle then was was refused";
  probe.fly(far + Vec3(0.0, 3.0, 0.0), far + Vec3(1.0, 3.0, 0.0), 924, ros::Time::now() + ros::Duration(0.5));
  probe.hover(1.5);
  EXPECT_EQ(probe.command->trajectory_id, 923u) << "a trajectory starting 3 m from the vehicle was taken";
  EXPECT_EQ(probe.command->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_READY);
}

// A trajectory starting now replaces one still waiting for its start as well as the running one: the
// superseded waiting one is not taken over when its start time comes (it was planned before the one now
// flown).
TEST_F(ProbeServerTest, ATrajectoryStartingNowReplacesOneWaiting) {
  const Vec3 vehicle = probe.vehicle;
  probe.hover(3.5);  // whatever an earlier test left running has ended
  const ros::Time later = ros::Time::now() + ros::Duration(1.0);
  probe.fly(vehicle + Vec3(0.0, 0.3, 0.0), vehicle + Vec3(0.0, 1.3, 0.0), 981, later);
  probe.hover(0.2);
  probe.fly(vehicle, vehicle + Vec3(1.0, 0.0, 0.0), 982, ros::Time::now());
  ASSERT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 982u; }, 20.0))
      << "the trajectory starting now was not followed";
  while (ros::ok() && ros::Time::now() < later + ros::Duration(0.5)) {
    probe.hover(0.05);
    ASSERT_EQ(probe.command->trajectory_id, 982u) << "the superseded waiting trajectory was taken over";
  }
}

// Every command of a followed trajectory is the trajectory sampled at the command's stamp: position,
// velocity, acceleration, heading and yaw rate (the feed-forward terms the controller flies by); the heading
// within (-pi, pi], as a flight controller's bridge takes it, though the spline's lies a turn above.
TEST_F(ProbeServerTest, CommandsAreTheTrajectorySampledAtTheirStamps) {
  const Vec3 a = probe.vehicle;
  Eigen::MatrixXd q(3, 7), y(1, 7);
  for (int i = 0; i < 7; ++i) q.col(i) = a + Vec3(0.6, 0.3, 0.1) * std::clamp((i - 1) / 4.0, 0.0, 1.0) * std::clamp((i - 1) / 4.0, 0.0, 1.0);
  y << 0.0, 0.0, 0.2, 0.5, 0.9, 1.2, 1.2;
  y.array() += 2 * M_PI;  // a heading a turn round (the vehicle's, 0): commanded within (-pi, pi]
  go_feap::ros_traj::Trajectory t;
  t.position = go_feap::trajectory::UniformBspline(q, 3, 0.75);
  t.yaw = go_feap::trajectory::UniformBspline(y, 3, 0.75);
  t.id = 941;
  t.start_time = ros::Time::now();
  probe.history.clear();
  probe.send(t);
  probe.hover(2.5);
  int checked = 0, moving = 0;
  for (const auto& c : probe.history) {
    if (c->trajectory_id != 941u) continue;
    const auto s = go_feap::trajectory::sampleTrajectory(t, c->header.stamp.toSec() - t.start_time.toSec());
    const Vec3 p(c->position.x, c->position.y, c->position.z), v(c->velocity.x, c->velocity.y, c->velocity.z),
        acc(c->acceleration.x, c->acceleration.y, c->acceleration.z);
    EXPECT_LT((p - s.position).norm(), 1e-9) << "at " << c->header.stamp;
    EXPECT_LT((v - s.velocity).norm(), 1e-9) << "at " << c->header.stamp;
    EXPECT_LT((acc - s.acceleration).norm(), 1e-9) << "at " << c->header.stamp;
    EXPECT_NEAR(std::remainder(c->yaw - s.yaw, 2 * M_PI), 0.0, 1e-9) << "at " << c->header.stamp;
    EXPECT_TRUE(c->yaw > -M_PI && c->yaw <= M_PI) << c->yaw << " at " << c->header.stamp;
    EXPECT_NEAR(c->yaw_dot, s.yaw_dot, 1e-9) << "at " << c->header.stamp;
    ++checked;
    moving += s.velocity.norm() > 0.05 && std::abs(s.yaw_dot) > 0.05 && s.acceleration.norm() > 0.01;
  }
  EXPECT_GT(checked, 100) << "commands of the trajectory";
  EXPECT_GT(moving, 20) << "commands while it moved, turned and accelerated";
}

// Odometry back after a gap holds the vehicle where the odometry now puts it (a VIO re-initialised in the
// gap, 3 m off): the server used to command the stale reference from before the gap, dragging the vehicle
// 3 m at once, while every plan from that held command was refused for starting too far from the
// odometry. A trajectory from where the vehicle is, is followed; so is the next gap's return. Through the
// gap the hold is flagged ABORT (held blind: a bridge may act on it), once odometry is back EMPTY again.
TEST_F(ProbeServerTest, OdometryBackAfterAGapIsHeldWhereItSays) {
  const double odom_timeout = param("server/odom_timeout");
  probe.hover(2.0 * odom_timeout, true);
  const Vec3 held = probe.commanded();
  probe.hover(0.2, true);
  EXPECT_EQ(probe.command->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_ABORT);
  EXPECT_LT((probe.commanded() - held).norm(), 1e-9) << "the reference moved during the gap";
  EXPECT_GT((held - (probe.vehicle + Vec3(3.0, 0.0, 0.0))).norm(), 1.0);
  probe.vehicle += Vec3(3.0, 0.0, 0.0);
  ASSERT_GT(3.0, param("server/max_start_offset"));
  probe.hover(0.3);
  EXPECT_EQ(probe.command->trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_EMPTY);
  EXPECT_LT((probe.commanded() - probe.vehicle).norm(), 1e-9) << "the stale reference is still held";
  probe.fly(probe.vehicle, probe.vehicle + Vec3(1.0, 0.0, 0.0), 931, ros::Time::now());
  ASSERT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 931u; }, 20.0))
      << "a trajectory from where the odometry is was refused";
  probe.hover(2.0 * odom_timeout, true);
  probe.vehicle -= Vec3(3.0, 0.0, 0.0);
  probe.hover(0.3);
  EXPECT_LT((probe.commanded() - probe.vehicle).norm(), 1e-9) << "not held where the odometry came back";
}

// Odometry jumping farther than server/max_start_offset from the reference with no gap (a VIO re-initialised,
// a loop closure applied at once, the vehicle carried): the trajectory is dropped, ended or running, and the
// reference holds where the vehicle now is. This was checked only with no trajectory at all: after the first
// flight the ended one's end stayed the reference (COMPLETED), and the controller flew the whole jump at once,
// through space nothing had checked, while hovering after a stop or waiting for a plan.
TEST_F(ProbeServerTest, AnOdometryJumpDropsTheTrajectoryEndedOrRunning) {
  using go_feap::PositionCommand;
  const double max_offset = param("server/max_start_offset");
  const Vec3 start = probe.vehicle;
  probe.fly(start, start + Vec3(1.0, 0.0, 0.0), 961, ros::Time::now());
  ASSERT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 961u; }, 20.0)) << "the trajectory was refused";
  probe.vehicle = start + Vec3(1.0, 0.0, 0.0);
  probe.hover(3.5);  // past its 3 s
  ASSERT_EQ(probe.command->trajectory_flag, PositionCommand::TRAJECTORY_STATUS_COMPLETED);
  const Vec3 end = probe.commanded();
  // A drift within the offset leaves the end held.
  probe.vehicle = end + Vec3(0.0, 0.0, 0.8 * max_offset);
  probe.hover(0.5);
  EXPECT_EQ(probe.command->trajectory_flag, PositionCommand::TRAJECTORY_STATUS_COMPLETED);
  EXPECT_LT((probe.commanded() - end).norm(), 1e-9) << "a drift moved the reference";
  // A jump past it: held where the vehicle is.
  probe.vehicle = end + Vec3(0.0, 1.2 * max_offset, 0.0);
  probe.hover(0.3);
  EXPECT_EQ(probe.command->trajectory_flag, PositionCommand::TRAJECTORY_STATUS_EMPTY);
  EXPECT_LT((probe.commanded() - probe.vehicle).norm(), 1e-9) << "the ended trajectory's end is still the reference";
  // Running: 0.5 s into a 3 s flight the odometry jumps sideways; the rest of it is not flown.
  const Vec3 from = probe.vehicle;
  probe.fly(from, from + Vec3(1.0, 0.0, 0.0), 962, ros::Time::now());
  ASSERT_TRUE(spinUntil([&] { return probe.hover(0.05)->trajectory_id == 962u; }, 20.0)) << "the trajectory was refused";
  probe.hover(0.5);
  ASSERT_EQ(probe.command->trajectory_flag, PositionCommand::TRAJECTORY_STATUS_READY);
  probe.vehicle = from + Vec3(0.0, -1.2 * max_offset, 0.0);
  probe.hover(0.3);
  probe.history.clear();
  probe.hover(1.0);
  ASSERT_FALSE(probe.history.empty());
  for (const auto& c : probe.history) {
    EXPECT_EQ(c->trajectory_flag, PositionCommand::TRAJECTORY_STATUS_EMPTY) << "trajectory " << c->trajectory_id;
    EXPECT_LT((Vec3(c->position.x, c->position.y, c->position.z) - probe.vehicle).norm(), 1e-9)
        << "not held where the vehicle jumped to";
  }
}

}  // namespace

GO_FEAP_ROSTEST_MAIN("test_trajectory_ros")
