// Metrics, tables, YAML parameter reading and the target hysteresis, against hand-computed values
// and brute force.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "go_feap/common/yaml_reader.h"
#include "go_feap/metrics/metrics.h"
#include "go_feap/metrics/table.h"
#include "go_feap/planning/local_planner.h"
#include "go_feap/sim/depth_camera.h"
#include "go_feap/world/generators.h"

namespace {

using go_feap::common::Vec3;
namespace fs = std::filesystem;
namespace metrics = go_feap::metrics;

go_feap::metrics::Summary summary(const std::string& scene, const std::string& planner, double time, double distance,
                                  double coverage, int collisions, const std::string& reason, double global_ms) {
  metrics::Summary s;
  s.scene = scene;
  s.planner = planner;
  s.exploration_time_s = time;
  s.flight_distance_m = distance;
  s.coverage = coverage;
  s.collisions = collisions;
  s.finish_reason = reason;
  s.compute["global"].add(global_ms);
  s.compute["global"].add(3.0 * global_ms);  // mean 2 * global_ms
  s.compute["mapping"].add(1.0);
  return s;
}

// A 6 x 4 x 3 m maze.
go_feap::common::Result<go_feap::world::Scene> smallMaze(std::uint64_t seed) {
  go_feap::world::MazeConfig config;
  config.size_x = 6.0;
  config.size_y = 4.0;
  return go_feap::world::generateMaze(config, seed);
}

// Time and distance are over the finished runs (a run stopped at the time limit, or stuck early, did not explore
// the scene in its time); coverage and collisions over all.
// A BoundedTrail stays within its bound for a run of any length and spans the whole run evenly: the first
// item, every stride-th after it (the stride a power of two), and the latest. (Dropping every other item of
// the trail as it stood, each new one kept, left the first item and the last few only.)
TEST(BoundedTrail, StaysBoundedAndSpansTheWholeRunEvenly) {
  for (const std::size_t max : {std::size_t{3}, std::size_t{64}, std::size_t{4096}}) {
    go_feap::metrics::BoundedTrail<int> trail(max);
    for (int i = 0; i < 100000; ++i) {
      trail.add(i);
      const std::vector<int>& t = trail.items();
      ASSERT_LE(t.size(), max) << "after " << i;
      ASSERT_EQ(t.front(), 0);
      ASSERT_EQ(t.back(), i);
      if (i % 997 != 0 && i != 99999) continue;
      ASSERT_GE(t.size(), std::min<std::size_t>(max / 2, static_cast<std::size_t>(i) + 1)) << "after " << i;
      const int stride = t.size() > 1 ? t[1] - t[0] : 1;
      ASSERT_EQ(stride & (stride - 1), 0) << "stride " << stride;
      for (std::size_t k = 1; k + 1 < t.size(); ++k) ASSERT_EQ(t[k] - t[k - 1], stride) << "after " << i << " at " << k;
      ASSERT_LE(t.back() - t[t.size() - 2], stride);
    }
  }
}
TEST(Table, AggregatesPerSceneAndPlannerWithPopulationStd) {
  const std::vector<metrics::Summary> runs = {
      summary("maze", "go_feap", 100, 200, 0.99, 0, "complete", 1.0),
      summary("maze", "fuel", 150, 250, 1.00, 1, "complete", 5.0),
      summary("maze", "go_feap", 120, 220, 0.97, 0, "time_limit", 2.0),
      summary("maze", "go_feap", 110, 210, 1.00, 2, "complete", 3.0),
  };
  const auto rows = metrics::aggregate(runs);
  ASSERT_EQ(rows.size(), 2u);
  const metrics::TableRow& g = rows[0];
  EXPECT_EQ(g.planner, "go_feap");
  EXPECT_EQ(g.runs, 3);
  EXPECT_EQ(g.finished, 2);
  EXPECT_DOUBLE_EQ(g.exploration_time_s.avg, 105.0);  // 100 and 110; not the time-limit run's 120
  EXPECT_NEAR(g.exploration_time_s.std, 5.0, 1e-12);  // deviations -5, 5
  EXPECT_DOUBLE_EQ(g.exploration_time_s.max, 110.0);
  EXPECT_DOUBLE_EQ(g.exploration_time_s.min, 100.0);
  EXPECT_DOUBLE_EQ(g.flight_distance_m.avg, 205.0);
  EXPECT_NEAR(g.coverage_avg, (0.99 + 0.97 + 1.0) / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(g.coverage_min, 0.97);
  EXPECT_EQ(g.collisions, 2);
  EXPECT_DOUBLE_EQ(g.compute_ms.at("global"), (2.0 + 4.0 + 6.0) / 3.0);
  EXPECT_DOUBLE_EQ(g.compute_ms.at("mapping"), 1.0);
  EXPECT_DOUBLE_EQ(g.compute_ms.at("total"), 4.0);  // mapping is not a planning block
  EXPECT_EQ(rows[1].planner, "fuel");
  EXPECT_EQ(rows[1].runs, 1);
  EXPECT_DOUBLE_EQ(rows[1].exploration_time_s.std, 0.0);

  const nlohmann::json j = nlohmann::json::parse(metrics::tableJson(rows));
  ASSERT_TRUE(j.is_array());
  ASSERT_EQ(j.size(), 2u);
  EXPECT_EQ(j[0]["scene"], "maze");
  EXPECT_EQ(j[0]["runs"], 3);
  EXPECT_EQ(j[0]["finished"], 2);
  EXPECT_DOUBLE_EQ(j[0]["exploration_time_s"]["avg"].get<double>(), 105.0);
  EXPECT_DOUBLE_EQ(j[0]["flight_distance_m"]["min"].get<double>(), 200.0);
  EXPECT_DOUBLE_EQ(j[0]["coverage"]["min"].get<double>(), 0.97);
  EXPECT_EQ(j[0]["collisions"], 2);
  EXPECT_DOUBLE_EQ(j[0]["compute_ms"]["total"].get<double>(), 4.0);
  // Each figure under its own name, for each row.
  EXPECT_EQ(j[0]["planner"], "go_feap");
  EXPECT_EQ(j[1]["planner"], "fuel");
  EXPECT_NEAR(j[0]["exploration_time_s"]["std"].get<double>(), 5.0, 1e-12);
  EXPECT_DOUBLE_EQ(j[0]["exploration_time_s"]["max"].get<double>(), 110.0);
  EXPECT_DOUBLE_EQ(j[0]["exploration_time_s"]["min"].get<double>(), 100.0);
  EXPECT_DOUBLE_EQ(j[0]["flight_distance_m"]["avg"].get<double>(), 205.0);
  EXPECT_NEAR(j[0]["flight_distance_m"]["std"].get<double>(), 5.0, 1e-12);
  EXPECT_DOUBLE_EQ(j[0]["flight_distance_m"]["max"].get<double>(), 210.0);
  EXPECT_NEAR(j[0]["coverage"]["avg"].get<double>(), (0.99 + 0.97 + 1.0) / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(j[1]["exploration_time_s"]["avg"].get<double>(), 150.0);
  // Every run is counted by how it ended, the time-limit one (FINISHED too, not finished) included.
  EXPECT_EQ(j[0]["finish_reasons"], nlohmann::json({{"complete", 2}, {"time_limit", 1}}));
  EXPECT_EQ(j[1]["finish_reasons"], nlohmann::json({{"complete", 1}}));
  const std::string md = metrics::tableMarkdown(rows);
  EXPECT_NE(md.find("| maze | go_feap | 3 | 2 | 105.0 | 5.0 | 110.0 | 100.0 | 205.0 |"), std::string::npos) << md;
  EXPECT_NE(md.find("maze, go_feap: 1 of 3 runs did not finish (1 time_limit)."), std::string::npos) << md;
  EXPECT_EQ(md.find("maze, fuel:"), std::string::npos) << md;
}

// Compute per call pools the calls of every run, as --perf does: a run of 1 call at 10 ms and one of 3 calls at
// 2 ms make 4 ms a call (16 ms over 4 calls), not the 6 ms of their two means.
TEST(Table, ComputeIsAMeanPerCallOverEveryCallOfTheRuns) {
  std::vector<metrics::Summary> runs = {summary("maze", "go_feap", 100, 200, 0.99, 0, "complete", 1.0),
                                        summary("maze", "go_feap", 110, 210, 0.99, 0, "complete", 1.0)};
  for (metrics::Summary& s : runs) s.compute.clear();
  runs[0].compute["local"].add(10.0);
  for (int i = 0; i < 3; ++i) runs[1].compute["local"].add(2.0);
  runs[1].compute["frontier"].add(1.0);
  const auto rows = metrics::aggregate(runs);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_DOUBLE_EQ(rows[0].compute_ms.at("local"), 4.0);
  EXPECT_DOUBLE_EQ(rows[0].compute_ms.at("frontier"), 1.0);  // the one run that called it
  EXPECT_DOUBLE_EQ(rows[0].compute_ms.at("total"), 5.0);
  EXPECT_EQ(rows[0].compute_ms.count("global"), 0u);  // no run called it: no figure ("–")
  EXPECT_NE(metrics::tableMarkdown(rows).find("| maze | go_feap | – | 1.00 | – | 4.00 | – | 5.00 |"), std::string::npos)
      << metrics::tableMarkdown(rows);
  // Runs that never planned (stopped at once) have no total either, rather than 0 ms.
  for (metrics::Summary& s : runs) s.compute.clear();
  runs[0].compute["mapping"].add(3.0);
  const auto unplanned = metrics::aggregate(runs);
  EXPECT_EQ(unplanned[0].compute_ms.count("total"), 0u);
  EXPECT_NE(metrics::tableMarkdown(unplanned).find("| maze | go_feap | 3.00 | – | – | – | – | – |"), std::string::npos)
      << metrics::tableMarkdown(unplanned);
}

// A row whose runs all stopped unfinished has no time or distance (null, "–"), and a block a run never ran (it
// stopped before its first plan) does not count as 0 ms.
TEST(Table, RowsWithoutFinishedRunsAndBlocksARunNeverRanHaveNoFigureForThem) {
  std::vector<metrics::Summary> runs = {
      summary("maze", "go_feap", 100, 200, 0.99, 0, "complete", 1.0),
      summary("maze", "go_feap", 3, 1, 0.02, 0, "diverged", 1.0),
      summary("maze", "fuel", 3000, 900, 0.90, 0, "time_limit", 5.0),
      summary("maze", "fuel", 40, 50, 0.30, 0, "interrupted", 5.0),
  };
  runs[1].compute.erase("global");  // diverged before its first plan
  const auto rows = metrics::aggregate(runs);
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_DOUBLE_EQ(rows[0].exploration_time_s.avg, 100.0);
  EXPECT_DOUBLE_EQ(rows[0].compute_ms.at("global"), 2.0);  // the finished run's; the other never planned
  EXPECT_DOUBLE_EQ(rows[0].compute_ms.at("mapping"), 1.0);
  EXPECT_EQ(rows[1].finished, 0);
  EXPECT_TRUE(std::isnan(rows[1].exploration_time_s.avg));
  EXPECT_TRUE(std::isnan(rows[1].flight_distance_m.min));
  EXPECT_NEAR(rows[1].coverage_avg, 0.6, 1e-12);
  const nlohmann::json j = nlohmann::json::parse(metrics::tableJson(rows));
  EXPECT_TRUE(j[1]["exploration_time_s"]["avg"].is_null());
  EXPECT_TRUE(j[1]["flight_distance_m"]["std"].is_null());
  const std::string md = metrics::tableMarkdown(rows);
  EXPECT_NE(md.find("| maze | fuel | 2 | 0 | – | – | – | – | – | – | – | – | 60.0 | 30.0 | 0 |"), std::string::npos) << md;
}

// A run can end "complete" with frontiers it gave up on (blacklisted after failed attempts): the tables say how
// many of the finished runs did.
TEST(Table, CountsFinishedRunsThatLeftBlacklistedFrontiers) {
  std::vector<metrics::Summary> runs = {
      summary("maze", "go_feap", 100, 200, 0.99, 0, "complete", 1.0),
      summary("maze", "go_feap", 110, 200, 0.98, 0, "complete", 1.0),
      summary("maze", "go_feap", 120, 200, 0.90, 0, "time_limit", 1.0),
  };
  runs[1].blacklisted_frontiers = 2;
  runs[2].blacklisted_frontiers = 1;  // not finished: counted there already
  const auto rows = metrics::aggregate(runs);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].finished, 2);
  EXPECT_EQ(rows[0].finished_with_blacklisted, 1);
  const nlohmann::json j = nlohmann::json::parse(metrics::tableJson(rows));
  EXPECT_EQ(j[0]["finished_with_blacklisted"], 1);
  const std::string md = metrics::tableMarkdown(rows);
  EXPECT_NE(md.find("| maze | go_feap | 3 | 2 (1 left blacklisted frontiers) | 105.0 |"), std::string::npos) << md;
  runs[1].blacklisted_frontiers = 0;
  EXPECT_EQ(metrics::aggregate(runs)[0].finished_with_blacklisted, 0);
}

TEST(Table, ComparesTheFirstPlannerWithEachOtherPairedBySeed) {
  auto run = [](const std::string& scene, const std::string& planner, std::uint64_t seed, double time,
                double distance, const std::string& reason) {
    metrics::Summary s = summary(scene, planner, time, distance, 1.0, 0, reason, 1.0);
    s.seed = seed;
    return s;
  };
  const std::vector<metrics::Summary> runs = {
      run("maze", "go_feap", 0, 100, 200, "complete"),  run("maze", "fuel", 0, 110, 210, "complete"),
      run("maze", "go_feap", 1, 120, 220, "complete"),  run("maze", "fuel", 1, 100, 230, "complete"),
      run("maze", "go_feap", 2, 90, 180, "complete"),   // no fuel run of seed 2
      run("maze", "fuel", 3, 200, 400, "complete"),     // no go_feap run of seed 3
      run("maze", "go_feap", 4, 50, 60, "stuck"),       // paired, but stuck early: its 50 s compare with nothing
      run("maze", "fuel", 4, 130, 260, "complete"),
      run("maze", "nearest", 0, 150, 300, "complete"),
      run("maze", "nearest", 0, 999, 999, "complete"),  // a second run of one seed: the first is paired
      run("pillar", "go_feap", 0, 50, 60, "complete"),  // one planner: nothing to compare
      run("office", "go_feap", 0, 3000, 900, "time_limit"),  // no pair where both finished
      run("office", "fuel", 0, 200, 300, "complete"),
  };
  const auto c = metrics::compare(runs);
  ASSERT_EQ(c.size(), 3u);
  EXPECT_EQ(c[0].scene, "maze");
  EXPECT_EQ(c[0].planner, "go_feap");
  EXPECT_EQ(c[0].baseline, "fuel");
  EXPECT_EQ(c[0].pairs, 3);
  EXPECT_EQ(c[0].both_finished, 2);
  EXPECT_DOUBLE_EQ(c[0].time_ratio, 220.0 / 210.0);
  EXPECT_DOUBLE_EQ(c[0].distance_ratio, 420.0 / 440.0);
  EXPECT_DOUBLE_EQ(c[0].time_diff_avg, 5.0);  // differences -10 and +20
  EXPECT_NEAR(c[0].time_diff_se, 15.0, 1e-9);  // sample std sqrt(450) over sqrt(2)
  EXPECT_EQ(c[0].faster, 1);
  EXPECT_EQ(c[1].baseline, "nearest");
  EXPECT_EQ(c[1].pairs, 1);
  EXPECT_DOUBLE_EQ(c[1].time_ratio, 100.0 / 150.0);
  EXPECT_DOUBLE_EQ(c[1].time_diff_avg, -50.0);
  EXPECT_TRUE(std::isnan(c[1].time_diff_se));  // one pair: no standard error
  EXPECT_EQ(c[1].faster, 1);
  EXPECT_EQ(c[2].scene, "office");
  EXPECT_EQ(c[2].pairs, 1);
  EXPECT_EQ(c[2].both_finished, 0);
  EXPECT_TRUE(std::isnan(c[2].time_ratio));
  EXPECT_EQ(c[2].faster, 0);
  // The other way round: a baseline run that did not finish compares with nothing either.
  const auto unfinished_baseline = metrics::compare({run("maze", "go_feap", 0, 100, 200, "complete"),
                                                     run("maze", "fuel", 0, 900, 300, "time_limit"),
                                                     run("maze", "go_feap", 1, 120, 220, "complete"),
                                                     run("maze", "fuel", 1, 100, 230, "complete")});
  ASSERT_EQ(unfinished_baseline.size(), 1u);
  EXPECT_EQ(unfinished_baseline[0].pairs, 2);
  EXPECT_EQ(unfinished_baseline[0].both_finished, 1);
  EXPECT_DOUBLE_EQ(unfinished_baseline[0].time_ratio, 120.0 / 100.0);  // not 220 / 1000
  EXPECT_DOUBLE_EQ(unfinished_baseline[0].distance_ratio, 220.0 / 230.0);
  EXPECT_DOUBLE_EQ(unfinished_baseline[0].time_diff_avg, 20.0);
  EXPECT_TRUE(std::isnan(unfinished_baseline[0].time_diff_se));
  EXPECT_EQ(unfinished_baseline[0].faster, 0);  // seed 0's 100 s against a stopped 900 s is not faster
  // Three pairs (differences 0, 10 and 20 s): the sample standard deviation 10 over sqrt(3). With two pairs
  // the population and sample forms of the standard error agree; here they do not.
  std::vector<metrics::Summary> three_pairs;
  for (std::uint64_t seed = 0; seed < 3; ++seed) {
    three_pairs.push_back(run("maze", "go_feap", seed, 100.0 + 10.0 * seed, 200, "complete"));
    three_pairs.push_back(run("maze", "fuel", seed, 100, 200, "complete"));
  }
  const auto three = metrics::compare(three_pairs);
  ASSERT_EQ(three.size(), 1u);
  EXPECT_EQ(three[0].both_finished, 3);
  EXPECT_DOUBLE_EQ(three[0].time_diff_avg, 10.0);
  EXPECT_NEAR(three[0].time_diff_se, 10.0 / std::sqrt(3.0), 1e-9);
  EXPECT_DOUBLE_EQ(three[0].time_ratio, 1.1);
  EXPECT_EQ(three[0].faster, 0);

  const nlohmann::json j = nlohmann::json::parse(metrics::comparisonJson(c));
  ASSERT_TRUE(j.is_array());
  ASSERT_EQ(j.size(), 3u);
  EXPECT_EQ(j[0]["baseline"], "fuel");
  EXPECT_EQ(j[0]["pairs"], 3);
  EXPECT_TRUE(j[1]["time_diff_s"]["se"].is_null());
  EXPECT_TRUE(j[2]["time_ratio"].is_null());
  EXPECT_TRUE(j[2]["distance_ratio"].is_null());
  EXPECT_DOUBLE_EQ(j[0]["time_ratio"].get<double>(), 220.0 / 210.0);
  EXPECT_DOUBLE_EQ(j[0]["distance_ratio"].get<double>(), 420.0 / 440.0);  // not the time ratio
  EXPECT_EQ(j[0]["both_finished"], 2);
  EXPECT_EQ(j[0]["faster"], 1);
  EXPECT_EQ(j[0]["scene"], "maze");
  EXPECT_EQ(j[0]["planner"], "go_feap");
  EXPECT_DOUBLE_EQ(j[0]["time_diff_s"]["avg"].get<double>(), 5.0);
  EXPECT_NEAR(j[0]["time_diff_s"]["se"].get<double>(), 15.0, 1e-9);
  const std::string md = metrics::tableMarkdown(metrics::aggregate(runs), c);
  EXPECT_NE(md.find("| maze | go_feap | fuel | 3 | 2 | 1.048 | 0.955 | 5.0 | 15.0 | 1 of 2 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| maze | go_feap | nearest | 1 | 1 | 0.667 | 0.667 | -50.0 | – | 1 of 1 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| office | go_feap | fuel | 1 | 0 | – | – | – | – | 0 of 0 |"), std::string::npos) << md;
  EXPECT_EQ(metrics::tableMarkdown(metrics::aggregate(runs)).find("Paired by seed"), std::string::npos);
}

// Collisions are totalled over every run of a row, finished or not (1 + 2 + 0, the second stopped at the time
// limit); a tie in the paired comparison is not "faster" (seed 0 at 100 s for both).
TEST(Table, CollisionsAreTotalledOverAllRunsAndATieIsNotFaster) {
  const std::vector<metrics::Summary> runs = {
      summary("maze", "go_feap", 100, 200, 0.9, 1, "complete", 1.0),
      summary("maze", "go_feap", 120, 220, 0.9, 2, "time_limit", 1.0),
      summary("maze", "go_feap", 110, 210, 0.9, 0, "complete", 1.0),
  };
  const auto rows = metrics::aggregate(runs);
  ASSERT_EQ(rows.size(), 1u);
  EXPECT_EQ(rows[0].collisions, 3);
  EXPECT_EQ(nlohmann::json::parse(metrics::tableJson(rows))[0]["collisions"], 3);
  // The Markdown row's last column is the collisions (3), not the finished runs (2).
  const std::string row_md = metrics::tableMarkdown(rows);
  EXPECT_NE(row_md.find("| maze | go_feap | 3 | 2 | 105.0 | 5.0 | 110.0 | 100.0 | 205.0 | 5.0 | 210.0 | 200.0 | 90.0 | "
                        "90.0 | 3 |"),
            std::string::npos)
      << row_md;

  auto run = [](const std::string& planner, std::uint64_t seed, double time) {
    metrics::Summary s = summary("maze", planner, time, 100, 1.0, 0, "complete", 1.0);
    s.seed = seed;
    return s;
  };
  const auto c = metrics::compare({run("go_feap", 0, 100), run("go_feap", 1, 90), run("fuel", 0, 100), run("fuel", 1, 100)});
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].both_finished, 2);
  EXPECT_EQ(c[0].faster, 1);
  EXPECT_DOUBLE_EQ(c[0].time_diff_avg, -5.0);
  const std::string md = metrics::tableMarkdown(metrics::aggregate({run("go_feap", 0, 100)}), c);
  EXPECT_NE(md.find("| 1 of 2 |"), std::string::npos) << md;
}

