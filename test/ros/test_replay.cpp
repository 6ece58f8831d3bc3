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
#include <std_msgs/String.h>
#include <tf2_msgs/TFMessage.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Core>

#include <algorithm>
#include <cstdlib>
#include <functional>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "go_feap/ExplorationStatus.h"
#include "go_feap/world/scene_files.h"
#include "../command_util.h"
#include "free_port.h"

namespace {

namespace fs = std::filesystem;
using go_feap::test::freeTcpPort;
using go_feap::test::readText;
using go_feap::test::replaceOnce;
using go_feap::test::runCommand;

// A path as a roslaunch argument's value on the bash command line the tests run (it may hold spaces).
std::string inQuotes(const fs::path& path) { return "\"" + path.string() + "\""; }

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
    return readText(out) + (status == 0 ? "" : "\n(launch exit status " + std::to_string(status) + ")");
  }
  // scripts/run on the small maze with the suite's own build at twice real time, `args` after it, its output
  // to `log` (a file, not a pipe: a leftover of a killed run would hold a pipe open); its exit status.
  int scriptsRunSmallMaze(const std::string& args, const fs::path& log) {
    return std::system(("GO_FEAP_BUILD=" + inQuotes(GO_FEAP_BUILD_DIR) + " timeout --kill-after=30 900 " +
                        GO_FEAP_SOURCE_DIR "/scripts/run " GO_FEAP_SOURCE_DIR
                        "/config/scenes/maze_small.yaml --no-build --rate-factor 2 " + args + " > " + log.string() +
                        " 2>&1 < /dev/null").c_str());
  }
  // The parameters a launch would set, as YAML (roslaunch --dump-params: no master, no node started).
  std::string dumpParams(const std::string& args) {
    // roslaunch's warnings go to a file of their own (runCommand merges the shell's stderr into the YAML).
    const auto [status, out] = runCommand("bash -c 'roslaunch --dump-params go_feap " + args + " 2> " +
                                          (dir_ / "params.err").string() + "'");
    EXPECT_EQ(status, 0) << args << ":\n" << out << readText(dir_ / "params.err");
    return out;
  }
  fs::path dir_, data_;
};

// The simulated camera's depth encoding decides what its 0 means: in 32FC1 nothing in range is +inf
// (REP 117) and 0/NaN is no measurement, skipped; in 16UC1 (record_flight.launch, as a D435i) 0 is also
// nothing in range, cast free, or the recording would map no free space beyond the walls' reach.
TEST_F(Replay, TheMapperCastsZeroDepthFreeOnlyForSixteenBitSimulation) {
  const std::string key = "/esdf_mapper/occupancy/invalid_as_free: ";
  const std::string recording = dumpParams("record_flight.launch bag:=" + inQuotes(data_ / "x.bag"));
  EXPECT_NE(recording.find(key + "true"), std::string::npos) << recording;
  for (const std::string& args : {std::string("sim_exploration.launch"), std::string("maze.launch"),
                                  std::string("onboard.launch"), "replay.launch bag:=" + inQuotes(data_ / "x.bag")}) {
    const std::string params = dumpParams(args);
    EXPECT_NE(params.find(key + "false"), std::string::npos) << args << ":\n" << params;
  }
}

// The command line roslaunch gives node `node` of a launch (its remaps included): no master needed.
std::string nodeArgs(const std::string& node, const std::string& args) {
  return runCommand("bash -c 'roslaunch --args " + node + " go_feap " + args + "'").second;
}

