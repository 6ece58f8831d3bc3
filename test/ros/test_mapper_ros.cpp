// rostest: simulator + EsdfMapper. The vehicle turns in place at the maze start; the
// occupied cloud must show the walls around it (checked against the ground truth), bad
// frames must be skipped without losing the map, and save_map must write a readable .bt.
#include <geometry_msgs/PoseStamped.h>
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <octomap/OcTree.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>
#include <Eigen/Geometry>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <cstdint>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <thread>
#include <tuple>
#include <vector>

#include "go_feap/MapUpdate.h"
#include "go_feap/PositionCommand.h"
#include "ros_test_util.h"
#include "go_feap/SaveMap.h"
#include "go_feap/world/scene_files.h"

namespace {

using go_feap::test::spinUntil;

using go_feap::common::Vec3;

struct CloudVerdict {
  std::size_t points = 0;
  double on_truth = 0.0;  // share of points within one voxel of a ground-truth obstacle
  int directions = 0;     // of +x, +y, -x, -y: walls seen within 2.5 m of the centre
};

CloudVerdict judge(const sensor_msgs::PointCloud2& cloud, const go_feap::world::Scene& scene, const Vec3& centre) {
  CloudVerdict v;
  std::size_t good = 0;
  bool dir[4] = {false, false, false, false};
  for (sensor_msgs::PointCloud2ConstIterator<float> it(cloud, "x"); it != it.end(); ++it) {
    const Vec3 p(it[0], it[1], it[2]);
    ++v.points;
    bool near_truth = false;
    for (int dx = -1; dx <= 1 && !near_truth; ++dx)
      for (int dy = -1; dy <= 1 && !near_truth; ++dy)
        for (int dz = -1; dz <= 1 && !near_truth; ++dz)
          near_truth = scene.isOccupied(Vec3(p + 0.1 * Vec3(dx, dy, dz)));
    good += near_truth;
    const Vec3 d = p - centre;
    if (p.z() < 0.3 || std::hypot(d.x(), d.y()) > 2.5) continue;  // walls, not floor
    const double a = std::atan2(d.y(), d.x());
    dir[static_cast<int>(std::lround(a / (M_PI / 2)) + 4) % 4] = true;
  }
  v.on_truth = v.points ? double(good) / v.points : 0.0;
  for (bool b : dir) v.directions += b;
  return v;
}

// `pose` moved dx along the world's x and turned `yaw` about the vertical.
geometry_msgs::PoseStamped movedPose(geometry_msgs::PoseStamped pose, double dx, double yaw) {
  pose.pose.position.x += dx;
  const auto& o = pose.pose.orientation;
  const Eigen::Quaterniond turned =
      Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())) * Eigen::Quaterniond(o.w, o.x, o.y, o.z);
  pose.pose.orientation.w = turned.w(), pose.pose.orientation.x = turned.x();
  pose.pose.orientation.y = turned.y(), pose.pose.orientation.z = turned.z();
  return pose;
}

class MapperTest : public ::testing::Test {
 protected:
  void SetUp() override {
    odom_sub_ = nh_.subscribe("odom", 10, &MapperTest::onOdom, this);
    cloud_sub_ = nh_.subscribe("occupied_cloud", 1, &MapperTest::onCloud, this);
    update_sub_ = nh_.subscribe("map_update", 10, &MapperTest::onUpdate, this);
    cmd_pub_ = nh_.advertise<go_feap::PositionCommand>("position_cmd", 10);
    depth_pub_ = nh_.advertise<sensor_msgs::Image>("depth", 10);
    pose_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("camera_pose", 10);
  }
  void onOdom(const nav_msgs::Odometry::ConstPtr& m) { odom_ = m; }
  void onCloud(const sensor_msgs::PointCloud2::ConstPtr& m) { cloud_ = m; }
  void onUpdate(const go_feap::MapUpdate::ConstPtr& m) {
    last_update_ = m;
    ++updates_;
  }

  ros::NodeHandle nh_;
  ros::Subscriber odom_sub_, cloud_sub_, update_sub_;
  ros::Publisher cmd_pub_, depth_pub_, pose_pub_;
  nav_msgs::Odometry::ConstPtr odom_;
  sensor_msgs::PointCloud2::ConstPtr cloud_;
  go_feap::MapUpdate::ConstPtr last_update_;
  std::size_t updates_ = 0;
};