// The trajectory block is planning: Table IV's total and summary.json's compute_ms.total are the planning
// blocks' means (trajectory 6 + global 2), without mapping (1).
TEST(Table, ThePlanningTotalCountsTheTrajectoryBlockAndNotMapping) {
  metrics::Summary s = summary("maze", "go_feap", 100, 200, 1.0, 0, "complete", 1.0);
  s.compute.clear();
  s.compute["trajectory"].add(6.0);
  s.compute["global"].add(2.0);
  s.compute["mapping"].add(1.0);
  EXPECT_TRUE(metrics::isComputeBlock("trajectory"));
  EXPECT_TRUE(metrics::isPlanningBlock("trajectory"));
  EXPECT_FALSE(metrics::isPlanningBlock("mapping"));
  EXPECT_DOUBLE_EQ(metrics::aggregate({s})[0].compute_ms.at("total"), 8.0);
  const nlohmann::json j = nlohmann::json::parse(metrics::summaryJson(s));
  EXPECT_DOUBLE_EQ(j["compute_ms"]["total"]["mean"].get<double>(), 8.0);
  // Table IV's columns in their order: mapping, frontier (none), global, local (none), trajectory, total.
  const std::string md = metrics::tableMarkdown(metrics::aggregate({s}));
  EXPECT_NE(md.find("| maze | go_feap | 1.00 | – | 2.00 | – | 6.00 | 8.00 |"), std::string::npos) << md;
  // Mapping is a block of the chain (the ROS recorder takes its times), though not a planning one.
  EXPECT_TRUE(metrics::isComputeBlock("mapping"));
  EXPECT_FALSE(metrics::isComputeBlock("total"));
}

