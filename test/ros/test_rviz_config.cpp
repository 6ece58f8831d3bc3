// rviz/exploration.rviz loads in rviz under Xvfb without errors (scripts/lib/rviz_screenshot.sh on
// a private master), and the screenshot taken then is a real, non-blank picture.
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "../command_util.h"
#include "free_port.h"

#ifndef GO_FEAP_SOURCE_DIR
#error "GO_FEAP_SOURCE_DIR must name the package's source directory"
#endif

namespace {

namespace fs = std::filesystem;

using go_feap::test::runCommand;

TEST(RvizConfig, LoadsUnderXvfbWithoutErrors) {
  const fs::path dir = fs::temp_directory_path() / ("go_feap_rviz_test_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const std::string port = std::to_string(go_feap::test::freeTcpPort());
  const std::string env = "ROS_MASTER_URI=http://localhost:" + port + " ROS_HOME=" + dir.string() + " ROS_LOG_DIR=" +
                          dir.string() + "/log";
  // A private master for the duration of the check.
  ASSERT_EQ(std::system((env + " roscore -p " + port + " >" + dir.string() + "/roscore.log 2>&1 & echo $! >" + dir.string() +
                         "/roscore.pid")
                            .c_str()),
            0);
  const auto [rc, output] =
      runCommand("export " + env + "; for i in $(seq 60); do rosnode list >/dev/null 2>&1 && break; sleep 0.5; done; timeout 180 " GO_FEAP_SOURCE_DIR "/scripts/lib/rviz_screenshot.sh " + (dir / "rviz.png").string() + " 12");
  std::system(("kill $(cat " + dir.string() + "/roscore.pid) 2>/dev/null; sleep 1").c_str());
  EXPECT_EQ(rc, 0) << output;
  EXPECT_NE(output.find("rviz printed no ERROR lines"), std::string::npos) << output;
  const std::string log = go_feap::test::readText(dir / "rviz.rviz.log");
  EXPECT_EQ(log.find("[ERROR]"), std::string::npos) << log;
  const cv::Mat shot = cv::imread((dir / "rviz.png").string());
  ASSERT_FALSE(shot.empty()) << "no screenshot";
  EXPECT_EQ(shot.cols, 1280);
  cv::Scalar mean, stddev;
  cv::meanStdDev(shot, mean, stddev);
  EXPECT_GT(stddev[0] + stddev[1] + stddev[2], 10.0) << "the screenshot is blank";
  fs::remove_all(dir);
}

// What the config shows, read as rviz reads it. The depth image is shown over its own range: a fixed range
// (0 to 4.5, as it was) suits 32FC1 metres only, and made a D435i's 16UC1 millimetres (onboard.launch,
// replay.launch) solid white. The 2D Nav Goal goes where the layer manager takes its trigger.
TEST(RvizConfig, TheDepthImageIsShownOverItsOwnRangeAndTheGoalTriggersExploration) {
  const YAML::Node config = YAML::LoadFile(GO_FEAP_SOURCE_DIR "/rviz/exploration.rviz");
  std::size_t depth_displays = 0;
  for (const YAML::Node& d : config["Visualization Manager"]["Displays"]) {
    if (d["Class"].as<std::string>() != "rviz/Image" || d["Image Topic"].as<std::string>("") != "/depth") continue;
    ++depth_displays;
    EXPECT_TRUE(d["Normalize Range"].as<bool>(false)) << "the depth image has a fixed range";
  }
  EXPECT_EQ(depth_displays, 1u);
  std::size_t goals = 0;
  for (const YAML::Node& t : config["Visualization Manager"]["Tools"]) {
    if (t["Class"].as<std::string>() != "rviz/SetGoal") continue;
    ++goals;
    EXPECT_EQ(t["Topic"].as<std::string>(""), "/move_base_simple/goal");
  }
  EXPECT_EQ(goals, 1u);
}

}  // namespace