// A launch's arguments reach the nodes they are documented for, as roslaunch --dump-params and --args give
// them (no master, no node started): the exploration box and world frame of onboard.launch and
// replay.launch (left out, a drone explored exploration.launch's default box, and a map in its VIO frame
// never filled); a config folder and camera config of the user's own (ignored, the shipped clearances and
// extrinsic flew); the planner mode in every planning nodelet; the simulated time limit; the depth encoding
// a recording uses; the topics the chain is given.
TEST_F(Replay, LaunchArgumentsReachTheNodesTheyName) {
  auto dumpYaml = [&](const std::string& args) {
    try {
      return YAML::Load(dumpParams(args));
    } catch (const YAML::Exception& e) {
      ADD_FAILURE() << args << ": " << e.what();
      return YAML::Node();
    }
  };
  auto asNumbers = [](const YAML::Node& n) {
    std::vector<double> v;
    if (n && n.IsSequence())
      for (const auto& x : n) v.push_back(x.as<double>());
    return v;
  };
  // Every key of `params` ending in `suffix`, with its value.
  auto keysEnding = [](const YAML::Node& params, const std::string& suffix) {
    std::vector<std::pair<std::string, YAML::Node>> found;
    for (const auto& kv : params) {
      const std::string key = kv.first.as<std::string>();
      if (key.size() >= suffix.size() && key.compare(key.size() - suffix.size(), suffix.size(), suffix) == 0)
        found.emplace_back(key, kv.second);
    }
    return found;
  };

  // A config folder of the user's own: one value changed in each file the chain reads.
  const fs::path config = dir_ / "my config";
  fs::copy(GO_FEAP_SOURCE_DIR "/config", config, fs::copy_options::recursive);
  ASSERT_TRUE(replaceOnce(config / "exploration.yaml", "s_near: 5.0", "s_near: 4.5"));
  ASSERT_TRUE(replaceOnce(config / "mapping.yaml", "pose_tolerance: 0.02", "pose_tolerance: 0.03"));
  ASSERT_TRUE(replaceOnce(config / "trajectory.yaml", "lambda_smooth: 1.0", "lambda_smooth: 1.25"));
  ASSERT_TRUE(replaceOnce(config / "d435i.yaml", "T_B_C: [0, 0, 1, 0.10,", "T_B_C: [0, 0, 1, 0.12,"));
  ASSERT_TRUE(replaceOnce(config / "d435i_viewpoints.yaml", "vfov: 0.98", "vfov: 0.97"));
  const std::string box = " box_min:=[-3.5,-2.5,0.5] box_max:=[4.5,3.5,2.5] world_frame:=vio";
  // camera_config follows config_dir (the copy's d435i.yaml); it used to be the package's whatever config_dir said.
  const std::string mine = " config_dir:=" + inQuotes(config);
  for (const std::string& launch : {std::string("onboard.launch"), "replay.launch bag:=" + inQuotes(data_ / "x.bag")}) {
    const YAML::Node p = dumpYaml(launch + box + mine);
    for (const char* node : {"/esdf_mapper", "/frontier_finder", "/layer_manager"}) {
      EXPECT_EQ(asNumbers(p[std::string(node) + "/exploration_box/min"]), (std::vector<double>{-3.5, -2.5, 0.5}))
          << launch << " " << node;
      EXPECT_EQ(asNumbers(p[std::string(node) + "/exploration_box/max"]), (std::vector<double>{4.5, 3.5, 2.5}))
          << launch << " " << node;
    }
    const auto frames = keysEnding(p, "world_frame");
    EXPECT_GE(frames.size(), launch == "onboard.launch" ? 9u : 7u) << launch;  // a replay has no server, no OdometryTf
    for (const auto& [key, value] : frames) EXPECT_EQ(value.as<std::string>(), "vio") << launch << " " << key;
    const auto s_near = keysEnding(p, "/frontier/s_near");
    EXPECT_GE(s_near.size(), 4u) << launch;
    for (const auto& [key, value] : s_near) EXPECT_DOUBLE_EQ(value.as<double>(), 4.5) << launch << " " << key;
    EXPECT_DOUBLE_EQ(p["/esdf_mapper/mapper/pose_tolerance"].as<double>(0.0), 0.03) << launch;
    EXPECT_DOUBLE_EQ(p["/trajectory_planner/optimizer/lambda_smooth"].as<double>(0.0), 1.25) << launch;
    if (launch == "onboard.launch") {
      const std::vector<double> T = asNumbers(p["/odometry_tf/T_B_C"]);
      ASSERT_EQ(T.size(), 16u);
      EXPECT_DOUBLE_EQ(T[3], 0.12) << "the extrinsic is not the camera_config's";
    }
    // The local planner's sensor model: on board the D435i's, from the config folder, over exploration.yaml's
    // simulated camera; a replay keeps exploration.yaml's unless told the flight's.
    const bool onboard = launch == "onboard.launch";
    EXPECT_DOUBLE_EQ(p["/local_planner/viewpoints/vfov"].as<double>(0.0), onboard ? 0.97 : 1.0472) << launch;
    EXPECT_DOUBLE_EQ(p["/local_planner/viewpoints/hfov"].as<double>(0.0), onboard ? 1.34 : 1.3963) << launch;
    EXPECT_DOUBLE_EQ(p["/local_planner/viewpoints/sensor_range"].as<double>(0.0), 4.5) << launch;
  }
  {
    const YAML::Node p = dumpYaml("replay.launch bag:=" + inQuotes(data_ / "x.bag") + mine +
                                  " viewpoint_config:=" + inQuotes(config / "d435i_viewpoints.yaml"));
    EXPECT_DOUBLE_EQ(p["/local_planner/viewpoints/vfov"].as<double>(0.0), 0.97);
    EXPECT_DOUBLE_EQ(p["/local_planner/viewpoints/hfov"].as<double>(0.0), 1.34);
  }
  // The planner mode: each key of modes/fuel.yaml, with its value, in every nodelet that loads a mode.
  {
    const YAML::Node p = dumpYaml("sim_exploration.launch planner:=fuel");
    const YAML::Node fuel = YAML::LoadFile(GO_FEAP_SOURCE_DIR "/config/modes/fuel.yaml");
    std::size_t checked = 0;
    std::function<void(const YAML::Node&, const std::string&)> leaves = [&](const YAML::Node& n, const std::string& at) {
      if (n.IsMap()) {
        for (const auto& kv : n) leaves(kv.second, at + "/" + kv.first.as<std::string>());
        return;
      }
      for (const char* node : {"/frontier_finder", "/global_planner", "/local_planner", "/trajectory_planner",
                               "/trajectory_server", "/layer_manager"}) {
        EXPECT_DOUBLE_EQ(p[node + at].as<double>(-12345.0), n.as<double>()) << node << at;
        ++checked;
      }
    };
    leaves(fuel, "");
    EXPECT_GE(checked, 6u * 10u);
    EXPECT_EQ(p["/metrics_recorder/metrics/planner"].as<std::string>(""), "fuel");
  }
  // The simulated time limit: the argument's, powerplant.launch's 3000 s, exploration.yaml's 900 s.
  EXPECT_DOUBLE_EQ(dumpYaml("sim_exploration.launch time_limit:=1234.5")["/layer_manager/layers/time_limit"].as<double>(0.0),
                   1234.5);
  EXPECT_DOUBLE_EQ(dumpYaml("powerplant.launch")["/layer_manager/layers/time_limit"].as<double>(0.0), 3000.0);
  EXPECT_DOUBLE_EQ(dumpYaml("maze.launch")["/layer_manager/layers/time_limit"].as<double>(0.0), 900.0);
  // A recording's depth is a D435i's, 16-bit millimetres; the simulation's own is 32-bit metres.
  EXPECT_EQ(dumpYaml("record_flight.launch bag:=" + inQuotes(data_ / "x.bag"))["/depth_camera/depth_camera/encoding"]
                .as<std::string>(""),
            "16UC1");
  EXPECT_EQ(dumpYaml("sim_exploration.launch")["/depth_camera/depth_camera/encoding"].as<std::string>(""), "32FC1");
  // The topics: the trajectory planner hears the commands where the server sends them, the mapper the
  // camera pose where it is given.
  EXPECT_NE(nodeArgs("/trajectory_planner", "onboard.launch position_cmd_topic:=/cmd_x").find("position_cmd:=/cmd_x"),
            std::string::npos);
  EXPECT_NE(nodeArgs("/trajectory_server", "onboard.launch position_cmd_topic:=/cmd_x").find("position_cmd:=/cmd_x"),
            std::string::npos);
  EXPECT_NE(nodeArgs("/esdf_mapper", "exploration.launch camera_pose_topic:=/pose_x").find("camera_pose:=/pose_x"),
            std::string::npos);
  EXPECT_NE(nodeArgs("/odometry_tf", "onboard.launch odom_topic:=/odom_x").find("odom:=/odom_x"), std::string::npos);
}