TEST_F(MapperTest, TurningInPlaceMapsTheWallsBadFramesAreSkippedSaveMapWorks) {
  auto scene = go_feap::test::sceneFromParams();
  ASSERT_TRUE(scene) << scene.message();
  ASSERT_TRUE(spinUntil([&] { return odom_ && last_update_; }, 60.0)) << "no odom or map_update";

  // Turn in place at the start: yaw ramps through a full circle in 8 s of sim time.
  const Vec3 centre = scene->start.position;
  ASSERT_TRUE(go_feap::test::turnInPlace(cmd_pub_, centre, [] { return true; }, 120.0));
  cloud_.reset();
  ASSERT_TRUE(spinUntil([&] { return cloud_ != nullptr; }, 30.0)) << "no occupied_cloud";
  const CloudVerdict before = judge(*cloud_, *scene, centre);
  std::cout << before.points << " occupied points, " << 100 * before.on_truth << " % on the truth, walls in "
            << before.directions << " of 4 directions\n";
  EXPECT_GT(before.points, 2000u);
  EXPECT_GE(before.on_truth, 0.97);
  EXPECT_EQ(before.directions, 4);
  EXPECT_GT(last_update_->sequence, 50u);

  // Bad frames: wrong encoding, and a camera pose 30 m away (relocalisation): skipped, so no map_update
  // carries their stamps (all-zero images change no voxel, so only the stamps can tell).
  std::vector<ros::Time> bad_stamps, update_stamps;
  ros::Subscriber updates = nh_.subscribe<go_feap::MapUpdate>(
      "map_update", 50, [&](const go_feap::MapUpdate::ConstPtr& m) { update_stamps.push_back(m->header.stamp); });
  ASSERT_TRUE(spinUntil([&] { return updates.getNumPublishers() > 0; }, 10.0));
  for (int i = 0; i < 5; ++i) {
    const ros::Time stamp = ros::Time::now() + ros::Duration(0.001 * (i + 1));
    bad_stamps.push_back(stamp);
    sensor_msgs::Image img;
    img.header.stamp = stamp;
    img.header.frame_id = "camera";
    img.width = 640;
    img.height = 480;
    img.encoding = i % 2 ? "rgb8" : "32FC1";
    img.step = img.encoding == "rgb8" ? 640 * 3 : 640 * 4;
    img.data.assign(img.step * img.height, 0);
    geometry_msgs::PoseStamped pose;
    pose.header = img.header;
    pose.header.frame_id = "world";
    pose.pose.position.x = i % 2 ? centre.x() : centre.x() + 30.0;
    pose.pose.position.y = centre.y();
    pose.pose.position.z = centre.z();
    pose.pose.orientation.w = 1.0;
    pose_pub_.publish(pose);
    depth_pub_.publish(img);
    spinUntil([] { return false; }, 0.2);
  }
  // Frames after them are integrated (so the map_updates were heard), none of theirs.
  const ros::Time last_bad = bad_stamps.back();
  EXPECT_TRUE(spinUntil([&] { return !update_stamps.empty() && update_stamps.back() > last_bad; }, 30.0));
  for (const ros::Time& t : bad_stamps)
    EXPECT_EQ(std::count(update_stamps.begin(), update_stamps.end(), t), 0) << "a bad frame was integrated";
  updates.shutdown();
  // A real frame and its pose again, stamped at 4e9 s (a sender's clock gone wrong): ros::Time arithmetic on
  // it throws, and once brought the nodelet manager down; a throttle stamped that far ahead must not stop
  // the clouds for good either.
  sensor_msgs::Image::ConstPtr real_depth;
  geometry_msgs::PoseStamped::ConstPtr real_pose;
  {
    ros::Subscriber d = nh_.subscribe<sensor_msgs::Image>(
        "depth", 5, [&](const sensor_msgs::Image::ConstPtr& m) { real_depth = m; });  // the simulator's, from now on
    ros::Subscriber q = nh_.subscribe<geometry_msgs::PoseStamped>(
        "camera_pose", 5, [&](const geometry_msgs::PoseStamped::ConstPtr& m) { real_pose = m; });
    ASSERT_TRUE(spinUntil([&] { return real_depth && real_pose && real_depth->header.stamp == real_pose->header.stamp; }, 30.0))
        << "no depth frame with its pose";
  }
  // That frame again with its pose 1.5 m off (more than mapper/max_pose_jump: a relocalisation) is skipped:
  // no map_update carries its stamp. Sent 0.05 m off it is taken (the check is not vacuous). The frames
  // above were all-zero images, which change nothing when integrated: they could not tell.
  double max_jump = 0.0;
  ASSERT_TRUE(ros::param::get("/esdf_mapper/mapper/max_pose_jump", max_jump));
  ASSERT_LT(max_jump, 1.5);
  std::vector<ros::Time> stamps;  // of every map_update from here on
  ros::Subscriber u = nh_.subscribe<go_feap::MapUpdate>(
      "map_update", 50, [&](const go_feap::MapUpdate::ConstPtr& m) { stamps.push_back(m->header.stamp); });
  ASSERT_TRUE(spinUntil([&] { return u.getNumPublishers() > 0; }, 10.0));
  const auto updated = [&](const ros::Time& t) { return std::count(stamps.begin(), stamps.end(), t) > 0; };
  // The real frame with its pose moved dx along x and turned `yaw` about the vertical.
  auto sendShifted = [&](double dx, double yaw = 0.0) {
    sensor_msgs::Image d = *real_depth;
    geometry_msgs::PoseStamped q = movedPose(*real_pose, dx, yaw);
    d.header.stamp = q.header.stamp = ros::Time::now() + ros::Duration(0.0005);
    pose_pub_.publish(q);
    depth_pub_.publish(d);
    return d.header.stamp;
  };
  const ros::Time jumped = sendShifted(1.5);
  // The simulator's frames go on: the next after the jump is a jump back (skipped), the one after is mapped.
  // Three mapped after it: the jump was judged by then, even had a simulator frame overtaken it.
  ASSERT_TRUE(spinUntil([&] { return std::count_if(stamps.begin(), stamps.end(), [&](const ros::Time& t) { return t > jumped; }) >= 3; },
                        30.0))
      << "no map_update after the jump";
  EXPECT_FALSE(updated(jumped)) << "a frame 1.5 m from the last was integrated";
  const ros::Time near = sendShifted(0.05);
  EXPECT_TRUE(spinUntil([&] { return updated(near); }, 30.0)) << "a frame 0.05 m from the last was not integrated";
  // Turned by 1 rad in place (more than mapper/max_rotation_jump: a VIO restarted with its heading at 0) is
  // skipped too; by 0.1 rad it is taken.
  double max_turn = 0.0;
  ASSERT_TRUE(ros::param::get("/esdf_mapper/mapper/max_rotation_jump", max_turn));
  ASSERT_LT(max_turn, 1.0);
  const ros::Time turned = sendShifted(0.0, 1.0);
  ASSERT_TRUE(spinUntil([&] { return std::count_if(stamps.begin(), stamps.end(), [&](const ros::Time& t) { return t > turned; }) >= 3; },
                        30.0))
      << "no map_update after the turn";
  EXPECT_FALSE(updated(turned)) << "a frame turned 1 rad from the last was integrated";
  const ros::Time slight = sendShifted(0.0, 0.1);
  EXPECT_TRUE(spinUntil([&] { return updated(slight); }, 30.0)) << "a frame turned 0.1 rad from the last was not integrated";
  sensor_msgs::Image far_depth = *real_depth;
  geometry_msgs::PoseStamped far_pose = *real_pose;
  far_depth.header.stamp = far_pose.header.stamp = ros::Time(4000000000u, 0);
  pose_pub_.publish(far_pose);
  depth_pub_.publish(far_depth);
  spinUntil([] { return false; }, 0.5);
  cloud_.reset();
  ASSERT_TRUE(spinUntil([&] { return cloud_ != nullptr; }, 30.0)) << "mapper stopped publishing";
  cloud_.reset();
  ASSERT_TRUE(spinUntil([&] { return cloud_ != nullptr && cloud_->header.stamp.sec < 4000000000u; }, 30.0))
      << "no cloud after the frame stamped far ahead";
  const CloudVerdict after = judge(*cloud_, *scene, centre);
  EXPECT_GE(after.points, before.points * 95 / 100) << "map lost after bad frames";
  EXPECT_EQ(after.directions, 4);

  // save_map writes a .bt that OctoMap reads back with the walls in it.
  const std::string path =
      (std::filesystem::temp_directory_path() / ("go_feap_mapper_" + std::to_string(::getpid()) + ".bt")).string();
  go_feap::SaveMap srv;
  srv.request.path = path;
  ASSERT_TRUE(ros::service::waitForService("save_map", ros::Duration(10.0)));
  ASSERT_TRUE(ros::service::call("save_map", srv));
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  octomap::OcTree tree(0.1);
  ASSERT_TRUE(tree.readBinary(path));
  std::size_t occupied = 0, on_truth = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    ++occupied;
    on_truth += scene->isOccupied(Vec3(it.getX(), it.getY(), it.getZ()));
  }
  std::filesystem::remove(path);
  EXPECT_GT(occupied, 1000u);
  EXPECT_GE(double(on_truth) / occupied, 0.95);
  srv.request.path = "/nonexistent_dir/x.bt";
  ASSERT_TRUE(ros::service::call("save_map", srv));
  EXPECT_FALSE(srv.response.success);
}

