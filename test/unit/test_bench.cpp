// The lock-step exploration loop (go_feap_bench's core) on the small maze: every planner mode
// explores it to FINISHED(complete) with at least 95 % coverage and no collision, and the same
// seed and options give the same run.
#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "../command_util.h"
#include "../../src/tools/camera_path.h"
#include "../../src/tools/cli_args.h"
#include "go_feap/bench/exploration_run.h"
#include "go_feap/metrics/metrics.h"
#include "go_feap/world/scene_files.h"

#ifndef GO_FEAP_CONFIG_DIR
#error "GO_FEAP_CONFIG_DIR must name the package's config directory"
#endif

namespace {

namespace bench = go_feap::bench;
using go_feap::test::readText;
using go_feap::test::replaceOnce;
using go_feap::test::runCommand;

const std::string kSmallMaze = GO_FEAP_CONFIG_DIR "/scenes/maze_small.yaml";

struct Outcome {
  go_feap::metrics::Summary summary;
  std::vector<go_feap::metrics::Sample> samples;
  std::vector<std::string> events;
};

Outcome explore(const std::string& planner, std::uint64_t seed, double max_sim_time, double noise = 0.0,
                double dropout = 0.0) {
  auto config = bench::loadExplorationConfig(GO_FEAP_CONFIG_DIR, planner);
  EXPECT_TRUE(config) << config.message();
  config->camera.noise_stddev_per_m = noise;
  config->camera.dropout_probability = dropout;
  auto scene = go_feap::world::makeScene(kSmallMaze, seed);
  EXPECT_TRUE(scene) << scene.message();
  bench::ExplorationRun run(*scene, *config, planner, max_sim_time);
  run.run();
  return {run.recorder().summary(), run.recorder().samples(), run.events()};
}

class PlannerModes : public ::testing::TestWithParam<std::string> {};

TEST_P(PlannerModes, ExploreTheSmallMazeCompletely) {
  const Outcome o = explore(GetParam(), 0, 300.0);
  const auto& s = o.summary;
  std::cout << GetParam() << ": " << s.finish_reason << " after " << s.exploration_time_s << " s, "
            << s.flight_distance_m << " m, coverage " << 100.0 * s.coverage << " %, closest approach "
            << s.min_obstacle_distance_m << " m\n";
  EXPECT_EQ(s.finish_reason, "complete");
  EXPECT_GE(s.coverage, 0.95);
  EXPECT_EQ(s.collisions, 0);
  EXPECT_GT(s.min_obstacle_distance_m, 0.1);
  // The clearance is measured: a whole maze is not explored without passing within the monitor's horizon of
  // a wall (a run whose positions never reached the collision monitor reports the horizon itself).
  EXPECT_LT(s.min_obstacle_distance_m, go_feap::metrics::CollisionMonitor::kHorizon - 0.05);
  EXPECT_GT(s.flight_distance_m, 5.0);
  EXPECT_GT(s.wall_time_s, 0.0);
  ASSERT_TRUE(s.extra.count("map_memory_mb"));
  EXPECT_GT(s.extra.at("map_memory_mb"), 0.0);
  // The time series ends where the summary does; coverage and distance never decrease.
  ASSERT_FALSE(o.samples.empty());
  EXPECT_DOUBLE_EQ(o.samples.back().coverage, s.coverage);
  EXPECT_DOUBLE_EQ(o.samples.back().distance, s.flight_distance_m);
  double polyline = 0.0;
  for (std::size_t i = 1; i < o.samples.size(); ++i) {
    EXPECT_GE(o.samples[i].coverage, o.samples[i - 1].coverage);
    EXPECT_GE(o.samples[i].distance, o.samples[i - 1].distance);
    polyline += (o.samples[i].position - o.samples[i - 1].position).norm();
  }
  // The distance is the path flown, summed finer than the samples: at least their polyline, and not much more
  // (a smooth flight between samples).
  EXPECT_GE(s.flight_distance_m, polyline - 1e-9);
  EXPECT_LE(s.flight_distance_m, 1.05 * polyline);
}

INSTANTIATE_TEST_SUITE_P(Bench, PlannerModes, ::testing::Values("go_feap", "fuel", "nearest"));

// go_feap_bench's SIGINT/SIGTERM: a run whose interrupt flag is raised ends at its next step with what it
// has, finish reason "interrupted", the time series ending there; without the flag it would go on.
TEST(Bench, AnInterruptedRunEndsWhereItStands) {
  auto config = bench::loadExplorationConfig(GO_FEAP_CONFIG_DIR, "go_feap");
  ASSERT_TRUE(config) << config.message();
  auto scene = go_feap::world::makeScene(kSmallMaze, 0);
  ASSERT_TRUE(scene) << scene.message();
  bench::ExplorationRun run(*scene, *config, "go_feap", 300.0);
  std::atomic<bool> interrupt{false};
  run.run([&](const bench::Progress& p) { interrupt = interrupt || p.t >= 8.0; }, &interrupt);
  const auto& s = run.recorder().summary();
  EXPECT_TRUE(run.ended());
  EXPECT_EQ(s.finish_reason, "interrupted");
  EXPECT_GE(s.exploration_time_s, 8.0);
  EXPECT_LT(s.exploration_time_s, 8.1);
  EXPECT_GT(s.coverage, 0.0);
  EXPECT_LT(s.coverage, 0.95);  // the small maze takes far longer (ExploreTheSmallMazeCompletely)
  ASSERT_FALSE(run.recorder().samples().empty());
  EXPECT_DOUBLE_EQ(run.recorder().samples().back().t, s.exploration_time_s);
  EXPECT_FALSE(run.step());  // ended for good
}

// go_feap_bench's own SIGTERM (SIGINT alike): blocked in every thread and taken by its signal thread. The run
// in progress ends where it stands and is written (finish reason "interrupted", the tables too), the runs not
// started are skipped by name, and the process exits 130. (The test above raises the run's flag itself.)
TEST(Bench, ATermToTheBenchWritesTheRunInProgressAndSkipsTheRest) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("go_feap_bench_term_" + std::to_string(getpid()));
  fs::remove_all(dir);
  // 5 s in: the maze's seed 0 (about 100 s simulated, 10 s or more of wall time here) is under way.
  const auto [rc, said] = runCommand("timeout --preserve-status -s TERM 5 " + std::string(GO_FEAP_BENCH_BIN) +
                                     " --scene maze --runs 3 --jobs 1 --out " + dir.string() + " 2>&1");
  EXPECT_EQ(rc, 130) << said;
  const fs::path first = dir / "maze" / "go_feap" / "seed0" / "summary.json";
  ASSERT_TRUE(fs::exists(first)) << said;
  const nlohmann::json summary = nlohmann::json::parse(std::ifstream(first));
  EXPECT_EQ(summary["finish_reason"], "interrupted") << said;
  for (const char* seed : {"seed1", "seed2"}) EXPECT_FALSE(fs::exists(dir / "maze" / "go_feap" / seed)) << seed;
  EXPECT_NE(said.find("seed 1 failed: not run: interrupted"), std::string::npos) << said;
  EXPECT_NE(said.find("seed 2 failed: not run: interrupted"), std::string::npos) << said;
  EXPECT_TRUE(fs::exists(dir / "table.json"));
  EXPECT_TRUE(fs::exists(dir / "table.md"));
  fs::remove_all(dir);
}

TEST(Bench, SameSeedAndOptionsGiveTheSameRun) {
  // 20 s: well before seed 1 of the small maze is explored (35.0 s), so the limit ends the run.
  const Outcome a = explore("go_feap", 1, 20.0), b = explore("go_feap", 1, 20.0);
  EXPECT_EQ(a.summary.finish_reason, b.summary.finish_reason);
  EXPECT_EQ(a.summary.exploration_time_s, b.summary.exploration_time_s);
  EXPECT_EQ(a.summary.flight_distance_m, b.summary.flight_distance_m);
  EXPECT_EQ(a.summary.coverage, b.summary.coverage);
  EXPECT_EQ(a.events, b.events);
  // The run's budget is the exploration's time limit (not exploration.yaml's layers/time_limit): the
  // layer manager ends it there, at its next step.
  EXPECT_EQ(a.summary.finish_reason, "time_limit");
  EXPECT_NEAR(a.summary.exploration_time_s, 20.0, 0.25);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    EXPECT_EQ(a.samples[i].position, b.samples[i].position) << i;
    EXPECT_EQ(a.samples[i].coverage, b.samples[i].coverage) << i;
  }
  // A different maze (seed) gives a different run.
  const Outcome c = explore("go_feap", 2, 40.0);
  EXPECT_NE(a.samples.back().position, c.samples.back().position);
}