// Every nodelet of every launch file is required: a nodelet that refuses its parameters (or dies) ends the
// launch, as the README says; without it scripts/run waited for its wall-clock guard (hours for the
// powerplant) with the chain broken. Read with roslaunch's own loader.
TEST_F(Replay, EveryNodeletOfEveryLaunchIsRequired) {
  const fs::path script = dir_ / "required.py";
  std::ofstream(script) << "import glob, sys\n"
                           "import roslaunch.config\n"
                           "checked = 0\n"
                           "for path in sorted(glob.glob(sys.argv[1] + '/launch/*.launch')):\n"
                           "    sys.argv = ['check', 'bag:=/tmp/x.bag', 'manager:=m', 'planner:=go_feap',\n"
                           "                'odom_topic:=/o', 'depth_topic:=/d']  # the arguments without defaults\n"
                           "    config = roslaunch.config.load_config_default([path], None, verbose=False)\n"
                           "    for node in config.nodes:\n"
                           "        if node.package != 'nodelet':\n"
                           "            continue\n"
                           "        checked += 1\n"
                           "        if not node.required:\n"
                           "            print('NOT REQUIRED', path, node.name)\n"
                           "print('checked', checked)\n";
  const auto [status, out] = runCommand("/usr/bin/python3 " + script.string() + " " GO_FEAP_SOURCE_DIR);
  EXPECT_EQ(status, 0) << out;
  EXPECT_EQ(out.find("NOT REQUIRED"), std::string::npos) << out;
  const std::size_t at = out.find("checked ");
  ASSERT_NE(at, std::string::npos) << out;
  EXPECT_GE(std::stoi(out.substr(at + 8)), 60) << out;
}

