// Record and replay, through the launch files a user runs: record_flight.launch records a short
// simulated maze flight with the onboard topic names (16UC1 depth, camera_info, odometry, TF);
// replay.launch plays it through the mapper and planners and saves the map. The recording must be a
// flight (the vehicle moved), the map must hold the walls the flight saw (many occupied voxels, nearly
// all of them ground-truth obstacles), and the recorder's files must be written when the bag ends. A bag
// without depth, or with topics of the wrong type, is refused with the topics named. Each launch gets
// its own ROS master.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <tf2_msgs/TFMessage.h>

#include <Eigen/Core>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "go_feap/world/scene_files.h"
#include "free_port.h"

namespace {

namespace fs = std::filesystem;
using go_feap::test::freeTcpPort;

class Replay : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("go_feap_replay_test_" + std::to_string(::getpid()));
    data_ = dir_ / "flight data";  // bags, maps and results in a folder whose name has a space
    fs::create_directories(data_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  // roslaunch with a private master on a free port, logs under dir_; returns its output (stdout and stderr).
  // It runs as scripts/run runs it, through run_in_own_session (scripts/lib/common.sh), written to a file
  // rather than a pipe: when the timeout has to kill roslaunch in the middle of its shutdown (seen on a
  // loaded machine), the master and manager it had not stopped yet would hold a pipe open (the test read
  // it for ever); the session's leftovers are killed and the file read.
  std::string launch(const std::string& args, int timeout_s) {
    const std::string tag = std::to_string(freeTcpPort());
    const fs::path out = dir_ / ("launch_" + tag + ".out");
    const std::string env = "ROS_MASTER_URI=http://localhost:" + tag + " ROS_HOME=" + dir_.string() +
                            " ROS_LOG_DIR=" + dir_.string() + "/log ROSCONSOLE_STDOUT_LINE_BUFFERED=1";
    const std::string command = "bash -c 'source " GO_FEAP_SOURCE_DIR "/scripts/lib/common.sh && "
                                "run_in_own_session env " + env + " timeout --signal=INT --kill-after=20 " +
                                std::to_string(timeout_s) + " roslaunch -p " + tag + " go_feap " + args + "' > " +
                                out.string() + " 2>&1 < /dev/null";
    const int status = std::system(command.c_str());
    std::ifstream out_file(out);
    std::stringstream text;
    text << out_file.rdbuf();
    return text.str() + (status == 0 ? "" : "\n(launch exit status " + std::to_string(status) + ")");
  }
  fs::path dir_, data_;
};

// A path as a roslaunch argument's value on the bash command line the tests run (it may hold spaces).
std::string inQuotes(const fs::path& path) { return "\"" + path.string() + "\""; }

// The simulated camera's depth encoding decides what its 0 means: in 32FC1 nothing in range is +inf
// (REP 117) and 0/NaN is no measurement, skipped; in 16UC1 (record_flight.launch, as a D435i) 0 is also
// nothing in range, cast free, or the recording would map no free space beyond the walls' reach.
TEST_F(Replay, TheMapperCastsZeroDepthFreeOnlyForSixteenBitSimulation) {
  auto dumped = [&](const std::string& args) {
    const fs::path out = dir_ / "params.out";
    const std::string command = "bash -c 'roslaunch --dump-params go_feap " + args + "' > " + out.string() + " 2>&1";
    EXPECT_EQ(std::system(command.c_str()), 0) << args;
    std::ifstream file(out);
    std::stringstream text;
    text << file.rdbuf();
    return text.str();
  };
  const std::string key = "/esdf_mapper/occupancy/invalid_as_free: ";
  const std::string recording = dumped("record_flight.launch bag:=" + inQuotes(data_ / "x.bag"));
  EXPECT_NE(recording.find(key + "true"), std::string::npos) << recording;
  for (const std::string& args : {std::string("sim_exploration.launch"), std::string("maze.launch"),
                                  std::string("onboard.launch"), "replay.launch bag:=" + inQuotes(data_ / "x.bag")}) {
    const std::string params = dumped(args);
    EXPECT_NE(params.find(key + "false"), std::string::npos) << args << ":\n" << params;
  }
}

TEST_F(Replay, RecordedFlightRebuildsTheWallsItSaw) {
  const std::string bag = (data_ / "flight.bag").string(), bt = (data_ / "replay.bt").string();
  const std::string rec = launch("record_flight.launch bag:=" + inQuotes(bag) + " duration:=12", 240);
  ASSERT_TRUE(fs::exists(bag)) << rec.substr(rec.size() > 3000 ? rec.size() - 3000 : 0);
  {
    // A flight, not a hover: the chain heard the simulator under the onboard names and flew. (Remapped
    // around the include, the names were overridden by each node's own remap, and the bag held the
    // vehicle hovering at its start.)
    rosbag::Bag in(bag, rosbag::bagmode::Read);
    std::optional<Eigen::Vector3d> first;
    double farthest = 0.0;
    for (const rosbag::MessageInstance& m : rosbag::View(in, rosbag::TopicQuery("/vins_estimator/odometry"))) {
      const nav_msgs::Odometry::ConstPtr odom = m.instantiate<nav_msgs::Odometry>();
      ASSERT_TRUE(odom);
      const auto& q = odom->pose.pose.position;
      const Eigen::Vector3d p(q.x, q.y, q.z);
      if (!first) first = p;
      farthest = std::max(farthest, (p - *first).norm());
    }
    ASSERT_TRUE(first) << "no odometry in the bag";
    EXPECT_GT(farthest, 1.0) << "the recorded vehicle stayed within 1 m of its start";
  }
  const fs::path results = data_ / "replay_results";
  const std::string rep = launch("replay.launch bag:=" + inQuotes(bag) + " save_map:=" + inQuotes(bt) + " invalid_as_free:=true output_dir:=" + inQuotes(results), 240);
  ASSERT_NE(rep.find("replay: save_map: wrote"), std::string::npos) << rep.substr(rep.size() > 3000 ? rep.size() - 3000 : 0);
  ASSERT_TRUE(fs::exists(bt));
  // The replayed exploration did not finish within 12 s of flight: the recorder wrote what it had when the
  // launch ended with the bag (it used to write nothing).
  std::ifstream summary(results / "summary.json");
  ASSERT_TRUE(summary.good()) << "no summary.json in output_dir after the replay";
  std::stringstream summary_text;
  summary_text << summary.rdbuf();
  EXPECT_NE(summary_text.str().find("\"finish_reason\": \"stopped\""), std::string::npos) << summary_text.str();

  auto scene = go_feap::world::makeScene("maze", 0);
  ASSERT_TRUE(scene) << scene.message();
  octomap::OcTree tree(bt);
  std::size_t occupied = 0, on_walls = 0, free_cells = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
    if (!tree.isNodeOccupied(*it)) {
      ++free_cells;
      continue;
    }
    ++occupied;
    // A mapped obstacle voxel: a ground-truth obstacle within one voxel (depth quantised to mm and
    // rays ending on voxel faces may put a return in the neighbour).
    const go_feap::common::Vec3 c(it.getX(), it.getY(), it.getZ());
    bool near = false;
    for (double dx : {-0.1, 0.0, 0.1})
      for (double dy : {-0.1, 0.0, 0.1})
        for (double dz : {-0.1, 0.0, 0.1}) near = near || scene->isOccupied(go_feap::common::Vec3(c + go_feap::common::Vec3(dx, dy, dz)));
    on_walls += near;
  }
  std::cout << occupied << " occupied voxels, " << on_walls << " on ground-truth walls, " << free_cells
            << " free leaves\n";
  EXPECT_GT(occupied, 1000u) << "the flight saw walls: the replayed map must hold them";
  EXPECT_GE(static_cast<double>(on_walls), 0.98 * static_cast<double>(occupied));
  EXPECT_GT(free_cells, 100u);
}

