// rostest: the MetricsRecorder nodelet measures a run it is told about. The test node drives the
// simulated clock and plays the layer manager (status), the vehicle (odometry) and the planners
// (compute_time); the recorder's summary.json must hold what was played: the layer manager's time, the
// length of the flown path, one collision for one pass through a ground-truth wall (found in the scene
// by the test itself), the mean compute time of each block. Statuses that are malformed, or that came
// before the run or whose elapsed time lies beyond the clock, must neither end the recorder nor count.
// Then the clock goes back, and a probe layer manager's elapsed time must stay at 0 or above; a probe
// global, local and trajectory planner, on a probe mapper's map of one synthetic frame, must plan again.
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/NodeletLoad.h>
#include <nodelet/NodeletUnload.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <rosgraph_msgs/Clock.h>
#include <rosgraph_msgs/Log.h>
#include <std_msgs/UInt32.h>
#include <std_msgs/UInt32MultiArray.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <geometry_msgs/PoseStamped.h>
#include <visualization_msgs/Marker.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <vector>

#include "go_feap/Bspline.h"
#include "go_feap/ComputeTime.h"
#include "go_feap/ExplorationStatus.h"
#include "go_feap/FrontierArray.h"
#include "go_feap/GlobalTour.h"
#include "go_feap/LayerBounds.h"
#include "go_feap/MapUpdate.h"
#include "go_feap/PositionCommand.h"
#include "go_feap/ViewpointPath.h"
#include "go_feap/ros/conversions.h"
#include "../command_util.h"
#include "flight_util.h"
#include "ros_test_util.h"

namespace {

using go_feap::test::spinUntil;
using Vec3 = Eigen::Vector3d;

// World-frame odometry at `p`, level, stamped `now`.
nav_msgs::Odometry odometryAt(const Vec3& p, double now) {
  nav_msgs::Odometry m;
  m.header.stamp = ros::Time(now);
  m.header.frame_id = "world";
  m.pose.pose.position.x = p.x(), m.pose.pose.position.y = p.y(), m.pose.pose.position.z = p.z();
  m.pose.pose.orientation.w = 1.0;
  return m;
}

void publishClock(const ros::Publisher& clock_pub, double now) {
  rosgraph_msgs::Clock c;
  c.clock = ros::Time(now);
  clock_pub.publish(c);
}

// Plays `seconds` of the clock in steps of `step`, from `now` (advanced): each step publishes the clock,
// lets the nodes hear it, stamps and publishes the step's messages (`send(now)`), and spins for `wait` s.
void playClock(const ros::Publisher& clock_pub, double& now, double seconds, double step, double wait,
               const std::function<void(double)>& send) {
  for (double t = 0.0; t < seconds - 1e-9; t += step) {
    now += step;
    publishClock(clock_pub, now);
    spinUntil([] { return false; }, 0.01);
    send(now);
    spinUntil([] { return false; }, wait);
  }
}

go_feap::ExplorationStatus status(std::uint8_t state, const char* name, double elapsed) {
  go_feap::ExplorationStatus s;
  s.state = state;
  s.state_name = name;
  s.elapsed = elapsed;
  s.coverage = -1.0;
  return s;
}

TEST(MetricsRecorder, SummaryHoldsThePlayedRunAndOddStatusesNeitherEndNorCountInIt) {
  ros::NodeHandle nh, pnh("~");
  std::string output_dir;
  ASSERT_TRUE(pnh.getParam("output_dir", output_dir));
  std::filesystem::remove_all(output_dir);
  std::vector<std::string> warnings;
  ros::Subscriber log_sub = nh.subscribe<rosgraph_msgs::Log>("/rosout", 100, [&](const rosgraph_msgs::Log::ConstPtr& m) {
    if (m->level == rosgraph_msgs::Log::WARN) warnings.push_back(m->msg);
  });
  auto warned = [&](const std::string& what) {
    return std::any_of(warnings.begin(), warnings.end(), [&](const std::string& w) { return w.find(what) != std::string::npos; });
  };
  auto scene = go_feap::test::sceneFromParams();
  ASSERT_TRUE(scene) << scene.message();

  // A wall met head-on along +x at 1.5 m height, with 1.5 m of clear way before it: `entry` is where the
  // line enters the wall (1 cm steps).
  std::optional<Vec3> entry;
  for (double y = scene->box.min.y() + 0.55; y < scene->box.max.y() - 0.5 && !entry; y += 0.1)
    for (double x = scene->box.min.x() + 2.0; x < scene->box.max.x() - 0.5 && !entry; x += 0.01) {
      const Vec3 e(x, y, 1.5);
      if (!scene->isOccupied(e) || scene->isOccupied(Vec3(e - Vec3(0.01, 0.0, 0.0)))) continue;
      bool clear = true;
      for (double back = 0.2; back <= 1.5 + 1e-9 && clear; back += 0.1)
        clear = go_feap::test::latticeClearance(*scene, e - back * Vec3::UnitX(), 0.15) >= 0.15;
      if (clear) entry = e;
    }
  ASSERT_TRUE(entry) << "no wall found in the scene";

  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  auto status_pub = nh.advertise<go_feap::ExplorationStatus>("status", 10);
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("odom", 50);
  auto compute_pub = nh.advertise<go_feap::ComputeTime>("compute_time", 50);
  int paths = 0;
  auto path_sub =
      nh.subscribe<nav_msgs::Path>("flown_path", 10, [&](const nav_msgs::Path::ConstPtr&) { ++paths; });
  // The recorder's status text sits 1 m above the last odometry it took.
  std::optional<Vec3> text_at;
  auto text_sub = nh.subscribe<visualization_msgs::Marker>("status_text", 10, [&](const visualization_msgs::Marker::ConstPtr& m) {
    text_at = Vec3(m->pose.position.x, m->pose.position.y, m->pose.position.z - 1.0);
  });
  ASSERT_TRUE(spinUntil(
      [&] {
        return status_pub.getNumSubscribers() > 0 && odom_pub.getNumSubscribers() > 0 &&
               compute_pub.getNumSubscribers() > 0 && clock_pub.getNumSubscribers() > 0 &&
               path_sub.getNumPublishers() > 0 && text_sub.getNumPublishers() > 0;
      },
      60.0))
      << "the metrics recorder is not connected";

  double now = 1.0;
  auto tick = [&](double dt) {  // the simulated clock moves on; the recorder gets time to act on it
    now += dt;
    publishClock(clock_pub, now);
    spinUntil([] { return false; }, 0.02);
  };
  // Each topic has its own queue in the recorder (odometry 20 deep), handled by the manager's threads in
  // any order: what must come before what is kept apart by a pause.
  auto settle = [] { spinUntil([] { return false; }, 0.5); };
  auto send = [&](const go_feap::ExplorationStatus& s) {
    go_feap::ExplorationStatus m = s;
    m.header.stamp = ros::Time(now);
    status_pub.publish(m);
    tick(0.05);
  };
  auto fly = [&](const Vec3& p) {
    odom_pub.publish(odometryAt(p, now));
    tick(0.05);
  };
  auto compute = [&](const char* block, double ms) {
    go_feap::ComputeTime m;
    m.header.stamp = ros::Time(now);
    m.block = block;
    m.ms = ms;
    compute_pub.publish(m);
    tick(0.01);
  };
  for (int i = 0; i < 20; ++i) tick(0.05);

  // Before the trigger: flying and computing count for nothing.
  send(status(go_feap::ExplorationStatus::WAIT_TRIGGER, "WAIT_TRIGGER", 0.0));
  const Vec3 start = *entry - Vec3(1.5, 0.0, 0.0);
  fly(start + Vec3(0.0, 0.0, -0.5));
  compute("frontier", 1000.0);
  fly(start);

  // Malformed statuses are refused: none starts the run.
  const double nan = std::numeric_limits<double>::quiet_NaN();
  send(status(go_feap::ExplorationStatus::EXPLORE, "EXPLORE", nan));
  send(status(7, "SEVEN", 1.0));
  fly(start + Vec3(0.0, 0.5, 0.0));
  fly(start);
  // The odometry so far taken (one queue, in order: the last message is the last taken), and the
  // statuses too (a pause), before the run starts.
  text_at.reset();
  ASSERT_TRUE(spinUntil([&] {
    tick(0.05);
    return text_at && (*text_at - start).norm() < 1e-9;
  }, 20.0)) << "the recorder took no odometry before the run";
  settle();
  // The run starts with a status whose elapsed time lies far beyond the clock (a status from a tool or
  // from another run): this ended the whole nodelet manager. Its first flown_path says it has started.
  send(status(go_feap::ExplorationStatus::EXPLORE, "EXPLORE", 500.0));
  ASSERT_TRUE(spinUntil([&] {
    tick(0.05);
    return paths > 0;
  }, 20.0)) << "no flown_path after the run started";
  settle();
  // Started 500 s into the exploration: the recorder says its figures count from here.
  EXPECT_TRUE(spinUntil([&] { return warned("/metrics_recorder: joined the exploration 500 s after its trigger"); }, 10.0));

  // The flight: to the wall, 5 cm into it, and back; 5 cm steps.
  std::vector<Vec3> path{start};
  const Vec3 inside = *entry + Vec3(0.05, 0.0, 0.0);
  for (double s = 0.05; s <= (inside - start).norm() + 1e-9; s += 0.05)
    path.push_back(start + s * Vec3::UnitX());
  for (double s = 0.05; s <= (inside - start).norm() + 1e-9; s += 0.05)
    path.push_back(inside - s * Vec3::UnitX());
  ASSERT_TRUE(scene->isOccupied(path[path.size() / 2])) << "the flight does not reach into the wall";
  double length = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) length += (path[i] - path[i - 1]).norm();
  for (const Vec3& p : path) fly(p);
  // Odometry in another frame (0.5 m aside) and odometry that is not finite are refused: neither adds to
  // the flight, nor does the way back from them.
  {
    nav_msgs::Odometry foreign = odometryAt(path.back() + Vec3(0.0, 0.5, 0.0), now);
    foreign.header.frame_id = "odom";
    odom_pub.publish(foreign);
    tick(0.05);
    odom_pub.publish(odometryAt(Vec3(nan, 0.0, 1.0), now));
    tick(0.05);
    fly(path.back());
  }
  // A relocalisation: the odometry jumps 1.2 m (more than metrics/max_odom_step, 1 m) and goes on from
  // there; the jump is not flight, the 5 cm after it are.
  settle();
  fly(start + Vec3(1.2, 0.0, 0.0));
  fly(start + Vec3(1.15, 0.0, 0.0));
  length += 0.05;
  for (double ms : {2.0, 4.0, 9.0}) compute("frontier", ms);
  compute("global", 5.0);
  // Times below 0 or not finite, and blocks the chain does not have, are refused.
  compute("frontier", -100.0);
  compute("frontier", nan);
  compute("bogus", 7.0);
  compute("total", 7.0);
  for (int i = 0; i < 10; ++i) tick(0.1);
  settle();