// The user scripts refuse bad arguments by name, exit 2, before the install and the build (minutes on a
// fresh machine): their build folder is pointed at one that must stay unmade, and a refusal that did not
// come is cut short by the timeout; --no-build is refused there, as there is no build to use (after
// record_flight has named its bag: a folder for --out gets a bag named by the time in it, where `DIR/` made
// the hidden DIR/.bag). --help is no error.
TEST_F(Replay, TheScriptsRefuseBadArgumentsBeforeInstallingOrBuilding) {
  const fs::path unmade = dir_ / "unmade build";
  const fs::path done = dir_ / "done";
  fs::create_directories(done);
  std::ofstream(done / "summary.json") << "{}\n";
  std::ofstream(done / "flight.bag") << "a bag\n";
  const std::string scripts = GO_FEAP_SOURCE_DIR "/scripts/";
  for (const auto& [call, says] : std::vector<std::pair<std::string, std::string>>{
           {"run --rate-factor 0", "--rate-factor must be a number in [0.01, 1000]"},
           {"run --rate-factor 0.001", "--rate-factor must be a number in [0.01, 1000]"},
           {"run --time-limit 0", "--time-limit must be a number of simulated seconds in (0, 1e6]"},
           {"run --time-limit nan", "--time-limit must be a number of simulated seconds in (0, 1e6]"},
           {"run --planner warp", "unknown planner 'warp'"},
           {"run --seed -1", "--seed must be a whole number"},
           {"run --seed", "--seed needs a value"},
           {"run maze powerplant", "one scene only"},
           {"run nowhere.yaml", "neither maze, powerplant nor an existing scene YAML"},
           {"run --out " + inQuotes(done), "already holds a run's summary.json"},
           {"run --fast", "unknown option --fast"},
           {"run --no-build", "--no-build: there is no build in"},
           {"record_flight --no-build --out " + inQuotes(dir_ / "none.bag"), "--no-build: there is no build in"},
           {"paper_tables --no-build", "--no-build: there is no build in"},
           {"record_flight --duration 0", "--duration must be a whole number of seconds"},
           {"record_flight --out " + inQuotes(done / "flight.bag"), "already exists"},
           {"record_flight --no-build --out " + inQuotes(done), "the bag: " + done.string() + "/flight-"},
           {"record_flight --no-build --out " + inQuotes(dir_ / "new") + "/", "the bag: " + (dir_ / "new").string() + "/flight-"},
           {"record_flight --seed x", "--seed must be a whole number"},
           {"paper_tables --runs 0", "--runs must be a whole number from 1 to 100000"},
           {"paper_tables --jobs 0", "--jobs must be a whole number from 1 to 256"},
           {"paper_tables --planners go_feap,warp", "unknown planner 'warp'"},
           {"paper_tables --scenes maze,", "'' is neither maze, powerplant nor an existing scene YAML"},
           {"paper_tables --scenes office", "'office' is neither maze, powerplant nor an existing scene YAML"}}) {
    const auto [status, out] = runCommand("GO_FEAP_BUILD=" + inQuotes(unmade) + " timeout 20 " + scripts + call);
    EXPECT_EQ(status, 2) << call << "\n" << out;
    EXPECT_NE(out.find(says), std::string::npos) << call << ":\n" << out;
    EXPECT_FALSE(fs::exists(unmade)) << call << " began a build";
  }
  for (const char* script : {"run", "record_flight", "paper_tables", "test"}) {
    const auto [status, out] = runCommand(scripts + script + " --help");
    EXPECT_EQ(status, 0) << script << " --help:\n" << out;
  }
}