TEST(Metrics, ObstacleDistanceMatchesBruteForceOverVoxelCubes) {
  auto scene = smallMaze(3);
  ASSERT_TRUE(scene) << scene.message();
  const auto& geo = scene->geometry();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> ux(-3, 3), uy(-2, 2), uz(0.2, 2.8);
  for (int k = 0; k < 200; ++k) {
    const Vec3 p(ux(rng), uy(rng), uz(rng));
    double brute = 0.6;
    for (std::size_t l = 0; l < geo.size(); ++l) {
      if (!scene->occupied[l]) continue;
      const Vec3 lo = geo.origin() + geo.unlinear(l).cast<double>() * geo.resolution();
      const Vec3 d = (lo - p).cwiseMax(p - (lo + Vec3::Constant(geo.resolution()))).cwiseMax(0.0);
      brute = std::min(brute, d.norm());
    }
    EXPECT_NEAR(metrics::obstacleDistance(*scene, p, 0.6), brute, 1e-12) << p.transpose();
  }
  // Far outside the grid (a wrong odometry, finite): the horizon. 2e8 m made an int loop bound overflow
  // and crashed the metrics recorder.
  const Vec3 corner = geo.bounds().max;
  for (const Vec3& far : {Vec3(214748353.75, 0.0, 1.0), Vec3(-2.2e9, 0.0, 1.0), Vec3(0.0, 1e30, -1e30),
                          Vec3(corner + Vec3::Constant(0.7)), Vec3(std::nan(""), 0.0, 1.0)})
    EXPECT_EQ(metrics::obstacleDistance(*scene, far, 0.6), 0.6) << far.transpose();
}

