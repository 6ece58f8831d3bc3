// rostest: QuadrotorSim + DepthCamera + SceneServer in one manager with use_sim_time.
#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <rosgraph_msgs/Log.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_listener.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <mutex>
#include <string>
#include <vector>

#include "go_feap/PositionCommand.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/world/scene_files.h"
#include "ros_test_util.h"

namespace {

using go_feap::test::spinUntil;

class SimulatorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    odom_sub_ = nh_.subscribe("odom", 100, &SimulatorTest::onOdom, this);
    depth_sub_ = nh_.subscribe("depth", 10, &SimulatorTest::onDepth, this);
    pose_sub_ = nh_.subscribe("camera_pose", 10, &SimulatorTest::onPose, this);
    info_sub_ = nh_.subscribe("camera_info", 10, &SimulatorTest::onInfo, this);
    cloud_sub_ = nh_.subscribe("scene_cloud", 1, &SimulatorTest::onCloud, this);
    cmd_pub_ = nh_.advertise<go_feap::PositionCommand>("position_cmd", 10);
  }

  // Spins until pred() holds or `wall_timeout` seconds pass.
  void spinSim(double sim_seconds) {
    const ros::Time end = ros::Time::now() + ros::Duration(sim_seconds);
    spinUntil([&] { return ros::Time::now() >= end; }, 10.0 * sim_seconds + 30.0);
  }

  void onOdom(const nav_msgs::Odometry::ConstPtr& m) {
    last_odom_ = m;
    ++odom_count_;
    if (keep_odoms_) odoms_.push_back(m);
  }
  void onDepth(const sensor_msgs::Image::ConstPtr& m) { depths_.push_back(m); }
  void onPose(const geometry_msgs::PoseStamped::ConstPtr& m) { poses_.push_back(m); }
  void onInfo(const sensor_msgs::CameraInfo::ConstPtr& m) { infos_.push_back(m); }
  void onCloud(const sensor_msgs::PointCloud2::ConstPtr& m) { cloud_ = m; }

  Eigen::Vector3d position() const {
    const auto& p = last_odom_->pose.pose.position;
    return Eigen::Vector3d(p.x, p.y, p.z);
  }
  void command(const Eigen::Vector3d& p, double yaw, double ax = 0.0) {
    go_feap::PositionCommand c = go_feap::test::holdCommand(p, yaw);
    c.acceleration.x = ax;
    cmd_pub_.publish(c);
  }

  ros::NodeHandle nh_;
  ros::Subscriber odom_sub_, depth_sub_, pose_sub_, info_sub_, cloud_sub_;
  ros::Publisher cmd_pub_;
  nav_msgs::Odometry::ConstPtr last_odom_;
  std::size_t odom_count_ = 0;
  bool keep_odoms_ = false;
  std::vector<nav_msgs::Odometry::ConstPtr> odoms_;
  std::deque<sensor_msgs::Image::ConstPtr> depths_;
  std::deque<geometry_msgs::PoseStamped::ConstPtr> poses_;
  std::deque<sensor_msgs::CameraInfo::ConstPtr> infos_;
  sensor_msgs::PointCloud2::ConstPtr cloud_;
};