// scripts/run, the main command, on the small maze with the suite's own build (--no-build): it explores
// through the ROS chain to the end, exits 0, prints progress lines and a summary whose figures are
// summary.json's, and leaves the results folder the README lists.
TEST_F(Replay, ScriptsRunExploresTheSmallMazeAndLeavesItsResults) {
  const fs::path out = data_ / "run results", log = dir_ / "run.log";
  const int status = scriptsRunSmallMaze("--out " + inQuotes(out), log);
  const std::string text = readText(log);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status << "\n" << text;
  EXPECT_NE(text.find("--no-build: using the build in"), std::string::npos) << text;
  EXPECT_EQ(text.find("dependencies"), std::string::npos) << "--no-build installed:\n" << text;
  EXPECT_EQ(text.find("building in"), std::string::npos) << "--no-build built:\n" << text;
  // Progress lines, one per line off a terminal, with the state and the coverage.
  EXPECT_NE(text.find("\n[go_feap] EXPLORE band"), std::string::npos) << text;

  for (const char* file : {"summary.json", "metrics.csv", "coverage.png", "scene/scene.json", "ros.log"})
    EXPECT_TRUE(fs::is_regular_file(out / file)) << file << " missing from " << out;
  const YAML::Node summary = YAML::LoadFile((out / "summary.json").string());  // JSON is YAML
  EXPECT_EQ(summary["scene"].as<std::string>(), "maze_small");
  EXPECT_EQ(summary["finish_reason"].as<std::string>(), "complete");
  const double coverage = summary["coverage"].as<double>();
  EXPECT_GE(coverage, 0.95);
  EXPECT_EQ(summary["collisions"].as<int>(), 0);
  std::ostringstream line;
  line << std::fixed << std::setprecision(1) << "summary: maze_small (seed 0, go_feap): complete after "
       << summary["exploration_time_s"].as<double>() << " s simulated, " << summary["flight_distance_m"].as<double>()
       << " m flown, coverage " << 100.0 * coverage << " %, 0 collision(s), wall ";
  EXPECT_NE(text.find(line.str()), std::string::npos) << "no '" << line.str() << "' in:\n" << text;
  EXPECT_NE(text.find("results: " + out.string() + " ("), std::string::npos) << text;
  // metrics.csv: its header and a row per sample (2 Hz of simulated time).
  std::istringstream csv(readText(out / "metrics.csv"));
  std::string header, row;
  std::getline(csv, header);
  int rows = 0;
  while (std::getline(csv, row)) rows += !row.empty();
  EXPECT_EQ(header.rfind("t,coverage,", 0), 0u) << header;
  EXPECT_GT(rows, 10) << "metrics.csv:\n" << header;
  const std::string png = readText(out / "coverage.png");
  EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8)) << "coverage.png is no PNG";
}