// A start nearer an obstacle than collision_distance (in free space, so validateScene() takes it) is refused
// naming the start, its clearance and the key: every run from there began with a collision.
TEST(Metrics, AStartNearerAnObstacleThanTheCollisionDistanceIsRefused) {
  auto scene = smallMaze(3);
  ASSERT_TRUE(scene) << scene.message();
  EXPECT_TRUE(metrics::checkStartClearance(*scene, 0.1).ok()) << metrics::checkStartClearance(*scene, 0.1).message();
  // Walk from the start until the clearance drops under 0.08 m.
  Vec3 p = scene->start.position;
  double clearance = metrics::obstacleDistance(*scene, p, 0.5);
  for (int k = 0; k < 1000 && clearance >= 0.08; ++k) {
    p.x() += 0.01;
    clearance = metrics::obstacleDistance(*scene, p, 0.5);
  }
  ASSERT_GT(clearance, 0.01);
  ASSERT_LT(clearance, 0.08);
  scene->start.position = p;
  ASSERT_TRUE(go_feap::world::validateScene(*scene).ok());
  const auto refused = metrics::checkStartClearance(*scene, 0.1);
  ASSERT_FALSE(refused.ok());
  std::ostringstream says;
  says << "the start (" << p.x() << ", " << p.y() << ", " << p.z() << ") lies " << clearance
       << " m from an obstacle, under metrics/collision_distance (0.1 m)";
  EXPECT_NE(refused.message().find(says.str()), std::string::npos) << refused.message() << "\n" << says.str();
  EXPECT_TRUE(metrics::checkStartClearance(*scene, 0.99 * clearance).ok());
}

TEST(Metrics, CollisionMonitorCountsEachEntryAndKeepsTheClosestApproach) {
  auto scene = smallMaze(3);
  ASSERT_TRUE(scene) << scene.message();
  // Along a line that crosses walls: every entry into the 0.1 m zone is one collision, which ends once
  // the clearance is back to 0.15 m.
  metrics::CollisionMonitor monitor(*scene, 0.1);
  int entries = 0;
  bool inside = false;
  double closest = metrics::CollisionMonitor::kHorizon;
  for (int k = 0; k < 4 * 581; ++k) {
    // Four lines along x, at y = -1.5, -0.5, 0.5, 1.5, walked one after the other.
    const Vec3 p(-2.9 + 0.01 * (k % 581), -1.5 + (k / 581), 1.0);
    const double d = metrics::obstacleDistance(*scene, p, metrics::CollisionMonitor::kHorizon);
    closest = std::min(closest, d);
    const bool entered = !inside && d < 0.1;
    entries += entered;
    inside = inside ? d < 0.15 : entered;
    EXPECT_EQ(monitor.update(p), entered) << p.transpose();
    EXPECT_DOUBLE_EQ(monitor.lastClearance(), d);
  }
  EXPECT_GT(entries, 0) << "the line must cross a wall in this fixture";
  EXPECT_EQ(monitor.collisions(), entries);
  EXPECT_DOUBLE_EQ(monitor.closestApproach(), closest);

  // Scraping along a wall, the clearance jittering between 0.09 and 0.12 m: one collision. Away to
  // 0.2 m and back: a second. Points at a given clearance: from a point on the line inside a wall,
  // out along an axis to open space (0.25 m clear 0.3 m out), bisected.
  Vec3 wall_point, out;
  bool found = false;
  for (int k = 0; k < 4 * 581 && !found; ++k) {
    wall_point = Vec3(-2.9 + 0.01 * (k % 581), -1.5 + (k / 581), 1.0);
    if (metrics::obstacleDistance(*scene, wall_point, 0.6) > 0.0) continue;
    for (const Vec3& dir : {Vec3(1, 0, 0), Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, -1, 0)})
      if (!found && metrics::obstacleDistance(*scene, wall_point + 0.3 * dir, 0.6) >= 0.25) {
        out = dir;
        found = true;
      }
  }
  ASSERT_TRUE(found) << "no wall point with open space beside it on the lines";
  const auto at = [&](double clearance) {
    double lo = 0.0, hi = 0.3;
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (lo + hi);
      (metrics::obstacleDistance(*scene, wall_point + mid * out, 0.6) < clearance ? lo : hi) = mid;
    }
    return Vec3(wall_point + hi * out);
  };
  metrics::CollisionMonitor scrape(*scene, 0.1);
  for (int k = 0; k < 20; ++k) scrape.update(at(k % 2 ? 0.09 : 0.12));
  EXPECT_EQ(scrape.collisions(), 1) << "a scrape with jitter round 0.1 m";
  scrape.update(at(0.2));
  scrape.update(at(0.09));
  EXPECT_EQ(scrape.collisions(), 2) << "away to 0.2 m and back";

  // A collision distance over a third of the horizon releases at the horizon (1.5 x 0.4 m would lie beyond
  // what a clearance can read, and the first collision would never end): in a wall, far off, in again is two.
  ASSERT_TRUE(metrics::CollisionMonitor::validDistance(metrics::CollisionMonitor::kHorizon));
  metrics::CollisionMonitor wide(*scene, 0.4);
  const Vec3 far = scene->geometry().bounds().max + Vec3::Constant(0.7);
  EXPECT_TRUE(wide.update(wall_point));
  EXPECT_FALSE(wide.update(far));
  EXPECT_TRUE(wide.update(wall_point));
  EXPECT_EQ(wide.collisions(), 2);
}