TEST_F(SimulatorTest, CommandMovesOdomCameraStampsMatchNanIsIgnored) {
  // The camera's topics connected too: it loads beside a second camera and the scene server, and a
  // window of frames counted before its connection is up counted none (0 frames, once in a full suite).
  ASSERT_TRUE(spinUntil(
      [&] {
        return last_odom_ && cloud_ && depth_sub_.getNumPublishers() > 0 && pose_sub_.getNumPublishers() > 0 &&
               info_sub_.getNumPublishers() > 0;
      },
      60.0))
      << "no odom or scene_cloud, or the camera's topics are not connected";
  // scene_cloud is the scene's occupied voxels, each once, at its centre, in the world frame.
  {
    auto scene = go_feap::world::makeScene("maze", 0);
    ASSERT_TRUE(scene) << scene.message();
    EXPECT_EQ(cloud_->header.frame_id, "world");
    ASSERT_EQ(std::size_t{cloud_->width} * cloud_->height, scene->occupiedCount());
    const auto& geo = scene->geometry();
    std::vector<char> seen(geo.size(), 0);
    std::size_t wrong = 0;
    sensor_msgs::PointCloud2ConstIterator<float> x(*cloud_, "x"), y(*cloud_, "y"), z(*cloud_, "z");
    for (; x != x.end(); ++x, ++y, ++z) {
      const Eigen::Vector3d p(*x, *y, *z);
      const go_feap::common::Index3 i = geo.coordToIndex(p);
      if (!geo.inside(i) || !scene->occupied[geo.linear(i)] || (geo.indexToCoord(i) - p).norm() > 1e-5 ||
          seen[geo.linear(i)]++)
        ++wrong;
    }
    EXPECT_EQ(wrong, 0u) << "points not at the centre of an occupied voxel, or repeated";
  }
  const Eigen::Vector3d start = position();
  // Maze seed 0 starts at the centre of cell (0, 0): (-9, -4, 1); 1 m ahead is free.
  EXPECT_LT((start - Eigen::Vector3d(-9, -4, 1)).norm(), 0.05);

  const Eigen::Vector3d target = start + Eigen::Vector3d(1.0, 0.5, 0.3);
  keep_odoms_ = true;
  ASSERT_TRUE(spinUntil(
      [&] {
        command(target, 0.5);
        return (position() - target).norm() < 0.05;
      },
      60.0))
      << "odom did not reach the target; at " << position().transpose();
  keep_odoms_ = false;
  // The twist is in the body frame (nav_msgs/Odometry: the child frame), turned 0.5 rad from the world's on
  // the way: the world velocity from the positions either side of each message is its orientation applied
  // to its twist.
  auto vec = [](const auto& v) { return Eigen::Vector3d(v.x, v.y, v.z); };
  std::size_t moving = 0;
  for (std::size_t k = 1; k + 1 < odoms_.size(); ++k) {
    const auto &before = *odoms_[k - 1], &at = *odoms_[k], &after = *odoms_[k + 1];
    const double dt = (after.header.stamp - before.header.stamp).toSec();
    if (!(dt > 0.0)) continue;
    const Eigen::Vector3d v_world = (vec(after.pose.pose.position) - vec(before.pose.pose.position)) / dt;
    if (v_world.norm() < 0.3) continue;
    const auto& q = at.pose.pose.orientation;
    const Eigen::Quaterniond attitude(q.w, q.x, q.y, q.z);
    EXPECT_LT((attitude * vec(at.twist.twist.linear) - v_world).norm(), 0.05 * v_world.norm() + 0.02)
        << "at " << at.header.stamp << ": body twist " << vec(at.twist.twist.linear).transpose() << ", world velocity "
        << v_world.transpose();
    // As the planners read it: the child frame says the twist is the body's (with "world" there they took
    // it as the world velocity, turned by the yaw).
    EXPECT_EQ(at.child_frame_id, "body");
    EXPECT_LT((go_feap::ros_conv::odometryVelocity(at) - v_world).norm(), 0.05 * v_world.norm() + 0.02)
        << "at " << at.header.stamp << ": odometryVelocity " << go_feap::ros_conv::odometryVelocity(at).transpose();
    ++moving;
  }
  EXPECT_GE(moving, 10u) << "too few odometry messages while moving to check the twist";

  // Depth and camera_pose: same stamps, 15 Hz, sensible content.
  depths_.clear();
  poses_.clear();
  infos_.clear();
  spinSim(1.0);
  ASSERT_GE(depths_.size(), 10u);
  ASSERT_GE(poses_.size(), 10u);
  std::size_t matched = 0;
  for (const auto& d : depths_)
    for (const auto& p : poses_) matched += d->header.stamp == p->header.stamp;
  EXPECT_GE(matched + 1, std::min(depths_.size(), poses_.size()));
  const auto& img = *depths_.back();
  EXPECT_EQ(img.encoding, "32FC1");
  EXPECT_EQ(img.width, 640u);
  EXPECT_EQ(img.height, 480u);
  ASSERT_FALSE(infos_.empty());
  // Every depth image has the camera_info of its stamp (compared this way round: the newest
  // camera_info may arrive before its image does, and the other way round: the images taken so far
  // are matched against the camera_infos that come in the next moment too). The one allowed miss is
  // the first image, whose camera_info may have come before the lists were cleared.
  const std::deque<sensor_msgs::Image::ConstPtr> images = depths_;
  spinUntil([] { return false; }, 0.3);
  std::size_t with_info = 0;
  for (const auto& d : images)
    for (const auto& i : infos_) {
      if (d->header.stamp == i->header.stamp) {
        ++with_info;
        break;
      }
    }
  EXPECT_GE(with_info + 1, images.size()) << "depth images without a camera_info of the same stamp";
  {  // the intrinsics config/sim.yaml derives from its fields of view: 640 x 480, 80 x 60 deg, centred
    const double fx = 320.0 / std::tan(40.0 * M_PI / 180.0), fy = 240.0 / std::tan(30.0 * M_PI / 180.0);
    const auto& info = *infos_.back();
    EXPECT_EQ(info.width, 640u);
    EXPECT_EQ(info.height, 480u);
    const std::vector<double> K(info.K.begin(), info.K.end()), P(info.P.begin(), info.P.end());
    const std::vector<double> K_expected{fx, 0, 319.5, 0, fy, 239.5, 0, 0, 1};
    const std::vector<double> P_expected{fx, 0, 319.5, 0, 0, fy, 239.5, 0, 0, 0, 1, 0};
    for (std::size_t i = 0; i < K.size(); ++i) EXPECT_NEAR(K[i], K_expected[i], 1e-6) << "K[" << i << "]";
    for (std::size_t i = 0; i < P.size(); ++i) EXPECT_NEAR(P[i], P_expected[i], 1e-6) << "P[" << i << "]";
  }
  const float* px = reinterpret_cast<const float*>(img.data.data());
  std::size_t valid = 0;
  for (std::size_t i = 0; i < img.width * img.height; ++i) valid += px[i] > 0.1f && px[i] <= 4.5f;
  EXPECT_GT(valid, img.width * img.height / 4) << "walls of the maze should fill much of the view";
  // The camera sits 0.1 m ahead of the body centre.
  const auto& cp = poses_.back()->pose.position;
  EXPECT_NEAR(std::hypot(cp.x - position().x(), cp.y - position().y()), 0.1, 0.02);

  // A NaN command (position or yaw), or one turning faster than simulation/max_command_yaw_rate, must not move
  // or turn the vehicle or stop the simulator. Each is a world-frame hold but for its one bad value, so only
  // the value check can refuse it.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<go_feap::PositionCommand> bad(3, go_feap::test::holdCommand(target, 0.5));
  bad[0].position.x = nan;
  bad[1].yaw = nan;
  bad[2] = go_feap::test::holdCommand(target, 0.5, 1e3);
  double max_yaw_rate = 0.0;
  ASSERT_TRUE(ros::param::get("quadrotor_sim/simulation/max_command_yaw_rate", max_yaw_rate));
  ASSERT_LT(max_yaw_rate, 1e3);
  const std::size_t before = odom_count_;
  for (int i = 0; i < 30; ++i) {
    cmd_pub_.publish(bad[i % 3]);
    spinSim(0.05);
  }
  go_feap::PositionCommand elsewhere = go_feap::test::holdCommand(target + Eigen::Vector3d(0.5, 0.0, 0.0), 0.5);
  elsewhere.header.frame_id = "map";  // another frame: refused, it was flown as if in the world frame
  for (int i = 0; i < 20; ++i) {
    cmd_pub_.publish(elsewhere);
    spinSim(0.05);
  }
  command(target + Eigen::Vector3d(0, 0, 0), 0.5, /*ax=*/1000.0);  // absurd acceleration: refused too
  go_feap::PositionCommand fast = go_feap::test::holdCommand(target, 0.5);
  fast.velocity.z = 1e308;  // finite: it made the controller's state NaN for good, and odometry stopped
  cmd_pub_.publish(fast);
  spinSim(1.0);
  EXPECT_GT(odom_count_, before + 50);
  EXPECT_LT((position() - target).norm(), 0.05) << "at " << position().transpose();
  const auto& q = last_odom_->pose.pose.orientation;
  const double yaw = std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
  EXPECT_LT(std::abs(std::remainder(yaw - 0.5, 2.0 * M_PI)), 0.05) << "turned to " << yaw << " rad";

  // One odometry message stamped far ahead (4e9 s, a clock gone wrong) must not hold the camera back until
  // then: frames follow the simulator's odometry again at once.
  ros::Publisher odom_pub = nh_.advertise<nav_msgs::Odometry>("odom", 1);
  ASSERT_TRUE(spinUntil([&] { return odom_pub.getNumSubscribers() >= 2; }, 10.0));  // the camera, and this test
  // The camera's odometry queue also takes the simulator's 100 Hz: a message may be dropped, so each
  // is sent again until the camera's frame of that stamp comes.
  auto sendUntilRendered = [&](const nav_msgs::Odometry& odom) {
    int sends = 0;
    ros::WallTime last;
    const bool rendered = spinUntil([&] {
      for (const auto& d : depths_)
        if (d->header.stamp == odom.header.stamp) return true;
      if (last.isZero() || (ros::WallTime::now() - last).toSec() >= 0.5) {
        odom_pub.publish(odom);
        ++sends;
        last = ros::WallTime::now();
      }
      return false;
    }, 20.0);
    return rendered ? sends : 0;
  };
  nav_msgs::Odometry far = *last_odom_;
  far.header.stamp = ros::Time(4000000000u, 0);
  depths_.clear();
  ASSERT_GE(sendUntilRendered(far), 1) << "no depth frame at the far stamp";
  spinSim(0.2);
  depths_.clear();
  spinSim(1.0);
  std::size_t current = 0;
  for (const auto& d : depths_) current += d->header.stamp.sec < 4000000000u;
  EXPECT_GE(current, 10u) << depths_.size() << " depth frames in 1 s after the far stamp, " << current
                          << " at the simulator's time";

  // One stamped within a frame period of the largest time a ros::Time holds: its frame is taken (the next
  // frame's time, one period on, is past that largest time), and the frames after it follow the simulator.
  nav_msgs::Odometry edge = *last_odom_;
  edge.header.stamp = ros::Time(4294967295u, 990000000u);
  depths_.clear();
  const int sends = sendUntilRendered(edge);
  ASSERT_GE(sends, 1) << "no depth frame at the stamp 1 ms before the largest ros::Time";
  spinSim(1.0);
  std::size_t at_edge = 0;
  current = 0;
  for (const auto& d : depths_) {
    at_edge += d->header.stamp == edge.header.stamp;
    current += d->header.stamp.sec < 4000000000u;
  }
  EXPECT_LE(at_edge, static_cast<std::size_t>(sends)) << "more frames at the edge stamp than it was sent";
  EXPECT_GE(current, 10u) << "after the stamp at the largest ros::Time";
}