// scripts/run with --time-limit: the exploration ends at the limit, its results are written, and the
// script exits 3 (finished, not complete), not 0 as for a box explored to the end.
TEST_F(Replay, ScriptsRunEndsWithStatus3WhenTheTimeLimitEndsTheExploration) {
  const fs::path out = data_ / "limited", log = dir_ / "limited.log";
  const int status = scriptsRunSmallMaze("--time-limit 4 --out " + inQuotes(out), log);
  const std::string text = readText(log);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 3) << "status " << status << "\n" << text;
  EXPECT_NE(text.find("finished without exploring the whole box"), std::string::npos) << text;
  ASSERT_TRUE(fs::is_regular_file(out / "summary.json")) << text;
  const YAML::Node summary = YAML::LoadFile((out / "summary.json").string());
  EXPECT_EQ(summary["finish_reason"].as<std::string>(), "time_limit");
  EXPECT_NEAR(summary["exploration_time_s"].as<double>(), 4.0, 0.5);
  EXPECT_LT(summary["coverage"].as<double>(), 0.9);
}

// scripts/record_flight records a short simulated flight (with the suite's own build), and replay.launch
// maps it.
TEST_F(Replay, RecordedFlightRebuildsTheWallsItSaw) {
  const std::string bag = (data_ / "flight.bag").string(), bt = (data_ / "replay.bt").string();
  const auto [recorded, rec] = runCommand("GO_FEAP_BUILD=" + inQuotes(GO_FEAP_BUILD_DIR) + " timeout --kill-after=30 300 " +
                                          GO_FEAP_SOURCE_DIR "/scripts/record_flight --no-build --duration 12 --out " +
                                          inQuotes(bag) + " < /dev/null");
  ASSERT_EQ(recorded, 0) << rec << readText(data_ / "flight.log");
  ASSERT_TRUE(fs::exists(bag)) << rec;
  {
    // A flight, not a hover: the chain heard the simulator under the onboard names and flew. (Remapped
    // around the include, the names were overridden by each node's own remap, and the bag held the
    // vehicle hovering at its start.)
    rosbag::Bag in(bag, rosbag::bagmode::Read);
    std::optional<Eigen::Vector3d> first;
    double farthest = 0.0;
    ros::Time last;
    for (const rosbag::MessageInstance& m : rosbag::View(in, rosbag::TopicQuery("/vins_estimator/odometry"))) {
      const nav_msgs::Odometry::ConstPtr odom = m.instantiate<nav_msgs::Odometry>();
      ASSERT_TRUE(odom);
      const auto& q = odom->pose.pose.position;
      const Eigen::Vector3d p(q.x, q.y, q.z);
      if (!first) first = p;
      farthest = std::max(farthest, (p - *first).norm());
      last = m.getTime();
    }
    ASSERT_TRUE(first) << "no odometry in the bag";
    EXPECT_GT(farthest, 1.0) << "the recorded vehicle stayed within 1 m of its start";
    in.close();
    // As a bag recorded with -a on a drone: topics the replay must not play, one of them past the end of
    // those it plays. A status FINISHED from the bag would end the replayed run's recorder with the bag's
    // reason; a message 30 s past the flight held the replay (the clock stops with the topics played) until
    // its wait ran out, and it said the bag had not played to its end.
    rosbag::Bag out(bag, rosbag::bagmode::Append);
    go_feap::ExplorationStatus finished;
    finished.header.stamp = last - ros::Duration(2.0);
    finished.state = go_feap::ExplorationStatus::FINISHED;
    finished.state_name = "FINISHED";
    finished.finish_reason = "from_the_bag";
    out.write("/status", finished.header.stamp, finished);
    std_msgs::String later;
    later.data = "recorded past the flight";
    out.write("/rosout_extra", last + ros::Duration(30.0), later);
  }
  const fs::path results = data_ / "replay_results";
  const std::string rep = launch("replay.launch bag:=" + inQuotes(bag) + " save_map:=" + inQuotes(bt) + " invalid_as_free:=true output_dir:=" + inQuotes(results), 240);
  ASSERT_NE(rep.find("replay: save_map: wrote"), std::string::npos) << rep.substr(rep.size() > 3000 ? rep.size() - 3000 : 0);
  EXPECT_EQ(rep.find("did not reach the bag's end"), std::string::npos) << "the replay waited for a topic it does not play";
  ASSERT_TRUE(fs::exists(bt));
  // The replayed exploration did not finish within 12 s of flight: the recorder wrote what it had when the
  // launch ended with the bag (it used to write nothing).
  ASSERT_TRUE(fs::is_regular_file(results / "summary.json")) << "no summary.json in output_dir after the replay";
  const std::string summary = readText(results / "summary.json");
  EXPECT_NE(summary.find("\"finish_reason\": \"stopped\""), std::string::npos) << summary;

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

// A TERM to scripts/run alone (`timeout 600 scripts/run`, a supervisor) stops the chain it started, which
// writes what it had (a run "stopped"), and the script ends with status 1 and leaves no process behind: it
// used to die at once and leave the whole chain running until its wall-clock guard (35 min for a maze).
TEST_F(Replay, ATermToScriptsRunStopsItsChain) {
  const fs::path out = data_ / "termed", log = dir_ / "termed.log";
  const auto [status, said] = runCommand(
      "bash -c 'GO_FEAP_BUILD=" + inQuotes(GO_FEAP_BUILD_DIR) + " " GO_FEAP_SOURCE_DIR "/scripts/run " GO_FEAP_SOURCE_DIR
      "/config/scenes/maze_small.yaml --no-build --out " + inQuotes(out) + " > " + inQuotes(log) +
      " 2>&1 < /dev/null & run=$!; sleep 10; kill -TERM $run; wait $run; echo \"status $?\"; "
      "pgrep -f " + inQuotes("[o]utput_dir:=" + out.string()) + " | wc -l'");  // [o]: not this shell's own line
  const std::string text = readText(log);
  EXPECT_NE(said.find("status 1\n0\n"), std::string::npos) << said << "\n" << text;
  EXPECT_NE(text.find("the run was stopped before exploration finished"), std::string::npos) << text;
  EXPECT_TRUE(fs::is_regular_file(out / "summary.json")) << text;
}

// Runs started together get folders of their own (the default name has one-second steps: two runs shared
// one, and one reported the other's summary as its own); a build folder given with a trailing slash keeps its
// logs beside it (they went inside a folder not yet made, and the configure "failed").
TEST_F(Replay, RunsStartedTogetherGetFoldersOfTheirOwn) {
  const fs::path base = dir_ / "runs" / "maze-now";
  const auto [status, out] = runCommand("bash -c 'source " GO_FEAP_SOURCE_DIR "/scripts/lib/common.sh; for i in 1 2 3 4; "
                                        "do new_folder " + inQuotes(base) + " & done; wait'");
  EXPECT_EQ(status, 0) << out;
  std::set<std::string> printed;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) printed.insert(line);
  const std::set<std::string> expected{base.string(), base.string() + "-2", base.string() + "-3", base.string() + "-4"};
  EXPECT_EQ(printed, expected) << out;
  for (const std::string& folder : expected) EXPECT_TRUE(fs::is_directory(folder)) << folder;
  const auto [rc, build] = runCommand("GO_FEAP_BUILD=" + inQuotes((dir_ / "b").string() + "//") + " bash -c 'source " GO_FEAP_SOURCE_DIR
                                      "/scripts/lib/common.sh; echo \"$GO_FEAP_BUILD\"'");
  EXPECT_EQ(build, (dir_ / "b").string() + "\n");
}

// A recording cut short (here a Ctrl-C 10 s into a 60 s one) keeps its bag and says it is short, exit 1:
// roslaunch ends 0 whenever the recorder stops, and the script used to report the short bag as a success.
TEST_F(Replay, ARecordingCutShortIsSaidToBeShort) {
  const fs::path bag = data_ / "short.bag", log = dir_ / "short.log";  // to a file, as scripts/run's test
  const int status = std::system(("GO_FEAP_BUILD=" + inQuotes(GO_FEAP_BUILD_DIR) +
                                  " timeout --preserve-status --signal=INT --kill-after=60 10 " GO_FEAP_SOURCE_DIR
                                  "/scripts/record_flight --no-build --duration 60 --out " +
                                  inQuotes(bag) + " > " + inQuotes(log) + " 2>&1 < /dev/null").c_str());
  const std::string out = readText(log);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1) << "status " << status << "\n" << out;
  EXPECT_NE(out.find("the recording stopped after"), std::string::npos) << out;
  EXPECT_NE(out.find(" of the 60 s asked"), std::string::npos) << out;
  EXPECT_TRUE(fs::is_regular_file(bag)) << "the short bag was not kept\n" << out;
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