// depth_camera/noise_stddev_per_m and dropout_probability reach the bench's camera as the DepthCamera
// nodelet's (the bench rendered noiseless images whatever they said), seeded by the run's seed: the same
// noisy run twice, another than without noise.
TEST(Bench, CameraNoiseIsAppliedAndSeededByTheRun) {
  const Outcome a = explore("go_feap", 1, 10.0, 0.02, 0.05), b = explore("go_feap", 1, 10.0, 0.02, 0.05);
  const Outcome plain = explore("go_feap", 1, 10.0);
  ASSERT_EQ(a.samples.size(), b.samples.size());
  for (std::size_t i = 0; i < a.samples.size(); ++i) {
    EXPECT_EQ(a.samples[i].position, b.samples[i].position) << i;
    EXPECT_EQ(a.samples[i].coverage, b.samples[i].coverage) << i;
  }
  ASSERT_FALSE(a.samples.empty());
  ASSERT_FALSE(plain.samples.empty());
  EXPECT_NE(a.samples.back().coverage, plain.samples.back().coverage) << "the noise changed nothing";
}

// A copy of the package's config in a fresh temporary folder, with modes/<mode>.yaml holding `yaml`.
std::filesystem::path configWithMode(const std::string& mode, const std::string& yaml) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("go_feap_modes_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::copy(GO_FEAP_CONFIG_DIR, dir, fs::copy_options::recursive);
  std::ofstream(dir / "modes" / (mode + ".yaml")) << yaml;
  return dir;
}

TEST(Bench, ModeOverlaysSetThePlannersDistanceSearchNotTheFlightSearch) {
  // A mode file is laid over exploration.yaml and trajectory.yaml alike: its distance_astar keys must
  // reach the planners' search only, its astar keys the flight search only.
  const std::filesystem::path dir =
      configWithMode("probe", "distance_astar:\n  max_expansions: 777\n  stride: 3\nastar:\n  max_expansions: 999\n");
  auto probe = bench::loadExplorationConfig(dir.string(), "probe");
  auto plain = bench::loadExplorationConfig(dir.string(), "go_feap");
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(probe) << probe.message();
  ASSERT_TRUE(plain) << plain.message();
  EXPECT_EQ(probe->distance_astar.max_expansions, 777);
  EXPECT_EQ(probe->distance_astar.stride, 3);
  EXPECT_EQ(probe->flight_astar.max_expansions, 999);
  EXPECT_EQ(probe->flight_astar.stride, plain->flight_astar.stride);
  EXPECT_EQ(probe->scout_astar.max_expansions, plain->scout_astar.max_expansions);
  EXPECT_EQ(probe->coarse_astar.max_expansions, plain->coarse_astar.max_expansions);
  EXPECT_NE(plain->distance_astar.max_expansions, 777);
  EXPECT_NE(plain->flight_astar.max_expansions, 999);
  // Validation messages name the section.
  EXPECT_EQ(probe->distance_astar.name, "distance_astar");
  EXPECT_EQ(probe->flight_astar.name, "astar");
  EXPECT_EQ(probe->scout_astar.name, "scout_astar");
  EXPECT_EQ(probe->coarse_astar.name, "coarse_astar");
}

// Without --out, two calls started together get folders of their own (a shared one kept only the last
// call's tables); off a terminal the progress is a line per run ended, with no carriage return (a log held
// one endless line).
TEST(Bench, CallsWithoutOutGetTheirOwnFoldersAndLogOneLinePerRun) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("go_feap_bench_default_out_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string call = std::string(GO_FEAP_BENCH_BIN) + " --scene maze --planner nearest --runs 1 --max-sim-time 1";
  const auto [rc, said] = runCommand("cd " + dir.string() + " && (timeout 120 " + call + " > a.out 2> a.err & timeout 120 " +
                                     call + " > b.out 2> b.err; wait) && cat a.err b.err");
  EXPECT_EQ(rc, 0) << said;
  std::vector<std::string> folders;
  for (const auto& entry : fs::directory_iterator(dir / "results")) {
    folders.push_back(entry.path().filename().string());
    EXPECT_TRUE(fs::exists(entry.path() / "table.json")) << entry.path();
  }
  EXPECT_EQ(folders.size(), 2u) << said;
  EXPECT_EQ(said.find('\r'), std::string::npos) << "carriage returns in a log";
  std::size_t lines = 0;
  for (std::size_t at = 0; (at = said.find("[1/1 runs] maze / nearest / seed 0: ", at)) != std::string::npos; ++at) ++lines;
  EXPECT_EQ(lines, 2u) << said;
  fs::remove_all(dir);
}

// Command-line values the tools refuse up front, naming the argument: 1e12 jobs or runs aborted the
// bench with bad_alloc, a file in --out's place aborted it after every run had been flown, and a
// --skip-pixel of 2^32 wrapped to 0 in go_feap_map_perf (a loop for ever).
TEST(Bench, CommandLineValuesOutOfRangeAreRefusedUpFront) {
  const std::string bench = GO_FEAP_BENCH_BIN, map_perf = GO_FEAP_MAP_PERF_BIN, esdf_perf = GO_FEAP_ESDF_PERF_BIN;
  const std::string scene = GO_FEAP_SCENE_BIN, sim_perf = GO_FEAP_SIM_PERF_BIN, tsp_perf = GO_FEAP_TSP_PERF_BIN;
  const std::filesystem::path file = std::filesystem::temp_directory_path() / ("go_feap_not_a_folder_" + std::to_string(getpid()));
  std::ofstream(file) << "a file\n";
  const std::string scratch = (std::filesystem::temp_directory_path() / ("go_feap_scene_out_" + std::to_string(getpid()))).string();
  for (const auto& [command, says] : std::vector<std::pair<std::string, std::string>>{
           {bench + " --jobs 1000000000000", "--jobs must be an integer from 1 to 256"},
           {bench + " --runs 1000000000000", "--runs must be an integer from 1 to 100000"},
           {bench + " --max-sim-time 2 --out " + file.string(), "--out " + file.string() + ": cannot make it a folder"},
           {bench + " --max-sim-time 3abc", "--max-sim-time must be a number > 0"},  // was taken as 3
           {bench + " --max-sim-time 0x4", "--max-sim-time must be a number > 0"},   // was taken as 4
           {bench + " --max-sim-time 0", "--max-sim-time must be a number > 0"},     // every run failed late
           {bench + " --max-sim-time -1", "--max-sim-time must be a number > 0"},
           {bench + " --max-sim-time 1e999", "--max-sim-time must be a number > 0"},  // infinite
           {bench + " --runs 0", "--runs must be an integer from 1 to 100000"},        // empty tables, exit 0
           {bench + " --jobs 0", "--jobs must be an integer from 1 to 256"},           // no worker: every run "failed"
           {bench + " --seed -1", "--seed must be an integer >= 0"},                   // 2^64 - 1
           {bench + " --seed", "--seed needs a value"},
           {bench + " --sede 3", "unknown argument '--sede'"},
           {bench + " --seed 18446744073709551615 --runs 2", "--seed + --runs - 1 must fit in 64 bits"},  // wrapped to 0
           {bench + " --scene maze,maze", "'maze' is named twice in --scene"},
           {bench + " --planner go_feap,fuel,go_feap", "'go_feap' is named twice in --planner"},
           {bench + " --runs 3 --max-sim-time 2 --runs 5", "--runs is given twice"},  // the last won
           {bench + " --planner go_feap,,fuel", "--planner has an empty name"},         // was dropped
           {bench + " --scene maze,", "--scene has an empty name"},
           {bench + " --planner ./go_feap", "a mode's name has letters, digits"},  // go_feap's file, another folder
           {bench + " --planner ../modes/fuel", "a mode's name has letters, digits"},
           {bench + " --out ''", "--out must name a folder"},  // fell back to the default folder
           {map_perf + " --scene maze --skip-pixel 4294967296", "--skip-pixel must be an integer from 1 to 640"},
           {map_perf + " --scene maze --frames 4294967296", "--frames must be an integer from 1 to 1000000"},
           {esdf_perf + " --max-distance 2abc", "--max-distance must be a number"},  // was taken as 2
           {map_perf + " --scene maze --skip-pixel 0", "--skip-pixel must be an integer from 1 to 640"},  // a step of 0
           {map_perf + " --scene maze --frames 0", "--frames must be an integer from 1 to 1000000"},  // a table of nan
           {esdf_perf + " --max-distance 0", "esdf: max_distance must be finite and > 0"},  // aborted
           {esdf_perf + " --max-distance 0.05", "esdf: max_distance must be >= the map's resolution"},
           {esdf_perf + " --repeats 0", "--repeats must be a positive integer"},
           {sim_perf + " --scene maze --frames 0", "--frames must be a positive integer"},
           {sim_perf + " --scene maze --frames 4294967296", "--frames must be a positive integer"},  // cast to 0
           {sim_perf + " --scene office", "--scene must be maze or powerplant"},
           {tsp_perf + " --repeats 0", "--repeats needs a whole number > 0"},
           {tsp_perf + " --seed -1", "--seed needs a whole number >= 0"},
           {scene + " --scene maze --seed -1 --out " + scratch, "--seed must be a non-negative integer"},
           {scene + " --scene maze", "--out is required"},
           {scene + " --out " + scratch, "--scene is required"},
           {scene + " --scene nowhere --out " + scratch, "unknown scene 'nowhere'"}}) {
    const auto [rc, out] = runCommand("timeout 60 " + command);
    EXPECT_TRUE(rc == 1 || rc == 2) << command << ": exit status " << rc << "\n" << out;
    EXPECT_NE(out.find(says), std::string::npos) << command << ":\n" << out;
  }
  EXPECT_TRUE(std::filesystem::is_regular_file(file));  // left as it was
  std::filesystem::remove(file);
  EXPECT_FALSE(std::filesystem::exists(scratch)) << "a refused call made its --out";
  std::filesystem::remove_all(scratch);
  // --help is no error, for every tool (go_feap_tsp_perf exited 2).
  for (const std::string& tool : {bench, map_perf, esdf_perf, scene, sim_perf, tsp_perf}) {
    const auto [rc, out] = runCommand("timeout 60 " + tool + " --help");
    EXPECT_EQ(rc, 0) << tool << "\n" << out;
    EXPECT_NE(out.find("usage:"), std::string::npos) << tool << "\n" << out;
  }
}