// The probe camera (probe/... in simulator.test) gets odometry whose stamp stands still: one frame, and
// then a warning naming the stamp, where it used to say nothing. Once the stamps advance, frames follow
// and it says so.
// The TF the simulator sends (world -> body from the odometry, body -> camera from the camera's T_B_C) gives
// the camera_pose of each frame at its stamp: what a mapper in sync_mode tf (a replayed record_flight bag)
// looks up instead of camera_pose. The vehicle turns meanwhile, so a transform inverted or its frames
// swapped would not agree.
TEST_F(SimulatorTest, TheTfAtAFramesStampIsItsCameraPose) {
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  ASSERT_TRUE(spinUntil([&] { return last_odom_ != nullptr; }, 60.0)) << "no odom";
  const Eigen::Vector3d centre = position();
  const ros::Time t0 = ros::Time::now();
  depths_.clear();
  poses_.clear();
  spinUntil([&] {
    cmd_pub_.publish(go_feap::test::holdCommand(centre, 0.8 * (ros::Time::now() - t0).toSec(), 0.8));
    return (ros::Time::now() - t0).toSec() > 1.5;
  }, 30.0);
  ASSERT_GE(poses_.size(), 10u);
  ASSERT_FALSE(depths_.empty());
  const std::string camera = depths_.back()->header.frame_id;
  std::size_t checked = 0;
  for (std::size_t i = 2; i + 2 < poses_.size(); ++i) {  // stamps the TF has on both sides
    const geometry_msgs::PoseStamped& p = *poses_[i];
    geometry_msgs::TransformStamped tf;
    try {
      tf = buffer.lookupTransform(p.header.frame_id, camera, p.header.stamp);
    } catch (const tf2::TransformException& e) {
      ADD_FAILURE() << "no TF " << p.header.frame_id << " -> " << camera << " at " << p.header.stamp << ": " << e.what();
      continue;
    }
    const auto& q = tf.transform.rotation;
    const auto& o = p.pose.orientation;
    EXPECT_NEAR(tf.transform.translation.x, p.pose.position.x, 1e-4);
    EXPECT_NEAR(tf.transform.translation.y, p.pose.position.y, 1e-4);
    EXPECT_NEAR(tf.transform.translation.z, p.pose.position.z, 1e-4);
    EXPECT_NEAR(std::abs(q.w * o.w + q.x * o.x + q.y * o.y + q.z * o.z), 1.0, 1e-6) << "at " << p.header.stamp;
    ++checked;
  }
  EXPECT_GE(checked, 5u);
}