  go_feap::ExplorationStatus finished = status(go_feap::ExplorationStatus::FINISHED, "FINISHED", 42.5);
  finished.finish_reason = "complete";
  finished.blacklisted_frontiers = 2;
  finished.layer = 2;
  finished.frontier_count = 17;
  send(finished);
  const std::string summary_path = output_dir + "/summary.json";
  // The recorder renames each file into place whole, summary.json last: once it is there, all three are.
  ASSERT_TRUE(spinUntil([&] { return std::filesystem::exists(summary_path); }, 20.0))
      << "no " << summary_path << ": the recorder did not finish the run (or is gone)";
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(summary_path));
  std::cout << summary.dump() << "\n";
  EXPECT_EQ(summary["scene"], "maze_small");
  EXPECT_EQ(summary["planner"], "metrics_test");
  EXPECT_EQ(summary["finish_reason"], "complete");
  EXPECT_EQ(summary["blacklisted_frontiers"], 2);
  EXPECT_DOUBLE_EQ(summary["exploration_time_s"].get<double>(), 42.5);
  EXPECT_NEAR(summary["flight_distance_m"].get<double>(), length, 1e-6);
  EXPECT_EQ(summary["collisions"], 1);
  EXPECT_DOUBLE_EQ(summary["min_obstacle_distance_m"].get<double>(), 0.0);
  EXPECT_NEAR(summary["compute_ms"]["frontier"]["mean"].get<double>(), 5.0, 1e-9);
  EXPECT_EQ(summary["compute_ms"]["frontier"]["count"], 3);
  EXPECT_NEAR(summary["compute_ms"]["global"]["mean"].get<double>(), 5.0, 1e-9);
  EXPECT_NEAR(summary["compute_ms"]["total"]["mean"].get<double>(), 10.0, 1e-9);
  EXPECT_FALSE(summary["compute_ms"].contains("bogus")) << summary.dump();
  EXPECT_TRUE(warned("/metrics_recorder: odometry refused: ")) << "no word of the odometry in frame 'odom'";
  EXPECT_TRUE(warned("/metrics_recorder: compute_time refused: block 'frontier'"));
  for (const char* f : {"metrics.csv", "coverage.png"})
    EXPECT_TRUE(std::filesystem::exists(output_dir + "/" + f)) << f;
  // metrics.csv's rows: the flight distance so far, never shrinking; the last row is the run as it finished
  // (its time, distance, band, frontier count and the vehicle's last position). No map here: no coverage.
  const auto rows = go_feap::test::readCsv(output_dir + "/metrics.csv");
  ASSERT_GE(rows.size(), 2u);
  for (std::size_t i = 1; i < rows.size(); ++i)
    EXPECT_GE(rows[i].at("distance"), rows[i - 1].at("distance")) << "row " << i;
  const auto& last = rows.back();
  EXPECT_NEAR(last.at("t"), 42.5, 1e-9);
  EXPECT_NEAR(last.at("distance"), length, 1e-3);
  EXPECT_EQ(last.at("layer"), 2.0);
  EXPECT_EQ(last.at("frontiers"), 17.0);
  EXPECT_EQ(last.at("coverage"), -1.0);
  EXPECT_EQ(last.at("explored_m3"), 0.0);
  const Vec3 flown_to = start + Vec3(1.15, 0.0, 0.0);
  EXPECT_LT((Vec3(last.at("x"), last.at("y"), last.at("z")) - flown_to).norm(), 2e-3)
      << "the last row's position is not the last odometry " << flown_to.transpose();

  // A recorder that first hears the exploration finished (loaded after the run) says so and writes nothing:
  // started by that status, the next one wrote a summary of a run it never saw.
  std::string late_dir;
  ASSERT_TRUE(pnh.getParam("late_output_dir", late_dir));
  std::filesystem::remove_all(late_dir);
  auto late_pub = nh.advertise<go_feap::ExplorationStatus>("late/status", 10);
  ASSERT_TRUE(spinUntil([&] { return late_pub.getNumSubscribers() > 0; }, 20.0)) << "the late recorder is not connected";
  for (int i = 0; i < 10; ++i) {
    finished.header.stamp = ros::Time(now);
    late_pub.publish(finished);
    tick(0.1);
  }
  EXPECT_TRUE(spinUntil([&] { return warned("/late_metrics_recorder: the exploration had finished (complete)"); }, 10.0));
  settle();
  EXPECT_FALSE(std::filesystem::exists(late_dir + "/summary.json")) << "a summary of a run the recorder never saw";
  // Heard waiting for the trigger and then stopped before it (WAIT_TRIGGER -> FINISHED(aborted)), the run it was
  // there for is one of nothing: its summary says so.
  go_feap::ExplorationStatus aborted = status(go_feap::ExplorationStatus::FINISHED, "FINISHED", 0.0);
  aborted.finish_reason = "aborted";
  for (const go_feap::ExplorationStatus& s : {status(go_feap::ExplorationStatus::WAIT_TRIGGER, "WAIT_TRIGGER", 0.0), aborted}) {
    for (int i = 0; i < 3; ++i) {
      go_feap::ExplorationStatus m = s;
      m.header.stamp = ros::Time(now);
      late_pub.publish(m);
      tick(0.1);
    }
    settle();
  }
  ASSERT_TRUE(spinUntil([&] { return std::filesystem::exists(late_dir + "/summary.json"); }, 20.0))
      << "no summary of the run stopped before its trigger";
  const nlohmann::json stopped = nlohmann::json::parse(std::ifstream(late_dir + "/summary.json"));
  EXPECT_EQ(stopped["finish_reason"], "aborted");
  EXPECT_DOUBLE_EQ(stopped["exploration_time_s"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(stopped["flight_distance_m"].get<double>(), 0.0);
}

// A layer manager (probe/... in metrics.test) has explored since the first test's odometry came. The
// clock then goes back (a bag played again): its statuses keep coming, and the exploration's clock pauses
// and goes on, so the elapsed time goes on from where it was. It used to be the clock minus the start,
// below 0, so that MetricsRecorder refused every status after it, the one saying FINISHED too; and then
// 0 for as long as the clock took to come back to the start, the stuck and time-limit timers with it.
TEST(LayerManager, ElapsedTimeGoesOnFromWhereItWasWhenTheClockGoesBack) {
  ros::NodeHandle nh;
  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  std::vector<go_feap::ExplorationStatus> statuses;
  auto status_sub = nh.subscribe<go_feap::ExplorationStatus>(
      "probe/status", 50, [&](const go_feap::ExplorationStatus::ConstPtr& m) { statuses.push_back(*m); });
  ASSERT_TRUE(spinUntil([&] { return status_sub.getNumPublishers() > 0 && clock_pub.getNumSubscribers() > 0; }, 30.0))
      << "the probe layer manager is not connected";
  double now = ros::Time::now().toSec();
  auto run_clock = [&](double seconds) {
    for (double t = 0.0; t < seconds; t += 0.05) {
      now += 0.05;
      publishClock(clock_pub, now);
      spinUntil([] { return false; }, 0.02);
    }
  };
  run_clock(2.0);
  ASSERT_FALSE(statuses.empty()) << "no status from the probe layer manager";
  const go_feap::ExplorationStatus last = statuses.back();
  ASSERT_NE(last.state, go_feap::ExplorationStatus::WAIT_TRIGGER) << "the probe layer manager did not start";
  ASSERT_GT(last.elapsed, 1.0);
  ASSERT_GT(now - last.elapsed, 0.6) << "the run started too early for the clock to go back before it";

  now = 0.5;  // before the run started
  statuses.clear();
  run_clock(2.0);
  ASSERT_GE(statuses.size(), 3u) << "no status after the clock went back";
  for (const go_feap::ExplorationStatus& s : statuses)
    EXPECT_GE(s.elapsed, last.elapsed - 1e-6) << "at " << s.header.stamp.toSec() << " s";
  EXPECT_GT(statuses.back().elapsed, last.elapsed + 1.0) << "the exploration's clock did not go on";
}

// The layer manager's own flight distance (status.distance) counts steps, not a jump of more than
// metrics/max_odom_step (a relocalisation): 0.1 m steps, a 2 m jump, more 0.1 m steps add only the steps
// (1.5 m). Its odometry queue is 2 deep: each position is sent three times, so that none is lost whole (a
// step lost next to the jump would merge into it).
TEST(LayerManager, FlightDistanceLeavesOutAnOdometryJump) {
  ros::NodeHandle nh;
  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("odom", 50);
  std::optional<go_feap::ExplorationStatus> last;
  auto status_sub = nh.subscribe<go_feap::ExplorationStatus>(
      "probe/status", 50, [&](const go_feap::ExplorationStatus::ConstPtr& m) { last = *m; });
  ASSERT_TRUE(spinUntil([&] {
    return status_sub.getNumPublishers() > 0 && clock_pub.getNumSubscribers() > 0 && odom_pub.getNumSubscribers() > 0;
  }, 30.0)) << "the probe layer manager is not connected";
  double max_step = 0.0;
  ASSERT_TRUE(ros::param::get("probe_layer_manager/metrics/max_odom_step", max_step));
  ASSERT_LT(max_step, 2.0);
  ASSERT_GT(max_step, 0.1);
  double now = ros::Time::now().toSec();
  auto fly = [&](const Vec3& p) {
    for (int copy = 0; copy < 3; ++copy) {
      now += 0.02;
      publishClock(clock_pub, now);
      odom_pub.publish(odometryAt(p, now));
      spinUntil([] { return false; }, 0.03);
    }
  };
  // The distance once the odometry stands at the start (and the statuses have caught up).
  const Vec3 start(0.0, 0.0, 1.0);
  for (int i = 0; i < 20; ++i) fly(start);
  ASSERT_TRUE(last);
  ASSERT_EQ(last->state, go_feap::ExplorationStatus::EXPLORE) << "the probe layer manager is not exploring";
  const double before = last->distance;
  Vec3 p = start;
  for (int i = 0; i < 10; ++i) fly(p += Vec3(0.1, 0.0, 0.0));
  fly(p += Vec3(0.0, 2.0, 0.0));  // the jump
  for (int i = 0; i < 5; ++i) fly(p += Vec3(0.0, 0.0, 0.1));
  for (int i = 0; i < 20; ++i) fly(p);  // standing: the statuses catch up
  EXPECT_NEAR(last->distance - before, 1.5, 1e-6) << "the jump was counted as flight, or steps were lost";
}

// Before any frontier list has come, the probe layer manager (started, its vehicle still, so never
// looked round) asks for no look round: an empty list is not yet known to be empty (a finder that never
// started ended the run "complete" after the look round). The first list, empty, lets its band settle
// (settle_time 1 s) and the look round is asked for. Before BlacklistFollowsTheFrontiersListed, the first
// test to send it frontiers.
TEST(LayerManager, NoBandSettlesBeforeTheFirstFrontierList) {
  ros::NodeHandle nh;
  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  auto frontiers_pub = nh.advertise<go_feap::FrontierArray>("probe/frontiers", 10);
  int layers = 0, looks = 0;
  auto layer_sub = nh.subscribe<go_feap::LayerBounds>("probe/layer", 50, [&](const go_feap::LayerBounds::ConstPtr& m) {
    ++layers;
    looks += m->look_around;
  });
  int exploring = 0;
  auto status_sub = nh.subscribe<go_feap::ExplorationStatus>("probe/status", 50, [&](const go_feap::ExplorationStatus::ConstPtr& m) {
    exploring += m->state == go_feap::ExplorationStatus::EXPLORE;
  });
  ASSERT_TRUE(spinUntil([&] {
    return frontiers_pub.getNumSubscribers() > 0 && layer_sub.getNumPublishers() > 0 &&
           status_sub.getNumPublishers() > 0 && clock_pub.getNumSubscribers() > 0;
  }, 30.0)) << "the probe layer manager is not connected";
  double now = ros::Time::now().toSec();
  auto tick_until = [&](double seconds, const std::function<bool()>& done) {
    for (double t = 0.0; t < seconds && !done(); t += 0.05) {
      now += 0.05;
      publishClock(clock_pub, now);
      spinUntil(done, 0.02);
    }
    return done();
  };
  const int before = exploring;
  tick_until(3.0, [] { return false; });  // three settle times
  ASSERT_GT(exploring, before + 10) << "the probe layer manager is not exploring";
  EXPECT_EQ(looks, 0) << "a look round asked for before any frontier list came";
  go_feap::FrontierArray none;
  none.header.stamp = ros::Time(now);
  none.header.frame_id = "world";
  frontiers_pub.publish(none);
  EXPECT_TRUE(tick_until(5.0, [&] { return looks > 0; })) << "no look round asked for once an empty list came";
}

// One depth frame for the probe mapper (probe/mapper/... in metrics.test; 3 m everywhere, from 1 m up
// looking along +x, stamped `stamp`), after which it shares its map with the probe planners. camera_info
// and the frame travel on separate connections, so the frame may come first and be skipped ("no
// camera_info received yet"): it is sent again, newly stamped, until the mapper integrates it. False when
// it integrated none of 10.
bool feedProbeMapper(ros::NodeHandle& nh, double stamp) {
  auto info_pub = nh.advertise<sensor_msgs::CameraInfo>("probe/mapper/camera_info", 1, /*latch=*/true);
  auto depth_pub = nh.advertise<sensor_msgs::Image>("probe/mapper/depth", 2);
  auto pose_pub = nh.advertise<geometry_msgs::PoseStamped>("probe/mapper/camera_pose", 2);
  int updates = 0;
  auto update_sub = nh.subscribe<go_feap::MapUpdate>("probe/mapper/map_update", 10,
                                                     [&](const go_feap::MapUpdate::ConstPtr&) { ++updates; });
  if (!spinUntil([&] {
        return info_pub.getNumSubscribers() > 0 && depth_pub.getNumSubscribers() > 0 &&
               pose_pub.getNumSubscribers() > 0 && update_sub.getNumPublishers() > 0;
      }, 30.0))
    return false;
  sensor_msgs::CameraInfo info;
  info.width = 64, info.height = 48;
  info.K = {40.0, 0.0, 32.0, 0.0, 40.0, 24.0, 0.0, 0.0, 1.0};
  info_pub.publish(info);
  sensor_msgs::Image depth;
  depth.width = 64, depth.height = 48, depth.encoding = "32FC1", depth.step = 64 * 4;
  depth.data.resize(depth.step * depth.height);
  const float metres = 3.0f;
  for (std::size_t i = 0; i < depth.data.size(); i += 4) std::memcpy(&depth.data[i], &metres, 4);
  geometry_msgs::PoseStamped pose;
  pose.header.frame_id = "world";
  pose.pose.position.z = 1.0;
  pose.pose.orientation.w = 0.5, pose.pose.orientation.x = -0.5, pose.pose.orientation.y = 0.5,
  pose.pose.orientation.z = -0.5;  // optical frame: z along +x, x along -y, y along -z
  for (int attempt = 0; attempt < 10 && updates == 0; ++attempt) {
    depth.header.stamp = pose.header.stamp = ros::Time(stamp + 0.01 * attempt);
    pose_pub.publish(pose);
    depth_pub.publish(depth);
    spinUntil([&] { return updates > 0; }, 2.0);
  }
  return updates > 0;
}

// A frontier of known free cells a metre ahead of the probe mapper's camera, id 1: x 2.05 m, y from
// -y_half to +y_half, z from 1.05 - z_half to 1.05 + z_half, 0.1 m apart.
go_feap::FrontierArray frontierAhead(double y_half, double z_half) {
  go_feap::FrontierArray frontiers;
  go_feap::Frontier f;
  f.id = 1;
  for (double y = -y_half; y <= y_half + 1e-9; y += 0.1)
    for (double z = -z_half; z <= z_half + 1e-9; z += 0.1) {
      geometry_msgs::Point c;
      c.x = 2.05, c.y = y + 0.05, c.z = 1.05 + z;
      f.cells.push_back(c);
    }
  f.average.x = 2.05, f.average.y = 0.05, f.average.z = 1.05;
  f.aabb_min = f.cells.front(), f.aabb_max = f.cells.back();
  f.active = true;
  frontiers.frontiers.push_back(f);
  return frontiers;
}

// The vehicle at rest where the probe mapper's camera was (1 m up, facing +x).
nav_msgs::Odometry odometryAtTheCamera() {
  nav_msgs::Odometry odom;
  odom.header.frame_id = "world";
  odom.pose.pose.position.z = 1.0;
  odom.pose.pose.orientation.w = 1.0;
  return odom;
}

// The probe layer manager's blacklist (max_retries 3) follows the frontiers listed. Frontier 5 fails three
// times and is blacklisted. Then, with the clock held, frontier 6 replaces it in the list and fails three
// times: at the next step 5 leaves the blacklist as 6 joins it. The list changes and keeps its size, and
// it is sent again (it used to be sent only when its size changed, and it kept ids that were gone).
// The wait layer manager hears its first odometry on the ground (band 0 of two 3 m bands), then the
// vehicle is taken up to 4.5 m (band 1) before the trigger, a 2D Nav Goal (layers/goal_trigger, as
// shipped): exploration starts in band 1, where the vehicle is. The band order used to be fixed at the
// first odometry, on the ground.
TEST(LayerManager, TheStartBandIsWhereTheVehicleIsAtTheTrigger) {
  ros::NodeHandle nh;
  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("wait/odom", 20);
  auto goal_pub = nh.advertise<geometry_msgs::PoseStamped>("wait/goal", 1);
  std::vector<go_feap::LayerBounds> layers;
  go_feap::ExplorationStatus::ConstPtr state;
  auto layer_sub = nh.subscribe<go_feap::LayerBounds>("wait/layer", 20, [&](const go_feap::LayerBounds::ConstPtr& m) { layers.push_back(*m); });
  auto status_sub = nh.subscribe<go_feap::ExplorationStatus>("wait/status", 20, [&](const go_feap::ExplorationStatus::ConstPtr& m) { state = m; });
  ASSERT_TRUE(spinUntil([&] { return odom_pub.getNumSubscribers() > 0 && goal_pub.getNumSubscribers() > 0 &&
                                     layer_sub.getNumPublishers() > 0; }, 30.0))
      << "the wait layer manager is not connected";
  double now = ros::Time::now().toSec();
  double z = 0.2;
  const auto send = [&](double t) { odom_pub.publish(odometryAt(Vec3(0.0, 0.0, z), t)); };
  playClock(clock_pub, now, 1.0, 0.05, 0.01, send);
  ASSERT_TRUE(spinUntil([&] { return state && !layers.empty(); }, 10.0)) << "no status or layer";
  EXPECT_EQ(state->state, go_feap::ExplorationStatus::WAIT_TRIGGER);
  EXPECT_EQ(layers.back().count, 2u);
  EXPECT_EQ(layers.back().index, 0u) << "on the ground: band 0";
  for (z = 0.2; z < 4.5; z += 0.05) playClock(clock_pub, now, 0.05, 0.05, 0.005, send);  // taken up by hand
  playClock(clock_pub, now, 0.5, 0.05, 0.01, send);
  geometry_msgs::PoseStamped goal;
  goal.header.frame_id = "world";
  goal.pose.orientation.w = 1.0;
  goal_pub.publish(goal);
  layers.clear();
  playClock(clock_pub, now, 1.0, 0.05, 0.01, send);
  ASSERT_TRUE(spinUntil([&] { return state->state == go_feap::ExplorationStatus::EXPLORE && !layers.empty(); }, 10.0))
      << "not exploring after the trigger: " << state->state_name;
  EXPECT_EQ(layers.back().index, 1u) << "the start band is the one of the first odometry, on the ground";
  // Time and distance count from the trigger (summary.json's exploration_time_s and flight_distance_m): not
  // the 5.8 s of clock and the 4.3 m the vehicle was carried before it, but the 1 s of hovering since.
  EXPECT_LT(state->elapsed, 1.5);
  EXPECT_LT(state->distance, 0.05);

  // A band's frontiers are those whose average lies in it: with the only frontier in band 0 (z 1.05 m),
  // band 1 is done once the vehicle has looked round, and band 0 comes next. (Counted in every band, it
  // kept band 1 open for good.)
  auto frontiers_pub = nh.advertise<go_feap::FrontierArray>("wait/frontiers", 5);
  ASSERT_TRUE(spinUntil([&] { return frontiers_pub.getNumSubscribers() > 0; }, 30.0));
  go_feap::FrontierArray below = frontierAhead(0.3, 0.3);
  below.header.frame_id = "world";
  double yaw = 0.0;
  const auto turn = [&](double t) {
    nav_msgs::Odometry odom = odometryAt(Vec3(0.0, 0.0, z), t);
    odom.pose.pose.orientation.z = std::sin(0.5 * yaw);
    odom.pose.pose.orientation.w = std::cos(0.5 * yaw);
    odom_pub.publish(odom);
    below.header.stamp = ros::Time(t);
    frontiers_pub.publish(below);
    yaw += 0.1;  // a turn in 3.2 s of clock
  };
  for (int k = 0; k < 200 && layers.back().index != 0u; ++k) playClock(clock_pub, now, 0.05, 0.05, 0.01, turn);
  EXPECT_EQ(layers.back().index, 0u) << "band 1 was not done with its only frontier in band 0, after a turn of "
                                     << yaw << " rad";
}

// The stuck layer manager (stuck/... in metrics.test, layers/stuck_timeout 2 s) hovers with a frontier in
// view and map updates that change no voxel: it ends FINISHED(stuck) 2 s after the trigger. A relocalisation
// jump of 2 m on the way (more than metrics/max_odom_step) is no progress either: counted as progress_travel
// flown, it put the end off by a second; and counting every map update as progress, it never came.
TEST(LayerManager, HoveringWithoutMapProgressIsStuckAndAJumpIsNoProgress) {
  ros::NodeHandle nh;
  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("stuck/odom", 20);
  auto update_pub = nh.advertise<go_feap::MapUpdate>("stuck/map_update", 20);
  auto frontiers_pub = nh.advertise<go_feap::FrontierArray>("stuck/frontiers", 5);
  std::optional<go_feap::ExplorationStatus> last;
  auto status_sub = nh.subscribe<go_feap::ExplorationStatus>(
      "stuck/status", 50, [&](const go_feap::ExplorationStatus::ConstPtr& m) { last = *m; });
  ASSERT_TRUE(spinUntil([&] {
    return odom_pub.getNumSubscribers() > 0 && update_pub.getNumSubscribers() > 0 &&
           frontiers_pub.getNumSubscribers() > 0 && status_sub.getNumPublishers() > 0;
  }, 30.0)) << "the stuck layer manager is not connected";
  double stuck_timeout = 0.0, travel = 0.0;
  ASSERT_TRUE(ros::param::get("stuck_layer_manager/layers/stuck_timeout", stuck_timeout));
  ASSERT_TRUE(ros::param::get("stuck_layer_manager/layers/progress_travel", travel));
  ASSERT_DOUBLE_EQ(stuck_timeout, 2.0);
  ASSERT_LT(travel, 2.0);
  double now = ros::Time::now().toSec();
  Vec3 at(0.0, 0.0, 1.0);
  std::uint64_t sequence = 0;
  std::optional<double> jumped;  // the elapsed time of the jump
  const auto send = [&](double t) {
    if (!jumped && last && last->state == go_feap::ExplorationStatus::EXPLORE && last->elapsed >= 1.0) {
      at += Vec3(0.0, 2.0, 0.0);
      jumped = last->elapsed;
    }
    odom_pub.publish(odometryAt(at, t));
    go_feap::MapUpdate update;
    update.header.stamp = ros::Time(t);
    update.header.frame_id = "world";
    update.sequence = ++sequence;
    update.changed_voxels = 0;
    update_pub.publish(update);
    go_feap::FrontierArray frontiers = frontierAhead(0.3, 0.3);
    frontiers.header.stamp = ros::Time(t);
    frontiers.header.frame_id = "world";
    frontiers_pub.publish(frontiers);
  };
  for (int k = 0; k < 200 && !(last && last->state == go_feap::ExplorationStatus::FINISHED); ++k)
    playClock(clock_pub, now, 0.05, 0.05, 0.01, send);
  ASSERT_TRUE(last);
  ASSERT_EQ(last->state, go_feap::ExplorationStatus::FINISHED) << "not stuck after 10 s of clock: " << last->state_name
                                                              << " at " << last->elapsed << " s";
  EXPECT_EQ(last->finish_reason, "stuck");
  ASSERT_TRUE(jumped) << "ended before the jump";
  EXPECT_LT(*jumped, stuck_timeout - 0.5);
  EXPECT_GE(last->elapsed, stuck_timeout);
  // Taken for progress, the jump (stepped at or after `jumped`) would have put the end at jumped + stuck_timeout
  // or later.
  EXPECT_LT(last->elapsed, *jumped + stuck_timeout) << "the jump at " << *jumped << " s was taken for progress";
}

TEST(LayerManager, BlacklistFollowsTheFrontiersListed) {
  ros::NodeHandle nh;
  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  auto frontiers_pub = nh.advertise<go_feap::FrontierArray>("probe/frontiers", 10);
  auto failed_pub = nh.advertise<std_msgs::UInt32>("probe/frontier_failed", 10);
  std::vector<std::vector<std::uint32_t>> lists;
  auto blacklist_sub = nh.subscribe<std_msgs::UInt32MultiArray>(
      "probe/blacklist", 10, [&](const std_msgs::UInt32MultiArray::ConstPtr& m) { lists.push_back(m->data); });
  int statuses = 0;
  go_feap::ExplorationStatus::ConstPtr last_status;
  auto status_sub = nh.subscribe<go_feap::ExplorationStatus>("probe/status", 50,
                                                             [&](const go_feap::ExplorationStatus::ConstPtr& m) {
                                                               ++statuses;
                                                               last_status = m;
                                                             });
  ASSERT_TRUE(spinUntil([&] {
    return frontiers_pub.getNumSubscribers() > 0 && failed_pub.getNumSubscribers() > 0 &&
           blacklist_sub.getNumPublishers() > 0 && status_sub.getNumPublishers() > 0 && clock_pub.getNumSubscribers() > 0;
  }, 30.0)) << "the probe layer manager is not connected";
  double now = ros::Time::now().toSec();
  auto tick_until = [&](const std::function<bool()>& done) {
    for (int i = 0; i < 100 && !done(); ++i) {
      now += 0.05;
      publishClock(clock_pub, now);
      spinUntil(done, 0.02);
    }
    return done();
  };
  ASSERT_TRUE(tick_until([&] { return statuses > 0; })) << "the probe layer manager sends no status";
  auto list_and_fail = [&](std::uint32_t id) {
    go_feap::FrontierArray frontiers = frontierAhead(0.3, 0.3);
    frontiers.header.stamp = ros::Time(now);
    frontiers.header.frame_id = "world";
    frontiers.frontiers[0].id = id;
    frontiers_pub.publish(frontiers);
    std_msgs::UInt32 failed;
    failed.data = id;
    for (int k = 0; k < 3; ++k) failed_pub.publish(failed);
  };
  using Ids = std::vector<std::uint32_t>;
  list_and_fail(5);
  ASSERT_TRUE(tick_until([&] { return !lists.empty() && lists.back() == Ids{5}; }))
      << "frontier 5 failed three times and is not blacklisted";
  // Both reach the layer manager before its next step, which only the clock starts.
  list_and_fail(6);
  spinUntil([] { return false; }, 0.5);
  EXPECT_TRUE(tick_until([&] { return lists.back() == Ids{6}; }))
      << "the blacklist is not [6] once 6 replaced 5 and failed three times (last sent: " << lists.back().size()
      << " ids, the first " << (lists.back().empty() ? 0u : lists.back().front()) << ")";
  for (const Ids& l : lists)
    for (std::uint32_t id : l) EXPECT_TRUE(id == 5 || id == 6) << "blacklisted " << id;
  // The status counts the frontiers listed (one, 6) and those of them blacklisted (6): summary.json's
  // blacklisted_frontiers, how a run "complete" with frontiers left unexplored shows.
  const int seen = statuses;
  EXPECT_TRUE(tick_until([&] { return statuses >= seen + 2; }));
  ASSERT_TRUE(last_status);
  EXPECT_EQ(last_status->frontier_count, 1u);
  EXPECT_EQ(last_status->blacklisted_frontiers, 1u);
  // Latched: a subscriber that comes later (a global planner loaded again, rostopic echo) hears the blacklist
  // as it stands, with the clock held.
  std::vector<Ids> late_lists;
  auto late_sub = nh.subscribe<std_msgs::UInt32MultiArray>(
      "probe/blacklist", 10, [&](const std_msgs::UInt32MultiArray::ConstPtr& m) { late_lists.push_back(m->data); });
  EXPECT_TRUE(spinUntil([&] { return !late_lists.empty(); }, 5.0)) << "no blacklist for a later subscriber";
  if (!late_lists.empty()) {
    EXPECT_EQ(late_lists.back(), Ids{6});
  }
}

// A frontier finder (probe/ff/... in metrics.test) on the probe mapper's updates: the frontiers' ages go on
// growing when the clock goes back 80 s (a bag played again), paused for as long; they read 0 for 80 s.
TEST(FrontierFinder, AgesGoOnFromWhereTheyWereWhenTheClockGoesBack) {
  ros::NodeHandle nh;
  std::vector<go_feap::FrontierArray> heard;
  auto sub = nh.subscribe<go_feap::FrontierArray>(
      "probe/ff/frontiers", 50, [&](const go_feap::FrontierArray::ConstPtr& m) { heard.push_back(*m); });
  ASSERT_TRUE(spinUntil([&] { return sub.getNumPublishers() > 0; }, 30.0)) << "the probe frontier finder is not up";
  // The durations of the frontiers sent for the frame stamped `stamp` (within the 10 ms of its attempts).
  auto durationsAt = [&](double stamp) {
    std::map<std::uint32_t, double> out;
    spinUntil([&] {
      return std::any_of(heard.begin(), heard.end(),
                         [&](const go_feap::FrontierArray& a) { return std::abs(a.header.stamp.toSec() - stamp) < 0.1; });
    }, 5.0);
    for (const go_feap::FrontierArray& a : heard)
      if (std::abs(a.header.stamp.toSec() - stamp) < 0.1)
        for (const go_feap::Frontier& f : a.frontiers) out[f.id] = f.duration;
    return out;
  };
  ASSERT_TRUE(feedProbeMapper(nh, 300.0));
  ASSERT_TRUE(feedProbeMapper(nh, 305.0));
  const auto before = durationsAt(305.0);
  ASSERT_FALSE(before.empty()) << "no frontiers from the probe mapper's frame";
  ASSERT_TRUE(feedProbeMapper(nh, 225.0));  // back 80 s
  ASSERT_TRUE(feedProbeMapper(nh, 227.0));
  const auto after = durationsAt(227.0);
  std::size_t kept = 0;
  for (const auto& [id, duration] : before) {
    const auto it = after.find(id);
    if (it == after.end()) continue;
    ++kept;
    EXPECT_NEAR(it->second, duration + 2.0, 0.1) << "frontier " << id;
  }
  EXPECT_GT(kept, 0u) << "no frontier of before the jump is left to compare";
}

// A latched EXPLORE status on `topic`: the probe planners act only while the exploration is under way.
ros::Publisher exploring(ros::NodeHandle& nh, const std::string& topic) {
  ros::Publisher pub = nh.advertise<go_feap::ExplorationStatus>(topic, 1, /*latch=*/true);
  go_feap::ExplorationStatus status;
  status.state = go_feap::ExplorationStatus::EXPLORE;
  status.state_name = "EXPLORE";
  pub.publish(status);
  return pub;
}

// A global planner (probe/gp/... in metrics.test) plans at global/rate (10 Hz) from the test's frontier
// messages. The clock then goes back 80 s (a bag played again): it plans again at once, where it used
// to wait until the clock had caught up with its last plan.
TEST(GlobalPlanner, PlansAgainAtOnceWhenTheClockGoesBack) {
  ros::NodeHandle nh;
  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("probe/gp/odom", 10);
  auto frontier_pub = nh.advertise<go_feap::FrontierArray>("probe/gp/frontiers", 10);
  auto status_pub = exploring(nh, "probe/gp/status");
  std::vector<go_feap::GlobalTour> tours;
  auto tour_sub = nh.subscribe<go_feap::GlobalTour>(
      "probe/gp/global_tour", 50, [&](const go_feap::GlobalTour::ConstPtr& m) { tours.push_back(*m); });
  ASSERT_TRUE(spinUntil([&] {
    return tour_sub.getNumPublishers() > 0 && clock_pub.getNumSubscribers() > 0 && odom_pub.getNumSubscribers() > 0 &&
           frontier_pub.getNumSubscribers() > 0 && status_pub.getNumSubscribers() > 0;
  }, 30.0)) << "the probe global planner is not connected";
  double now = 100.0;
  ASSERT_TRUE(feedProbeMapper(nh, now)) << "the probe mapper integrated none of 10 frames";
  go_feap::FrontierArray frontiers = frontierAhead(0.1, 0.0);
  nav_msgs::Odometry odom = odometryAtTheCamera();
  auto run = [&](double seconds) {  // clock, odometry and frontiers every 0.05 s
    playClock(clock_pub, now, seconds, 0.05, 0.02, [&](double t) {
      odom.header.stamp = frontiers.header.stamp = ros::Time(t);
      odom_pub.publish(odom);
      frontier_pub.publish(frontiers);
    });
  };
  run(2.0);
  ASSERT_GE(tours.size(), 3u) << "the probe global planner planned no tours";
  EXPECT_EQ(tours.back().frontier_ids, std::vector<std::uint32_t>{1});
  // At global/rate, not at each frontier message (20 Hz here).
  double rate = 0.0;
  ASSERT_TRUE(ros::param::get("/probe_global_planner/global/rate", rate));
  ASSERT_LT(rate, 20.0);
  EXPECT_LE(static_cast<double>(tours.size()), 2.0 * rate + 2.0) << "tours in 2 s of frontiers every 0.05 s";
  now = 20.0;
  tours.clear();
  run(2.0);
  int planned = 0;
  for (const go_feap::GlobalTour& t : tours) planned += !t.repeated && t.header.stamp.toSec() < 30.0;
  EXPECT_GE(planned, 5) << tours.size() << " tours in 2 s after the clock went back 80 s";

  // The blacklist (from the layer manager) keeps a frontier out of the tours until it leaves the list.
  // Frontier 2 is frontier 1 moved 0.4 m aside.
  go_feap::Frontier second = frontiers.frontiers.front();
  second.id = 2;
  for (geometry_msgs::Point* c : {&second.average, &second.aabb_min, &second.aabb_max}) c->y += 0.4;
  for (geometry_msgs::Point& c : second.cells) c.y += 0.4;
  frontiers.frontiers.push_back(second);
  ros::Publisher blacklist_pub = nh.advertise<std_msgs::UInt32MultiArray>("probe/gp/blacklist", 1, /*latch=*/true);
  ASSERT_TRUE(spinUntil([&] { return blacklist_pub.getNumSubscribers() > 0; }, 10.0));
  auto tourIds = [&](const std::vector<std::uint32_t>& listed) {  // the ids of the tours planned after it
    std_msgs::UInt32MultiArray blacklist;
    blacklist.data = listed;
    blacklist_pub.publish(blacklist);
    spinUntil([] { return false; }, 0.3);
    const double sent_at = now;  // tours planned from frontiers stamped after it: the list had come
    tours.clear();
    run(1.0);
    std::set<std::uint32_t> ids;
    std::size_t counted = 0;
    for (const go_feap::GlobalTour& t : tours) {
      if (t.header.stamp.toSec() <= sent_at) continue;
      ids.insert(t.frontier_ids.begin(), t.frontier_ids.end());
      ++counted;
    }
    EXPECT_GE(counted, 3u) << "no tours with the blacklist " << ::testing::PrintToString(listed);
    return ids;
  };
  EXPECT_EQ(tourIds({1}), std::set<std::uint32_t>{2}) << "a blacklisted frontier in a tour";
  EXPECT_EQ(tourIds({}), (std::set<std::uint32_t>{1, 2})) << "a frontier off the blacklist left out";
}

// A local planner in the fuel mode (probe/lp/... in metrics.test) takes a viewpoint of the test's frontier
// as its target and then, while it holds it, plans again only every replan_period (1.5 s, past
// commit_time), not at each tour. The clock then goes back 80 s (a bag played again): it plans again
// within commit_time and replan_period, where it used to wait until the clock had caught up with its
// last plan and its commitment. Then (below) a target reached in vain, nothing from a stale odometry, and
// nothing from frontiers with a cell far outside the map.
TEST(LocalPlanner, PlansAgainWhenTheClockGoesBackAndNothingFromAStaleOdometry) {
  ros::NodeHandle nh;
  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("probe/lp/odom", 10);
  auto frontier_pub = nh.advertise<go_feap::FrontierArray>("probe/lp/frontiers", 10);
  auto tour_pub = nh.advertise<go_feap::GlobalTour>("probe/lp/global_tour", 10);
  auto status_pub = exploring(nh, "probe/lp/status");
  std::size_t plans = 0;  // compute_time messages of the local block: one per plan
  auto compute_sub = nh.subscribe<go_feap::ComputeTime>("probe/lp/compute_time", 50, [&](const go_feap::ComputeTime::ConstPtr& m) {
    if (m->block == "local") ++plans;
  });
  std::vector<go_feap::ViewpointPath> targets;
  auto target_sub = nh.subscribe<go_feap::ViewpointPath>(
      "probe/lp/local_target", 50, [&](const go_feap::ViewpointPath::ConstPtr& m) { targets.push_back(*m); });
  ASSERT_TRUE(spinUntil([&] {
    return compute_sub.getNumPublishers() > 0 && target_sub.getNumPublishers() > 0 && clock_pub.getNumSubscribers() > 0 &&
           odom_pub.getNumSubscribers() > 0 && frontier_pub.getNumSubscribers() > 0 && tour_pub.getNumSubscribers() > 0 &&
           status_pub.getNumSubscribers() > 0;
  }, 30.0)) << "the probe local planner is not connected";
  double now = 200.0;
  ASSERT_TRUE(feedProbeMapper(nh, now)) << "the probe mapper integrated none of 10 frames";
  go_feap::FrontierArray frontiers = frontierAhead(0.3, 0.2);  // 35 cells: more than min_visible
  go_feap::GlobalTour tour;
  tour.header.frame_id = "world";
  tour.frontier_ids = {1};
  tour.waypoints = {frontiers.frontiers[0].average};
  nav_msgs::Odometry odom = odometryAtTheCamera();
  bool odometry = true, touring = true;  // sent with the rest
  auto run = [&](double seconds) {  // clock, odometry, frontiers and a tour every 0.1 s
    playClock(clock_pub, now, seconds, 0.1, 0.04, [&](double t) {
      odom.header.stamp = frontiers.header.stamp = tour.header.stamp = ros::Time(t);
      if (odometry) odom_pub.publish(odom);
      frontier_pub.publish(frontiers);
      if (touring) tour_pub.publish(tour);
    });
  };
  run(4.0);
  ASSERT_FALSE(targets.empty()) << "the probe local planner chose no target";
  ASSERT_EQ(targets.front().frontier_ids, std::vector<std::uint32_t>{1}) << "its target is not a viewpoint of frontier 1";
  // Held: planned at the first tour and then every 1.5 s, not at each of the 40 tours.
  ASSERT_GE(plans, 2u);
  ASSERT_LE(plans, 4u) << "the probe local planner plans at every tour: the held target is not held";
  now -= 80.0;
  plans = 0;
  run(4.0);
  EXPECT_GE(plans, 1u) << "no plan in 4 s after the clock went back 80 s";

  // Reached in vain after its frontier was regrown under a new id: the vehicle at rest at the target, its
  // frontier (the same cells) now listed and toured as 7 (first with the odometry stopped: nothing judged).
  // The failed attempt is reported for 7, the id the layer manager knows; 1 is gone, and its failures with it (a failure reported for it was lost, so a
  // frontier renamed between attempts was never blacklisted).
  std::vector<std::uint32_t> failed;
  auto failed_sub = nh.subscribe<std_msgs::UInt32>("probe/lp/frontier_failed", 10,
                                                   [&](const std_msgs::UInt32::ConstPtr& m) { failed.push_back(m->data); });
  ASSERT_TRUE(spinUntil([&] { return failed_sub.getNumPublishers() > 0; }, 10.0));
  const go_feap::ViewpointPath target = targets.back();
  ASSERT_EQ(target.frontier_ids.at(0), 1u);
  odom.pose.pose.position = target.positions.at(0);
  odom.pose.pose.orientation.w = std::cos(0.5 * target.yaws.at(0));
  odom.pose.pose.orientation.z = std::sin(0.5 * target.yaws.at(0));
  frontiers.frontiers[0].id = 7;
  tour.frontier_ids = {7};
  // The odometry stops there (a VIO dropout) after one message, before the next tour: the tours that come
  // past local/odom_timeout plan nothing and judge nothing (the frozen pose, at rest at the target, was
  // judged reached in vain at every other tour).
  touring = false;
  run(0.1);
  odometry = false;
  run(1.0);
  failed.clear();
  plans = 0;
  touring = true;
  run(6.0);
  EXPECT_TRUE(failed.empty()) << failed.size() << " failures reported from a stale odometry";
  EXPECT_EQ(plans, 0u) << "planned from a stale odometry";
  odometry = true;
  run(6.0);
  ASSERT_FALSE(failed.empty()) << "the target, reached and proposed again, was not reported failed";
  EXPECT_EQ(failed.front(), 7u) << "the failure went to the target's first id, gone since";

  // Frontiers with a cell far outside the map (y = 1e300: finite, so the message checks pass): refused whole
  // before any index is taken from them (the float-to-int cast is undefined there), nothing planned; the
  // next sound frontiers are planned from again.
  const go_feap::FrontierArray sound = frontiers;
  frontiers.frontiers[0].cells.back().y = 1e300;
  plans = 0;
  run(2.0);
  EXPECT_EQ(plans, 0u) << "planned from frontiers with a cell 1e300 m away";
  frontiers = sound;
  run(3.0);
  EXPECT_GE(plans, 1u) << "no plan from sound frontiers after the refused ones";
}

// A trajectory planner (probe/tp/... in metrics.test) flies the vehicle, held still by the test at 1 m up,
// towards a target 1.5 m ahead in the probe mapper's known space; the test's position commands, a
// reference 0.3 m ahead of the odometry, are where its plans start. The clock then goes back 80 s (a bag
// played again): its trajectory's times are void, and it plans again at once, from the odometry, where
// it used to plan nothing until the clock had caught up with its last plan.
TEST(TrajectoryPlanner, PlansAgainFromTheOdometryWhenTheClockGoesBack) {
  ros::NodeHandle nh;
  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("probe/tp/odom", 10);
  auto target_pub = nh.advertise<go_feap::ViewpointPath>("probe/tp/local_target", 10);
  auto cmd_pub = nh.advertise<go_feap::PositionCommand>("probe/tp/position_cmd", 10);
  std::vector<go_feap::Bspline> trajectories;
  auto bspline_sub = nh.subscribe<go_feap::Bspline>(
      "probe/tp/bspline", 50, [&](const go_feap::Bspline::ConstPtr& m) { trajectories.push_back(*m); });
  ASSERT_TRUE(spinUntil([&] {
    return bspline_sub.getNumPublishers() > 0 && clock_pub.getNumSubscribers() > 0 && odom_pub.getNumSubscribers() > 0 &&
           target_pub.getNumSubscribers() > 0 && cmd_pub.getNumSubscribers() > 0;
  }, 30.0)) << "the probe trajectory planner is not connected";
  double now = 300.0;
  ASSERT_TRUE(feedProbeMapper(nh, now)) << "the probe mapper integrated none of 10 frames";
  go_feap::ViewpointPath target;
  target.header.frame_id = "world";
  geometry_msgs::Point ahead;
  ahead.x = 1.5, ahead.z = 1.0;
  target.positions = {ahead};
  target.yaws = {0.0};
  target.frontier_ids = {1};
  target.target_seq = 1;
  nav_msgs::Odometry odom = odometryAtTheCamera();
  go_feap::PositionCommand cmd;  // the server's reference, at rest, following the planner's last trajectory
  cmd.header.frame_id = "world";
  cmd.position.x = 0.3, cmd.position.z = 1.0;
  cmd.trajectory_flag = go_feap::PositionCommand::TRAJECTORY_STATUS_READY;
  auto run = [&](double seconds) {  // clock, odometry, the command and the target every 0.05 s
    playClock(clock_pub, now, seconds, 0.05, 0.02, [&](double t) {
      odom.header.stamp = target.header.stamp = cmd.header.stamp = ros::Time(t);
      if (!trajectories.empty()) cmd.trajectory_id = static_cast<std::uint32_t>(trajectories.back().traj_id);
      odom_pub.publish(odom);
      cmd_pub.publish(cmd);
      target_pub.publish(target);
    });
  };
  // Where a trajectory starts: its first control point (at rest, the first three coincide there).
  auto startOf = [](const go_feap::Bspline& b) {
    return Vec3(b.pos_pts.front().x, b.pos_pts.front().y, b.pos_pts.front().z);
  };
  const Vec3 at_odometry(0.0, 0.0, 1.0), at_command(0.3, 0.0, 1.0);
  run(3.0);
  ASSERT_FALSE(trajectories.empty()) << "the probe trajectory planner planned no trajectory";
  ASSERT_LT((startOf(trajectories.back()) - at_command).norm(), 0.1) << "the plans do not start at the command";
  const double back_from = now;
  now -= 80.0;
  trajectories.clear();
  run(3.0);
  std::optional<go_feap::Bspline> first_since;
  for (const go_feap::Bspline& b : trajectories)
    if (b.start_time.toSec() < back_from - 70.0) {  // planned since the clock went back
      first_since = b;
      break;
    }
  ASSERT_TRUE(first_since) << trajectories.size() << " trajectories in 3 s after the clock went back 80 s, none since";
  EXPECT_LT((startOf(*first_since) - at_odometry).norm(), 0.1)
      << "starts at " << startOf(*first_since).transpose() << ", not at the odometry";
}

// A trajectory server (probe/ts/... in metrics.test) follows a 3 s flight along x when the clock goes
// back to 0.5 s before the flight's start (a bag played again): the flight's times are void. Kept, it
// started over once the clock came back to its start, the reference leaping back to where the vehicle
// had been, with none of the checks a trajectory taken over gets. It is dropped: the last reference is
// held at rest, and the next trajectory sent is followed.
TEST(TrajectoryServer, DropsItsTrajectoryWhenTheClockGoesBack) {
  ros::NodeHandle nh;
  auto clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("probe/ts/odom", 10);
  auto bspline_pub = nh.advertise<go_feap::Bspline>("probe/ts/bspline", 10);
  std::vector<go_feap::PositionCommand> commands;
  auto cmd_sub = nh.subscribe<go_feap::PositionCommand>(
      "probe/ts/position_cmd", 200, [&](const go_feap::PositionCommand::ConstPtr& m) { commands.push_back(*m); });
  ASSERT_TRUE(spinUntil([&] {
    return cmd_sub.getNumPublishers() > 0 && clock_pub.getNumSubscribers() > 0 && odom_pub.getNumSubscribers() > 0 &&
           bspline_pub.getNumSubscribers() > 0;
  }, 30.0)) << "the probe trajectory server is not connected";
  auto positionOf = [](const go_feap::PositionCommand& c) { return go_feap::ros_conv::toVec3(c.position); };
  // The odometry on the reference (where a controller keeps the vehicle), at the start before any.
  Vec3 vehicle(0.0, 0.0, 1.0);
  auto run = [&](double& now, double seconds) {
    playClock(clock_pub, now, seconds, 0.05, 0.02, [&](double t) {
      if (!commands.empty()) vehicle = positionOf(commands.back());
      odom_pub.publish(odometryAt(vehicle, t));
    });
  };
  // A straight 3 s flight from a to b, heading 0, from `start`.
  auto fly = [&](const Vec3& a, const Vec3& b, std::int64_t id, double start) {
    bspline_pub.publish(go_feap::ros_traj::toMsg(go_feap::test::straightFlight(a, b, id, ros::Time(start))));
  };
  double now = 1000.0;
  run(now, 0.5);
  const double start = now;
  fly(vehicle, vehicle + Vec3(3.0, 0.0, 0.0), 1, start);
  run(now, 1.5);
  ASSERT_FALSE(commands.empty()) << "no command while the flight was sent";
  ASSERT_EQ(commands.back().trajectory_id, 1u);
  ASSERT_EQ(commands.back().trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_READY);
  const Vec3 held = positionOf(commands.back());
  ASSERT_GT(held.x(), 0.5) << "the flight has not moved on";
  spinUntil([] { return false; }, 0.2);  // the commands in flight; none comes while the clock stands
  commands.clear();
  now = start - 0.5;
  run(now, 2.0);  // 1.5 s past the flight's start: it would be flown from the start again by now
  ASSERT_GE(commands.size(), 20u) << "the server fell silent after the clock went back";
  for (const go_feap::PositionCommand& c : commands) {
    EXPECT_EQ(c.trajectory_flag, go_feap::PositionCommand::TRAJECTORY_STATUS_EMPTY)
        << "at " << c.header.stamp.toSec() << ": trajectory " << c.trajectory_id << " flag " << int(c.trajectory_flag)
        << " at " << positionOf(c).transpose();
    EXPECT_LT((positionOf(c) - held).norm(), 1e-6) << "at " << c.header.stamp.toSec() << ": not the last reference";
    EXPECT_EQ(Vec3(c.velocity.x, c.velocity.y, c.velocity.z).norm(), 0.0);
  }
  // The next trajectory, timed on the clock as it is now, is followed.
  fly(held, held + Vec3(0.0, 1.0, 0.0), 2, now);
  run(now, 1.0);
  EXPECT_EQ(commands.back().trajectory_id, 2u);
  EXPECT_GT(positionOf(commands.back()).y(), 0.2) << "the next trajectory is not followed";
}

// A run that began and is stopped before it finishes (the launch ends: here the recorder is unloaded)
// still writes what it measured, with finish_reason "stopped": output_dir used to stay empty (replay.launch
// at the bag's end, Ctrl-C in a simulated run). A second recorder with the first's parameters and a
// folder of its own, on topics of its own.
TEST(MetricsRecorder, ARunStoppedBeforeItFinishesWritesItsFiguresSoFar) {
  ros::NodeHandle nh;
  XmlRpc::XmlRpcValue params;
  ASSERT_TRUE(ros::param::get("/metrics_recorder", params));
  const std::string output_dir = "/tmp/go_feap_metrics_stop_test_" + std::to_string(::getpid());
  std::filesystem::remove_all(output_dir);
  params["metrics"]["output_dir"] = output_dir;
  ros::param::set("/stop_recorder", params);
  auto status_pub = nh.advertise<go_feap::ExplorationStatus>("stop/status", 5, /*latch=*/true);
  auto odom_pub = nh.advertise<nav_msgs::Odometry>("stop/odom", 20);
  nodelet::NodeletLoad load;
  load.request.name = "/stop_recorder";
  load.request.type = "go_feap/MetricsRecorder";
  for (const char* topic : {"status", "odom", "compute_time", "map_handle", "status_text", "coverage", "flown_path"}) {
    load.request.remap_source_args.push_back(std::string("/") + topic);
    load.request.remap_target_args.push_back(std::string("/stop/") + topic);
  }
  ASSERT_TRUE(ros::service::call("go_feap_manager/load_nodelet", load) && load.response.success);
  ASSERT_TRUE(spinUntil([&] { return status_pub.getNumSubscribers() > 0 && odom_pub.getNumSubscribers() > 0; }, 20.0));
  status_pub.publish(status(go_feap::ExplorationStatus::EXPLORE, "EXPLORE", 7.5));
  spinUntil([] { return false; }, 0.5);
  nav_msgs::Odometry odom;
  odom.header.frame_id = "world";
  odom.pose.pose.orientation.w = 1.0;
  for (double x : {0.0, 0.25, 0.5}) {
    odom.pose.pose.position.x = x;
    odom.pose.pose.position.z = 1.0;
    odom_pub.publish(odom);
    spinUntil([] { return false; }, 0.2);
  }
  EXPECT_FALSE(std::filesystem::exists(output_dir + "/summary.json")) << "written before the run ended";
  nodelet::NodeletUnload unload;
  unload.request.name = "/stop_recorder";
  ASSERT_TRUE(ros::service::call("go_feap_manager/unload_nodelet", unload) && unload.response.success);
  const std::string summary_path = output_dir + "/summary.json";
  ASSERT_TRUE(spinUntil([&] { return std::filesystem::exists(summary_path); }, 10.0))
      << "no " << summary_path << " after the recorder was unloaded mid-run";
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(summary_path));
  EXPECT_EQ(summary["finish_reason"], "stopped");
  EXPECT_DOUBLE_EQ(summary["exploration_time_s"].get<double>(), 7.5);
  EXPECT_NEAR(summary["flight_distance_m"].get<double>(), 0.5, 1e-9);
  for (const char* f : {"metrics.csv", "coverage.png"})
    EXPECT_TRUE(std::filesystem::exists(output_dir + "/" + f)) << f;
  std::filesystem::remove_all(output_dir);
}

}  // namespace

GO_FEAP_ROSTEST_MAIN("test_metrics_ros")
