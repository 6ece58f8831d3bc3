// The exploration state machine: every transition, band order, blacklist bound, termination.
#include <gtest/gtest.h>

#include <cmath>
#include <utility>

#include "go_feap/planning/layer_manager.h"

using namespace go_feap::planning;
using go_feap::common::Aabb;
using go_feap::common::Vec3;

namespace {

const Aabb kBox{Vec3(0, 0, 0), Vec3(10, 10, 5.5)};  // 6 bands of 1 m (the top one 0.5 m)

LayerManagerConfig config() {
  LayerManagerConfig c;
  c.layer_height = 1.0;
  c.settle_time = 1.0;
  c.max_retries = 2;
  c.time_limit = 1000.0;
  c.stuck_timeout = 50.0;
  return c;
}

LayerInputs frontiers(std::vector<std::uint32_t> band, std::vector<std::uint32_t> all, double known_volume) {
  LayerInputs in;
  in.band_frontiers = std::move(band);
  in.all_frontiers = std::move(all);
  in.known_volume = known_volume;  // m^3
  return in;
}

}  // namespace

TEST(LayerManager, BandsGoUpFromTheStartBandThenDown) {
  LayerManager m(config(), kBox, 2.3);
  EXPECT_EQ(m.bandOrder(), (std::vector<int>{2, 3, 4, 5, 1, 0}));
  EXPECT_DOUBLE_EQ(m.band(5).z_min, 5.0);
  EXPECT_DOUBLE_EQ(m.band(5).z_max, 5.5);
  EXPECT_EQ(m.band(0).count, 6);
  LayerManager low(config(), kBox, 0.0), high(config(), kBox, 5.5);
  EXPECT_EQ(low.bandOrder(), (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(high.bandOrder(), (std::vector<int>{5, 4, 3, 2, 1, 0}));
}

TEST(LayerManager, WalksEveryTransitionToComplete) {
  LayerManager m(config(), kBox, 2.3);
  double t = 0.0;
  std::uint64_t progress = 0;
  // Waits for the trigger.
  LayerOutputs out = m.step(frontiers({1}, {1}, progress), t);
  EXPECT_EQ(out.state, ExplorationState::kWaitTrigger);
  EXPECT_TRUE(out.transitions.empty());
  LayerInputs trig = frontiers({1}, {1}, progress);
  trig.trigger = true;
  out = m.step(trig, t += 0.1);
  ASSERT_EQ(out.state, ExplorationState::kExplore);
  ASSERT_EQ(out.transitions.size(), 1u);
  EXPECT_EQ(out.transitions[0].to, ExplorationState::kExplore);
  EXPECT_EQ(out.transitions[0].band_from, -1);
  EXPECT_EQ(out.transitions[0].band_to, 2);
  EXPECT_EQ(out.band.index, 2);
  // A second trigger is ignored.
  out = m.step(trig, t += 0.1);
  EXPECT_TRUE(out.trigger_ignored);
  EXPECT_TRUE(out.transitions.empty());
  // Each band empties; it is left only after settle_time without frontiers.
  std::vector<int> visited{2};
  for (int guard = 0; guard < 100 && out.state == ExplorationState::kExplore; ++guard) {
    out = m.step(frontiers({}, {7}, ++progress), t += 0.5);
    if (out.transitions.empty()) continue;
    // Each transition names the band left and the band entered (-1: none, in the final pass).
    ASSERT_EQ(out.transitions.size(), 1u);
    EXPECT_EQ(out.transitions[0].band_from, visited.back());
    EXPECT_EQ(out.transitions[0].band_to, out.state == ExplorationState::kExplore ? out.band.index : -1);
    if (out.state == ExplorationState::kExplore) visited.push_back(out.band.index);
  }
  EXPECT_EQ(visited, (std::vector<int>{2, 3, 4, 5, 1, 0}));
  ASSERT_EQ(out.state, ExplorationState::kFinalPass);
  EXPECT_TRUE(out.band.final_pass);
  EXPECT_DOUBLE_EQ(out.band.z_min, 0.0);
  EXPECT_DOUBLE_EQ(out.band.z_max, 5.5);
  // Final pass: frontier 7 remains anywhere; it goes, then the box settles.
  out = m.step(frontiers({}, {7}, ++progress), t += 5.0);
  EXPECT_EQ(out.state, ExplorationState::kFinalPass);
  out = m.step(frontiers({}, {}, ++progress), t += 0.5);  // box empty since now
  EXPECT_EQ(out.state, ExplorationState::kFinalPass);
  out = m.step(frontiers({}, {}, ++progress), t += 0.6);  // 0.6 s < settle_time
  EXPECT_EQ(out.state, ExplorationState::kFinalPass);
  out = m.step(frontiers({}, {}, ++progress), t += 0.4);  // 1.0 s: settled
  ASSERT_EQ(out.state, ExplorationState::kFinished);
  EXPECT_EQ(out.reason, FinishReason::kComplete);
  EXPECT_EQ(out.transitions.back().why, "no frontier left in the box");
  // Finished stays finished.
  out = m.step(frontiers({3}, {3}, ++progress), t += 1.0);
  EXPECT_EQ(out.state, ExplorationState::kFinished);
  EXPECT_TRUE(out.transitions.empty());
}

TEST(LayerManager, FrontiersReappearingResetTheSettleTimer) {
  LayerManager m(config(), kBox, 0.5);
  LayerInputs trig = frontiers({}, {}, 0);
  trig.trigger = true;
  m.step(trig, 0.0);
  m.step(frontiers({}, {}, 1), 0.5);                      // empty since 0.5
  m.step(frontiers({4}, {4}, 2), 1.2);                    // a frontier appears: timer reset
  LayerOutputs out = m.step(frontiers({}, {}, 3), 1.6);   // empty since 1.6
  EXPECT_EQ(out.band.index, 0);
  out = m.step(frontiers({}, {}, 4), 2.3);
  EXPECT_EQ(out.band.index, 0);
  out = m.step(frontiers({}, {}, 5), 2.7);
  EXPECT_EQ(out.band.index, 1);
}

TEST(LayerManager, UnreachableFrontiersAreBlacklistedAfterBoundedRetries) {
  LayerManager m(config(), {Vec3(0, 0, 0), Vec3(10, 10, 1)}, 0.5);  // one band
  LayerInputs trig = frontiers({9}, {9}, 0);
  trig.trigger = true;
  m.step(trig, 0.0);
  LayerInputs fail = frontiers({9}, {9}, 1);
  fail.failed = {9};
  LayerOutputs out = m.step(fail, 1.0);
  EXPECT_FALSE(m.isBlacklisted(9));
  fail.known_volume = 2.0;
  out = m.step(fail, 2.0);  // second failure: max_retries = 2
  EXPECT_TRUE(m.isBlacklisted(9));
  // Only the blacklisted frontier is left: the band and then the final pass finish.
  double t = 2.0;
  std::uint64_t p = 3;
  for (int i = 0; i < 20 && out.state != ExplorationState::kFinished; ++i) out = m.step(frontiers({9}, {9}, ++p), t += 0.6);
  EXPECT_EQ(out.state, ExplorationState::kFinished);
  EXPECT_EQ(out.reason, FinishReason::kComplete);
  // The finish says that a frontier was left unexplored.
  EXPECT_NE(out.transitions.back().why.find("1 blacklisted"), std::string::npos) << out.transitions.back().why;
}

TEST(LayerManager, TimeLimitAndStuckTerminate) {
  LayerManagerConfig c = config();
  c.time_limit = 10.0;
  LayerManager a(c, kBox, 0.5);
  LayerInputs trig = frontiers({1}, {1}, 0);
  trig.trigger = true;
  a.step(trig, 100.0);
  LayerOutputs out;
  std::uint64_t p = 0;
  for (double t = 100.0; t < 115.0 && out.state != ExplorationState::kFinished; t += 0.5)
    out = a.step(frontiers({1}, {1}, ++p), t);
  EXPECT_EQ(out.reason, FinishReason::kTimeLimit);

  c.time_limit = 1000.0;
  c.stuck_timeout = 5.0;
  LayerManager b(c, kBox, 0.5);
  b.step(trig, 0.0);
  out = LayerOutputs();
  for (double t = 0.5; t < 20.0 && out.state != ExplorationState::kFinished; t += 0.5)
    out = b.step(frontiers({1}, {1}, 42), t);  // the map stops growing
  EXPECT_EQ(out.reason, FinishReason::kStuck);
  ASSERT_FALSE(out.transitions.empty());
  EXPECT_NE(out.transitions.back().why.find("no map progress"), std::string::npos);
}

// Progress is growth of the known map by stuck_min_volume: a trickle of voxels does not hold a run open.
TEST(LayerManager, StuckNeedsTheMapToGrowByTheMinimumVolume) {
  LayerManagerConfig c = config();
  c.stuck_timeout = 5.0;
  c.stuck_min_volume = 0.5;
  auto run = [&](double growth_per_step, double min_volume) {
    c.stuck_min_volume = min_volume;
    LayerManager m(c, kBox, 0.5);
    LayerInputs trig = frontiers({1}, {1}, 100.0);
    trig.trigger = true;
    m.step(trig, 0.0);
    double volume = 100.0;
    LayerOutputs out;
    double t = 0.0;
    while (t < 30.0 && out.state != ExplorationState::kFinished)
      out = m.step(frontiers({1}, {1}, volume += growth_per_step), t += 0.5);
    return std::make_pair(out.reason, t);
  };
  // 0.1 m^3 per 5 s: stuck when the timeout has passed since the trigger, not a step later.
  auto [reason, t] = run(0.01, 0.5);
  EXPECT_EQ(reason, FinishReason::kStuck);
  EXPECT_DOUBLE_EQ(t, 5.0);
  // The same trickle is progress when any growth counts.
  EXPECT_EQ(run(0.01, 0.0).first, FinishReason::kNone);
  // 1 m^3 per 5 s reaches 0.5 m^3 every 2.5 s: never stuck.
  EXPECT_EQ(run(0.1, 0.5).first, FinishReason::kNone);
  // Just below the minimum over the whole timeout (0.45 m^3 in 5 s): stuck.
  EXPECT_EQ(run(0.045, 0.5).first, FinishReason::kStuck);

  // A map cleared by its owner (smaller than before) starts the count again: no stuck at the drop.
  c.stuck_min_volume = 0.5;
  LayerManager m(c, kBox, 0.5);
  LayerInputs trig = frontiers({1}, {1}, 100.0);
  trig.trigger = true;
  m.step(trig, 0.0);
  EXPECT_EQ(m.step(frontiers({1}, {1}, 100.0), 4.5).state, ExplorationState::kExplore);
  EXPECT_EQ(m.step(frontiers({1}, {1}, 1.0), 4.9).state, ExplorationState::kExplore);
  EXPECT_EQ(m.step(frontiers({1}, {1}, 1.2), 9.5).state, ExplorationState::kExplore);
  EXPECT_EQ(m.step(frontiers({1}, {1}, 1.2), 9.9).reason, FinishReason::kStuck);
}

TEST(LayerManager, ValidateNamesKeys) {
  LayerManagerConfig c = config();
  c.layer_height = 0.0;
  EXPECT_NE(c.validate().message().find("layer_height"), std::string::npos);
  c = config();
  c.max_retries = 0;
  EXPECT_NE(c.validate().message().find("max_retries"), std::string::npos);
  for (double bad : {-0.1, std::nan(""), static_cast<double>(INFINITY)}) {
    c = config();
    c.stuck_min_volume = bad;
    EXPECT_NE(c.validate().message().find("stuck_min_volume"), std::string::npos) << bad;
  }
  c.stuck_min_volume = 0.0;
  EXPECT_TRUE(c.validate().ok());
  EXPECT_STREQ(toString(FinishReason::kStuck), "stuck");
  EXPECT_STREQ(toString(ExplorationState::kFinalPass), "FINAL_PASS");
}