TEST_F(SimulatorTest, OdometryWhoseStampStandsStillIsReported) {
  ASSERT_TRUE(spinUntil([&] { return last_odom_ != nullptr; }, 60.0)) << "no odom";
  ros::Publisher odom_pub = nh_.advertise<nav_msgs::Odometry>("probe/odom", 10);
  std::vector<ros::Time> frames;
  ros::Subscriber depth_sub = nh_.subscribe<sensor_msgs::Image>(
      "probe/depth", 10, [&](const sensor_msgs::Image::ConstPtr& m) { frames.push_back(m->header.stamp); });
  std::vector<std::string> said;
  ros::Subscriber log_sub = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->msg.find("/probe_depth_camera:") != std::string::npos) said.push_back(m->msg);  // m->name is the manager
  });
  ASSERT_TRUE(spinUntil([&] { return odom_pub.getNumSubscribers() > 0 && depth_sub.getNumPublishers() > 0 &&
                                     log_sub.getNumPublishers() > 0; }, 30.0))
      << "the probe camera is not connected";
  auto heard = [&](const std::string& what) {
    for (const std::string& m : said)
      if (m.find(what) != std::string::npos) return true;
    return false;
  };
  nav_msgs::Odometry odom = *last_odom_;
  odom.header.stamp = ros::Time(1000.0);
  // Sent at 50 Hz of wall time, well within what the camera takes: none is dropped from its queue.
  int sends = 0;
  const bool warned = spinUntil([&] {
    if (heard("odometry stamp 1000 s repeated")) return true;
    odom_pub.publish(odom);
    ++sends;
    ros::WallDuration(0.02).sleep();
    return false;
  }, 20.0);
  EXPECT_TRUE(warned) << sends << " messages stamped 1000 s and no word of it";
  EXPECT_LE(frames.size(), 1u) << "frames from one repeated stamp";
  for (const ros::Time& f : frames) EXPECT_EQ(f, odom.header.stamp);

  frames.clear();
  for (int k = 1; k <= 20; ++k) {
    odom.header.stamp = ros::Time(1000.0 + 0.05 * k);
    odom_pub.publish(odom);
    spinUntil([] { return false; }, 0.02);
  }
  EXPECT_TRUE(spinUntil([&] { return frames.size() >= 5 && heard("odometry stamps advance again"); }, 10.0))
      << frames.size() << " frames over 1 s of advancing stamps";
}