// go_feap_scene on a scene of 2 x 1 x 1 m at 0.5 m read from a .pcd: one obstacle voxel in the box, one
// beyond it in the grid's margin. scene.json's box is the exploration box (scripts/run passes it on to the
// launch), its counts those of the box, the grid and the observable set, and a file scene takes no seed.
TEST(Bench, SceneToolWritesTheScenesFiguresAndFiles) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("go_feap_scene_tool_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  using go_feap::common::Vec3;
  go_feap::world::Scene tiny = go_feap::world::makeEmptyScene("tiny", {Vec3(0, 0, 0), Vec3(2, 1, 1)}, 0.5, 0.5);
  ASSERT_TRUE(go_feap::world::markOccupied(tiny, Vec3(1.75, 0.25, 0.25)));  // voxel (4, 1, 1), in the box
  ASSERT_TRUE(go_feap::world::markOccupied(tiny, Vec3(2.25, 0.25, 0.25)));  // voxel (5, 1, 1), in the margin
  ASSERT_TRUE(go_feap::world::saveScenePcd(tiny, (dir / "tiny.pcd").string()));
  std::ofstream(dir / "tiny.yaml") << "scene:\n  name: tiny\n  file: tiny.pcd\n"
                                      "  T_world_file: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n  resolution: 0.5\n"
                                      "  margin: 0.5\n  box: {min: [0, 0, 0], max: [2, 1, 1]}\n"
                                      "  start: {position: [0.25, 0.25, 0.25], yaw: 0}\n  ground_plane: false\n";
  const std::string tool = GO_FEAP_SCENE_BIN;
  const auto [rc, said] = runCommand("timeout 60 " + tool + " --scene " + (dir / "tiny.yaml").string() +
                                     " --seed 5 --out " + (dir / "out").string());
  ASSERT_EQ(rc, 0) << said;
  EXPECT_NE(said.find("scene 'tiny' (seed 0): 1 occupied, 15 free voxels in the box, 16 observable"), std::string::npos)
      << said;
  for (const char* f : {"scene.pcd", "scene.bt", "scene.json", "scene.png"})
    EXPECT_TRUE(fs::is_regular_file(dir / "out" / f)) << f;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "out" / "scene.json"));
  EXPECT_EQ(j["name"], "tiny");
  EXPECT_EQ(j["seed"], 0);
  EXPECT_DOUBLE_EQ(j["resolution"].get<double>(), 0.5);
  EXPECT_EQ(j["box"]["min"], nlohmann::json({0.0, 0.0, 0.0}));
  EXPECT_EQ(j["box"]["max"], nlohmann::json({2.0, 1.0, 1.0}));
  EXPECT_EQ(j["grid"]["origin"], nlohmann::json({-0.5, -0.5, -0.5}));
  EXPECT_EQ(j["grid"]["dims"], nlohmann::json({6, 4, 4}));
  EXPECT_EQ(j["start"]["position"], nlohmann::json({0.25, 0.25, 0.25}));
  // The box's voxel centres: x 0.25 .. 1.75, y and z 0.25 and 0.75 (4 x 2 x 2); the flood fill from the start
  // reaches its 15 free voxels and sees the occupied one.
  EXPECT_EQ(j["voxels"]["occupied_in_box"], 1);
  EXPECT_EQ(j["voxels"]["free_in_box"], 15);
  EXPECT_EQ(j["voxels"]["occupied_in_grid"], 2);
  EXPECT_EQ(j["voxels"]["observable"], 16);
  EXPECT_EQ(j["voxels"]["observable_free"], 15);
  EXPECT_EQ(j["voxels"]["observable_occupied"], 1);
  // A procedural scene keeps its seed.
  const auto [rc2, said2] = runCommand("timeout 60 " + tool + " --scene " + kSmallMaze + " --seed 7 --out " +
                                       (dir / "maze").string());
  ASSERT_EQ(rc2, 0) << said2;
  const nlohmann::json m = nlohmann::json::parse(std::ifstream(dir / "maze" / "scene.json"));
  EXPECT_EQ(m["seed"], 7);
  EXPECT_EQ(m["box"]["min"], nlohmann::json({-5.0, -3.0, 0.0}));
  EXPECT_EQ(m["box"]["max"], nlohmann::json({5.0, 3.0, 3.0}));
  fs::remove_all(dir);
}