// The probe mapper (probe/... in mapper.test) is fed only by this test: its inputs, its map_updates counted,
// and a real frame with its pose and camera_info from the simulated camera to feed it.
struct Probe {
  /// The probe mapper whose topics start with `prefix` (mapper.test: probe/ in sync_mode exact,
  /// approx_probe/ in approximate).
  explicit Probe(const std::string& prefix = "probe/")
      : info_pub(nh.advertise<sensor_msgs::CameraInfo>(prefix + "camera_info", 5, /*latch=*/true)),
        depth_pub(nh.advertise<sensor_msgs::Image>(prefix + "depth", 5)),
        pose_pub(nh.advertise<geometry_msgs::PoseStamped>(prefix + "camera_pose", 5)),
        update_sub(nh.subscribe<go_feap::MapUpdate>(prefix + "map_update", 10,
                                                    [this](const go_feap::MapUpdate::ConstPtr& m) {
                                                      ++updates;
                                                      last_update = m;
                                                      received.push_back(m);
                                                    })) {}
  ros::NodeHandle nh;
  ros::Publisher info_pub, depth_pub, pose_pub;
  std::size_t updates = 0;
  go_feap::MapUpdate::ConstPtr last_update;
  std::vector<go_feap::MapUpdate::ConstPtr> received;  ///< every map_update heard
  ros::Subscriber update_sub;
  sensor_msgs::CameraInfo::ConstPtr info;
  sensor_msgs::Image::ConstPtr depth;
  geometry_msgs::PoseStamped::ConstPtr pose;
  int frame = 0;

  // Takes a frame, its pose and the camera_info from the simulated camera, and waits for the probe.
  ::testing::AssertionResult connect() {
    {
      auto i = nh.subscribe<sensor_msgs::CameraInfo>("camera_info", 5, [&](const sensor_msgs::CameraInfo::ConstPtr& m) { info = m; });
      auto d = nh.subscribe<sensor_msgs::Image>("depth", 5, [&](const sensor_msgs::Image::ConstPtr& m) { depth = m; });
      auto q = nh.subscribe<geometry_msgs::PoseStamped>("camera_pose", 5,
                                                        [&](const geometry_msgs::PoseStamped::ConstPtr& m) { pose = m; });
      if (!spinUntil([&] { return info && depth && pose && depth->header.stamp == pose->header.stamp; }, 30.0))
        return ::testing::AssertionFailure() << "no camera_info, or no depth frame with its pose";
    }
    if (!spinUntil(
            [&] {
              return info_pub.getNumSubscribers() > 0 && depth_pub.getNumSubscribers() > 0 &&
                     pose_pub.getNumSubscribers() > 0 && update_sub.getNumPublishers() > 0;
            },
            30.0))
      return ::testing::AssertionFailure() << "the probe mapper is not connected";
    return ::testing::AssertionSuccess();
  }
  // Sends an image and a pose, newly stamped alike (the pair is matched by stamp), and waits 0.5 s.
  void send(sensor_msgs::Image d, geometry_msgs::PoseStamped q) {
    d.header.stamp = q.header.stamp = depth->header.stamp + ros::Duration(0.001 * ++frame);
    pose_pub.publish(q);
    depth_pub.publish(d);
    spinUntil([] { return false; }, 0.5);
  }
  void sendReal() { send(*depth, *pose); }
  /// The stamp send() gave the last frame.
  ros::Time lastSent() const { return depth->header.stamp + ros::Duration(0.001 * frame); }
  /// The map_update heard for the frame stamped `t`, or null.
  go_feap::MapUpdate::ConstPtr updateAt(const ros::Time& t) const {
    for (const auto& u : received)
      if (u->header.stamp == t) return u;
    return nullptr;
  }
  // Sends the real frame, newly stamped, until the probe integrates one (at most 10 times): a camera_info
  // published just before travels on another connection and may arrive after the frame, which is then
  // skipped. Then waits 0.5 s more, so that `updates` is settled.
  ::testing::AssertionResult sendRealUntilIntegrated() {
    const std::size_t before = updates;
    for (int attempt = 0; attempt < 10 && updates == before; ++attempt) {
      sendReal();
      spinUntil([&] { return updates > before; }, 2.0);
    }
    spinUntil([] { return false; }, 0.5);
    if (updates > before) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure() << "none of 10 real frames was integrated";
  }
};