// The scene's observable voxels known in the map, over all of them: with the map at the scene's resolution,
// and with a coarser map (0.2 m over a 0.1 m scene), where one map voxel stands for the several scene voxels
// whose centres it holds and counts for each of them.
TEST(Metrics, CoverageTrackerEqualsTheWorldDefinition) {
  auto scene = smallMaze(1);
  ASSERT_TRUE(scene);
  ASSERT_DOUBLE_EQ(scene->resolution(), 0.1);
  const auto observable = go_feap::world::computeObservableSet(*scene);
  for (const double resolution : {0.1, 0.2}) {
    SCOPED_TRACE("map resolution " + std::to_string(resolution));
    go_feap::map::OccupancyConfig config;
    config.resolution = resolution;
    go_feap::map::OccupancyMap map(config, scene->box);
    std::mt19937 rng(2);
    const auto& geo = map.geometry();
    const metrics::CoverageTracker tracker(*scene, geo);
    EXPECT_EQ(tracker.coverage(map), 0.0);
    for (int k = 0; k < 20000; ++k) {
      const go_feap::common::Index3 idx(rng() % geo.dims().x(), rng() % geo.dims().y(), rng() % geo.dims().z());
      map.setState(idx, k % 3 ? go_feap::map::VoxelState::kFree : go_feap::map::VoxelState::kOccupied);
    }
    const double expected = go_feap::world::coverage(
        observable, [&](const Vec3& c) { return map.state(c) != go_feap::map::VoxelState::kUnknown; });
    EXPECT_GT(expected, 0.0);
    EXPECT_LT(expected, 1.0);
    EXPECT_DOUBLE_EQ(tracker.coverage(map), expected);
    EXPECT_EQ(tracker.observableCount(), observable.total());
    // Every map voxel known: all of it.
    for (std::size_t l = 0; l < geo.size(); ++l) map.setState(geo.unlinear(l), go_feap::map::VoxelState::kFree);
    EXPECT_DOUBLE_EQ(tracker.coverage(map), 1.0);
  }
}

// The incremental count (reset, then the changed voxels of each frame) equals a full count after every
// frame of a camera flying through the maze, integrated by the real mapper: with the map at the scene's
// resolution and with a coarser one (0.2 m over 0.1 m), whose voxels each count for several scene voxels.
TEST(Metrics, IncrementalCoverageEqualsTheFullCountFrameByFrame) {
  auto scene = smallMaze(1);
  ASSERT_TRUE(scene);
  ASSERT_DOUBLE_EQ(scene->resolution(), 0.1);
  const go_feap::sim::DepthRenderer renderer(go_feap::sim::DepthCameraConfig(), *scene);
  const auto& ci = renderer.intrinsics();
  const go_feap::map::DepthIntrinsics K{ci.width, ci.height, ci.fx, ci.fy, ci.cx, ci.cy};
  Eigen::Matrix3d R_B_C;  // optical frame (z forward, x right, y down) in the body frame (x forward, z up)
  R_B_C << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  for (const double resolution : {0.1, 0.2}) {
    SCOPED_TRACE("map resolution " + std::to_string(resolution));
    go_feap::map::OccupancyConfig config;
    config.resolution = resolution;
    go_feap::map::OccupancyMap map(config, scene->box);
    metrics::CoverageTracker tracker(*scene, map.geometry());
    tracker.reset(map);
    EXPECT_EQ(tracker.current(), 0.0);
    cv::Mat depth;
    double last = 0.0;
    for (int k = 0; k < 24; ++k) {
      // Turn in place at the start, then step along x: the camera looks along the body x axis.
      Eigen::Isometry3d T_W_C = Eigen::Isometry3d::Identity();
      const double yaw = 0.5 * k;
      T_W_C.linear() = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix() * R_B_C;
      T_W_C.translation() = scene->start.position + Vec3(k >= 12 ? 0.1 * (k - 12) : 0.0, 0.0, 0.0);
      renderer.render(T_W_C, depth);
      auto change = map.integrate(depth, K, T_W_C);
      ASSERT_TRUE(change) << change.message();
      tracker.update(map, change->changed);
      ASSERT_DOUBLE_EQ(tracker.current(), tracker.coverage(map)) << "frame " << k;
      EXPECT_GE(tracker.current(), last);
      last = tracker.current();
    }
    EXPECT_GT(last, 0.05);
    // A fresh start from the same map agrees too.
    metrics::CoverageTracker again(*scene, map.geometry());
    again.reset(map);
    EXPECT_DOUBLE_EQ(again.current(), tracker.coverage(map));
  }
}

// A finish reason (it comes in a status message) that is not UTF-8: the summary is still written, with
// U+FFFD for the bad byte. nlohmann's dump threw, and the run ended without summary.json.
TEST(Metrics, SummaryWithBytesThatAreNotTextIsStillWritten) {
  metrics::Summary s = summary("maze", "go_feap", 10.0, 12.5, 0.5, 1, "comp\xfflete", 2.0);
  std::string json;
  ASSERT_NO_THROW(json = metrics::summaryJson(s));
  EXPECT_NE(json.find("\"finish_reason\": \"comp\xef\xbf\xbdlete\""), std::string::npos) << json;
  metrics::Recorder r;
  r.summary() = s;
  const fs::path dir = fs::temp_directory_path() / "go_feap_test_recorder_bytes";
  fs::remove_all(dir);
  EXPECT_TRUE(r.writeAll(dir.string()).ok());
  EXPECT_TRUE(fs::exists(dir / "summary.json"));
  fs::remove_all(dir);
}