// scripts/test's last line and exit status come from scripts/lib/count_results.py: a failure, an error, a
// skip without a reason (a failing SetUpTestSuite), an unreadable result, a ctest run that stopped early, a
// failed rostest wrapper and a folder without results all count as failed; a skip with a reason and a test
// not run count as skipped; a passed rostest wrapper (its node's cases are counted) does not count. A gtest
// binary ctest lists as failed whose result passed (it crashed after writing it) counts once more, by name;
// one whose result shows its failures adds nothing; another test listed when no result failed counts once.
TEST(Bench, TheTestCountCountsEveryOutcome) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("go_feap_count_results_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir / "mixed");
  fs::create_directories(dir / "good");
  fs::create_directories(dir / "empty");
  std::ofstream(dir / "mixed" / "a.xml")
      << "<testsuites><testsuite name=\"S\">\n"
         "<testcase classname=\"S\" name=\"ok\" status=\"run\"/>\n"
         "<testcase classname=\"S\" name=\"bad\" status=\"run\"><failure message=\"x.cpp:3&#10;boom\"/></testcase>\n"
         "<testcase classname=\"S\" name=\"err\"><error message=\"crashed\"/></testcase>\n"
         "<testcase classname=\"S\" name=\"why\" status=\"run\" result=\"skipped\"><skipped message=\"x.cpp:9&#10;needs shared/\"/></testcase>\n"
         "<testcase classname=\"S\" name=\"bare\" status=\"run\" result=\"skipped\"><skipped message=\"x.cpp:9&#10;\"/></testcase>\n"
         "<testcase classname=\"S\" name=\"off\" status=\"notrun\"/>\n"
         "</testsuite></testsuites>\n";
  std::ofstream(dir / "good" / "b.xml") << "<testsuites><testsuite name=\"S\"><testcase classname=\"S\" name=\"ok\" "
                                           "status=\"run\"/></testsuite></testsuites>\n";
  // A rostest's wrapper case: its node's cases have a result of their own, so a pass of it is not counted
  // again; a failure of it (the node crashed or timed out) is.
  std::ofstream(dir / "good" / "rostest-x.xml")
      << "<testsuite errors=\"0\" failures=\"0\" tests=\"1\"><testcase classname=\"rostest.runner.RosTest\" "
         "name=\"testx\" time=\"3.8\" /></testsuite>\n";
  std::ofstream(dir / "mixed" / "rostest-y.xml")
      << "<testsuite errors=\"1\" failures=\"0\" tests=\"1\"><testcase classname=\"rostest.runner.RosTest\" "
         "name=\"testy\"><error message=\"test [y] did not generate test results\"/></testcase></testsuite>\n";
  const std::string count = "/usr/bin/python3 " GO_FEAP_CONFIG_DIR "/../scripts/lib/count_results.py ";
  auto lastLine = [](const std::string& out) {
    const std::size_t end = out.find_last_not_of('\n');
    return out.substr(out.rfind('\n', end) + 1, end - out.rfind('\n', end));
  };
  {
    const auto [rc, out] = runCommand(count + (dir / "mixed").string());
    EXPECT_EQ(rc, 1) << out;
    EXPECT_EQ(lastLine(out), "1 passed, 4 failed") << out;
    for (const char* line : {"FAILED S.bad: x.cpp:3\n", "FAILED S.err: crashed\n", "FAILED S.bare: skipped with no reason given",
                             "FAILED rostest.runner.RosTest.testy: test [y] did not generate test results\n",
                             "\n2 skipped\n"})
      EXPECT_NE(out.find(line), std::string::npos) << line << "\n" << out;
  }
  {  // ctest stopped (124: its timeout) before every test ran
    const auto [rc, out] = runCommand(count + (dir / "mixed").string() + " 124");
    EXPECT_EQ(rc, 1) << out;
    EXPECT_EQ(lastLine(out), "1 passed, 5 failed") << out;
    EXPECT_NE(out.find("ctest exited 124 with no test failed"), std::string::npos) << out;
  }
  {
    const auto [rc, out] = runCommand(count + (dir / "good").string() + " 0");
    EXPECT_EQ(rc, 0) << out;
    EXPECT_EQ(lastLine(out), "1 passed, 0 failed") << out;
  }
  // ctest's list of failed tests ('N:name'), catkin's names: gtest-c.xml passed though its binary exited
  // non-zero; gtest-d.xml holds the failure its binary exited for.
  std::ofstream(dir / "good" / "gtest-c.xml") << "<testsuites><testsuite name=\"C\"><testcase classname=\"C\" name=\"ok\" "
                                                 "status=\"run\"/></testsuite></testsuites>\n";
  std::ofstream(dir / "failed.log") << "3:_ctest_go_feap_gtest_c\n";
  {
    const auto [rc, out] = runCommand(count + (dir / "good").string() + " 8 " + (dir / "failed.log").string());
    EXPECT_EQ(rc, 1) << out;
    EXPECT_EQ(lastLine(out), "2 passed, 1 failed") << out;
    EXPECT_NE(out.find("FAILED _ctest_go_feap_gtest_c: exited non-zero, and its result gtest-c.xml shows no failure"),
              std::string::npos) << out;
    EXPECT_EQ(out.find("ctest exited"), std::string::npos) << "the status is the listed test's\n" << out;
  }
  std::ofstream(dir / "mixed" / "gtest-d.xml") << "<testsuites><testsuite name=\"D\"><testcase classname=\"D\" name=\"bad\" "
                                                  "status=\"run\"><failure message=\"d.cpp:1\"/></testcase></testsuite></testsuites>\n";
  std::ofstream(dir / "failed.log") << "4:_ctest_go_feap_gtest_d\n5:_ctest_go_feap_rostest_test_ros_y.test\n";
  {
    const auto [rc, out] = runCommand(count + (dir / "mixed").string() + " 8 " + (dir / "failed.log").string());
    EXPECT_EQ(rc, 1) << out;
    EXPECT_EQ(lastLine(out), "1 passed, 5 failed") << out;  // the 4 before and D.bad, nothing more
  }
  // A binary that crashed before writing its result: catkin writes MISSING-gtest-e.xml with one failure, and
  // ctest lists it as failed; that is one failure, not two.
  fs::create_directories(dir / "crashed");
  std::ofstream(dir / "crashed" / "MISSING-gtest-e.xml")
      << "<testsuite tests=\"1\" failures=\"1\" time=\"1\" errors=\"0\" name=\"gtest-e.xml\"><testcase "
         "name=\"test_ran\" status=\"run\" time=\"1\" classname=\"Results\"><failure message=\"Unable to find "
         "test results for gtest-e.xml, test did not run.\" type=\"\"/></testcase></testsuite>\n";
  std::ofstream(dir / "crashed" / "b.xml") << "<testsuites><testsuite name=\"S\"><testcase classname=\"S\" name=\"ok\" "
                                              "status=\"run\"/></testsuite></testsuites>\n";
  std::ofstream(dir / "failed.log") << "6:_ctest_go_feap_gtest_e\n";
  {
    const auto [rc, out] = runCommand(count + (dir / "crashed").string() + " 8 " + (dir / "failed.log").string());
    EXPECT_EQ(rc, 1) << out;
    EXPECT_EQ(lastLine(out), "1 passed, 1 failed") << out;
    EXPECT_NE(out.find("FAILED Results.test_ran: Unable to find test results for gtest-e.xml"), std::string::npos)
        << out;
  }
  std::ofstream(dir / "failed.log") << "5:_ctest_go_feap_rostest_test_ros_z.test\n";
  {  // a rostest that exited non-zero with every result passed
    const auto [rc, out] = runCommand(count + (dir / "good").string() + " 8 " + (dir / "failed.log").string());
    EXPECT_EQ(rc, 1) << out;
    EXPECT_EQ(lastLine(out), "2 passed, 1 failed") << out;
    EXPECT_NE(out.find("FAILED _ctest_go_feap_rostest_test_ros_z.test: exited non-zero, and no result shows a failure"),
              std::string::npos) << out;
  }
  for (const fs::path& nothing : {dir / "empty", dir / "missing"}) {
    const auto [rc, out] = runCommand(count + nothing.string());
    EXPECT_EQ(rc, 1) << out;
    EXPECT_NE(out.find("no test results found under"), std::string::npos) << out;
    EXPECT_EQ(lastLine(out), "0 passed, 1 failed") << out;
  }
  std::ofstream(dir / "empty" / "broken.xml") << "<testsuite";
  {
    const auto [rc, out] = runCommand(count + (dir / "empty").string());
    EXPECT_EQ(rc, 1) << out;
    EXPECT_NE(out.find("FAILED broken.xml: unreadable result"), std::string::npos) << out;
    EXPECT_EQ(lastLine(out), "0 passed, 1 failed") << out;
  }
  fs::remove_all(dir);
}

// The perf tools' camera path keeps 0.3 m from every obstacle, inside the box at 1 to 2 m, looking level.
TEST(Bench, ThePerfToolsCameraPathKeepsClearOfObstacles) {
  using go_feap::common::Vec3;
  go_feap::world::Scene s = go_feap::world::makeEmptyScene("t", {Vec3(0, 0, 0), Vec3(2, 2, 2)}, 0.1, 0.0);
  ASSERT_TRUE(go_feap::world::markOccupied(s, Vec3(1.05, 1.05, 1.05)));  // voxel (10, 10, 10)
  EXPECT_FALSE(go_feap::tools::isClear(s, Vec3(1.05, 1.05, 1.25), 0.3));
  EXPECT_TRUE(go_feap::tools::isClear(s, Vec3(1.05, 1.05, 1.45), 0.3));  // voxels 11 .. 17 along z
  EXPECT_FALSE(go_feap::tools::isClear(s, Vec3(1.05, 1.05, 0.75), 0.3));  // 5 .. 10: the last one counts
  EXPECT_FALSE(go_feap::tools::isClear(s, Vec3(0.75, 1.05, 1.05), 0.3));
  EXPECT_FALSE(go_feap::tools::isClear(s, Vec3(1.05, 0.75, 1.05), 0.3));
  auto maze = go_feap::world::makeScene("maze", 0);
  ASSERT_TRUE(maze) << maze.message();
  const auto poses = go_feap::tools::cameraPath(*maze, 300, 2256);
  ASSERT_EQ(poses.size(), 300u);
  for (const auto& T : poses) {
    const Vec3 p = T.translation();
    EXPECT_TRUE(go_feap::tools::isClear(*maze, p, 0.3)) << p.transpose();
    EXPECT_TRUE(maze->box.contains(p)) << p.transpose();
    EXPECT_GE(p.z(), 1.0 - 1e-9);
    EXPECT_LE(p.z(), 2.0 + 1e-9);
    EXPECT_NEAR(T.linear().col(2).z(), 0.0, 1e-9) << "the optical axis is not level";
    EXPECT_NEAR(T.linear().col(1).z(), -1.0, 1e-9) << "the image's y does not point down";
  }
}