// esdf_slice, beside the occupied_cloud of the same stamp (published together), holds the known voxels of the
// layer at mapper/esdf_slice_height, each with the distance to the nearest mapped obstacle: at least the
// brute-force distance between voxel centres over the cloud's obstacles, at most a voxel diagonal more (the
// ESDF's bound), truncated at esdf/max_distance.
TEST_F(MapperTest, TheEsdfSliceHoldsTheDistanceToTheNearestMappedObstacle) {
  double slice_height = 0.0, max_distance = 0.0, resolution = 0.0;
  ASSERT_TRUE(ros::param::get("esdf_mapper/mapper/esdf_slice_height", slice_height));
  ASSERT_TRUE(ros::param::get("esdf_mapper/esdf/max_distance", max_distance));
  ASSERT_TRUE(ros::param::get("esdf_mapper/occupancy/resolution", resolution));
  std::map<double, sensor_msgs::PointCloud2::ConstPtr> slices, clouds;
  auto slice_sub = nh_.subscribe<sensor_msgs::PointCloud2>(
      "esdf_slice", 5, [&](const sensor_msgs::PointCloud2::ConstPtr& m) { slices[m->header.stamp.toSec()] = m; });
  auto cloud_sub = nh_.subscribe<sensor_msgs::PointCloud2>(
      "occupied_cloud", 5, [&](const sensor_msgs::PointCloud2::ConstPtr& m) { clouds[m->header.stamp.toSec()] = m; });
  double stamp = -1.0;
  ASSERT_TRUE(spinUntil([&] {
    for (const auto& [t, m] : slices)
      if (clouds.count(t) && m->width > 100) stamp = t;
    return stamp >= 0.0;
  }, 60.0)) << "no esdf_slice of 100 points or more with its occupied_cloud";
  std::vector<Vec3> obstacles;
  for (sensor_msgs::PointCloud2ConstIterator<float> it(*clouds[stamp], "x"); it != it.end(); ++it)
    obstacles.emplace_back(it[0], it[1], it[2]);
  ASSERT_FALSE(obstacles.empty());
  const double layer_z = (std::floor(slice_height / resolution) + 0.5) * resolution;  // the grid is on multiples of it
  std::size_t points = 0, truncated = 0;
  sensor_msgs::PointCloud2ConstIterator<float> it(*slices[stamp], "x"), d(*slices[stamp], "distance");
  for (; it != it.end(); ++it, ++d) {
    const Vec3 p(it[0], it[1], it[2]);
    ++points;
    ASSERT_NEAR(p.z(), layer_z, 1e-4) << "a slice point off the layer at " << slice_height << " m";
    double best = max_distance;
    for (const Vec3& o : obstacles) best = std::min(best, (o - p).norm());
    truncated += best >= max_distance;
    ASSERT_GE(*d, best - 1e-4) << "at " << p.transpose();
    ASSERT_LE(*d, std::min(max_distance, best + std::sqrt(3.0) * resolution) + 1e-4) << "at " << p.transpose();
  }
  std::cout << points << " slice points, " << truncated << " truncated at " << max_distance << " m, against "
            << obstacles.size() << " obstacles\n";
  EXPECT_GT(points - truncated, 100u) << "few distances below the truncation: little tested";
}

// A camera_info the mapper cannot use (a zero K, NaN, a 0x0 image) is refused and the last valid
// intrinsics stay, so the next real frame and its pose are integrated (a map_update each), where it used
// to skip every frame until a valid camera_info came. Before any valid one, a frame is skipped.
TEST_F(MapperTest, ACameraInfoThatCannotBeUsedIsRefusedAndTheLastValidOneStays) {
  Probe probe;
  ASSERT_TRUE(probe.connect());
  // The intrinsics are P's (the rectified image's), K's where P is unset: each broken in the one used.
  sensor_msgs::CameraInfo zero_k = *probe.info;
  std::fill(zero_k.K.begin(), zero_k.K.end(), 0.0);
  std::fill(zero_k.P.begin(), zero_k.P.end(), 0.0);
  sensor_msgs::CameraInfo nan_fx = *probe.info;
  nan_fx.P[0] = std::numeric_limits<double>::quiet_NaN();
  sensor_msgs::CameraInfo no_size = *probe.info;
  no_size.width = no_size.height = 0;
  // Finite and > 0, but every ray NaN: it was taken, and each frame then cast rays of 2^31 steps.
  sensor_msgs::CameraInfo tiny_fy = *probe.info;
  tiny_fy.P[5] = 1e-310;
  sensor_msgs::CameraInfo tiny_fy_in_k = tiny_fy;
  std::fill(tiny_fy_in_k.P.begin(), tiny_fy_in_k.P.end(), 0.0);
  tiny_fy_in_k.K[4] = 1e-310;

  probe.info_pub.publish(zero_k);  // before any valid one: the frame is skipped
  spinUntil([] { return false; }, 0.3);
  probe.sendReal();
  EXPECT_EQ(probe.updates, 0u) << "a frame integrated with a zero K";
  probe.info_pub.publish(*probe.info);
  ASSERT_TRUE(probe.sendRealUntilIntegrated()) << "after a valid camera_info";
  for (const sensor_msgs::CameraInfo& bad : {zero_k, nan_fx, no_size, tiny_fy, tiny_fy_in_k}) {
    const std::size_t before = probe.updates;
    probe.info_pub.publish(bad);
    spinUntil([] { return false; }, 0.3);
    probe.sendReal();
    EXPECT_TRUE(spinUntil([&] { return probe.updates == before + 1; }, 10.0))
        << "no frame integrated after a camera_info with P " << bad.P[0] << ", " << bad.P[5] << ", K " << bad.K[0] << ", "
        << bad.K[4] << ", " << bad.width << "x"
        << bad.height;
  }
}

// A camera_info in another frame than the depth image's (the depth camera's intrinsics beside a depth image
// aligned to the colour camera, of the same size) is used, and said: the warning names both frames.
TEST_F(MapperTest, ACameraInfoInAnotherFrameThanTheDepthImageIsNamedInAWarning) {
  Probe probe;
  ASSERT_TRUE(probe.connect());
  std::vector<std::string> warnings;
  ros::Subscriber log_sub = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->level == rosgraph_msgs::Log::WARN) warnings.push_back(m->msg);
  });
  ASSERT_TRUE(spinUntil([&] { return log_sub.getNumPublishers() > 0; }, 30.0));
  auto warned = [&] {
    return std::any_of(warnings.begin(), warnings.end(), [&](const std::string& w) {
      return w.find("camera_info is in frame 'colour_optical' but the depth image in '" +
                    probe.depth->header.frame_id + "'") != std::string::npos;
    });
  };
  probe.info_pub.publish(*probe.info);
  ASSERT_TRUE(probe.sendRealUntilIntegrated());
  spinUntil([] { return false; }, 1.0);
  EXPECT_FALSE(warned()) << "warned with the camera_info in the image's own frame";
  sensor_msgs::CameraInfo colour = *probe.info;
  colour.header.frame_id = "colour_optical";
  ASSERT_NE(colour.header.frame_id, probe.depth->header.frame_id);
  probe.info_pub.publish(colour);
  spinUntil([] { return false; }, 0.3);
  const std::size_t before = probe.updates;
  probe.sendReal();
  EXPECT_TRUE(spinUntil([&] { return probe.updates > before; }, 10.0)) << "the frame was not integrated";
  EXPECT_TRUE(spinUntil(warned, 10.0)) << "no warning naming both frames";
}