// summary.json's figures are the run's own: its seed, collisions, closest approach and each block's calls.
TEST(Metrics, SummaryJsonHoldsTheRunsSeedCollisionsAndCallCounts) {
  metrics::Summary s = summary("maze", "go_feap", 10.0, 12.5, 0.5, 2, "complete", 2.0);
  s.seed = 7;
  s.min_obstacle_distance_m = 0.25;
  s.compute["frontier"].add(1.0);
  s.compute["frontier"].add(3.0);
  const nlohmann::json j = nlohmann::json::parse(metrics::summaryJson(s));
  EXPECT_EQ(j["seed"], 7);
  EXPECT_EQ(j["collisions"], 2);
  EXPECT_DOUBLE_EQ(j["min_obstacle_distance_m"].get<double>(), 0.25);
  EXPECT_EQ(j["compute_ms"]["frontier"]["count"], 2);
  EXPECT_DOUBLE_EQ(j["compute_ms"]["frontier"]["mean"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(j["compute_ms"]["frontier"]["max"].get<double>(), 3.0);
  EXPECT_EQ(j["compute_ms"]["global"]["count"], 2);
  EXPECT_EQ(j["compute_ms"]["mapping"]["count"], 1);
  EXPECT_DOUBLE_EQ(j["compute_ms"]["total"]["mean"].get<double>(), 2.0 + 4.0);  // frontier and global, not mapping
}

// Onboard or in a replay there is no scene to compare with: the figures that need one are null, not the
// 0 m from an obstacle, no collision and coverage -1 that read as measured.
TEST(Metrics, FiguresWithoutGroundTruthAreNull) {
  metrics::Summary s = summary("onboard", "go_feap", 10.0, 12.5, -1.0, 0, "complete", 2.0);
  s.ground_truth = false;
  const nlohmann::json j = nlohmann::json::parse(metrics::summaryJson(s));
  for (const char* key : {"coverage", "collisions", "min_obstacle_distance_m"}) EXPECT_TRUE(j[key].is_null()) << key;
  EXPECT_DOUBLE_EQ(j["exploration_time_s"].get<double>(), 10.0);
  EXPECT_DOUBLE_EQ(j["flight_distance_m"].get<double>(), 12.5);
  // With a scene but no map heard before the end (the mapper down), coverage is -1: not measured, null.
  s.ground_truth = true;
  const nlohmann::json k = nlohmann::json::parse(metrics::summaryJson(s));
  EXPECT_TRUE(k["coverage"].is_null()) << k.dump();
  EXPECT_EQ(k["collisions"].get<int>(), 0);
  s.coverage = 0.0;
  EXPECT_DOUBLE_EQ(nlohmann::json::parse(metrics::summaryJson(s))["coverage"].get<double>(), 0.0);
}

// Samples of unknown coverage (negative: onboard, replayed, or before the first map) are not drawn: a series
// of them alone leaves only its legend in the series' colour, where a measured one draws its line (at 0 %
// they used to be drawn as a line along the bottom).
TEST(Metrics, ThePlotLeavesOutSamplesOfUnknownCoverage) {
  auto colourPixels = [](const std::vector<metrics::Sample>& samples) {
    const std::filesystem::path png = std::filesystem::temp_directory_path() / "go_feap_test_plot_unknown.png";
    EXPECT_TRUE(metrics::plotCoverage({{"run", samples}}, "unknown", png.string()).ok());
    const cv::Mat img = cv::imread(png.string());
    std::filesystem::remove(png);
    int n = 0;
    for (int y = 0; y < img.rows; ++y)
      for (int x = 0; x < img.cols; ++x) {
        const cv::Vec3b p = img.at<cv::Vec3b>(y, x);  // BGR; the first series is (200, 90, 20)
        n += std::abs(p[0] - 200) < 40 && std::abs(p[1] - 90) < 40 && std::abs(p[2] - 20) < 40;
      }
    return n;
  };
  std::vector<metrics::Sample> unknown(11), measured(11);
  for (int i = 0; i <= 10; ++i) {
    unknown[i].t = measured[i].t = i;
    unknown[i].coverage = -1.0;
    measured[i].coverage = 0.0;
  }
  const int legend = colourPixels(unknown), line = colourPixels(measured);
  EXPECT_GT(legend, 0) << "no legend";
  EXPECT_GT(line, legend + 300) << "the measured series drew no line";
  EXPECT_LT(legend, 200) << "samples of unknown coverage were drawn";
}

TEST(Metrics, RecorderWritesSummaryCsvAndPlot) {
  metrics::Recorder r;
  r.summary() = summary("maze", "go_feap", 10.0, 12.5, 0.5, 1, "complete", 2.0);
  r.summary().blacklisted_frontiers = 3;
  r.summary().wall_time_s = 3.5;
  r.summary().extra["map_memory_mb"] = 12.25;
  for (int i = 0; i <= 10; ++i) {
    metrics::Sample s;  // every field its own value, so that a column swapped or dropped shows
    s.t = i;
    s.coverage = 0.05 * i;
    s.explored_m3 = 2.5 * i;
    s.distance = 1.25 * i;
    s.layer = i % 3;
    s.frontiers = 10 + i;
    s.position = Vec3(i, -0.5 * i, 1.0 + 0.1 * i);
    r.addSample(s);
  }
  const fs::path dir = fs::temp_directory_path() / "go_feap_test_recorder";
  fs::remove_all(dir);
  ASSERT_TRUE(r.writeAll(dir.string()).ok());
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "summary.json"));
  for (const char* key : {"scene", "seed", "planner", "finish_reason", "exploration_time_s", "flight_distance_m",
                          "coverage", "collisions", "blacklisted_frontiers", "compute_ms"})
    EXPECT_TRUE(j.contains(key)) << key;
  EXPECT_EQ(j["blacklisted_frontiers"], 3);
  EXPECT_DOUBLE_EQ(j["wall_time_s"].get<double>(), 3.5);
  EXPECT_DOUBLE_EQ(j["map_memory_mb"].get<double>(), 12.25);  // the extra figures, each at the top level
  EXPECT_DOUBLE_EQ(j["compute_ms"]["global"]["mean"].get<double>(), 4.0);
  EXPECT_DOUBLE_EQ(j["compute_ms"]["global"]["max"].get<double>(), 6.0);
  std::ifstream csv(dir / "metrics.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header, "t,coverage,explored_m3,distance,layer,frontiers,x,y,z");
  std::vector<std::string> rows;
  while (std::getline(csv, line)) rows.push_back(line);
  ASSERT_EQ(rows.size(), 11u);
  EXPECT_EQ(rows[5], "5.000,0.25000,12.500,6.250,2,15,5.000,-2.500,1.500");
  {  // samples 1 ms apart (metrics/sample_rate up to 1000 Hz) keep their own times
    metrics::Recorder fast;
    for (int i = 0; i < 3; ++i) {
      metrics::Sample s;
      s.t = 10.0 + 0.001 * i;
      fast.addSample(s);
    }
    const fs::path fast_csv = fs::temp_directory_path() / "go_feap_test_fast.csv";
    ASSERT_TRUE(fast.writeCsv(fast_csv.string()).ok());
    std::ifstream in(fast_csv);
    std::vector<std::string> times;
    for (std::getline(in, line); std::getline(in, line);) times.push_back(line.substr(0, line.find(',')));
    EXPECT_EQ(times, (std::vector<std::string>{"10.000", "10.001", "10.002"}));
    fs::remove(fast_csv);
  }
  const cv::Mat plot = cv::imread((dir / "coverage.png").string());
  ASSERT_EQ(plot.cols, 800);
  ASSERT_EQ(plot.rows, 500);
  // The series (the first colour, BGR 200 90 20) passes through (5 s, 25 %): the plot area spans x 70 .. 780
  // for 0 .. 10 s and y 445 .. 40 for 0 .. 100 %; at (5 s, 75 %) there is none.
  auto seriesAt = [&](int x, int y) {
    return cv::norm(cv::Vec3d(plot.at<cv::Vec3b>(y, x)) - cv::Vec3d(200, 90, 20)) < 60.0;
  };
  EXPECT_TRUE(seriesAt(425, 445 - 101));
  EXPECT_FALSE(seriesAt(425, 445 - 304));
  EXPECT_FALSE(r.writeAll("/proc/go_feap_no_such_dir").ok());
  for (const auto& entry : fs::directory_iterator(dir))
    EXPECT_EQ(entry.path().filename().string().rfind(".partial-", 0), std::string::npos) << entry.path() << " left";
  fs::remove_all(dir);

  // summary.json comes last: when the plot cannot take its place (a directory of that name is in the
  // way), the call fails naming it and there is no summary.json to say the run's files are all there.
  fs::create_directories(dir / "coverage.png" / "in_the_way");
  const go_feap::common::Status blocked = r.writeAll(dir.string());
  EXPECT_FALSE(blocked.ok());
  EXPECT_NE(blocked.message().find("coverage.png"), std::string::npos) << blocked.message();
  EXPECT_FALSE(fs::exists(dir / "summary.json"));
  EXPECT_TRUE(fs::exists(dir / "metrics.csv"));
  EXPECT_FALSE(fs::exists(dir / ".partial-coverage.png"));
  fs::remove_all(dir);
}

TEST(YamlReader, ReadsNestedKeysOverlaysAndNamesBadOnes) {
  const fs::path dir = fs::temp_directory_path() / "go_feap_test_yaml";
  fs::create_directories(dir);
  std::ofstream(dir / "base.yaml") << "a:\n  x: 1.5\n  n: 3\n  v: [1, 2, 3]\n  s: word\nflag: true\n";
  std::ofstream(dir / "over.yaml") << "a:\n  x: 2.5\n";
  go_feap::common::YamlReader r({(dir / "base.yaml").string(), (dir / "over.yaml").string()});
  double x = 0;
  int n = 0;
  bool flag = false;
  std::string s;
  Eigen::Vector3d v;
  r.get("a/x", x).get("a/n", n).get("flag", flag).get("a/s", s).getVec3("a/v", v);
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_DOUBLE_EQ(x, 2.5);  // the overlay wins
  EXPECT_EQ(n, 3);           // the base still answers what the overlay lacks
  EXPECT_TRUE(flag);
  EXPECT_EQ(s, "word");
  EXPECT_EQ(v, Eigen::Vector3d(1, 2, 3));
  // has(): a section or a key of any type, in any file; never a key under a scalar.
  EXPECT_TRUE(r.has("a"));
  EXPECT_TRUE(r.has("a/s"));
  EXPECT_TRUE(r.has("flag"));
  EXPECT_FALSE(r.has("b"));
  EXPECT_FALSE(r.has("a/missing"));
  EXPECT_FALSE(r.has("flag/x"));
  EXPECT_TRUE(r.ok()) << "has() is no failed read";
  double missing = 0;
  r.get("a/missing", missing);
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.error(), (dir / "base.yaml").string() + " + " + (dir / "over.yaml").string() +
                           ": parameter 'a/missing' is missing");  // the files it looked in, and the key
  go_feap::common::YamlReader under_scalar((dir / "base.yaml").string());
  under_scalar.get("flag/x", missing);  // was read as the null under true: "has the wrong type"
  EXPECT_NE(under_scalar.error().find("parameter 'flag/x' is missing"), std::string::npos) << under_scalar.error();
  go_feap::common::YamlReader typed((dir / "base.yaml").string());
  int wrong = 0;
  typed.get("a/s", wrong);
  EXPECT_NE(typed.error().find("parameter 'a/s' has the wrong type"), std::string::npos) << typed.error();
  // Vectors and matrices hold exactly their count of numbers; a matrix is read row-major.
  std::ofstream(dir / "shapes.yaml") << "a:\n  v4: [1, 2, 3, 4]\n  m17: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]\n"
                                        "  m16: [1, 0, 0, 0.1, 0, 1, 0, 0.2, 0, 0, 1, 0.3, 0, 0, 0, 1]\n"
                                        "  v2: [1, 2]\n  m15: [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0]\n";
  go_feap::common::YamlReader four((dir / "shapes.yaml").string());
  four.getVec3("a/v4", v);
  EXPECT_NE(four.error().find("parameter 'a/v4' must hold 3 numbers"), std::string::npos) << four.error();
  go_feap::common::YamlReader two((dir / "shapes.yaml").string());
  two.getVec3("a/v2", v);  // too few too: the third was read past the end
  EXPECT_NE(two.error().find("parameter 'a/v2' must hold 3 numbers"), std::string::npos) << two.error();
  go_feap::common::YamlReader fifteen((dir / "shapes.yaml").string());
  Eigen::Matrix4d M15;
  fifteen.getMatrix4("a/m15", M15);
  EXPECT_NE(fifteen.error().find("must hold 16 numbers"), std::string::npos) << fifteen.error();
  Eigen::Matrix4d M;
  go_feap::common::YamlReader seventeen((dir / "shapes.yaml").string());
  seventeen.getMatrix4("a/m17", M);
  EXPECT_NE(seventeen.error().find("must hold 16 numbers"), std::string::npos) << seventeen.error();
  go_feap::common::YamlReader sixteen((dir / "shapes.yaml").string());
  sixteen.getMatrix4("a/m16", M);
  ASSERT_TRUE(sixteen.ok()) << sixteen.error();
  EXPECT_EQ(M(0, 3), 0.1);
  EXPECT_EQ(M(2, 3), 0.3);
  EXPECT_EQ(M(3, 0), 0.0);
  go_feap::common::YamlReader none((dir / "nope.yaml").string());
  EXPECT_FALSE(none.ok());
  EXPECT_NE(none.error().find("nope.yaml"), std::string::npos);
  fs::remove_all(dir);
}