// The tools' argument parsing: a flag takes no value (the next argument is read on its own), an option's
// value must be there, numbers are whole and finite.
TEST(Bench, ArgumentsParseFlagsOptionsAndWholeNumbersOnly) {
  const std::map<std::string, bool> known = {{"--seed", true}, {"--perf", false}, {"--runs", true}};
  auto parse = [&](std::vector<std::string> words, std::map<std::string, std::string>& values, bool& help) {
    std::vector<char*> argv;
    for (std::string& w : words) argv.push_back(w.data());
    argv.push_back(nullptr);
    return go_feap::tools::parseArgs(static_cast<int>(words.size()), argv.data(), known, values, help);
  };
  std::map<std::string, std::string> values;
  bool help = true;
  EXPECT_EQ(parse({"p", "--perf", "--runs", "2"}, values, help), "");
  EXPECT_FALSE(help);
  EXPECT_EQ(values, (std::map<std::string, std::string>{{"--perf", "1"}, {"--runs", "2"}}));
  values.clear();
  EXPECT_EQ(parse({"p", "--runs", "2", "--seed"}, values, help), "--seed needs a value");
  values.clear();
  EXPECT_EQ(parse({"p", "--sede", "3"}, values, help), "unknown argument '--sede'");
  values.clear();
  EXPECT_EQ(parse({"p", "--runs", "2", "-h"}, values, help), "");
  EXPECT_TRUE(help);

  unsigned long long n = 7;
  EXPECT_TRUE(go_feap::tools::parseCount("42", n));
  EXPECT_EQ(n, 42u);
  EXPECT_TRUE(go_feap::tools::parseCount("18446744073709551615", n));
  EXPECT_EQ(n, 18446744073709551615ull);
  for (const char* bad : {"", "3abc", "-1", " 1", "+1", "1.0", "18446744073709551616"}) {
    n = 7;
    EXPECT_FALSE(go_feap::tools::parseCount(bad, n)) << "'" << bad << "'";
  }
  double d = 0.0;
  EXPECT_TRUE(go_feap::tools::parseNumber("1e308", d));
  EXPECT_DOUBLE_EQ(d, 1e308);
  EXPECT_TRUE(go_feap::tools::parseNumber("-2.5", d));
  EXPECT_DOUBLE_EQ(d, -2.5);
  for (const char* bad : {"", "1e999", "-1e999", "inf", "nan", "0x4", "2abc", "1 "}) {
    d = 3.0;
    EXPECT_FALSE(go_feap::tools::parseNumber(bad, d)) << "'" << bad << "'";
    EXPECT_DOUBLE_EQ(d, 3.0) << "'" << bad << "' changed the value";
  }
}

// Results as a user reads them, in one folder: a scene read from a file (it takes no seed) is run once per
// planner, as seed 0, however many runs are asked (each run of it is the same run: the table showed N
// copies as N runs, labelled seed 0 in folders seed1...); a scene whose name is not UTF-8 still gets its
// tables (the table dump threw, leaving table.json empty and no table.md); a comparison.json left by an
// earlier call goes when the next compares nothing; two scenes bound for one results folder are refused.
TEST(Bench, ResultsFoldersHoldEachRunOnceAndTheTablesWhole) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("go_feap_bench_results_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto maze = go_feap::world::makeScene(kSmallMaze, 0);
  ASSERT_TRUE(maze) << maze.message();
  ASSERT_TRUE(go_feap::world::saveScenePcd(*maze, (dir / "small.pcd").string()));
  const go_feap::common::Vec3 s = maze->start.position;
  std::ofstream(dir / "from_file.yaml") << "scene:\n  name: from_file\n  file: small.pcd\n"
                                           "  T_world_file: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n  resolution: 0.1\n"
                                           "  box: {min: [-5, -3, 0], max: [5, 3, 3]}\n"
                                           "  start: {position: [" << s.x() << ", " << s.y() << ", " << s.z()
                                        << "], yaw: 0}\n  ground_plane: false\n";
  // A name in UTF-8 (a Latin-1 byte is refused by the scene loader: it aborted go_feap_scene's JSON).
  std::ofstream(dir / "named.yaml") << "scene:\n  name: caf\xc3\xa9\n  generator: maze\n"
                                       "  maze: {size_x: 10.0, size_y: 6.0, height: 3.0, cell_size: 2.0}\n";
  const std::string bench = GO_FEAP_BENCH_BIN, out = (dir / "out").string();
  const auto [rc, said] = runCommand("timeout 300 " + bench + " --scene " + (dir / "from_file.yaml").string() + "," +
                                     (dir / "named.yaml").string() + " --planner go_feap,fuel --runs 2 --seed 3 "
                                     "--max-sim-time 2 --perf --out " + out);
  ASSERT_EQ(rc, 0) << said;
  EXPECT_NE(said.find("takes no seed: run once per planner"), std::string::npos) << said;
  std::size_t mapping_calls = 0;  // over the six runs' summaries
  for (const char* planner : {"go_feap", "fuel"}) {
    EXPECT_TRUE(fs::is_regular_file(fs::path(out) / "from_file" / planner / "seed0" / "summary.json")) << planner;
    EXPECT_FALSE(fs::exists(fs::path(out) / "from_file" / planner / "seed3")) << planner;
    EXPECT_FALSE(fs::exists(fs::path(out) / "from_file" / planner / "seed4")) << planner;
    for (const char* file : {"seed3/summary.json", "seed4/summary.json", "seed3/events.log"})
      EXPECT_TRUE(fs::is_regular_file(fs::path(out) / "named" / planner / file)) << planner << " " << file;
    for (const auto& [folder, seed] : std::vector<std::pair<std::string, int>>{{"from_file/", 0}, {"named/", 3}, {"named/", 4}}) {
      const fs::path file = fs::path(out) / (folder + std::string(planner)) / ("seed" + std::to_string(seed)) / "summary.json";
      const nlohmann::json summary = nlohmann::json::parse(readText(file), nullptr, false);
      ASSERT_TRUE(summary.is_object()) << file;
      EXPECT_EQ(summary["seed"], seed) << file;  // the run's own seed, which pairs the runs below
      mapping_calls += summary["compute_ms"]["mapping"]["count"].get<std::size_t>();
    }
  }
  // --perf: the calls of each block counted over every run.
  const std::size_t perf_at = said.find("\n  mapping ");
  ASSERT_NE(perf_at, std::string::npos) << said;
  const std::size_t calls_at = said.find('(', perf_at);
  EXPECT_EQ(said.substr(calls_at, said.find('\n', calls_at) - calls_at), "(" + std::to_string(mapping_calls) + " calls)")
      << said;
  // One coverage plot per scene (of its first seed), from_file's with its one seed.
  EXPECT_TRUE(fs::is_regular_file(fs::path(out) / "from_file_coverage.png"));
  EXPECT_TRUE(fs::is_regular_file(fs::path(out) / "named_coverage.png"));
  // The paired comparison: both of café's seeds, from_file's one.
  const nlohmann::json pairs = nlohmann::json::parse(readText(fs::path(out) / "comparison.json"), nullptr, false);
  ASSERT_TRUE(pairs.is_array() && pairs.size() == 2u) << pairs.dump();
  for (const nlohmann::json& c : pairs) EXPECT_EQ(c["pairs"], c["scene"] == "from_file" ? 1 : 2) << c.dump();
  const std::string table = readText(fs::path(out) / "table.json");
  EXPECT_NE(table.find("\"scene\": \"from_file\""), std::string::npos) << table;
  EXPECT_NE(table.find("\"runs\": 1"), std::string::npos) << table;
  EXPECT_NE(table.find("\"runs\": 2"), std::string::npos) << table;
  EXPECT_NE(table.find("\"scene\": \"caf\xc3\xa9\""), std::string::npos) << table;
  EXPECT_TRUE(fs::is_regular_file(fs::path(out) / "table.md"));
  EXPECT_TRUE(fs::is_regular_file(fs::path(out) / "comparison.json"));
  // Into the same folder with one planner: nothing compared, no comparison.json left over. One run with two
  // jobs: the table says one run had the cores.
  const auto [rc2, said2] = runCommand("timeout 300 " + bench + " --scene " + (dir / "named.yaml").string() +
                                       " --max-sim-time 2 --jobs 2 --out " + out);
  ASSERT_EQ(rc2, 0) << said2;
  EXPECT_NE(said2.find("already holds results"), std::string::npos) << said2;
  EXPECT_EQ(said.find("already holds results"), std::string::npos) << said;  // the first call's folder was new
  EXPECT_FALSE(fs::exists(fs::path(out) / "comparison.json"));
  const std::string md = readText(fs::path(out) / "table.md");
  EXPECT_NE(md.find("Compute times measured with 1 run(s) at a time"), std::string::npos) << md;
  // A scene name that would break table.md's rows: refused before any run.
  std::ofstream(dir / "piped.yaml") << "scene:\n  name: \"a|b\"\n  generator: maze\n"
                                       "  maze: {size_x: 10.0, size_y: 6.0, height: 3.0, cell_size: 2.0}\n";
  const auto [rc4, said4] = runCommand("timeout 60 " + bench + " --scene " + (dir / "piped.yaml").string() +
                                       " --max-sim-time 2 --out " + out);
  EXPECT_EQ(rc4, 1) << said4;
  EXPECT_NE(said4.find("its name has a '|' or a line break"), std::string::npos) << said4;
  // Two scenes bound for one results folder (the spec's stem names it): refused before any run.
  fs::copy_file(kSmallMaze, dir / "maze.yaml");
  const auto [rc3, said3] = runCommand("timeout 60 " + bench + " --scene maze," + (dir / "maze.yaml").string() +
                                       " --max-sim-time 2 --out " + out);
  EXPECT_EQ(rc3, 1) << said3;
  EXPECT_NE(said3.find("share the results folder"), std::string::npos) << said3;
  // Two scenes of one name (the tables group runs by it, and would merge them into one row): refused too.
  std::ofstream(dir / "named_again.yaml") << "scene:\n  name: caf\xc3\xa9\n  generator: maze\n"
                                             "  maze: {size_x: 8.0, size_y: 6.0, height: 3.0, cell_size: 2.0}\n";
  const auto [rc5, said5] = runCommand("timeout 60 " + bench + " --scene " + (dir / "named.yaml").string() + "," +
                                       (dir / "named_again.yaml").string() + " --max-sim-time 1 --out " + out);
  EXPECT_EQ(rc5, 1) << said5;
  EXPECT_NE(said5.find("share the scene name 'caf\xc3\xa9'"), std::string::npos) << said5;
  fs::remove_all(dir);
}