// OdometryTf puts only odometry the map can use into TF: a pose in another frame (VIO's "odom" beside the
// map's "world"), a pose that is not finite and a stamp of 0 are refused, said, and leave no TF; the next
// good message is world -> body at its stamp, and the camera hangs below the body by the extrinsic.
TEST_F(SimulatorTest, OdometryTfSendsOnlyOdometryInTheWorldFrame) {
  tf2_ros::Buffer buffer;
  tf2_ros::TransformListener listener(buffer);
  ros::Publisher odom_pub = nh_.advertise<nav_msgs::Odometry>("probe/vio_odom", 10);
  std::vector<std::string> said;
  ros::Subscriber log_sub = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->msg.find("/probe_odometry_tf:") != std::string::npos) said.push_back(m->msg);
  });
  ASSERT_TRUE(spinUntil([&] { return odom_pub.getNumSubscribers() > 0 && log_sub.getNumPublishers() > 0; }, 30.0))
      << "the probe OdometryTf is not connected";
  auto heard = [&](const std::string& what) {
    return std::any_of(said.begin(), said.end(), [&](const std::string& m) { return m.find(what) != std::string::npos; });
  };
  auto odometry = [](const char* frame, double t, const Eigen::Vector3d& p) {
    nav_msgs::Odometry m;
    m.header.stamp = ros::Time(t);
    m.header.frame_id = frame;
    m.child_frame_id = "probe_body";
    m.pose.pose.position.x = p.x(), m.pose.pose.position.y = p.y(), m.pose.pose.position.z = p.z();
    m.pose.pose.orientation.w = 1.0;
    return m;
  };
  const double t0 = ros::Time::now().toSec() + 50.0;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  // Sent again until its refusal is heard (a /rosout connection from the manager may come up after the first).
  EXPECT_TRUE(spinUntil([&] {
    odom_pub.publish(odometry("odom", t0, Eigen::Vector3d(2.0, 0.0, 1.0)));
    return spinUntil([&] { return heard("odometry refused: odometry is in frame 'odom'"); }, 0.3);
  }, 20.0)) << "no word of the odometry in frame 'odom'";
  odom_pub.publish(odometry("world", t0 + 0.05, Eigen::Vector3d(nan, 0.0, 1.0)));
  odom_pub.publish(odometry("world", 0.0, Eigen::Vector3d(3.0, 0.0, 1.0)));
  spinUntil([] { return false; }, 0.3);
  odom_pub.publish(odometry("world", t0 + 0.1, Eigen::Vector3d(1.0, 0.0, 1.0)));
  odom_pub.publish(odometry("world", t0 + 0.2, Eigen::Vector3d(1.2, 0.0, 1.0)));
  ASSERT_TRUE(spinUntil([&] { return buffer.canTransform("world", "probe_body", ros::Time(t0 + 0.2)); }, 10.0))
      << "no TF from the odometry in the world frame";
  const geometry_msgs::TransformStamped at = buffer.lookupTransform("world", "probe_body", ros::Time(t0 + 0.1));
  EXPECT_NEAR(at.transform.translation.x, 1.0, 1e-9);
  EXPECT_NEAR(at.transform.translation.z, 1.0, 1e-9);
  EXPECT_FALSE(buffer.canTransform("world", "probe_body", ros::Time(t0))) << "the pose in frame 'odom' is in TF";
  // The stamp of 0 was refused by name (after nothing accepted it equals the unset last stamp, and would
  // not show in TF either way). (The NaN pose's refusal shares the frame's message site, within its period.)
  EXPECT_TRUE(spinUntil([&] { return heard("header.stamp is unset (0)"); }, 10.0)) << "no word of the stamp of 0";
  EXPECT_FALSE(buffer.canTransform("world", "probe_body", ros::Time(t0 + 0.05))) << "the NaN pose is in TF";
  // The extrinsic: the camera 0.1 m ahead of the body (config/d435i.yaml T_B_C), looking along its x.
  const geometry_msgs::TransformStamped camera = buffer.lookupTransform("probe_body", "probe_camera", ros::Time(0));
  EXPECT_NEAR(camera.transform.translation.x, 0.10, 1e-9);
  EXPECT_NEAR(camera.transform.translation.z, 0.02, 1e-9);
  // Level odometry said nothing of its frame.
  // The limit is max_body_tilt (1 rad, 57 degrees, in d435i.yaml): a body pitched 50 degrees (a hard
  // braking) is not said, one pitched 70 degrees is.
  EXPECT_FALSE(heard("from the world's up")) << "level odometry was said to be tilted";
  auto pitched = [&](double t, double degrees) {
    nav_msgs::Odometry m = odometry("world", t, Eigen::Vector3d(1.4, 0.0, 1.0));
    const double half = 0.5 * degrees * M_PI / 180.0;
    m.pose.pose.orientation.w = std::cos(half), m.pose.pose.orientation.y = std::sin(half);
    return m;
  };
  odom_pub.publish(pitched(t0 + 0.3, 50.0));
  ASSERT_TRUE(spinUntil([&] { return buffer.canTransform("world", "probe_body", ros::Time(t0 + 0.3)); }, 10.0));
  spinUntil([] { return false; }, 0.5);
  EXPECT_FALSE(heard("from the world's up")) << "a body pitched 50 degrees, under max_body_tilt, was said to be tilted";
  odom_pub.publish(pitched(t0 + 0.35, 70.0));
  EXPECT_TRUE(spinUntil([&] { return heard("odometry's body z axis lies 70"); }, 10.0)) << "no word of a body pitched 70 degrees";
  // A body on its side (a camera IMU's frame, z forward, as VINS-Fusion's stock D435i set-up reports it) is
  // named too, and still sent; sent again until its word comes (once a warn_period, 2 s).
  double t = t0 + 0.4;
  EXPECT_TRUE(spinUntil([&] {
    odom_pub.publish(pitched(t += 0.05, 90.0));
    return spinUntil([&] { return heard("odometry's body z axis lies 90"); }, 0.3);
  }, 20.0)) << "no word of a body on its side";
  EXPECT_TRUE(spinUntil([&] { return buffer.canTransform("world", "probe_body", ros::Time(t)); }, 10.0));
  // A body rolled 75 degrees and heading 0.7 rad: said too (the tilt is any rotation of the z axis away from
  // up, roll as well as pitch), and sent whole, its rotation the odometry's.
  const Eigen::Quaterniond rolled = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ())) *
                                    Eigen::Quaterniond(Eigen::AngleAxisd(75.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()));
  EXPECT_TRUE(spinUntil([&] {
    nav_msgs::Odometry m = odometry("world", t += 0.05, Eigen::Vector3d(1.4, 0.0, 1.0));
    m.pose.pose.orientation.w = rolled.w(), m.pose.pose.orientation.x = rolled.x();
    m.pose.pose.orientation.y = rolled.y(), m.pose.pose.orientation.z = rolled.z();
    odom_pub.publish(m);
    return spinUntil([&] { return heard("odometry's body z axis lies 75"); }, 0.3);
  }, 20.0)) << "no word of a body rolled 75 degrees";
  ASSERT_TRUE(spinUntil([&] { return buffer.canTransform("world", "probe_body", ros::Time(t)); }, 10.0));
  const auto& r = buffer.lookupTransform("world", "probe_body", ros::Time(t)).transform.rotation;
  EXPECT_NEAR(std::abs(Eigen::Quaterniond(r.w, r.x, r.y, r.z).dot(rolled)), 1.0, 1e-9)
      << "the TF's rotation is not the odometry's";
}