// A camera_info with lens distortion (a coefficient of D not 0: an image that is not rectified) is used and
// said; the simulated camera's, D all 0, is not.
TEST_F(MapperTest, ACameraInfoWithLensDistortionIsSaid) {
  Probe probe;
  ASSERT_TRUE(probe.connect());
  std::vector<std::string> warnings;
  ros::Subscriber log_sub = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->level == rosgraph_msgs::Log::WARN && m->msg.find("/probe_mapper: ") != std::string::npos)
      warnings.push_back(m->msg);
  });
  ASSERT_TRUE(spinUntil([&] { return log_sub.getNumPublishers() > 0; }, 30.0));
  auto warned = [&] {
    return std::any_of(warnings.begin(), warnings.end(), [&](const std::string& w) {
      return w.find("camera_info gives lens distortion (D of model 'plumb_bob' is not 0)") != std::string::npos;
    });
  };
  ASSERT_FALSE(probe.info->D.empty());
  probe.info_pub.publish(*probe.info);
  ASSERT_TRUE(probe.sendRealUntilIntegrated());
  spinUntil([] { return false; }, 1.0);
  EXPECT_FALSE(warned()) << "warned of the simulated camera's D, all 0";
  sensor_msgs::CameraInfo raw = *probe.info;
  raw.distortion_model = "plumb_bob";
  raw.D.back() = 0.01;
  probe.info_pub.publish(raw);
  spinUntil([] { return false; }, 0.3);
  const std::size_t before = probe.updates;
  probe.sendReal();
  EXPECT_TRUE(spinUntil([&] { return probe.updates > before; }, 10.0)) << "the frame was not integrated";
  EXPECT_TRUE(spinUntil(warned, 10.0)) << "no word of the distortion";
}

// A frame that maps nothing is integrated and said: one with no usable depth pixel (all 0: a covered lens,
// an emitter off), and one whose camera lies so far off the map that every ray misses it (a camera pose
// in another frame than the map's). The next real frame is integrated as before.
TEST_F(MapperTest, AFrameThatMapsNothingIsSaid) {
  Probe probe;
  ASSERT_TRUE(probe.connect());
  std::vector<std::string> warnings;
  ros::Subscriber log_sub = nh_.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->level == rosgraph_msgs::Log::WARN && m->msg.find("/probe_mapper: ") != std::string::npos)
      warnings.push_back(m->msg);
  });
  ASSERT_TRUE(spinUntil([&] { return log_sub.getNumPublishers() > 0; }, 30.0));
  auto warned = [&](const std::string& what) {
    return std::any_of(warnings.begin(), warnings.end(),
                       [&](const std::string& w) { return w.find(what) != std::string::npos; });
  };
  const std::string blind = "no usable depth pixel in the frame stamped";
  const std::string outside = "sees nothing of the map, which spans (-10.5, -5.5, -0.5) to (10.5, 5.5, 3.5) m";
  probe.info_pub.publish(*probe.info);
  ASSERT_TRUE(probe.sendRealUntilIntegrated());
  spinUntil([] { return false; }, 1.0);
  EXPECT_FALSE(warned(blind) || warned(outside)) << "warned of a real frame";

  sensor_msgs::Image zeros = *probe.depth;
  std::fill(zeros.data.begin(), zeros.data.end(), 0);
  std::size_t before = probe.updates;
  probe.send(zeros, *probe.pose);
  EXPECT_TRUE(spinUntil([&] { return probe.updates > before; }, 10.0)) << "the frame of zeros was not integrated";
  EXPECT_TRUE(spinUntil([&] { return warned(blind); }, 10.0)) << "no word of a frame without a usable pixel";
  EXPECT_FALSE(warned(outside));

  const geometry_msgs::PoseStamped far = movedPose(*probe.pose, 100.0, 0.0);
  before = probe.updates;
  probe.send(*probe.depth, far);  // a jump of 100 m: skipped, its pose the reference
  probe.send(*probe.depth, far);
  EXPECT_TRUE(spinUntil([&] { return probe.updates > before; }, 10.0)) << "the frame far off was not integrated";
  EXPECT_EQ(probe.last_update->changed_voxels, 0u);
  EXPECT_TRUE(spinUntil([&] { return warned(outside); }, 10.0)) << "no word of a camera outside the map";

  before = probe.updates;
  probe.sendReal();  // back: a jump again
  probe.sendReal();
  EXPECT_TRUE(spinUntil([&] { return probe.updates > before; }, 10.0)) << "the next real frame was not integrated";
}