TEST(Bench, ConfigErrorsNameTheModeOrKey) {
  auto unknown = bench::loadExplorationConfig(GO_FEAP_CONFIG_DIR, "warp");
  ASSERT_FALSE(unknown);
  EXPECT_NE(unknown.message().find("unknown planner 'warp'"), std::string::npos) << unknown.message();
  auto missing = bench::loadExplorationConfig("/nonexistent", "go_feap");
  EXPECT_FALSE(missing);
  // A bad key of the coarse flight search stops the run with its section and key.
  const std::filesystem::path dir = configWithMode("bad", "coarse_astar:\n  stride: 0\n");
  auto bad = bench::loadExplorationConfig(dir.string(), "bad");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.message().find("coarse_astar: stride"), std::string::npos) << bad.message();
  std::filesystem::remove_all(dir);
  // A planning rate of 1e12 Hz: steps of a picosecond, a run that never ends.
  const std::filesystem::path fast_dir = configWithMode("fast", "global:\n  rate: 1.0e12\n");
  auto fast = bench::loadExplorationConfig(fast_dir.string(), "fast");
  ASSERT_FALSE(fast);
  EXPECT_NE(fast.message().find("global: rate must be in (0, 1000] Hz"), std::string::npos) << fast.message();
  std::filesystem::remove_all(fast_dir);
  // Faster than the control loop (100 Hz in bench.yaml): it ran at 100 Hz without a word.
  const std::filesystem::path over_dir = configWithMode("over", "global:\n  rate: 200.0\n");
  auto over = bench::loadExplorationConfig(over_dir.string(), "over");
  ASSERT_FALSE(over);
  EXPECT_NE(over.message().find("global: rate must be at most loop: control_rate (100.000000 Hz)"), std::string::npos)
      << over.message();
  std::filesystem::remove_all(over_dir);
  // Every mode is measured alike: a mode setting the collision rule is refused.
  const std::filesystem::path rule_dir = configWithMode("lenient", "metrics:\n  collision_distance: 0.01\n");
  auto lenient = bench::loadExplorationConfig(rule_dir.string(), "lenient");
  ASSERT_FALSE(lenient);
  EXPECT_NE(lenient.message().find("must not set 'metrics/*'"), std::string::npos) << lenient.message();
  // A collision distance of 0 never counted a collision (a centre inside an obstacle is at 0, not below), one
  // beyond the clearance horizon (0.5 m) counted one at the start and never another.
  const std::string yaml = readText(rule_dir / "exploration.yaml");
  const std::string key = "collision_distance: 0.1";
  const std::size_t at = yaml.find(key);
  ASSERT_NE(at, std::string::npos);
  for (const std::string distance : {"0.0", "0.6"}) {
    std::ofstream(rule_dir / "exploration.yaml") << std::string(yaml).replace(at, key.size(), "collision_distance: " + distance);
    auto bad_rule = bench::loadExplorationConfig(rule_dir.string(), "go_feap");
    ASSERT_FALSE(bad_rule) << distance;
    EXPECT_NE(bad_rule.message().find("metrics: collision_distance must be in (0, 0.5] m"), std::string::npos)
        << bad_rule.message();
  }
  std::filesystem::remove_all(rule_dir);
  // Any metrics key: max_odom_step would reach the ROS chain's layer manager and not its recorder.
  const std::filesystem::path step_dir = configWithMode("step", "metrics:\n  max_odom_step: 5.0\n");
  auto step = bench::loadExplorationConfig(step_dir.string(), "step");
  ASSERT_FALSE(step);
  EXPECT_NE(step.message().find("must not set 'metrics/*'"), std::string::npos) << step.message();
  std::filesystem::remove_all(step_dir);
}

// Each rate and the camera's extrinsic is checked, naming its key; a rate equal to the control rate is fine
// (each stage runs at most once a control step), and a run's time limit must be finite and > 0.
TEST(Bench, EveryRateAndTheTimeLimitAreCheckedNamingTheKey) {
  bench::LoopConfig loop;
  ASSERT_TRUE(loop.validate().ok()) << loop.validate().message();
  loop.sample_rate = 0.0;  // a metrics.csv of its first and last rows only
  EXPECT_EQ(loop.validate().message(), "metrics: sample_rate must be in (0, 1000] Hz");
  loop = bench::LoopConfig();
  loop.control_rate = 1e12;
  EXPECT_EQ(loop.validate().message(), "loop: control_rate must be in (0, 1000] Hz");
  loop.control_rate = 1000.0;
  EXPECT_TRUE(loop.validate().ok()) << loop.validate().message();

  auto loaded = bench::loadExplorationConfig(GO_FEAP_CONFIG_DIR, "go_feap");
  ASSERT_TRUE(loaded) << loaded.message();
  const bench::ExplorationConfig base = *loaded;
  auto says = [](const bench::ExplorationConfig& c, const std::string& what) {
    const go_feap::common::Status st = c.validate();
    EXPECT_FALSE(st.ok()) << what;
    EXPECT_NE(st.message().find(what), std::string::npos) << st.message();
  };
  {
    // A mapper reaching past the camera's range would take its "nothing in range" for free space through walls.
    bench::ExplorationConfig c = base;
    c.map.occupancy.max_range = c.camera.max_range + 0.5;
    says(c, "occupancy: max_range must not exceed depth_camera: max_range");
    c.map.occupancy.max_range = c.camera.max_range;
    EXPECT_TRUE(c.validate().ok()) << c.validate().message();
  }
  {
    // A camera wider than the mapper takes (rays within 85 degrees of the axis) had every frame refused in silence.
    bench::ExplorationConfig c = base;
    c.camera.hfov_deg = 175.0;
    says(c, "depth_camera: hfov_deg and vfov_deg (or fx, fy, cx, cy) are too wide for the mapper");
    c.camera.hfov_deg = 160.0;
    EXPECT_TRUE(c.validate().ok()) << c.validate().message();
    c = base;
    c.camera.fx = c.camera.fy = 1.0;  // given intrinsics: a focal length of one pixel
    c.camera.cx = 0.5 * c.camera.width;
    c.camera.cy = 0.5 * c.camera.height;
    says(c, "are too wide for the mapper: camera intrinsics are invalid");
  }
  {
    // A path ends at a voxel's centre: a goal tolerance under half a voxel's diagonal refused targets as blocked.
    bench::ExplorationConfig c = base;
    c.planner.goal_tolerance = 0.05;
    says(c, "planner: goal_tolerance must be at least half a voxel's diagonal (0.086603 m");
  }
  {
    // A viewpoint model that sees farther or wider than the mapper and the camera scores viewpoints on cells
    // a flight there does not map. Equal is fine: the shipped 80 x 60 degrees are written in rounded radians.
    bench::ExplorationConfig c = base;
    c.viewpoints.sensor_range = c.map.occupancy.max_range + 0.5;
    says(c, "viewpoints: sensor_range (5.000000 m) must not exceed occupancy: max_range (4.500000 m)");
    c.viewpoints.sensor_range = c.map.occupancy.max_range;
    c.viewpoints.hfov = c.camera.hfov_deg * M_PI / 180.0;
    c.viewpoints.vfov = c.camera.vfov_deg * M_PI / 180.0;
    EXPECT_TRUE(c.validate().ok()) << c.validate().message();
    c.viewpoints.hfov += 0.01;
    says(c, "viewpoints: hfov (1.406263 rad) must not exceed the depth camera's (1.396263 rad)");
    c.viewpoints.hfov -= 0.01;
    c.viewpoints.vfov += 0.01;
    says(c, "viewpoints: vfov");
    // Given intrinsics: a principal point 100 pixels off centre narrows the symmetric view to its near side.
    c = base;
    const auto K = c.camera.intrinsics();
    c.camera.fx = K.fx;
    c.camera.fy = K.fy;
    c.camera.cx = K.cx - 100.0;
    c.camera.cy = K.cy;
    says(c, "viewpoints: hfov");
    c.viewpoints.hfov = 2.0 * std::atan((K.cx - 99.5) / K.fx);
    EXPECT_TRUE(c.validate().ok()) << c.validate().message();
  }
  for (const double bad : {0.0, -5.0, std::numeric_limits<double>::quiet_NaN()}) {
    bench::ExplorationConfig c = base;
    c.layer_rate = bad;  // at 0 the state machine never stepped again; below, the run ended at once
    says(c, "layers: rate must be in (0, 1000] Hz");
    c = base;
    c.planner_rate = bad;
    says(c, "planner: rate must be in (0, 1000] Hz");
    c = base;
    c.camera_rate = bad;
    says(c, "depth_camera: rate must be in (0, 100] Hz");
  }
  bench::ExplorationConfig scaled = base;
  scaled.T_B_C.linear() *= 2.0;
  says(scaled, "depth_camera: T_B_C must be a finite rigid transform");
  bench::ExplorationConfig far = base;  // 100 mm written as metres
  far.T_B_C.translation() = go_feap::common::Vec3(100.0, 0.0, 20.0);
  says(far, "depth_camera: T_B_C must be a finite rigid transform with a translation of at most 2.000000 m");
  far.T_B_C.translation() = go_feap::common::Vec3(1.2, 0.0, 1.6);  // 2 m: a mount on a large vehicle
  EXPECT_TRUE(far.validate().ok()) << far.validate().message();
  // Each stage runs at most once a control step: a faster rate is refused by name (it ran at the control rate).
  const double control = base.loop.control_rate;
  auto faster = [&](auto set, const std::string& key) {
    bench::ExplorationConfig c = base;
    set(c);
    says(c, key + " must be at most loop: control_rate");
  };
  faster([&](bench::ExplorationConfig& c) { c.planner_rate = 2.0 * control; }, "planner: rate");
  faster([&](bench::ExplorationConfig& c) { c.layer_rate = 2.0 * control; }, "layers: rate");
  faster([&](bench::ExplorationConfig& c) { c.loop.sample_rate = 2.0 * control; }, "metrics: sample_rate");
  faster([&](bench::ExplorationConfig& c) { c.loop.plan_rate = 2.0 * control; }, "global: rate");
  faster([](bench::ExplorationConfig& c) { c.loop.control_rate = 50.0, c.camera_rate = 60.0; }, "depth_camera: rate");
  bench::ExplorationConfig equal = base;
  equal.loop.sample_rate = equal.loop.control_rate;  // once a control step: allowed
  equal.planner_rate = equal.loop.control_rate;
  EXPECT_TRUE(equal.validate().ok()) << equal.validate().message();

  auto scene = go_feap::world::makeScene(kSmallMaze, 0);
  ASSERT_TRUE(scene) << scene.message();
  for (const double bad : {0.0, -1.0, std::numeric_limits<double>::infinity(), std::numeric_limits<double>::quiet_NaN()})
    EXPECT_THROW(bench::ExplorationRun(*scene, base, "go_feap", bad), std::invalid_argument) << bad;
  // A start in free space but nearer a wall than metrics/collision_distance: a collision before the first step.
  go_feap::world::Scene near_wall = *scene;
  while (go_feap::metrics::obstacleDistance(near_wall, near_wall.start.position, 0.5) >= 0.05)
    near_wall.start.position.x() -= 0.01;
  ASSERT_FALSE(near_wall.isOccupied(near_wall.start.position));
  try {
    bench::ExplorationRun run(near_wall, base, "go_feap", 10.0);
    ADD_FAILURE() << "a start " << go_feap::metrics::obstacleDistance(near_wall, near_wall.start.position, 0.5)
                  << " m from a wall was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("under metrics/collision_distance"), std::string::npos) << e.what();
  }
}