// The probe camera runs at 50 Hz: on odometry every 0.01 s it sends a frame with every other stamp. Its
// schedule is a sum of periods in doubles and the stamps whole nanoseconds, so a frame due with a stamp came
// out 1e-12 s after it and waited for the next one: frames 0.03 s apart, then 0.01 s, and some lost. After
// a 1 s gap in the odometry the schedule starts again from the first stamp back, 50 Hz still (catching up
// period by period, it sent a frame with every stamp for a second).
TEST_F(SimulatorTest, ACameraAtHalfTheOdometryRateSendsEveryOtherStamp) {
  ASSERT_TRUE(spinUntil([&] { return last_odom_ != nullptr; }, 60.0)) << "no odom";
  ros::Publisher odom_pub = nh_.advertise<nav_msgs::Odometry>("probe/odom", 200);
  std::vector<double> frames;
  ros::Subscriber depth_sub = nh_.subscribe<sensor_msgs::Image>(
      "probe/depth", 200, [&](const sensor_msgs::Image::ConstPtr& m) { frames.push_back(m->header.stamp.toSec()); });
  ASSERT_TRUE(spinUntil([&] { return odom_pub.getNumSubscribers() > 0 && depth_sub.getNumPublishers() > 0; }, 30.0))
      << "the probe camera is not connected";
  nav_msgs::Odometry odom = *last_odom_;
  constexpr int kStamps = 300, kAfterGap = 100;  // 2.00 .. 4.99 s, then 6.00 .. 6.99 s
  for (int k = 0; k < kStamps + kAfterGap; ++k) {
    // Rounded to whole nanoseconds, as a clock's stamps are.
    odom.header.stamp = ros::Time(k < kStamps ? 2.0 + 0.01 * k : 6.0 + 0.01 * (k - kStamps));
    odom_pub.publish(odom);
    spinUntil([] { return false; }, 0.01);
  }
  spinUntil([&] { return frames.size() >= (kStamps + kAfterGap) / 2; }, 10.0);
  ASSERT_GE(frames.size(), 2u);
  std::size_t off = 0, restarts = 0;
  for (std::size_t i = 1; i < frames.size(); ++i) {
    if (frames[i - 1] < 5.0 && frames[i] >= 6.0) {  // across the gap: from the first stamp back
      restarts += std::abs(frames[i] - 6.0) < 1e-6;
      continue;
    }
    off += std::abs(frames[i] - frames[i - 1] - 0.02) > 1e-6;
  }
  EXPECT_EQ(off, 0u) << frames.size() << " frames, " << off << " of them not 0.02 s after the one before";
  EXPECT_EQ(restarts, 1u) << "no frame at 6.00 s, the first stamp after the gap";
  EXPECT_EQ(frames.size(), static_cast<std::size_t>((kStamps + kAfterGap) / 2));
}