TEST_F(Replay, ABagWithoutDepthIsRefusedNamingTheMissingTopic) {
  const std::string bag = (data_ / "odom_only.bag").string();
  {
    rosbag::Bag out(bag, rosbag::bagmode::Write);
    nav_msgs::Odometry odom;
    odom.header.frame_id = "world";
    odom.pose.pose.orientation.w = 1.0;
    for (int i = 1; i <= 20; ++i) {
      odom.header.stamp = ros::Time(i * 0.1);
      out.write("/vins_estimator/odometry", odom.header.stamp, odom);
    }
  }
  const std::string rep = launch("replay.launch bag:=" + inQuotes(bag), 120);
  EXPECT_NE(rep.find("lacks the topic(s) /camera/depth/image_rect_raw, /camera/depth/camera_info"), std::string::npos)
      << rep.substr(rep.size() > 3000 ? rep.size() - 3000 : 0);
}

// Every topic is there, but the depth is a CompressedImage and the odometry a PoseStamped: rosbag play
// would send them to no subscriber, and the replay end with an empty map saved as a success.
TEST_F(Replay, ABagWithTopicsOfTheWrongTypeIsRefusedNamingThem) {
  const std::string bag = (data_ / "wrong_types.bag").string();
  {
    rosbag::Bag out(bag, rosbag::bagmode::Write);
    for (int i = 1; i <= 5; ++i) {
      const ros::Time t(i * 0.1);
      sensor_msgs::CompressedImage depth;
      depth.header.stamp = t;
      out.write("/camera/depth/image_rect_raw", t, depth);
      sensor_msgs::CameraInfo info;
      info.header.stamp = t;
      out.write("/camera/depth/camera_info", t, info);
      geometry_msgs::PoseStamped pose;
      pose.header.stamp = t;
      pose.pose.orientation.w = 1.0;
      out.write("/vins_estimator/odometry", t, pose);
      tf2_msgs::TFMessage tf;
      out.write("/tf", t, tf);
      out.write("/tf_static", t, tf);
    }
  }
  const std::string rep = launch("replay.launch bag:=" + inQuotes(bag), 120);
  EXPECT_NE(rep.find("has topics of the wrong type: /camera/depth/image_rect_raw is sensor_msgs/CompressedImage, not "
                     "sensor_msgs/Image; /vins_estimator/odometry is geometry_msgs/PoseStamped, not nav_msgs/Odometry"),
            std::string::npos)
      << rep.substr(rep.size() > 3000 ? rep.size() - 3000 : 0);
}

}  // namespace