// A mistyped value in any of the five files is refused naming the file and the key: a group whose reader's
// error went unchecked flew its struct default without a word.
TEST(Bench, AMistypedValueInAnyFileIsNamedWithTheFile) {
  const std::string go_feap_mode = readText(GO_FEAP_CONFIG_DIR "/modes/go_feap.yaml");
  for (const auto& [file, from, to, key] :
       std::vector<std::array<std::string, 4>>{
           {"sim.yaml", "  fx: 0.0", "  fx: wide", "depth_camera/fx"},
           {"mapping.yaml", "max_distance: 2.0", "max_distance: far", "esdf/max_distance"},
           {"exploration.yaml", "same_target_yaw: 0.3", "same_target_yaw: [0.3]", "local/same_target_yaw"},
           {"trajectory.yaml", "  a_max: 2.0", "  a_max: high", "optimizer/a_max"},
           {"bench.yaml", "control_rate: 100.0", "control_rate: fast", "loop/control_rate"}}) {
    const std::filesystem::path dir = configWithMode("go_feap", go_feap_mode);
    ASSERT_TRUE(replaceOnce(dir / file, from, to));
    auto c = bench::loadExplorationConfig(dir.string(), "go_feap");
    std::filesystem::remove_all(dir);
    ASSERT_FALSE(c) << file;
    EXPECT_NE(c.message().find("/" + file), std::string::npos) << c.message();
    EXPECT_NE(c.message().find(": parameter '" + key + "' has the wrong type"), std::string::npos) << c.message();
  }
}

// Rates whose shipped values equal the struct defaults are read all the same: a user's edit of any of them
// reaches the run. So do neighbouring keys of one line whose shipped values are equal (v_max and a_max 2.0,
// the same-target distance and heading 0.3, the camera's intrinsics all 0), each to its own field. (The
// intrinsics give 85 x 62 degrees: at least the viewpoints' 80 x 60.)
TEST(Bench, TheRatesAndNeighbouringKeysAreReadFromTheirFiles) {
  const std::filesystem::path dir = configWithMode("rates", "planner:\n  rate: 20.0\nlayers:\n  rate: 4.0\n");
  ASSERT_TRUE(replaceOnce(dir / "exploration.yaml", "sample_rate: 2.0", "sample_rate: 4.0"));
  ASSERT_TRUE(replaceOnce(dir / "bench.yaml", "control_rate: 100.0", "control_rate: 200.0"));
  ASSERT_TRUE(replaceOnce(dir / "sim.yaml", "  rate: 15.0", "  rate: 20.0"));
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"  fx: 0.0", "  fx: 350.0"}, {"  fy: 0.0", "  fy: 400.0"},
           {"  cx: 0.0", "  cx: 319.5"}, {"  cy: 0.0", "  cy: 239.5"}})
    ASSERT_TRUE(replaceOnce(dir / "sim.yaml", from, to));
  ASSERT_TRUE(replaceOnce(dir / "exploration.yaml", "same_target_distance: 0.3", "same_target_distance: 0.25"));
  ASSERT_TRUE(replaceOnce(dir / "trajectory.yaml", "  a_max: 2.0", "  a_max: 3.0"));
  auto c = bench::loadExplorationConfig(dir.string(), "rates");
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(c) << c.message();
  EXPECT_DOUBLE_EQ(c->planner_rate, 20.0);
  EXPECT_DOUBLE_EQ(c->layer_rate, 4.0);
  EXPECT_DOUBLE_EQ(c->loop.sample_rate, 4.0);
  EXPECT_DOUBLE_EQ(c->loop.control_rate, 200.0);
  EXPECT_DOUBLE_EQ(c->camera_rate, 20.0);
  EXPECT_DOUBLE_EQ(c->camera.fx, 350.0);
  EXPECT_DOUBLE_EQ(c->camera.fy, 400.0);
  EXPECT_DOUBLE_EQ(c->camera.cx, 319.5);
  EXPECT_DOUBLE_EQ(c->camera.cy, 239.5);
  EXPECT_DOUBLE_EQ(c->local.same_target_distance, 0.25);
  EXPECT_DOUBLE_EQ(c->local.same_target_yaw, 0.3);
  EXPECT_DOUBLE_EQ(c->optimizer.a_max, 3.0);
  EXPECT_DOUBLE_EQ(c->optimizer.v_max, 2.0);
}