// A save_map in progress does not stop mapping: the save is held in the middle (the file it writes, beside its
// path, is a FIFO nobody reads yet, so its open waits) while a frame is sent, and that frame is integrated;
// then the FIFO is read, and what the save wrote is a whole OctoMap file. (On the queue that integrates
// depth, the save held every frame until it ended: a large map's save froze mapping for seconds.)
TEST_F(MapperTest, MappingGoesOnWhileAMapIsSaved) {
  Probe probe;
  ASSERT_TRUE(probe.connect());
  probe.info_pub.publish(*probe.info);
  ASSERT_TRUE(probe.sendRealUntilIntegrated());
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("go_feap_mapper_fifo_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "held.bt").string();
  ASSERT_EQ(::mkfifo((path + ".part").c_str(), 0600), 0);
  ros::ServiceClient save = nh_.serviceClient<go_feap::SaveMap>("probe/save_map");
  ASSERT_TRUE(save.waitForExistence(ros::Duration(10.0)));
  go_feap::SaveMap srv;
  srv.request.path = path;
  std::atomic<bool> answered{false}, called{false};
  std::thread caller([&] {
    called = save.call(srv);
    answered = true;
  });
  spinUntil([] { return false; }, 1.0);  // the save is waiting for a reader of its FIFO
  EXPECT_FALSE(answered) << "the save did not wait for its FIFO: " << srv.response.message;
  const std::size_t before = probe.updates;
  probe.sendReal();
  EXPECT_TRUE(spinUntil([&] { return probe.updates > before; }, 10.0)) << "no frame integrated during the save";
  std::string bytes;
  {
    std::ifstream fifo(path + ".part", std::ios::binary);  // lets the save go on
    bytes.assign(std::istreambuf_iterator<char>(fifo), std::istreambuf_iterator<char>());
  }
  caller.join();
  EXPECT_TRUE(called);
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  EXPECT_EQ(bytes.rfind("# Octomap OcTree binary file", 0), 0u) << bytes.substr(0, 80);
  std::istringstream in(bytes);
  octomap::OcTree tree(0.1);
  EXPECT_TRUE(tree.readBinary(in));
  EXPECT_GT(tree.getNumLeafNodes(), 100u);
  std::filesystem::remove_all(dir);
}

// Frames that would put wrong data in the map, or read past an image's buffer, are skipped and the mapper
// takes the next real frame: a camera_pose whose orientation is unset (all zero, which tf2 reads as no
// rotation) or given in another frame than the map's, and an image whose 480 rows of 8947852 bytes wrap
// round 2^32 to the 1664 bytes it carries (cv_bridge's own size check passes it, and the mapper read
// gigabytes past the buffer and took the nodelet manager down), or whose step is not a whole pixel.
TEST_F(MapperTest, FramesWithAnUnsetOrForeignPoseOrAnImageShorterThanItsSizeAreSkipped) {
  Probe probe;
  ASSERT_TRUE(probe.connect());
  probe.info_pub.publish(*probe.info);
  ASSERT_TRUE(probe.sendRealUntilIntegrated());
  const std::size_t base = probe.updates;

  geometry_msgs::PoseStamped unset = *probe.pose;
  unset.pose.orientation = geometry_msgs::Quaternion();  // x = y = z = w = 0
  geometry_msgs::PoseStamped foreign = *probe.pose;
  foreign.header.frame_id = "odom";
  sensor_msgs::Image wrapped = *probe.depth;
  wrapped.step = 8947852;
  wrapped.data.assign(1664, 0);
  ASSERT_EQ(std::uint64_t{wrapped.height} * wrapped.step % (std::uint64_t{1} << 32), wrapped.data.size());
  sensor_msgs::Image odd_step = *probe.depth;
  odd_step.step = odd_step.width * 4 + 2;
  odd_step.data.assign(std::size_t{odd_step.height} * odd_step.step, 0);
  probe.send(*probe.depth, unset);
  probe.send(*probe.depth, foreign);
  probe.send(wrapped, *probe.pose);
  probe.send(odd_step, *probe.pose);
  // Stamped 0 (a driver before its clock is set): the frame would date its frontiers to the epoch for good.
  sensor_msgs::Image epoch = *probe.depth;
  geometry_msgs::PoseStamped epoch_pose = *probe.pose;
  epoch.header.stamp = epoch_pose.header.stamp = ros::Time(0);
  probe.pose_pub.publish(epoch_pose);
  probe.depth_pub.publish(epoch);
  spinUntil([] { return false; }, 1.0);
  EXPECT_EQ(probe.updates, base)
      << "a frame with an unset or foreign pose, an unreadable image or the stamp 0 was integrated";
  probe.sendReal();
  EXPECT_TRUE(spinUntil([&] { return probe.updates == base + 1; }, 10.0)) << "the next real frame was not integrated";
  // A quaternion 8e-4 off unit length (accepted within 1e-3): integrated, at this 120-degree camera
  // rotation too (its rotation matrix, scaled off rigid, was refused as no rotation).
  geometry_msgs::PoseStamped scaled = *probe.pose;
  for (double* c : {&scaled.pose.orientation.x, &scaled.pose.orientation.y, &scaled.pose.orientation.z,
                    &scaled.pose.orientation.w})
    *c *= 1.0008;
  probe.send(*probe.depth, scaled);
  EXPECT_TRUE(spinUntil([&] { return probe.updates == base + 2; }, 10.0))
      << "a frame whose pose quaternion is 8e-4 off unit length was not integrated";
}

// sync_mode approximate: message_filters' ApproximateTime subtracts the stamps it holds as ros::Time, which
// throws past 2^31 s; a depth image or pose stamped 4e9 s (a sender's clock gone wrong) took the whole
// nodelet manager down. Such messages are skipped, and the next real frames are integrated.
TEST_F(MapperTest, InApproximateModeMessagesStampedFarAheadAreSkippedAndTheNextFramesIntegrated) {
  Probe probe("approx_probe/");
  ASSERT_TRUE(probe.connect());
  probe.info_pub.publish(*probe.info);
  ASSERT_TRUE(probe.sendRealUntilIntegrated());
  const ros::Time far(4000000000u, 0);
  sensor_msgs::Image far_depth = *probe.depth;
  geometry_msgs::PoseStamped far_pose = *probe.pose;
  far_depth.header.stamp = far_pose.header.stamp = far;
  // A pose with a usual stamp waits in the synchroniser for its image; an image stamped far ahead comes
  // instead (the synchroniser weighs their interval: 4e9 s less the pose's stamp).
  geometry_msgs::PoseStamped waiting = *probe.pose;
  waiting.header.stamp = probe.depth->header.stamp + ros::Duration(0.001 * ++probe.frame);
  probe.pose_pub.publish(waiting);
  spinUntil([] { return false; }, 0.5);
  probe.depth_pub.publish(far_depth);
  spinUntil([] { return false; }, 0.5);
  probe.pose_pub.publish(far_pose);  // a pair stamped far ahead
  probe.depth_pub.publish(far_depth);
  spinUntil([] { return false; }, 0.5);
  EXPECT_TRUE(probe.sendRealUntilIntegrated()) << "after messages stamped far ahead";

  // The synchroniser pairs an image with the nearest pose however far it is: an image whose only pose is
  // 0.3 s away (more than mapper/pose_tolerance, 0.02 s) is skipped, one whose pose is 0.015 s away is
  // integrated. Each is the only pair the synchroniser can make: the next frames come 2 s later.
  double tolerance = 0.0;
  ASSERT_TRUE(ros::param::get("/approx_probe_mapper/mapper/pose_tolerance", tolerance));
  ASSERT_LT(0.015, tolerance);
  ASSERT_GT(0.3, tolerance);
  for (const double apart : {0.3, 0.015}) {
    probe.frame += 2000;
    const ros::Time t = probe.lastSent();
    sensor_msgs::Image image = *probe.depth;
    geometry_msgs::PoseStamped pose = *probe.pose;
    image.header.stamp = t;
    pose.header.stamp = t + ros::Duration(apart);
    probe.pose_pub.publish(pose);
    probe.depth_pub.publish(image);
    spinUntil([] { return false; }, 0.5);
    probe.frame += 2000;
    EXPECT_TRUE(probe.sendRealUntilIntegrated()) << "after an image with its pose " << apart << " s away";
    if (apart > tolerance)
      EXPECT_EQ(probe.updateAt(t), nullptr) << "an image was integrated at a pose " << apart << " s from it";
    else
      EXPECT_NE(probe.updateAt(t), nullptr) << "an image with its pose " << apart << " s away was not integrated";
  }
}

// sync_mode tf: a depth frame waits, without blocking the mapper, for a transform that comes late (VIO
// lags the camera; the mapper used to wait pose_tolerance, 20 ms, inside its callback and skip the frame,
// and with the clock stopped it waited for ever, save_map too). A frame whose transform never comes is
// pushed out by tf_queue (3) newer ones, which are integrated.
TEST_F(MapperTest, InTfModeAFrameWaitsForALateTransformAndOneWithoutNeverBlocksTheNext) {
  Probe probe;  // for a real frame, its pose and the camera_info
  ASSERT_TRUE(probe.connect());
  ros::Publisher info_pub = nh_.advertise<sensor_msgs::CameraInfo>("tf_probe/camera_info", 5, /*latch=*/true);
  ros::Publisher depth_pub = nh_.advertise<sensor_msgs::Image>("tf_probe/depth", 10);
  std::size_t updates = 0;
  ros::Subscriber update_sub = nh_.subscribe<go_feap::MapUpdate>(
      "tf_probe/map_update", 10, [&](const go_feap::MapUpdate::ConstPtr&) { ++updates; });
  ros::ServiceClient save = nh_.serviceClient<go_feap::SaveMap>("tf_probe/save_map");
  ASSERT_TRUE(spinUntil([&] { return depth_pub.getNumSubscribers() > 0 && update_sub.getNumPublishers() > 0; }, 30.0));
  ASSERT_TRUE(save.waitForExistence(ros::Duration(30.0)));
  info_pub.publish(*probe.info);
  spinUntil([] { return false; }, 0.5);
  tf2_ros::TransformBroadcaster tf_pub;
  // The probe's camera pose, moved dx along x.
  auto transformAt = [&](const ros::Time& stamp, const std::string& frame, double dx = 0.0) {
    geometry_msgs::TransformStamped tf;
    tf.header.stamp = stamp;
    tf.header.frame_id = probe.pose->header.frame_id;
    tf.child_frame_id = frame;
    tf.transform.translation.x = probe.pose->pose.position.x + dx;
    tf.transform.translation.y = probe.pose->pose.position.y;
    tf.transform.translation.z = probe.pose->pose.position.z;
    tf.transform.rotation = probe.pose->pose.orientation;
    return tf;
  };
  auto frameAt = [&](const ros::Time& stamp, const std::string& frame) {
    sensor_msgs::Image d = *probe.depth;
    d.header.stamp = stamp;
    d.header.frame_id = frame;
    return d;
  };

  // The transform 0.5 s (wall) after the image.
  const ros::Time s0 = ros::Time::now();
  depth_pub.publish(frameAt(s0, "tf_probe_camera"));
  spinUntil([] { return false; }, 0.5);
  EXPECT_EQ(updates, 0u) << "integrated with no transform";
  tf_pub.sendTransform(transformAt(s0, "tf_probe_camera"));
  EXPECT_TRUE(spinUntil([&] { return updates == 1; }, 10.0)) << "the frame was not integrated once its transform came";

  // A frame in a camera frame nobody publishes waits; save_map answers meanwhile. Three newer frames, whose
  // transforms come after all three, push it out of the queue (3) and are integrated.
  depth_pub.publish(frameAt(s0 + ros::Duration(0.1), "tf_probe_nowhere"));
  spinUntil([] { return false; }, 0.2);
  go_feap::SaveMap srv;
  srv.request.path = (std::filesystem::temp_directory_path() / ("go_feap_tf_probe_" + std::to_string(::getpid()) + ".bt")).string();
  ASSERT_TRUE(save.call(srv)) << "save_map did not answer while a frame waited for its transform";
  EXPECT_TRUE(srv.response.success) << srv.response.message;
  std::filesystem::remove(srv.request.path);
  std::vector<ros::Time> stamps;
  for (int k = 1; k <= 3; ++k) {
    stamps.push_back(s0 + ros::Duration(0.1 + 0.05 * k));
    depth_pub.publish(frameAt(stamps.back(), "tf_probe_camera"));
    spinUntil([] { return false; }, 0.2);
  }
  EXPECT_EQ(updates, 1u);
  for (const ros::Time& stamp : stamps) tf_pub.sendTransform(transformAt(stamp, "tf_probe_camera"));
  EXPECT_TRUE(spinUntil([&] { return updates == 4; }, 10.0)) << updates - 1 << " of the 3 frames after it integrated";
  spinUntil([] { return false; }, 0.5);
  EXPECT_EQ(updates, 4u);

  // An odometry gap: samples 1 s apart (mapper/max_tf_gap 0.5 s), the camera 0.3 m further on at the
  // second. tf2 gives a pose inside the gap on the straight line between them; the frame there is
  // skipped. One at the sample after the gap, and one between samples 0.3 s apart, are integrated; so is
  // one between samples 1 s apart of a camera that held still (interpolated exactly).
  tf_pub.sendTransform(transformAt(s0 + ros::Duration(1.0), "tf_probe_camera"));
  tf_pub.sendTransform(transformAt(s0 + ros::Duration(2.0), "tf_probe_camera", 0.3));
  tf_pub.sendTransform(transformAt(s0 + ros::Duration(2.3), "tf_probe_camera", 0.35));
  tf_pub.sendTransform(transformAt(s0 + ros::Duration(3.3), "tf_probe_camera", 0.35));
  spinUntil([] { return false; }, 0.5);
  depth_pub.publish(frameAt(s0 + ros::Duration(1.5), "tf_probe_camera"));
  spinUntil([] { return false; }, 1.0);
  EXPECT_EQ(updates, 4u) << "a frame whose pose was interpolated across a 1 s gap was integrated";
  depth_pub.publish(frameAt(s0 + ros::Duration(2.0), "tf_probe_camera"));
  EXPECT_TRUE(spinUntil([&] { return updates == 5; }, 10.0)) << "the frame at the sample after the gap";
  depth_pub.publish(frameAt(s0 + ros::Duration(2.15), "tf_probe_camera"));
  EXPECT_TRUE(spinUntil([&] { return updates == 6; }, 10.0)) << "a frame between samples 0.3 s apart";
  depth_pub.publish(frameAt(s0 + ros::Duration(2.8), "tf_probe_camera"));
  EXPECT_TRUE(spinUntil([&] { return updates == 7; }, 10.0)) << "a frame between samples 1 s apart of a still camera";

  // As on a drone: the camera is a static link (/tf_static) below a body that odometry moves. The gap is in
  // the body's samples, a link of the chain above the image's frame: the frame inside it is skipped too,
  // the one at the sample after it integrated.
  tf2_ros::StaticTransformBroadcaster static_pub;
  geometry_msgs::TransformStamped mount;
  mount.header.stamp = s0;
  mount.header.frame_id = "tf_probe_body";
  mount.child_frame_id = "tf_probe_mounted_camera";
  mount.transform.rotation.w = 1.0;
  static_pub.sendTransform(mount);
  tf_pub.sendTransform(transformAt(s0 + ros::Duration(4.0), "tf_probe_body"));
  tf_pub.sendTransform(transformAt(s0 + ros::Duration(5.0), "tf_probe_body", 0.3));
  spinUntil([] { return false; }, 0.5);
  depth_pub.publish(frameAt(s0 + ros::Duration(4.5), "tf_probe_mounted_camera"));
  spinUntil([] { return false; }, 1.0);
  EXPECT_EQ(updates, 7u) << "a frame whose body pose was interpolated across a 1 s gap was integrated";
  depth_pub.publish(frameAt(s0 + ros::Duration(5.0), "tf_probe_mounted_camera"));
  EXPECT_TRUE(spinUntil([&] { return updates == 8; }, 10.0)) << "the frame at the body's sample after the gap";

  // A frame stamped 0 (a driver before its clock is set) is skipped: tf2 reads time 0 as the latest
  // transform, which is not the image's pose, and its map update would date its frontiers to the epoch.
  depth_pub.publish(frameAt(ros::Time(0), "tf_probe_camera"));
  spinUntil([] { return false; }, 1.0);
  EXPECT_EQ(updates, 8u) << "a frame stamped 0 was integrated at the latest transform";
}

// A relocalisation moves the reference later frames are judged by (the probe mapper, fed only by the tests;
// this one last, as the camera_info test needs a probe that has had no valid intrinsics yet):
// a frame 1.5 m off is skipped, the next at that pose integrated; the way back is a jump again, skipped, and the
// next frame back integrated. The same for a turn of 1 rad. (Dropping the reference's move would map every
// frame after a VIO restart as a jump, for good; the chain's own mapper, fed by the simulator, could not show it.)
TEST_F(MapperTest, ARelocalisationMovesTheReferenceLaterFramesAreJudgedBy) {
  Probe probe;
  ASSERT_TRUE(probe.connect());
  double max_range = 0.0;
  ASSERT_TRUE(ros::param::get("/probe_mapper/occupancy/max_range", max_range));
  probe.info_pub.publish(*probe.info);
  ASSERT_TRUE(probe.sendRealUntilIntegrated());
  struct Jump {
    double dx, yaw;
  };
  // How far a changed voxel can lie from the camera along an axis: a return at depth max_range in the image's
  // corner, and a voxel.
  const sensor_msgs::CameraInfo& k = *probe.info;
  const double tan_x = std::max(k.K[2], k.width - k.K[2]) / k.K[0], tan_y = std::max(k.K[5], k.height - k.K[5]) / k.K[4];
  const double reach = max_range * std::sqrt(1.0 + tan_x * tan_x + tan_y * tan_y);
  ASSERT_TRUE(probe.last_update);
  std::uint64_t sequence = probe.last_update->sequence;
  std::vector<ros::Time> skipped;
  for (const Jump jump : {Jump{1.5, 0.0}, Jump{0.0, 1.0}}) {
    const geometry_msgs::PoseStamped home = *probe.pose, away = movedPose(home, jump.dx, jump.yaw);
    const std::pair<const geometry_msgs::PoseStamped*, bool> steps[] = {
        {&away, false}, {&away, true}, {&home, false}, {&home, true}};
    for (std::size_t i = 0; i < 4; ++i) {
      const auto [pose, integrated] = steps[i];
      probe.send(*probe.depth, *pose);
      const ros::Time stamp = probe.lastSent();
      if (!integrated) {
        skipped.push_back(stamp);  // judged below, once a later frame's map_update has come
        continue;
      }
      go_feap::MapUpdate::ConstPtr u;
      EXPECT_TRUE(spinUntil([&] { return (u = probe.updateAt(stamp)) != nullptr; }, 15.0))
          << "frame " << i << " of the jump of " << jump.dx << " m and " << jump.yaw << " rad was not integrated";
      if (!u) continue;
      // Its map_update: the next sequence number, and the changed voxels (a new view: some) in a box within the
      // sensor's reach of the camera.
      EXPECT_EQ(u->sequence, sequence + 1);
      sequence = u->sequence;
      if (i != 1) continue;
      ASSERT_GT(u->changed_voxels, 0u) << "a view from 1.5 m off (or turned 1 rad) changed nothing";
      const auto& c = pose->pose.position;
      const double pad = 2.0 * u->resolution;
      for (const auto& [lo, hi, at] : {std::tuple{u->changed_min.x, u->changed_max.x, c.x},
                                      std::tuple{u->changed_min.y, u->changed_max.y, c.y},
                                      std::tuple{u->changed_min.z, u->changed_max.z, c.z}}) {
        EXPECT_LE(lo, hi);
        EXPECT_GE(lo, at - reach - pad);
        EXPECT_LE(hi, at + reach + pad);
      }
    }
  }
  // The frames are integrated in order: a skipped one's map_update would have come before the last one's.
  for (std::size_t j = 0; j < skipped.size(); ++j)
    EXPECT_FALSE(probe.updateAt(skipped[j])) << "jump frame " << j << " (of 4: there, back, there, back) was integrated";
}

}  // namespace

GO_FEAP_ROSTEST_MAIN("test_mapper_ros")