// Depth noise and dropouts each apply alone (depth_camera/noise_stddev_per_m without dropouts, and the other
// way round): two frames from one pose differ in most of their returns with noise, and about a fifth of the
// returns are NaN (REP 117's no measurement) with a dropout probability of 0.2, where the clean renderer
// gives none.
TEST_F(SimulatorTest, NoiseAndDropoutsEachApplyAlone) {
  ASSERT_TRUE(spinUntil([&] { return last_odom_ != nullptr; }, 60.0)) << "no odom";
  struct Camera {
    ros::Publisher odom;
    ros::Subscriber depth;
    std::vector<sensor_msgs::Image::ConstPtr> frames;
  };
  Camera noisy, dropping;
  for (auto [camera, name] : {std::make_pair(&noisy, "noisy"), std::make_pair(&dropping, "dropping")}) {
    camera->odom = nh_.advertise<nav_msgs::Odometry>(std::string(name) + "/odom", 10);
    camera->depth = nh_.subscribe<sensor_msgs::Image>(std::string(name) + "/depth", 10,
                                                      [camera](const sensor_msgs::Image::ConstPtr& m) { camera->frames.push_back(m); });
  }
  ASSERT_TRUE(spinUntil(
      [&] {
        return noisy.odom.getNumSubscribers() > 0 && noisy.depth.getNumPublishers() > 0 &&
               dropping.odom.getNumSubscribers() > 0 && dropping.depth.getNumPublishers() > 0;
      },
      30.0))
      << "the noisy and dropping cameras are not connected";
  nav_msgs::Odometry odom = *last_odom_;
  // Two frames from the pose (1 s apart, past the 15 Hz period), sent again until each camera has both.
  ASSERT_TRUE(spinUntil(
      [&] {
        for (Camera* camera : {&noisy, &dropping}) {
          if (camera->frames.size() >= 2) continue;
          odom.header.stamp = ros::Time(100.0 + static_cast<double>(camera->frames.size()));
          camera->odom.publish(odom);
        }
        spinUntil([] { return false; }, 0.1);
        return noisy.frames.size() >= 2 && dropping.frames.size() >= 2;
      },
      30.0))
      << noisy.frames.size() << " noisy and " << dropping.frames.size() << " dropping frames";
  // Read as the mapper reads them, through cv_bridge.
  ASSERT_EQ(noisy.frames[0]->encoding, "32FC1");
  ASSERT_EQ(dropping.frames[0]->encoding, "32FC1");
  const cv::Mat a = cv_bridge::toCvShare(noisy.frames[0], "32FC1")->image;
  const cv::Mat b = cv_bridge::toCvShare(noisy.frames[1], "32FC1")->image;
  std::size_t both = 0, differ = 0;
  for (int v = 0; v < a.rows; ++v)
    for (int u = 0; u < a.cols; ++u)
      if (std::isfinite(a.at<float>(v, u)) && std::isfinite(b.at<float>(v, u))) {
        ++both;
        differ += a.at<float>(v, u) != b.at<float>(v, u);
      }
  ASSERT_GT(both, 1000u) << "the pose sees too little";
  EXPECT_GT(differ, both / 2) << differ << " of " << both << " returns differ between two frames from one pose";
  const cv::Mat d = cv_bridge::toCvShare(dropping.frames[0], "32FC1")->image;
  std::size_t returns = 0, dropped = 0;
  for (int v = 0; v < d.rows; ++v)
    for (int u = 0; u < d.cols; ++u) {
      const float depth = d.at<float>(v, u);
      dropped += std::isnan(depth);
      returns += std::isnan(depth) || std::isfinite(depth);  // +-inf: nothing in range, or too near
    }
  ASSERT_GT(returns, 1000u);
  EXPECT_NEAR(static_cast<double>(dropped) / static_cast<double>(returns), 0.2, 0.05) << dropped << " of " << returns;
}

}  // namespace