// What a run records, against the run itself: rows of metrics.csv at t = 0 and every 1 / sample_rate s, the
// explored volume as the map's known voxels, the mapping block timed once a frame (the frontier update is
// its own block).
TEST(Bench, ARunsSamplesAndComputeTimesFollowItsRates) {
  auto config = bench::loadExplorationConfig(GO_FEAP_CONFIG_DIR, "go_feap");
  ASSERT_TRUE(config) << config.message();
  auto scene = go_feap::world::makeScene(kSmallMaze, 0);
  ASSERT_TRUE(scene) << scene.message();
  bench::ExplorationRun run(*scene, *config, "go_feap", 1.2);
  const auto wall0 = std::chrono::steady_clock::now();
  run.run();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  // The summary's wall time in seconds, within the call's; the map's memory in MiB.
  EXPECT_GT(run.recorder().summary().wall_time_s, 0.0);
  EXPECT_LE(run.recorder().summary().wall_time_s, wall);
  EXPECT_NEAR(run.recorder().summary().extra.at("map_memory_mb") * 1024.0 * 1024.0,
              static_cast<double>(run.map().memoryBytes()), 1e-6 * static_cast<double>(run.map().memoryBytes()));
  const auto& samples = run.recorder().samples();
  const double period = 1.0 / config->loop.sample_rate, dt = 1.0 / config->loop.control_rate;
  ASSERT_GE(samples.size(), 3u);
  EXPECT_EQ(samples[0].t, 0.0);
  for (std::size_t i = 1; i + 1 < samples.size(); ++i)  // the last is taken at the end
    EXPECT_NEAR(samples[i].t, i * period, dt + 1e-9) << i;
  const double res = run.map().geometry().resolution();
  EXPECT_DOUBLE_EQ(samples.back().explored_m3, static_cast<double>(run.map().occupancy().knownCount()) * res * res * res);
  EXPECT_GT(samples.back().explored_m3, 0.0);
  const auto& compute = run.recorder().summary().compute;
  ASSERT_TRUE(compute.count("mapping"));
  ASSERT_TRUE(compute.count("frontier"));
  const double end = run.recorder().summary().exploration_time_s;
  const std::size_t frames = static_cast<std::size_t>(std::floor(end * config->camera_rate + 1e-9)) + 1;
  EXPECT_LE(compute.at("mapping").count, frames) << "end " << end;
  EXPECT_GE(compute.at("mapping").count + 1, frames) << "end " << end;
  EXPECT_GE(compute.at("frontier").count, 1u);
  EXPECT_LE(compute.at("frontier").count, compute.at("mapping").count);
}

// The global tour and the local viewpoint run at global/rate, not at the trajectory planner's planner/rate:
// at 2 Hz a 5 s run plans at most 11 times (at 0, 0.5, ..., 5 s).
TEST(Bench, PlanningRunsAtTheGlobalRate) {
  auto config = bench::loadExplorationConfig(GO_FEAP_CONFIG_DIR, "go_feap");
  ASSERT_TRUE(config) << config.message();
  ASSERT_NE(config->planner_rate, 2.0);
  config->loop.plan_rate = 2.0;
  auto scene = go_feap::world::makeScene(kSmallMaze, 0);
  ASSERT_TRUE(scene) << scene.message();
  bench::ExplorationRun run(*scene, *config, "go_feap", 5.0);
  run.run();
  const auto& compute = run.recorder().summary().compute;
  ASSERT_TRUE(compute.count("global"));
  EXPECT_GE(compute.at("global").count, 2u);
  EXPECT_LE(compute.at("global").count, 11u);
  EXPECT_LE(compute.count("local") ? compute.at("local").count : 0u, compute.at("global").count);
}

// go_feap_map_perf's --skip-pixel thins the rays it integrates: every 8th pixel of the same three frames
// gives fewer rays per frame, after merging, than every pixel.
TEST(Bench, MapPerfsSkipPixelThinsTheRays) {
  auto raysPerFrame = [](int skip) {
    const auto [rc, said] = runCommand("timeout 120 " GO_FEAP_MAP_PERF_BIN " --scene maze --frames 3 --skip-pixel " +
                                       std::to_string(skip));
    EXPECT_EQ(rc, 0) << said;
    const std::string tag = "skip_pixel " + std::to_string(skip) + ", ";
    const std::size_t at = said.find(tag);
    EXPECT_NE(at, std::string::npos) << said;
    return at == std::string::npos ? -1.0 : std::stod(said.substr(at + tag.size()));
  };
  const double every = raysPerFrame(1), eighth = raysPerFrame(8);
  EXPECT_GT(eighth, 0.0);
  EXPECT_GT(every, eighth);
}

// A collision in a bench run reaches its summary: the start 0.2 m from an obstacle, with a collision distance
// of 0.5 m, is one collision (the vehicle hovering there does not leave it, so it is not counted again).
TEST(Bench, ACollisionReachesTheSummary) {
  auto config = bench::loadExplorationConfig(GO_FEAP_CONFIG_DIR, "go_feap");
  ASSERT_TRUE(config) << config.message();
  config->loop.collision_distance = 0.5;
  auto scene = go_feap::world::makeScene(kSmallMaze, 0);
  ASSERT_TRUE(scene) << scene.message();
  // An obstacle 0.2 m from the vehicle once the run has begun (a start that near one is refused): the run
  // holds the scene by reference, as its ground truth.
  bench::ExplorationRun run(*scene, *config, "go_feap", 5.0);
  ASSERT_TRUE(go_feap::world::markOccupied(*scene, scene->start.position + go_feap::common::Vec3(0.2, 0.0, 0.0)));
  ASSERT_TRUE(run.step());
  EXPECT_EQ(run.recorder().summary().collisions, 1);
  EXPECT_LE(run.recorder().summary().min_obstacle_distance_m, 0.2 + 1e-9);
}

// The camera's noise is drawn from the run's seed: the same maze under another seed is a run of its own.
TEST(Bench, TheNoiseFollowsTheSeed) {
  auto config = bench::loadExplorationConfig(GO_FEAP_CONFIG_DIR, "go_feap");
  ASSERT_TRUE(config) << config.message();
  config->camera.noise_stddev_per_m = 0.02;
  config->camera.dropout_probability = 0.05;
  auto scene = go_feap::world::makeScene(kSmallMaze, 1);
  ASSERT_TRUE(scene) << scene.message();
  go_feap::world::Scene other = *scene;
  other.seed = 2;  // the same walls
  bench::ExplorationRun a(*scene, *config, "go_feap", 5.0), b(other, *config, "go_feap", 5.0);
  ASSERT_TRUE(a.step());
  ASSERT_TRUE(b.step());
  EXPECT_NE(a.map().occupancy().knownCount(), b.map().occupancy().knownCount());
  // Dropouts alone (no noise) reach the camera too: with 90 % of the returns dropped the first frame maps less.
  config->camera.noise_stddev_per_m = 0.0;
  config->camera.dropout_probability = 0.9;
  bench::ExplorationRun dropped(*scene, *config, "go_feap", 5.0);
  config->camera.dropout_probability = 0.0;
  bench::ExplorationRun clean(*scene, *config, "go_feap", 5.0);
  ASSERT_TRUE(dropped.step());
  ASSERT_TRUE(clean.step());
  EXPECT_LT(dropped.map().occupancy().knownCount(), clean.map().occupancy().knownCount());
}

// A run never outlasts its time limit by more than a second of simulated time, however slowly the layer
// manager (which ends it there, at its next step) is stepped: at layers/rate 0.02 Hz a 2 s run flew 50 s.
TEST(Bench, ARunEndsWithinASecondOfItsTimeLimitWhateverTheLayerRate) {
  const std::filesystem::path dir = configWithMode("slow", "layers:\n  rate: 0.02\n");
  auto config = bench::loadExplorationConfig(dir.string(), "slow");
  std::filesystem::remove_all(dir);
  ASSERT_TRUE(config) << config.message();
  ASSERT_DOUBLE_EQ(config->layer_rate, 0.02);
  auto scene = go_feap::world::makeScene(kSmallMaze, 0);
  ASSERT_TRUE(scene) << scene.message();
  bench::ExplorationRun run(*scene, *config, "slow", 2.0);
  run.run();
  EXPECT_TRUE(run.ended());
  EXPECT_EQ(run.recorder().summary().finish_reason, "max_sim_time");
  EXPECT_LE(run.recorder().summary().exploration_time_s, 3.0 + 1e-9);
}

// The full maze's start (seed 2) faces a wall: the first view's frontier has about 200 cells. With a
// size limit of 220 nothing is a frontier there, and the run ended "complete" after 2.2 s at 0.1 %
// coverage; the layer manager now has the vehicle turn in place first, and the run explores.
TEST(Bench, AStartFacingAWallLooksRoundInsteadOfEndingComplete) {
  auto config = bench::loadExplorationConfig(GO_FEAP_CONFIG_DIR, "go_feap");
  ASSERT_TRUE(config) << config.message();
  config->frontier.min_cluster_cells = 220;
  auto scene = go_feap::world::makeScene("maze", 2);
  ASSERT_TRUE(scene) << scene.message();
  bench::ExplorationRun run(*scene, *config, "go_feap", 20.0);
  run.run();
  const auto& s = run.recorder().summary();
  EXPECT_EQ(s.finish_reason, "time_limit");
  EXPECT_GT(s.coverage, 0.05);
  EXPECT_GT(s.flight_distance_m, 2.0);
  bool turned = false;
  for (const std::string& e : run.events()) turned = turned || e.find("before a look round") != std::string::npos;
  EXPECT_TRUE(turned);
}

}  // namespace