TEST(TargetHysteresis, KeepsSwitchesAndReportsTargetsReachedInVain) {
  go_feap::planning::LocalPlannerConfig c;
  c.commit_time = 1.5;
  go_feap::frontier::Viewpoint a, b;
  a.position = Vec3(0, 0, 1);
  a.yaw = 0.0;
  b.position = Vec3(3, 0, 1);
  b.yaw = 1.0;
  using go_feap::planning::TargetDecision;
  // Costs as the callers' pathCost() would give them; counts the calls (only the commitment rule asks).
  double cost_a = 2.0, cost_b = 1.0;
  int asked = 0;
  auto cost = [&](const go_feap::frontier::Viewpoint& v) {
    ++asked;
    return (v.position - a.position).norm() < 0.5 ? cost_a : cost_b;
  };
  EXPECT_EQ(go_feap::planning::decideTarget(nullptr, b, cost, 0.0, 10, c), TargetDecision::kSwitch);
  go_feap::planning::CurrentTarget cur;
  cur.viewpoint = a;
  cur.committed_at = 0.0;
  cur.remaining_visible = 50;
  // Within the commitment: kept, unless nothing is left to see or it was reached.
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 1.0, 10, c), TargetDecision::kKeep);
  cur.remaining_visible = 5;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 1.0, 10, c), TargetDecision::kSwitch);
  EXPECT_EQ(asked, 0);
  cur.remaining_visible = 50;
  // After it: only a quicker proposal replaces it (no taking turns between two targets).
  cost_b = 3.0;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 2.0, 10, c), TargetDecision::kKeep);
  EXPECT_EQ(asked, 2);
  cost_b = 1.0;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 2.0, 10, c), TargetDecision::kSwitchQuicker);
  // The commitment ends at commit_time itself (1.5 s), not after it; a moment before, the target is kept.
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 1.5, 10, c), TargetDecision::kSwitchQuicker);
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 1.499, 10, c), TargetDecision::kKeep);
  // A target that won on cost is not replaced on cost in turn (costs estimated through unknown space
  // can cross and cross back as the vehicle flies: the two would take turns for ever).
  cur.quicker = true;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 2.0, 10, c), TargetDecision::kKeep);
  cur.remaining_visible = 5;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 2.0, 10, c), TargetDecision::kSwitch);
  cur.remaining_visible = 50;
  cur.quicker = false;
  // The same target proposed again: kept while flying, reported once reached.
  go_feap::frontier::Viewpoint same = a;
  same.position.x() += 0.1;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, same, cost, 5.0, 10, c), TargetDecision::kKeep);
  cur.reached = true;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, same, cost, 5.0, 10, c), TargetDecision::kReachedInVain);
  cost_b = 3.0;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 1.0, 10, c), TargetDecision::kSwitch);
  // Reached while still braking, the camera tilted (not settled): the view the viewpoint was chosen for
  // has not been had yet, so the same target is kept, not reported; another proposal still replaces it.
  cur.settled = false;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, same, cost, 5.0, 10, c), TargetDecision::kKeep);
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 1.0, 10, c), TargetDecision::kSwitch);
  cur.reached = false;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, same, cost, 5.0, 10, c), TargetDecision::kKeep);
  cur.settled = true;
  // Reached means close, facing it and slow.
  EXPECT_TRUE(go_feap::planning::targetReached(Vec3(0.1, 0, 1), 0.1, 0.05, a, c));
  EXPECT_TRUE(go_feap::planning::targetReached(Vec3(0.1, 0, 1), 0.1, 0.9 * c.reached_speed, a, c));  // braking the last centimetres
  EXPECT_FALSE(go_feap::planning::targetReached(Vec3(0.1, 0, 1), 0.1, 1.1 * c.reached_speed, a, c));
  EXPECT_FALSE(go_feap::planning::targetReached(Vec3(0.1, 0, 1), 1.0, 0.05, a, c));
  EXPECT_FALSE(go_feap::planning::targetReached(Vec3(1.0, 0, 1), 0.0, 0.0, a, c));
  // Headings compare the short way round: a target facing 3.1 rad is reached, and proposed again, at -3.1 rad
  // (0.083 rad apart).
  go_feap::frontier::Viewpoint back = a;
  back.yaw = 3.1;
  EXPECT_TRUE(go_feap::planning::targetReached(back.position, -3.1, 0.0, back, c));
  go_feap::planning::CurrentTarget at_back;
  at_back.viewpoint = back;
  at_back.reached = at_back.settled = true;
  at_back.remaining_visible = 50;
  go_feap::frontier::Viewpoint again = back;
  again.yaw = -3.1;
  EXPECT_EQ(go_feap::planning::decideTarget(&at_back, again, cost, 5.0, 10, c), TargetDecision::kReachedInVain);
  // After the commitment a proposal exactly as quick as the target is no reason to switch.
  cost_a = cost_b = 2.0;
  EXPECT_EQ(go_feap::planning::decideTarget(&cur, b, cost, 5.0, 10, c), TargetDecision::kKeep);
}

