// Message <-> Eigen conversions of the nodelets (go_feap/ros/conversions.h), against rotations worked
// out by hand: the simulator publishes the odometry twist in the body frame, and the local planner needs
// it in the world frame.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

#include <cv_bridge/cv_bridge.h>
#include <sensor_msgs/image_encodings.h>
#include <std_msgs/UInt32.h>

#include <boost/make_shared.hpp>
#include <stdexcept>

#include "go_feap/ros/bspline_conversion.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/trajectory/replan.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/message_checks.h"
#include "go_feap/ros/shared_map.h"
#include "go_feap/ros/tf_gaps.h"

namespace {

using go_feap::common::Vec3;
using go_feap::ros_conv::odometryPoseProblem;
using go_feap::ros_conv::odometryProblem;
using go_feap::ros_conv::odometryVelocity;
using go_feap::ros_conv::worldVelocity;
using go_feap::ros_conv::yawOf;
using go_feap::ros_check::frontierArrayProblem;
using go_feap::ros_check::frontierOutside;
using go_feap::ros_check::globalTourProblem;
using go_feap::ros_check::depthImageProblem;
using go_feap::ros_check::explorationStatusProblem;
using go_feap::ros_check::layerBoundsProblem;
using go_feap::ros_check::mapUpdateProblem;
using go_feap::ros_check::positionCommandProblem;

geometry_msgs::Quaternion quat(double w, double x, double y, double z) {
  geometry_msgs::Quaternion q;
  q.w = w, q.x = x, q.y = y, q.z = z;
  return q;
}

geometry_msgs::Point point(double x, double y, double z) {
  geometry_msgs::Point p;
  p.x = x, p.y = y, p.z = z;
  return p;
}

geometry_msgs::Vector3 vec(double x, double y, double z) {
  geometry_msgs::Vector3 v;
  v.x = x, v.y = y, v.z = z;
  return v;
}

TEST(Conversions, WorldVelocityTurnsTheBodyTwistIntoTheWorld) {
  const double h = std::sqrt(0.5);
  // Level, heading +y (90 deg about z): flying forward in the body is +y in the world.
  const auto yaw90 = quat(h, 0, 0, h);
  EXPECT_NEAR(yawOf(yaw90), M_PI / 2, 1e-12);
  EXPECT_TRUE(worldVelocity(yaw90, vec(2, 0, 0)).isApprox(Vec3(0, 2, 0), 1e-12));
  EXPECT_TRUE(worldVelocity(yaw90, vec(0, 1, 0)).isApprox(Vec3(-1, 0, 0), 1e-12));
  // Heading back (180 deg): forward is -x; up stays up.
  EXPECT_TRUE(worldVelocity(quat(0, 0, 0, 1), vec(1, 0, 0.5)).isApprox(Vec3(-1, 0, 0.5), 1e-12));
  // Pitched nose down by 90 deg about y: body forward points down the world z.
  EXPECT_TRUE(worldVelocity(quat(h, 0, h, 0), vec(1, 0, 0)).isApprox(Vec3(0, 0, -1), 1e-12));
  // Identity, and a quaternion not of unit length (normalised first): the speed is kept.
  EXPECT_TRUE(worldVelocity(quat(1, 0, 0, 0), vec(0.3, -0.2, 0.1)).isApprox(Vec3(0.3, -0.2, 0.1), 1e-12));
  EXPECT_TRUE(worldVelocity(quat(2 * h, 0, 0, 2 * h), vec(2, 0, 0)).isApprox(Vec3(0, 2, 0), 1e-12));
  // The inverse of what the simulator publishes: body = q^-1 * world.
  const Eigen::Quaterniond q = Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized();
  const Vec3 world(1.2, -0.7, 0.4);
  const Vec3 body = q.inverse() * world;
  EXPECT_TRUE(worldVelocity(quat(q.w(), q.x(), q.y(), q.z()), vec(body.x(), body.y(), body.z()))
                  .isApprox(world, 1e-12));
}

// nav_msgs/Odometry's twist is in child_frame_id: the body (turned into the world), or the header's own
// frame when the two are the same (VINS writes "world" for both): then it is taken as it is. It used to be
// turned by the heading whatever the frames said: VINS odometry at yaw 90 deg flying +x planned from +y.
// Odometry in another frame than the map's is refused, naming both.
TEST(Conversions, OdometryVelocityFollowsTheChildFrameAndTheFrameMustBeTheMaps) {
  const double h = std::sqrt(0.5);
  nav_msgs::Odometry odom;
  odom.header.frame_id = "world";
  odom.pose.pose.orientation = quat(h, 0, 0, h);  // heading +y
  odom.twist.twist.linear = vec(2, 0, 0.5);
  odom.child_frame_id = "body";
  EXPECT_TRUE(odometryVelocity(odom).isApprox(Vec3(0, 2, 0.5), 1e-12));
  odom.child_frame_id = "";  // unnamed: still the child frame, as the message defines
  EXPECT_TRUE(odometryVelocity(odom).isApprox(Vec3(0, 2, 0.5), 1e-12));
  odom.child_frame_id = "world";
  EXPECT_TRUE(odometryVelocity(odom).isApprox(Vec3(2, 0, 0.5), 1e-12));
  Vec3 v;
  EXPECT_EQ(odometryProblem(odom, "world", 20.0, "planner/max_input_speed", v), "");
  EXPECT_TRUE(v.isApprox(Vec3(2, 0, 0.5), 1e-12));
  EXPECT_EQ(odometryPoseProblem(odom, "world"), "");
  odom.header.frame_id = "odom";
  odom.child_frame_id = "body";
  for (const std::string& bad : {odometryPoseProblem(odom, "world"), odometryProblem(odom, "world", 20.0, "x", v)}) {
    EXPECT_NE(bad.find("'odom'"), std::string::npos) << bad;
    EXPECT_NE(bad.find("'world'"), std::string::npos) << bad;
  }
  odom.header.frame_id = "world";
  odom.twist.twist.linear = vec(30, 0, 0);
  EXPECT_NE(odometryProblem(odom, "world", 20.0, "planner/max_input_speed", v).find("planner/max_input_speed"),
            std::string::npos);
}

TEST(Conversions, YawOfAnyScaledQuaternionIsItsRotationsHeading) {
  // Against the heading of the rotation matrix's x axis, for rotations about every axis and scales.
  const Eigen::Quaterniond rotations[] = {
      Eigen::Quaterniond(Eigen::AngleAxisd(2.5, Vec3::UnitZ())),
      Eigen::Quaterniond(Eigen::AngleAxisd(-1.2, Vec3::UnitZ()) * Eigen::AngleAxisd(0.3, Vec3::UnitY())),
      Eigen::Quaterniond(0.9, 0.1, -0.3, 0.2).normalized()};
  for (const Eigen::Quaterniond& r : rotations) {
    const Vec3 x = r.toRotationMatrix().col(0);
    for (double scale : {1.0, 0.5, 3.0})
      EXPECT_NEAR(yawOf(quat(scale * r.w(), scale * r.x(), scale * r.y(), scale * r.z())), std::atan2(x.y(), x.x()),
                  1e-12)
          << "scale " << scale;
  }
}

TEST(Conversions, OdometryPosesThatAreNotFiniteOrNotARotationAreNamed) {
  geometry_msgs::Pose pose;
  pose.position.x = 1.0, pose.position.y = -2.0, pose.position.z = 1.5;
  pose.orientation = quat(std::sqrt(0.5), 0, 0, std::sqrt(0.5));
  EXPECT_EQ(odometryPoseProblem(pose), "");
  const double nan = std::numeric_limits<double>::quiet_NaN();
  geometry_msgs::Pose bad = pose;
  bad.position.y = nan;
  EXPECT_NE(odometryPoseProblem(bad).find("position"), std::string::npos) << odometryPoseProblem(bad);
  bad = pose;
  bad.position.z = std::numeric_limits<double>::infinity();
  EXPECT_NE(odometryPoseProblem(bad).find("position"), std::string::npos);
  bad = pose;
  bad.orientation.z = nan;  // a finite position with an unusable heading: what the planners once took
  EXPECT_NE(odometryPoseProblem(bad).find("orientation"), std::string::npos) << odometryPoseProblem(bad);
  bad.orientation = quat(0, 0, 0, 0);  // left unset
  EXPECT_NE(odometryPoseProblem(bad).find("not a unit quaternion"), std::string::npos) << odometryPoseProblem(bad);
  bad.orientation = quat(2.0, 0, 0, 0);
  EXPECT_NE(odometryPoseProblem(bad).find("orientation"), std::string::npos);
  // Within 1e-3 of unit length (as tf2 accepts): used.
  bad.orientation = quat(1.0005, 0, 0, 0);
  EXPECT_EQ(odometryPoseProblem(bad), "");
}

// The chain's own messages checked on arrival (go_feap/ros/message_checks.h): a well-formed message
// passes, and each single fault is refused with its field (and the frontier's id) named.
go_feap::FrontierArray twoFrontiers() {
  go_feap::FrontierArray msg;
  for (std::uint32_t id : {7u, 9u}) {
    go_feap::Frontier f;
    f.id = id;
    for (double x : {1.05, 1.15, 1.25}) f.cells.push_back(point(x, -0.95, 1.45));
    f.average = point(1.15, -0.95, 1.45);
    f.aabb_min = point(1.0, -1.0, 1.4);
    f.aabb_max = point(1.3, -0.9, 1.5);
    f.duration = 3.5;
    f.omission_likelihood = 0.2;
    msg.frontiers.push_back(f);
  }
  return msg;
}

bool says(const std::string& problem, const std::string& what) {
  return problem.find(what) != std::string::npos;
}

// Flown distance from odometry: the first message adds nothing, a step up to max_step adds its length,
// a longer one is a jump (a relocalisation) and adds nothing.
// Stamps that ApproximateTime may hold together: any two accepted against one clock are less than 2^31 s
// apart (its ros::Time subtraction throws beyond); with no clock yet (now 0), stamps below 2^31 s.
TEST(Conversions, PairableStampsAreLessThan2To31SecondsApart) {
  using go_feap::ros_conv::pairableStamp;
  const double k30 = std::ldexp(1.0, 30), k31 = std::ldexp(1.0, 31);
  for (double now : {100.0, 1.8e9, 4.0e9}) {
    EXPECT_TRUE(pairableStamp(now, now));
    EXPECT_TRUE(pairableStamp(now + k30 - 1.0, now));
    EXPECT_FALSE(pairableStamp(now + k30, now));
    EXPECT_TRUE(pairableStamp(now - k30 + 1.0, now));
    EXPECT_FALSE(pairableStamp(now - k30, now));
    EXPECT_FALSE(pairableStamp(now + 4.0e9, now));
  }
  EXPECT_FALSE(pairableStamp(4.0e9, 100.0));  // a sender's clock gone wrong, under sim time
  EXPECT_FALSE(pairableStamp(4.0e9, 1.8e9));  // and under wall time
  EXPECT_FALSE(pairableStamp(1.8e9, 100.0));  // wall stamps under a simulated clock
  // No clock yet: wall stamps pass, stamps from 2^31 s on do not.
  EXPECT_TRUE(pairableStamp(1.8e9, 0.0));
  EXPECT_TRUE(pairableStamp(0.5, 0.0));
  EXPECT_FALSE(pairableStamp(k31, 0.0));
  EXPECT_FALSE(pairableStamp(4.0e9, 0.0));
}

TEST(Conversions, VelocitiesNotFiniteOrFasterThanTheLimitAreNamed) {
  using go_feap::ros_conv::velocityProblem;
  EXPECT_EQ(velocityProblem(Vec3(12, 0, 16), 20.0, "planner/max_input_speed"), "");  // 20 m/s
  EXPECT_TRUE(says(velocityProblem(Vec3(0, std::nan(""), 0), 20.0, "x"), "velocity (0, nan, 0) is not finite"))
      << velocityProblem(Vec3(0, std::nan(""), 0), 20.0, "x");
  // 1e200 m/s: its square overflows, and the speed named is still the true one.
  const std::string fast = velocityProblem(Vec3(1e200, 0, 0), 20.0, "/tp/planner/max_input_speed");
  EXPECT_TRUE(says(fast, "speed 1e+200 m/s is above /tp/planner/max_input_speed (20 m/s)")) << fast;
  EXPECT_TRUE(says(velocityProblem(Vec3(0, 0, -20.5), 20.0, "x"), "speed 20.5 m/s")) << velocityProblem(Vec3(0, 0, -20.5), 20.0, "x");
}

// What the trajectory server refuses: a trajectory commanding more than its speed, acceleration or heading
// rate limit.
TEST(Conversions, TrajectoriesMovingFasterThanTheServerTakesAreNamed) {
  using go_feap::ros_traj::motionProblem;
  go_feap::ros_traj::Trajectory t;
  // A braking plan from 20 m/s (planner/max_input_speed) at 2 m/s^2: its polygon stays within 30 m/s.
  t.position = go_feap::trajectory::safeStop(Vec3(0, 0, 1), Vec3(20, 0, 0), 2.0);
  // A heading turn of 3 rad as the planner makes them (1 rad/s, 5 rad/s^2): within 1 rad/s and a little.
  go_feap::trajectory::OptimizerConfig turn;
  auto yaw = go_feap::trajectory::yawTurn(0.0, 3.0, 0.0, turn);
  ASSERT_TRUE(yaw) << yaw.message();
  t.yaw = *yaw;
  EXPECT_EQ(motionProblem(t, 30.0, 50.0, 20.0), "");
  EXPECT_EQ(motionProblem(t, 30.0, 50.0, turn.yaw_rate_max * (1.0 + turn.limit_tolerance)), "");
  EXPECT_TRUE(says(motionProblem(t, 30.0, 1.5, 20.0), "m/s^2, above 1.5 m/s^2")) << motionProblem(t, 30.0, 1.5, 20.0);
  EXPECT_TRUE(says(motionProblem(t, 30.0, 50.0, 0.5), "rad/s, above 0.5 rad/s")) << motionProblem(t, 30.0, 50.0, 0.5);
  // The same points 1e-9 s apart: the reference would leap to the end at once.
  Eigen::MatrixXd q = t.position.controlPoints();
  t.position = go_feap::trajectory::UniformBspline(q, 3, 1e-9);
  EXPECT_TRUE(says(motionProblem(t, 30.0, 50.0, 20.0), "m/s, above 30 m/s")) << motionProblem(t, 30.0, 50.0, 20.0);
  // Finite control points whose differences overflow.
  q.col(q.cols() - 1) << 1e308, -1e308, 0.0;
  t.position = go_feap::trajectory::UniformBspline(q, 3, 0.1);
  EXPECT_TRUE(says(motionProblem(t, 30.0, 50.0, 20.0), "above 30 m/s")) << motionProblem(t, 30.0, 50.0, 20.0);
  // Standing still is fine.
  t.position = go_feap::trajectory::UniformBspline(Eigen::MatrixXd::Ones(3, 6), 3, 0.1);
  EXPECT_EQ(motionProblem(t, 30.0, 50.0, 20.0), "");
  // A heading that leaps 1e6 rad in one 0.05 s span (1e7 rad/s), and one whose points of +-1e308 rad make
  // the rate inf - inf (NaN) on the curve.
  Eigen::MatrixXd leap(1, 4);
  leap << 0.0, 0.0, 1e6, 1e6;
  t.yaw = go_feap::trajectory::UniformBspline(leap, 3, 0.05);
  EXPECT_TRUE(says(motionProblem(t, 30.0, 50.0, 20.0), "yaw control polygon turns at 2e+07 rad/s, above 20 rad/s"))
      << motionProblem(t, 30.0, 50.0, 20.0);
  leap << 0.0, 0.0, -1e6, -1e6;  // the other way round
  t.yaw = go_feap::trajectory::UniformBspline(leap, 3, 0.05);
  EXPECT_TRUE(says(motionProblem(t, 30.0, 50.0, 20.0), "yaw control polygon turns at 2e+07 rad/s, above 20 rad/s"))
      << motionProblem(t, 30.0, 50.0, 20.0);
  leap << 0.0, 0.0, 0.0, 1e6;  // in the last span
  t.yaw = go_feap::trajectory::UniformBspline(leap, 3, 0.05);
  EXPECT_TRUE(says(motionProblem(t, 30.0, 50.0, 20.0), "yaw control polygon turns at 2e+07 rad/s, above 20 rad/s"))
      << motionProblem(t, 30.0, 50.0, 20.0);
  Eigen::MatrixXd huge(1, 8);
  huge << 1e308, 0.0, 1e308, 0.0, 1e308, 0.0, 1e308, 0.0;
  t.yaw = go_feap::trajectory::UniformBspline(huge, 3, 0.05);
  EXPECT_TRUE(says(motionProblem(t, 30.0, 50.0, 20.0), "rad/s, above 20 rad/s")) << motionProblem(t, 30.0, 50.0, 20.0);
}

// A Bspline message the server flies is the planner's own kind: cubic (degree 2 at least: degree 1 jumps in
// velocity at each knot), uniform finite knots starting at -order spans (a sender counting knots from 0
// had its spline shifted order spans late in silence; a NaN knot passed the uniformity test).
TEST(Conversions, BsplineMessagesRoundTripAndMalformedOnesAreNamed) {
  go_feap::ros_traj::Trajectory t;
  static_cast<go_feap::trajectory::Trajectory&>(t) =
      go_feap::trajectory::stopTrajectory(Vec3(0, 0, 1), Vec3(2, 0, 0), 0.5, go_feap::trajectory::OptimizerConfig());
  t.id = 7;
  // A turning heading on a timeline of its own (0.37 s spans) and a start time: both come back as they were.
  t.yaw = go_feap::trajectory::UniformBspline((Eigen::MatrixXd(1, 6) << 0.0, 0.2, 0.5, 0.9, 1.2, 1.2).finished(), 3, 0.37);
  t.start_time = ros::Time(12, 500000000);
  ASSERT_NE(t.position.knotSpan(), 0.37);
  const go_feap::Bspline good = go_feap::ros_traj::toMsg(t);
  const auto back = go_feap::ros_traj::fromMsg(good);
  ASSERT_TRUE(back) << back.message();
  EXPECT_EQ(back->id, 7);
  for (double s : {0.0, 0.3, t.position.duration()})
    EXPECT_LT((back->position.position(s) - t.position.position(s)).norm(), 1e-12) << s;
  EXPECT_EQ(back->yaw.knotSpan(), 0.37);
  EXPECT_EQ(back->yaw.controlPoints(), t.yaw.controlPoints());
  EXPECT_EQ(back->start_time, t.start_time);
  auto refused = [&](const std::function<void(go_feap::Bspline&)>& spoil, const std::string& says_what) {
    go_feap::Bspline m = good;
    spoil(m);
    const auto r = go_feap::ros_traj::fromMsg(m);
    ASSERT_FALSE(r) << says_what;
    EXPECT_TRUE(says(r.message(), says_what)) << r.message();
  };
  refused([](go_feap::Bspline& m) { m.knots[3] = std::nan(""); }, "knots are not uniform (or not finite)");
  refused([](go_feap::Bspline& m) { m.knots[0] = std::nan(""); }, "knot span must be finite");
  refused([](go_feap::Bspline& m) {
    const double dt = m.knots[1] - m.knots[0];
    for (std::size_t i = 0; i < m.knots.size(); ++i) m.knots[i] = i * dt;  // from 0: order spans late
  }, "knots must start at -order * knot span");
  refused([](go_feap::Bspline& m) {  // degree 1 with knots that fit it
    m.order = 1;
    m.knots.pop_back();
    m.knots.pop_back();
    const double dt = m.knots[1] - m.knots[0];
    for (std::size_t i = 0; i < m.knots.size(); ++i) m.knots[i] = (static_cast<double>(i) - 1.0) * dt;
  }, "order 1 is not in [2, 7]");
  refused([](go_feap::Bspline& m) { m.pos_pts[2].y = std::nan(""); }, "a control point is not finite");
  refused([](go_feap::Bspline& m) { m.yaw_pts.resize(3); }, "at least 4 control points");
  refused([](go_feap::Bspline& m) { m.yaw_dt = -0.1; }, "yaw_dt must be finite and > 0");
  refused([](go_feap::Bspline& m) { m.yaw_pts[1] = std::numeric_limits<double>::infinity(); },
          "yaw control point is not finite");
  refused([](go_feap::Bspline& m) { m.knots.pop_back(); }, "knots, expected");
}

TEST(Conversions, FlownStepsCountUpToTheJumpLimit) {
  using go_feap::ros_conv::flownStep;
  EXPECT_EQ(flownStep(std::nullopt, Vec3(5, 0, 0), 1.0), std::optional<double>(0.0));
  EXPECT_NEAR(*flownStep(Vec3(0, 0, 0), Vec3(0.6, 0.8, 0), 1.0), 1.0, 1e-12);
  EXPECT_FALSE(flownStep(Vec3(0, 0, 0), Vec3(0, 0, 1.2), 1.0).has_value());
  EXPECT_NE(go_feap::ros_conv::odometryJump(Vec3(0, 0, 0), Vec3(0, 0, 1.2)).find("1.2"), std::string::npos);
}

TEST(MessageChecks, FrontierArraysWithAnyValueThatIsNotFiniteOrACountThatDoesNotMatchAreNamed) {
  const go_feap::FrontierArray good = twoFrontiers();
  EXPECT_EQ(frontierArrayProblem(good), "");
  EXPECT_EQ(frontierArrayProblem(go_feap::FrontierArray()), "") << "no frontier is a frontier array";
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  auto broken = [&](const std::function<void(go_feap::Frontier&)>& fault) {
    go_feap::FrontierArray msg = good;
    fault(msg.frontiers[1]);
    return frontierArrayProblem(msg);
  };
  std::string why = broken([&](go_feap::Frontier& f) { f.cells[2].z = nan; });
  EXPECT_TRUE(says(why, "frontier 9 (index 1)") && says(why, "cell 2")) << why;
  why = broken([&](go_feap::Frontier& f) { f.average.y = -inf; });
  EXPECT_TRUE(says(why, "frontier 9") && says(why, "average")) << why;
  why = broken([&](go_feap::Frontier& f) { f.aabb_max.x = nan; });
  EXPECT_TRUE(says(why, "box") && says(why, "not finite")) << why;
  why = broken([&](go_feap::Frontier& f) { std::swap(f.aabb_min, f.aabb_max); });
  EXPECT_TRUE(says(why, "box") && says(why, "inverted")) << why;
  why = broken([&](go_feap::Frontier& f) { f.aabb_min.z = f.aabb_max.z + 0.1; });  // inverted in z alone
  EXPECT_TRUE(says(why, "box") && says(why, "inverted")) << why;
  EXPECT_EQ(broken([&](go_feap::Frontier& f) { f.aabb_min = f.aabb_max; }), "") << "a box of one point";
  why = broken([&](go_feap::Frontier& f) { f.duration = -1.0; });
  EXPECT_TRUE(says(why, "duration")) << why;
  why = broken([&](go_feap::Frontier& f) { f.duration = inf; });
  EXPECT_TRUE(says(why, "duration")) << why;
  why = broken([&](go_feap::Frontier& f) {
    f.viewpoint_positions = {point(0.5, -0.5, 1.5)};
    f.viewpoint_yaws = {nan};
    f.viewpoint_visible = {40};
  });
  EXPECT_TRUE(says(why, "viewpoint 0")) << why;
  why = broken([&](go_feap::Frontier& f) { f.duration = nan; });
  EXPECT_TRUE(says(why, "duration")) << why;
  why = broken([&](go_feap::Frontier& f) { f.omission_likelihood = inf; });
  EXPECT_TRUE(says(why, "omission_likelihood")) << why;
  why = broken([&](go_feap::Frontier& f) { f.cells.clear(); });
  EXPECT_TRUE(says(why, "frontier 9") && says(why, "no cells")) << why;
  why = broken([&](go_feap::Frontier& f) { f.id = 0; });
  EXPECT_TRUE(says(why, "id 0")) << why;
  why = broken([&](go_feap::Frontier& f) { f.id = 7; });
  EXPECT_TRUE(says(why, "frontier 7 (index 1)") && says(why, "twice")) << why;
  // Viewpoints: optional, but as many yaws and counts as positions, all finite.
  why = broken([&](go_feap::Frontier& f) {
    f.viewpoint_positions = {point(0.5, -0.5, 1.5), point(0.6, -0.5, 1.5)};
    f.viewpoint_yaws = {0.1, 0.2};
    f.viewpoint_visible = {40, 35};
  });
  EXPECT_EQ(why, "");
  why = broken([&](go_feap::Frontier& f) {
    f.viewpoint_positions = {point(0.5, -0.5, 1.5), point(0.6, -0.5, 1.5)};
    f.viewpoint_yaws = {0.1};
    f.viewpoint_visible = {40, 35};
  });
  EXPECT_TRUE(says(why, "2 viewpoint positions but 1 yaws")) << why;
  why = broken([&](go_feap::Frontier& f) {
    f.viewpoint_positions = {point(0.5, -0.5, 1.5), point(0.6, -0.5, 1.5)};
    f.viewpoint_yaws = {0.1, 0.2};
    f.viewpoint_visible = {40};
  });
  EXPECT_TRUE(says(why, "2 viewpoint positions but 2 yaws and 1 visible counts")) << why;
  why = broken([&](go_feap::Frontier& f) { f.omission_likelihood = -0.1; });  // finite, but below 0
  EXPECT_TRUE(says(why, "omission_likelihood")) << why;
  why = broken([&](go_feap::Frontier& f) {
    f.viewpoint_positions = {point(0.5, nan, 1.5)};
    f.viewpoint_yaws = {0.1};
    f.viewpoint_visible = {40};
  });
  EXPECT_TRUE(says(why, "viewpoint 0")) << why;
}

TEST(MessageChecks, FrontierCellsAndAveragesOutsideTheMapAreNamed) {
  const go_feap::common::Aabb map{Vec3(-1.0, -2.0, 0.0), Vec3(2.0, 2.0, 3.0)};
  go_feap::FrontierArray msg = twoFrontiers();
  EXPECT_EQ(frontierOutside(msg, map), "");
  msg.frontiers[1].cells[0].x = 2.0;  // on the map's face: still inside
  EXPECT_EQ(frontierOutside(msg, map), "");
  msg.frontiers[1].cells[1].x = 2.0 + 1e-9;
  std::string why = frontierOutside(msg, map);
  EXPECT_TRUE(says(why, "frontier 9") && says(why, "cell 1") && says(why, "outside the map")) << why;
  msg = twoFrontiers();
  msg.frontiers[0].cells[2].z = 1e300;  // finite, but no voxel index holds it
  EXPECT_TRUE(says(frontierOutside(msg, map), "frontier 7 (index 0): cell 2")) << frontierOutside(msg, map);
  msg = twoFrontiers();
  msg.frontiers[0].average.z = -0.5;
  EXPECT_TRUE(says(frontierOutside(msg, map), "average")) << frontierOutside(msg, map);
}

TEST(MessageChecks, ToursLayersMapUpdatesAndStatusesThatAreMalformedAreNamed) {
  go_feap::GlobalTour tour;
  tour.frontier_ids = {7, 9};
  tour.waypoints = {point(1, 0, 1), point(2, 0, 1)};
  EXPECT_EQ(globalTourProblem(tour), "");
  EXPECT_EQ(globalTourProblem(go_feap::GlobalTour()), "");
  go_feap::GlobalTour bad = tour;
  bad.waypoints.pop_back();
  EXPECT_TRUE(says(globalTourProblem(bad), "2 frontier ids but 1 waypoints")) << globalTourProblem(bad);
  bad = tour;
  bad.waypoints[1].y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(says(globalTourProblem(bad), "waypoint 1") && says(globalTourProblem(bad), "frontier 9"))
      << globalTourProblem(bad);
  bad = tour;
  bad.frontier_ids = {7, 9, 7};
  bad.waypoints.push_back(point(3, 0, 1));
  EXPECT_TRUE(says(globalTourProblem(bad), "frontier 7 appears twice (at 2)")) << globalTourProblem(bad);

  go_feap::LayerBounds layer;
  layer.index = 1, layer.count = 3, layer.z_min = 1.0, layer.z_max = 2.0;
  EXPECT_EQ(layerBoundsProblem(layer), "");
  go_feap::LayerBounds bad_layer = layer;
  bad_layer.z_min = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(says(layerBoundsProblem(bad_layer), "band z")) << layerBoundsProblem(bad_layer);
  for (const auto& [lo, hi] : {std::pair{1.0, std::numeric_limits<double>::infinity()},
                                std::pair{-std::numeric_limits<double>::infinity(), 2.0}}) {
    bad_layer = layer;
    bad_layer.z_min = lo, bad_layer.z_max = hi;  // ordered, but not a band
    EXPECT_TRUE(says(layerBoundsProblem(bad_layer), "band z")) << layerBoundsProblem(bad_layer);
  }
  bad_layer = layer;
  bad_layer.z_max = 1.0;  // empty
  EXPECT_TRUE(says(layerBoundsProblem(bad_layer), "z_min < z_max")) << layerBoundsProblem(bad_layer);
  bad_layer = layer;
  bad_layer.index = 3;
  EXPECT_TRUE(says(layerBoundsProblem(bad_layer), "index 3")) << layerBoundsProblem(bad_layer);
  bad_layer.index = 0, bad_layer.count = 0;
  EXPECT_TRUE(says(layerBoundsProblem(bad_layer), "count 0")) << layerBoundsProblem(bad_layer);

  go_feap::MapUpdate update;
  update.changed_voxels = 12;
  update.changed_min = point(0, 0, 0);
  update.changed_max = point(1, 1, 1);
  EXPECT_EQ(mapUpdateProblem(update), "");
  go_feap::MapUpdate bad_update = update;
  bad_update.changed_max.z = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(says(mapUpdateProblem(bad_update), "not finite")) << mapUpdateProblem(bad_update);
  bad_update.changed_voxels = 0;  // nothing changed: the box means nothing
  EXPECT_EQ(mapUpdateProblem(bad_update), "");
  bad_update = update;
  std::swap(bad_update.changed_min, bad_update.changed_max);
  EXPECT_TRUE(says(mapUpdateProblem(bad_update), "inverted")) << mapUpdateProblem(bad_update);

  go_feap::ExplorationStatus status;
  status.state = go_feap::ExplorationStatus::FINISHED;
  status.elapsed = 118.5, status.distance = 120.0, status.coverage = -1.0;  // -1: coverage unknown
  EXPECT_EQ(explorationStatusProblem(status), "");
  go_feap::ExplorationStatus bad_status = status;
  bad_status.state = 4;
  EXPECT_TRUE(says(explorationStatusProblem(bad_status), "state 4")) << explorationStatusProblem(bad_status);
  bad_status = status;
  bad_status.elapsed = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(says(explorationStatusProblem(bad_status), "elapsed")) << explorationStatusProblem(bad_status);
  bad_status.elapsed = 1e12;  // finite, but past what a ros::Duration holds
  EXPECT_TRUE(says(explorationStatusProblem(bad_status), "elapsed")) << explorationStatusProblem(bad_status);
  bad_status.elapsed = -1.0;  // finite, but before the start
  EXPECT_TRUE(says(explorationStatusProblem(bad_status), "elapsed")) << explorationStatusProblem(bad_status);
  bad_status = status;
  bad_status.distance = -3.0;
  EXPECT_TRUE(says(explorationStatusProblem(bad_status), "distance")) << explorationStatusProblem(bad_status);
  bad_status.distance = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(says(explorationStatusProblem(bad_status), "distance")) << explorationStatusProblem(bad_status);
  bad_status = status;
  bad_status.coverage = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(says(explorationStatusProblem(bad_status), "coverage")) << explorationStatusProblem(bad_status);

  go_feap::PositionCommand cmd;
  cmd.header.frame_id = "world";
  cmd.position = point(1, 2, 1.5);
  cmd.velocity.x = 0.5, cmd.acceleration.z = -0.2, cmd.yaw = 0.3, cmd.yaw_dot = 0.1;
  EXPECT_EQ(positionCommandProblem(cmd, "world"), "");
  go_feap::PositionCommand bad_cmd = cmd;
  bad_cmd.header.frame_id = "map";
  EXPECT_EQ(positionCommandProblem(bad_cmd, "world"), "the command is in frame 'map', not 'world' (world_frame)");
  bad_cmd.header.frame_id = "";
  EXPECT_TRUE(says(positionCommandProblem(bad_cmd, "world"), "frame ''")) << positionCommandProblem(bad_cmd, "world");
  bad_cmd = cmd;
  bad_cmd.position.z = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(says(positionCommandProblem(bad_cmd, "world"), "position")) << positionCommandProblem(bad_cmd, "world");
  bad_cmd = cmd;
  bad_cmd.velocity.y = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(says(positionCommandProblem(bad_cmd, "world"), "velocity")) << positionCommandProblem(bad_cmd, "world");
  bad_cmd = cmd;
  bad_cmd.acceleration.x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(says(positionCommandProblem(bad_cmd, "world"), "acceleration")) << positionCommandProblem(bad_cmd, "world");
  bad_cmd = cmd;
  bad_cmd.yaw_dot = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(says(positionCommandProblem(bad_cmd, "world"), "yaw")) << positionCommandProblem(bad_cmd, "world");
  // Every component counts: the yaw itself, and the vertical velocity and acceleration.
  bad_cmd = cmd;
  bad_cmd.yaw = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(positionCommandProblem(bad_cmd, "world"), "yaw or yaw_dot is not finite");
  bad_cmd = cmd;
  bad_cmd.velocity.z = std::numeric_limits<double>::infinity();
  EXPECT_EQ(positionCommandProblem(bad_cmd, "world"), "velocity or acceleration is not finite");
  bad_cmd = cmd;
  bad_cmd.acceleration.z = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(positionCommandProblem(bad_cmd, "world"), "velocity or acceleration is not finite");
}

// ros_guard: an exception a nodelet's callback throws stays in the callback (roscpp would pass it to
// std::terminate and end the nodelet manager); the callback runs again for the next message.
struct ThrowsOnZero {
  int calls = 0;
  void onMessage(const std_msgs::UInt32::ConstPtr& msg) {
    ++calls;
    if (msg->data == 0) throw std::runtime_error("zero");
  }
};

// Depth images: what the check passes, cv_bridge reads as a cv::Mat whose rows all lie in the data; what
// it names is each way of getting that wrong, including a step whose height x step wraps round 2^32 and
// so matches a tiny buffer in cv_bridge's own 32-bit check.
// The planners' gate opens with EXPLORE, stays open through FINAL_PASS and closes with FINISHED (the
// only update that says so); a refused status changes nothing.
TEST(MessageChecks, TheExplorationGateIsOpenOnlyWhileExploring) {
  ros::Time::init();  // its refusals are logged throttled, by the clock
  go_feap::ros_check::ExplorationGate gate("open", "closed");
  go_feap::ExplorationStatus status;
  EXPECT_FALSE(gate.open());  // nothing heard yet: waiting
  const std::pair<std::uint8_t, bool> steps[] = {{go_feap::ExplorationStatus::WAIT_TRIGGER, false},
                                                 {go_feap::ExplorationStatus::EXPLORE, true},
                                                 {go_feap::ExplorationStatus::EXPLORE, true},
                                                 {go_feap::ExplorationStatus::FINAL_PASS, true},
                                                 {go_feap::ExplorationStatus::FINISHED, false},
                                                 {go_feap::ExplorationStatus::FINISHED, false}};
  bool was_open = false;
  for (const auto& [state, open] : steps) {
    status.state = state;
    EXPECT_EQ(gate.update(status, "test"), was_open && !open) << int(state);
    EXPECT_EQ(gate.open(), open) << int(state);
    was_open = open;
  }
  status.state = go_feap::ExplorationStatus::EXPLORE;
  status.elapsed = std::numeric_limits<double>::quiet_NaN();  // refused: still closed
  EXPECT_FALSE(gate.update(status, "test"));
  EXPECT_FALSE(gate.open());
  status.elapsed = 1.0;
  EXPECT_FALSE(gate.update(status, "test"));
  EXPECT_TRUE(gate.open());
  status.state = 9;  // refused: still open
  EXPECT_FALSE(gate.update(status, "test"));
  EXPECT_TRUE(gate.open());
}

TEST(MessageChecks, DepthImagesThatCannotBeReadWholeAreNamed) {
  sensor_msgs::Image img;
  img.encoding = sensor_msgs::image_encodings::TYPE_32FC1;
  img.width = 4;
  img.height = 3;
  img.step = 20;  // padded rows
  img.data.assign(60, 0);
  EXPECT_EQ(depthImageProblem(img), "");
  const cv::Mat m = cv_bridge::toCvShare(boost::make_shared<sensor_msgs::Image>(img))->image;
  EXPECT_EQ(m.rows, 3);
  EXPECT_EQ(m.cols, 4);
  EXPECT_LE(static_cast<std::size_t>(m.ptr(2) - m.ptr(0)) + 16u, img.data.size());
  for (const char* mm : {"16UC1", "mono16"}) {
    sensor_msgs::Image u = img;
    u.encoding = mm;
    u.step = 8;
    u.data.assign(24, 0);
    EXPECT_EQ(depthImageProblem(u), "") << mm;
  }

  sensor_msgs::Image bad = img;
  bad.encoding = "rgb8";
  EXPECT_TRUE(says(depthImageProblem(bad), "encoding 'rgb8'")) << depthImageProblem(bad);
  bad = img;
  bad.width = 0;
  EXPECT_TRUE(says(depthImageProblem(bad), "0x3")) << depthImageProblem(bad);
  bad = img;
  bad.height = 0;  // no rows, no bytes: nothing to read either
  bad.data.clear();
  EXPECT_TRUE(says(depthImageProblem(bad), "4x0")) << depthImageProblem(bad);
  bad = img;
  bad.step = 12;  // narrower than 4 pixels of 4 bytes
  EXPECT_TRUE(says(depthImageProblem(bad), "step 12")) << depthImageProblem(bad);
  bad = img;
  bad.step = 18;  // not a whole number of pixels
  bad.data.assign(54, 0);
  EXPECT_TRUE(says(depthImageProblem(bad), "step 18")) << depthImageProblem(bad);
  bad = img;
  bad.data.pop_back();
  EXPECT_TRUE(says(depthImageProblem(bad), "59 bytes")) << depthImageProblem(bad);
  // 480 rows of 8947852 bytes are 4294968960 bytes, which is 1664 modulo 2^32.
  bad = img;
  bad.width = 640;
  bad.height = 480;
  bad.step = 8947852;
  bad.data.assign(1664, 0);
  EXPECT_TRUE(says(depthImageProblem(bad), "needs 4294968960")) << depthImageProblem(bad);
  // The other byte order: cv_bridge read a big-endian 32FC1 image as CV_8UC4 (refused as a wrong encoding).
  bad = img;
  bad.is_bigendian = 1;
  EXPECT_TRUE(says(depthImageProblem(bad), "is_bigendian 1")) << depthImageProblem(bad);
}

// A reader holds the map it got first; a handle to another one (the mapper reloaded) is named, not taken in
// silence, and an error of acceptHandle (no map) stays acceptHandle's.
TEST(SharedMap, AHandleToAnotherMapIsNamed) {
  namespace rm = go_feap::ros_map;
  const go_feap::common::Aabb box{Vec3(0, 0, 0), Vec3(1, 1, 1)};
  auto first = std::make_shared<rm::SharedMap>(std::make_unique<go_feap::map::VoxelMap>(go_feap::map::MapConfig(), box));
  auto second = std::make_shared<rm::SharedMap>(std::make_unique<go_feap::map::VoxelMap>(go_feap::map::MapConfig(), box));
  EXPECT_EQ(rm::otherMapProblem(rm::MapHandle{first}, first), "");
  EXPECT_EQ(rm::otherMapProblem(rm::MapHandle{}, first), "");
  EXPECT_NE(rm::otherMapProblem(rm::MapHandle{second}, first).find("another map"), std::string::npos);
}

// The samples round a stamp, as tf2 interpolates between them: the sample itself at its stamp, the two
// neighbours inside (moved or not), the last before with none after yet past the newest, none before the
// oldest or for a link never heard; out-of-order samples take their place, a clock gone back by more than
// the kept window starts afresh, old samples are dropped.
TEST(TfSampleLog, GivesTheSamplesRoundAStampAsTf2InterpolatesBetweenThem) {
  go_feap::ros_tf::SampleLog log(10.0);
  const auto t = [](double s) { return ros::Time(s); };
  const auto at = [](double x, double yaw = 0.0) {
    geometry_msgs::Transform p;
    p.translation.x = x;
    p.rotation.w = std::cos(0.5 * yaw), p.rotation.z = std::sin(0.5 * yaw);
    return p;
  };
  for (double s : {100.0, 100.1, 100.2}) log.add("body", t(s), at(s - 100.0));
  log.add("body", t(101.5), at(0.2));                       // still since 100.2
  log.add("body", t(103.0), at(0.2, 0.1));                  // turned
  log.add("/body", t(100.05), at(0.05));                    // out of order, named with tf's old leading '/'
  EXPECT_FALSE(log.around("camera", t(100.1)).has_value()) << "a link never heard";
  EXPECT_FALSE(log.around("body", t(99.0)).has_value()) << "before the first sample";
  auto b = log.around("body", t(104.0));  // past the newest: the last before, none after yet
  ASSERT_TRUE(b);
  EXPECT_EQ(b->before, t(103.0));
  EXPECT_FALSE(b->after.has_value());
  b = log.around("body", t(100.1));
  ASSERT_TRUE(b && b->after);
  EXPECT_EQ(b->before, t(100.1));
  EXPECT_EQ(*b->after, t(100.1));
  EXPECT_FALSE(b->moved);
  b = log.around("/body", t(100.07));
  ASSERT_TRUE(b && b->after);
  EXPECT_EQ(b->before, t(100.05));
  EXPECT_EQ(*b->after, t(100.1));
  EXPECT_TRUE(b->moved);
  b = log.around("body", t(101.0));  // a gap the link held still across: interpolated exactly
  ASSERT_TRUE(b && b->after);
  EXPECT_EQ(b->before, t(100.2));
  EXPECT_EQ(*b->after, t(101.5));
  EXPECT_FALSE(b->moved);
  b = log.around("body", t(102.0));  // a gap it turned across
  ASSERT_TRUE(b && b->after);
  EXPECT_TRUE(b->moved);
  log.add("body", t(111.0), at(0.0));  // 100.x now more than 10 s behind: dropped
  EXPECT_FALSE(log.around("body", t(100.1)).has_value());
  b = log.around("body", t(105.0));
  ASSERT_TRUE(b);
  EXPECT_EQ(b->before, t(103.0));
  log.add("body", t(50.0), at(0.0));  // a clock gone back (a bag played again): the link starts afresh
  EXPECT_FALSE(log.around("body", t(49.0)).has_value());
  b = log.around("body", t(50.0));
  ASSERT_TRUE(b && b->after);
  EXPECT_EQ(*b->after, t(50.0));
  log.add("body", t(0.0), at(0.0));  // a stamp of 0 is no sample
  EXPECT_FALSE(log.around("body", t(0.0)).has_value());
}

// A link moved between two samples when it went more than 1 mm or turned more than 1 mrad, along any axis:
// 5 mm up, 5 mrad about z and 5 mm along x are moves, 0.5 mm is none.
TEST(TfSampleLog, AMoveIsAMillimetreOrAMilliradianAlongAnyAxis) {
  go_feap::ros_tf::SampleLog log(10.0);
  auto pose = [](double x, double z, double yaw) {
    geometry_msgs::Transform p;
    p.translation.x = x, p.translation.z = z;
    p.rotation.w = std::cos(0.5 * yaw), p.rotation.z = std::sin(0.5 * yaw);
    return p;
  };
  const std::vector<std::tuple<std::string, geometry_msgs::Transform, bool>> cases = {
      {"up", pose(0.0, 1.005, 0.0), true},
      {"turned", pose(0.0, 1.0, 0.005), true},
      {"along", pose(0.005, 1.0, 0.0), true},
      {"jitter", pose(0.0005, 1.0, 0.0), false}};
  for (const auto& [link, after, moved] : cases) {
    log.add(link, ros::Time(10.0), pose(0.0, 1.0, 0.0));
    log.add(link, ros::Time(11.0), after);
    const auto b = log.around(link, ros::Time(10.5));
    ASSERT_TRUE(b && b->after) << link;
    EXPECT_EQ(b->moved, moved) << link;
  }
}

TEST(Guarded, AnExceptionFromACallbackStaysInItAndTheNextMessageIsTaken) {
  namespace guard = go_feap::ros_guard;
  ros::Time::init();  // the log's throttle reads the clock (a nodelet's is always set up)
  ThrowsOnZero object;
  const auto callback = guard::wrap("/probe", "the callback of 'count'", &ThrowsOnZero::onMessage, &object);
  auto zero = boost::make_shared<std_msgs::UInt32>(), one = boost::make_shared<std_msgs::UInt32>();
  zero->data = 0, one->data = 1;
  EXPECT_NO_THROW(callback(zero));
  EXPECT_NO_THROW(callback(one));
  EXPECT_NO_THROW(callback(zero));
  EXPECT_EQ(object.calls, 3);
  go_feap::ros_log::Throttle throttle;
  EXPECT_FALSE(guard::run("/probe", "a block", throttle, [] { throw std::out_of_range("index"); }));
  EXPECT_TRUE(guard::run("/probe", "a block", throttle, [] {}));
  // Only std::exception: others (boost::thread_interrupted stops the manager's threads) pass on.
  EXPECT_THROW(guard::run("/probe", "a block", throttle, [] { throw 7; }), int);
}

// The messages a test hears from rosconsole, as a nodelet's would go to /rosout.
class HeardLog : public ros::console::LogAppender {
 public:
  HeardLog() { ros::console::register_appender(this); }
  ~HeardLog() override { ros::console::deregister_appender(this); }
  void log(ros::console::Level, const char* str, const char*, const char*, int) override { lines.emplace_back(str); }
  std::size_t count(const std::string& part) const {
    return std::count_if(lines.begin(), lines.end(), [&](const std::string& l) { return l.find(part) != std::string::npos; });
  }
  std::vector<std::string> lines;
};

// A camera_info's intrinsics are the rectified image's, P's fx (P[0]), fy (P[5]), cx (P[2]) and cy (P[6]),
// which may differ from K's (the raw image's); K's fx (K[0]), fy (K[4]), cx (K[2]) and cy (K[5]) where P is
// unset (a driver filling K alone). Sides past int's range are clamped to it (then refused by
// DepthIntrinsics::validate() for an image that big, not wrapped negative). Distortion is any D not 0.
TEST(Conversions, CameraInfoGivesTheRectifiedIntrinsicsAndSidesWithinInt) {
  sensor_msgs::CameraInfo info;
  info.width = 640, info.height = 480;
  info.K = {381.0, 0.0, 319.5, 0.0, 382.0, 239.5, 0.0, 0.0, 1.0};
  const go_feap::map::DepthIntrinsics K = go_feap::ros_conv::depthIntrinsics(info);
  EXPECT_EQ(K, (go_feap::map::DepthIntrinsics{640, 480, 381.0, 382.0, 319.5, 239.5}));
  EXPECT_NE(K, (go_feap::map::DepthIntrinsics{640, 480, 381.0, 382.0, 319.5, 239.0}));
  info.P = {371.0, 0.0, 318.0, 0.0, 0.0, 372.0, 241.0, 0.0, 0.0, 0.0, 1.0, 0.0};
  EXPECT_EQ(go_feap::ros_conv::depthIntrinsics(info), (go_feap::map::DepthIntrinsics{640, 480, 371.0, 372.0, 318.0, 241.0}));
  info.width = std::numeric_limits<std::uint32_t>::max();
  EXPECT_EQ(go_feap::ros_conv::depthIntrinsics(info).width, std::numeric_limits<int>::max());
  EXPECT_FALSE(go_feap::ros_conv::hasDistortion(info));  // none given
  info.D = {0.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_FALSE(go_feap::ros_conv::hasDistortion(info));
  info.D[3] = -1e-4;
  EXPECT_TRUE(go_feap::ros_conv::hasDistortion(info));
}

// Handles without a map are normal at start-up (a latched copy; the mapper's next frame brings the map): said
// only once they have come for the whole patience, then once a patience; a clock gone back waits again.
TEST(SharedMap, EmptyHandlesAreSaidOnlyWhenTheyLast) {
  go_feap::ros_map::EmptyHandles empty(10.0);
  EXPECT_FALSE(empty.due(1.0));
  EXPECT_FALSE(empty.due(5.0));
  EXPECT_FALSE(empty.due(10.99));
  EXPECT_TRUE(empty.due(11.0));
  EXPECT_FALSE(empty.due(20.0));
  EXPECT_TRUE(empty.due(21.0));
  EXPECT_FALSE(empty.due(0.5));  // the clock went back
  EXPECT_FALSE(empty.due(10.0));
  EXPECT_TRUE(empty.due(10.5));
}

// A site's first message passes at once, whatever the clock says, then one a period; sites and throttles
// are apart; a clock that went back lets one pass at once. rosconsole's own throttle, one static per call
// site for the whole process counted from time 0, dropped every message of a simulation's first period.
TEST(LogThrottle, TheFirstMessagePassesThenOneAPeriodForEachSiteAndThrottle) {
  go_feap::ros_log::Throttle a, b;
  EXPECT_TRUE(a.pass("odometry", 2.0, 0.5));
  EXPECT_FALSE(a.pass("odometry", 2.0, 1.0));
  EXPECT_FALSE(a.pass("odometry", 2.0, 2.49));
  EXPECT_TRUE(a.pass("odometry", 2.0, 2.5));
  EXPECT_FALSE(a.pass("odometry", 2.0, 4.0));
  EXPECT_TRUE(a.pass("depth", 2.0, 4.0));  // another site
  EXPECT_TRUE(b.pass("odometry", 2.0, 4.0));  // another nodelet's
  EXPECT_TRUE(a.pass("odometry", 2.0, 0.1));  // the clock went back (a bag looped)
  EXPECT_FALSE(a.pass("odometry", 2.0, 0.2));
}

// Under a simulated clock at 0.5 s, a callback's first exception is logged, by each nodelet's callback;
// the same one again within the second is not, and a second later it is.
TEST(Guarded, TheFirstExceptionOfASimulationIsLogged) {
  namespace guard = go_feap::ros_guard;
  ros::Time::setNow(ros::Time(0.5));
  HeardLog heard;
  ThrowsOnZero one, other;
  const auto callback = guard::wrap("/one", "the callback of 'count'", &ThrowsOnZero::onMessage, &one);
  const auto others = guard::wrap("/other", "the callback of 'count'", &ThrowsOnZero::onMessage, &other);
  auto zero = boost::make_shared<std_msgs::UInt32>();
  callback(zero);
  callback(zero);
  others(zero);
  EXPECT_EQ(heard.count("/one: the callback of 'count' aborted by an exception: zero"), 1u);
  EXPECT_EQ(heard.count("/other: the callback of 'count' aborted by an exception: zero"), 1u);
  ros::Time::setNow(ros::Time(1.5));
  callback(zero);
  EXPECT_EQ(heard.count("/one: the callback of 'count' aborted"), 2u);
  EXPECT_EQ(one.calls, 3);
  ros::Time::init();  // the system clock again, for the tests after
}

}  // namespace