// Commands that stop: after simulation/command_timeout without one, the vehicle hovers where it is (and says
// so) instead of flying on to the last command's position. Sent towards a point 6 m away for 0.2 s, it is at
// rest well short of it; followed to the end, it would stand on it.
// A simulator given a start of its own (use_scene_start false: simulator.launch's start_x/y/z and
// start_yaw; start_sim/... in simulator.test, on the first one's clock) starts there, not at the scene's.
// Without publish_clock it follows the ROS clock, here the first one's at twice real time: its odometry is
// stamped with that clock (paced by the wall clock, its stamps fell behind by half of the time run).
TEST_F(SimulatorTest, AStartOfItsOwnIsWhereTheVehicleStarts) {
  nav_msgs::Odometry::ConstPtr first, last;
  ros::Subscriber sub = nh_.subscribe<nav_msgs::Odometry>("start_sim/odom", 10, [&](const nav_msgs::Odometry::ConstPtr& m) {
    if (!first) first = m;
    last = m;
  });
  ASSERT_TRUE(spinUntil([&] { return first != nullptr; }, 60.0)) << "no odometry from start_sim";
  std::vector<double> start;
  double yaw = 0.0;
  ASSERT_TRUE(ros::param::get("start_sim/start", start) && start.size() == 3);
  ASSERT_TRUE(ros::param::get("start_sim/start_yaw", yaw));
  const auto& p = first->pose.pose.position;
  EXPECT_LT((Eigen::Vector3d(p.x, p.y, p.z) - Eigen::Vector3d(start[0], start[1], start[2])).norm(), 0.05)
      << "starts at " << p.x << ", " << p.y << ", " << p.z;
  EXPECT_NEAR(go_feap::ros_conv::yawOf(first->pose.pose.orientation), yaw, 0.02);
  double rate_factor = 0.0;
  ASSERT_TRUE(ros::param::get("quadrotor_sim/simulation/rate_factor", rate_factor));
  ASSERT_GT(rate_factor, 1.5);
  spinSim(4.0);
  ASSERT_TRUE(last);
  EXPECT_LT(std::abs((last->header.stamp - ros::Time::now()).toSec()), 0.2)
      << "start_sim's odometry is stamped " << last->header.stamp << " on a clock at " << ros::Time::now();
}

TEST_F(SimulatorTest, WithoutCommandsTheVehicleHoversWhereItIs) {
  ASSERT_TRUE(spinUntil([&] { return last_odom_ != nullptr; }, 60.0)) << "no odom";
  std::vector<std::string> said;
  ros::Subscriber log_sub = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->msg.find("/quadrotor_sim:") != std::string::npos) said.push_back(m->msg);
  });
  // Heard from the simulator before anything counts (this node's own /rosout publisher already counts as one):
  // a command refused for its NaN position makes it speak.
  go_feap::PositionCommand bad = go_feap::test::holdCommand(position(), 0.5);
  bad.position.x = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(spinUntil([&] {
    cmd_pub_.publish(bad);
    spinSim(0.3);
    return !said.empty();
  }, 30.0)) << "nothing heard from /quadrotor_sim on /rosout";
  double timeout = 0.0;
  ASSERT_TRUE(ros::param::get("quadrotor_sim/simulation/command_timeout", timeout));
  const Eigen::Vector3d goal = position() + Eigen::Vector3d(6.0, 0.0, 0.0);
  const ros::Time until = ros::Time::now() + ros::Duration(0.2);
  spinUntil([&] {
    command(goal, 0.5);
    return ros::Time::now() >= until;
  }, 30.0);
  said.clear();
  spinSim(timeout + 3.0);
  const Eigen::Vector3d v(last_odom_->twist.twist.linear.x, last_odom_->twist.twist.linear.y,
                          last_odom_->twist.twist.linear.z);
  EXPECT_GT((goal - position()).norm(), 1.5) << "flew on to the last command's position: at " << position().transpose();
  EXPECT_LT(v.norm(), 0.1) << "not hovering";
  const Eigen::Vector3d held = position();
  spinSim(1.0);
  EXPECT_LT((position() - held).norm(), 0.05) << "not holding its place";
  bool warned = false;
  for (const std::string& m : said) warned = warned || m.find("no position_cmd for") != std::string::npos;
  EXPECT_TRUE(warned) << "the hold was not reported";
}

GO_FEAP_ROSTEST_MAIN("test_simulator_ros")