// planDue(): with replan_period 0 every tick plans. With FUEL's cadence (> 0) planning is skipped
// while the target is held, and only where decideTarget() would keep it whatever were proposed (checked
// over every combination of the target's state, the time and proposals near, far, cheaper and dearer,
// with the period elapsed); past commit_time a kept target is planned against every replan_period.
TEST(TargetHysteresis, PlanningIsSkippedOnlyWhereAnyProposalWouldBeRefused) {
  using go_feap::planning::TargetDecision;
  go_feap::planning::LocalPlannerConfig c;
  c.commit_time = 1.5;
  go_feap::frontier::Viewpoint a;
  a.position = Vec3(0, 0, 1);
  std::vector<go_feap::frontier::Viewpoint> proposals(3, a);
  proposals[1].position.x() += 0.1;  // the same target
  proposals[2].position = Vec3(3, 0, 1);
  proposals[2].yaw = 1.0;
  for (double period : {0.0, 1.5}) {
    c.replan_period = period;
    EXPECT_TRUE(go_feap::planning::planDue(nullptr, 0.0, -1e9, 10, c));
    int skipped = 0;
    for (bool reached : {false, true})
      for (bool quicker : {false, true})
        for (int visible : {0, 9, 10, 50})
          for (double t : {0.0, 1.0, 1.49, 1.5, 2.0, 10.0}) {
            go_feap::planning::CurrentTarget cur;
            cur.viewpoint = a;
            cur.reached = reached;
            cur.quicker = quicker;
            cur.remaining_visible = visible;
            if (go_feap::planning::planDue(&cur, t, t - 1e3, 10, c)) continue;
            ++skipped;
            for (const auto& p : proposals)
              for (double cost_p : {0.5, 5.0}) {
                auto cost = [&](const go_feap::frontier::Viewpoint& v) { return &v == &p ? cost_p : 1.0; };
                EXPECT_EQ(go_feap::planning::decideTarget(&cur, p, cost, t, 10, c), TargetDecision::kKeep)
                    << "reached " << reached << " quicker " << quicker << " visible " << visible << " t " << t;
              }
          }
    // Skipped exactly where the target is held (not reached, in sight, and committed or won on cost),
    // and never at period 0.
    EXPECT_EQ(skipped, period > 0.0 ? 2 /*visible*/ * (3 /*t < commit*/ + 6 /*quicker*/) : 0) << period;
  }
  // Past commit_time a target that did not win on cost is planned against once per replan_period.
  c.replan_period = 1.5;
  go_feap::planning::CurrentTarget cur;
  cur.viewpoint = a;
  cur.remaining_visible = 50;
  EXPECT_FALSE(go_feap::planning::planDue(&cur, 1.0, 0.0, 10, c));  // committed
  EXPECT_TRUE(go_feap::planning::planDue(&cur, 2.0, 0.0, 10, c));
  EXPECT_FALSE(go_feap::planning::planDue(&cur, 2.1, 2.0, 10, c));
  EXPECT_TRUE(go_feap::planning::planDue(&cur, 3.5, 2.0, 10, c));
  cur.remaining_visible = 5;  // seen out: at once
  EXPECT_TRUE(go_feap::planning::planDue(&cur, 2.1, 2.0, 10, c));
  cur.remaining_visible = 50;
  cur.reached = true;  // reached: at once
  EXPECT_TRUE(go_feap::planning::planDue(&cur, 0.2, 0.1, 10, c));
  c.replan_period = -1.0;
  EXPECT_NE(c.validate().message().find("replan_period"), std::string::npos);
}

}  // namespace
