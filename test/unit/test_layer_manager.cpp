// The exploration state machine: every transition, band order, blacklist bound, termination.
#include <gtest/gtest.h>

#include <limits>
#include <memory>

#include "go_feap/planning/layer_manager.h"

using namespace go_feap::planning;
using go_feap::common::Aabb;
using go_feap::common::Vec3;

namespace {

const Aabb kBox{Vec3(0, 0, 0), Vec3(10, 10, 5.5)};  // 6 equal bands of at most 1 m: 0.917 m

LayerManagerConfig config() {
  LayerManagerConfig c;
  c.layer_height = 1.0;
  c.settle_time = 1.0;
  c.max_retries = 2;
  c.time_limit = 1000.0;
  c.stuck_timeout = 50.0;
  return c;
}

LayerInputs frontiers(std::vector<std::uint32_t> band, std::vector<std::uint32_t> all, std::uint64_t progress) {
  LayerInputs in;
  in.band_frontiers = std::move(band);
  in.all_frontiers = std::move(all);
  in.map_progress = progress;
  return in;
}

// The vehicle turns round once at time t, seeing frontier 1 (nothing becomes explored on the way).
void lookRound(LayerManager& m, double t) {
  for (int k = 0; k < 8; ++k) {
    LayerInputs in = frontiers({1}, {1}, 0);
    in.yaw = -M_PI + (k + 0.5) * M_PI / 4.0;
    m.step(in, t);
  }
  ASSERT_TRUE(m.lookedAround());
}

// Frontier 1 in the band and the box, with the trigger.
LayerInputs triggerInput() {
  LayerInputs in = frontiers({1}, {1}, 0);
  in.trigger = true;
  return in;
}

}  // namespace

TEST(LayerManager, BandsGoUpFromTheStartBandThenDown) {
  LayerManager m(config(), kBox, 2.3);
  EXPECT_EQ(m.bandOrder(), (std::vector<int>{2, 3, 4, 5, 1, 0}));
  // Equal bands, the box's height over their count: no thin remainder on top (it was 0.5 m here, and at
  // 0.1 m under the viewpoints' clearance it held no viewpoint).
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(m.band(k).z_min, k * 5.5 / 6.0, 1e-12) << k;
    EXPECT_NEAR(m.band(k).z_max - m.band(k).z_min, 5.5 / 6.0, 1e-12) << k;
  }
  EXPECT_EQ(m.band(5).z_max, 5.5);  // exactly the box's top
  EXPECT_EQ(m.band(0).count, 6);
  LayerManager low(config(), kBox, 0.0), high(config(), kBox, 5.5);
  EXPECT_EQ(low.bandOrder(), (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(high.bandOrder(), (std::vector<int>{5, 4, 3, 2, 1, 0}));
  // A start far outside the box (odometry gone wrong) takes the nearest band; the cast to int of the band
  // number, 1e300, was undefined.
  LayerManager far_up(config(), kBox, 1e300), far_down(config(), kBox, -1e300);
  EXPECT_EQ(far_up.bandOrder(), (std::vector<int>{5, 4, 3, 2, 1, 0}));
  EXPECT_EQ(far_down.bandOrder(), (std::vector<int>{0, 1, 2, 3, 4, 5}));
  // A height that is a whole number of layer heights but divides a hair over it (2.1 / 0.7 is
  // 3.0000000000000004 in doubles) makes that many bands, not one more.
  LayerManagerConfig c = config();
  c.layer_height = 0.7;
  ASSERT_GT(2.1 / 0.7, 3.0);
  LayerManager whole(c, Aabb{Vec3(0, 0, 0), Vec3(10, 10, 2.1)}, 0.0);
  EXPECT_EQ(whole.bandOrder(), (std::vector<int>{0, 1, 2}));
  EXPECT_NEAR(whole.band(0).z_max, 0.7, 1e-12);
}

// Before any frontier list has arrived (a finder that has not started, a camera that sends nothing), the
// empty lists say nothing: no look round is asked for, no band settles and the run does not end
// "complete" (the heading may go round all the same); the first list, empty, lets the box settle.
TEST(LayerManager, NoBandIsExploredBeforeAnyFrontierListArrives) {
  LayerManagerConfig c = config();
  c.layer_height = 100.0;  // one band
  LayerManager m(c, kBox, 2.3);
  LayerInputs in;
  in.frontiers_known = false;
  in.trigger = true;
  double t = 0.0;
  ASSERT_EQ(m.step(in, t).state, ExplorationState::kExplore);
  in.trigger = false;
  bool asked_to_look = false;
  for (int k = 0; k < 400; ++k) {  // 40 s, the heading going round, the map growing
    in.yaw = 0.1 * k;
    in.map_progress = static_cast<std::uint64_t>(k);
    const LayerOutputs out = m.step(in, t += 0.1);
    ASSERT_EQ(out.state, ExplorationState::kExplore) << "at " << t << " s";
    asked_to_look = asked_to_look || out.look_around;
  }
  EXPECT_FALSE(asked_to_look) << "a look round asked for with no frontier list";
  EXPECT_TRUE(m.lookedAround());
  in.frontiers_known = true;
  LayerOutputs out;
  for (int k = 0; k < 12 && out.state != ExplorationState::kFinished; ++k) out = m.step(in, t += 0.1);
  EXPECT_EQ(out.state, ExplorationState::kFinished);
  EXPECT_EQ(out.reason, FinishReason::kComplete);
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
  lookRound(m, t);
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
  lookRound(m, 0.0);
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
  lookRound(m, 0.0);
  LayerInputs fail = frontiers({9}, {9}, 1);
  fail.failed = {9};
  LayerOutputs out = m.step(fail, 1.0);
  EXPECT_FALSE(m.isBlacklisted(9));
  fail.map_progress = 2;
  out = m.step(fail, 2.0);  // second failure: max_retries = 2
  EXPECT_TRUE(m.isBlacklisted(9));
  // Only the blacklisted frontier is left: the band and then the final pass finish.
  double t = 2.0;
  std::uint64_t p = 3;
  for (int i = 0; i < 20 && out.state != ExplorationState::kFinished; ++i) out = m.step(frontiers({9}, {9}, ++p), t += 0.6);
  EXPECT_EQ(out.state, ExplorationState::kFinished);
  EXPECT_EQ(out.reason, FinishReason::kComplete);
  // The finish says that a frontier was left unexplored, and so do the outputs.
  EXPECT_NE(out.transitions.back().why.find("1 blacklisted"), std::string::npos) << out.transitions.back().why;
  EXPECT_EQ(out.blacklisted_left, 1u);
  out = m.step(frontiers({9}, {9, 10}, ++p), t += 0.6);
  EXPECT_EQ(out.blacklisted_left, 1u);  // 10 is not blacklisted
  out = m.step(frontiers({}, {10}, ++p), t += 0.6);
  EXPECT_EQ(out.blacklisted_left, 0u);  // 9 was cleared after all
}

TEST(LayerManager, RecordsOfFrontiersThatAreGoneAreForgotten) {
  LayerManager m(config(), {Vec3(0, 0, 0), Vec3(10, 10, 1)}, 0.5);  // one band, max_retries = 2
  LayerInputs trig = frontiers({9}, {9}, 0);
  trig.trigger = true;
  m.step(trig, 0.0);
  lookRound(m, 0.0);  // lists frontier 1 only: 9 is at or below the highest id seen, but no record yet
  std::uint64_t p = 1;
  double t = 1.0;
  auto failing = [&](std::vector<std::uint32_t> all, std::vector<std::uint32_t> failed) {
    LayerInputs in = frontiers(all, all, ++p);
    in.failed = std::move(failed);
    return m.step(in, t += 0.1);
  };
  failing({9}, {9});
  failing({9}, {9});
  EXPECT_TRUE(m.isBlacklisted(9));
  // A failure on 12 reported before any list held 12 (the planners saw a newer frontier update than the
  // one here): kept, and it counts towards the blacklist once the lists catch up.
  failing({9}, {12});
  EXPECT_EQ(m.failureRecords(), 2u);
  failing({9, 12}, {12});
  EXPECT_TRUE(m.isBlacklisted(12));
  EXPECT_EQ(failing({9, 12}, {}).blacklisted_left, 2u);
  // 9 is gone (its cells changed, so it came back, if at all, under a new id): its records go with it.
  EXPECT_EQ(failing({12, 20}, {}).blacklisted_left, 1u);
  EXPECT_FALSE(m.isBlacklisted(9));
  EXPECT_TRUE(m.isBlacklisted(12));
  EXPECT_EQ(m.failureRecords(), 1u);
  failing({20}, {});
  EXPECT_TRUE(m.blacklist().empty());
  EXPECT_EQ(m.failureRecords(), 0u);
  // A long run: a thousand frontiers each fail twice and vanish; the records stay bounded.
  for (std::uint32_t id = 100; id < 1100; ++id) {
    failing({id}, {id});
    failing({id}, {id});
    ASSERT_TRUE(m.isBlacklisted(id));
  }
  failing({2000}, {});
  EXPECT_TRUE(m.blacklist().empty());
  EXPECT_EQ(m.failureRecords(), 0u);
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
  double ended = -1.0;  // the step that finished
  for (double t = 100.0; t < 115.0 && out.state != ExplorationState::kFinished; t += 0.5) {
    out = a.step(frontiers({1}, {1}, ++p), t);
    ended = t;
  }
  EXPECT_EQ(out.reason, FinishReason::kTimeLimit);
  EXPECT_DOUBLE_EQ(ended, 110.0);  // time_limit after the trigger (at 100 s), not after t = 0 nor later

  c.time_limit = 1000.0;
  c.stuck_timeout = 5.0;
  LayerManager b(c, kBox, 0.5);
  b.step(trig, 0.0);
  out = LayerOutputs();
  for (double t = 0.5; t < 20.0 && out.state != ExplorationState::kFinished; t += 0.5) {
    out = b.step(frontiers({1}, {1}, 42), t);  // the map stops growing
    ended = t;
  }
  EXPECT_EQ(out.reason, FinishReason::kStuck);
  EXPECT_DOUBLE_EQ(ended, 5.5);  // stuck_timeout after the last progress (the map changed at 0.5 s)
  ASSERT_FALSE(out.transitions.empty());
  EXPECT_NE(out.transitions.back().why.find("no map progress"), std::string::npos);
}

// The time limit and stuck detection hold in the final pass too: a frontier left in the box but in no band
// keeps the pass from settling, and the run ends time_limit after the trigger, or stuck_timeout after the
// map last changed.
TEST(LayerManager, TimeLimitAndStuckTerminateInTheFinalPass) {
  for (const FinishReason expected : {FinishReason::kTimeLimit, FinishReason::kStuck}) {
    LayerManagerConfig c = config();
    c.time_limit = expected == FinishReason::kTimeLimit ? 30.0 : 1000.0;
    c.stuck_timeout = 5.0;
    LayerManager m(c, kBox, 2.3);
    m.step(triggerInput(), 0.0);
    lookRound(m, 0.0);
    double t = 0.0;
    std::uint64_t progress = 0;
    LayerOutputs out;
    for (int guard = 0; guard < 100 && out.state != ExplorationState::kFinalPass; ++guard)
      out = m.step(frontiers({}, {7}, ++progress), t += 0.5);  // every band empties, frontier 7 stays
    ASSERT_EQ(out.state, ExplorationState::kFinalPass);
    ASSERT_LT(t, 20.0);
    const bool growing = expected == FinishReason::kTimeLimit;
    const double last_progress = t;
    double ended = -1.0;
    for (int guard = 0; guard < 200 && out.state == ExplorationState::kFinalPass; ++guard) {
      out = m.step(frontiers({}, {7}, growing ? ++progress : progress), t += 0.5);
      ended = t;
    }
    ASSERT_EQ(out.state, ExplorationState::kFinished) << "the final pass never ended";
    EXPECT_EQ(out.reason, expected);
    EXPECT_DOUBLE_EQ(ended, growing ? 30.0 : last_progress + 5.0);
  }
}

// A flight counts as progress (a long transit through mapped space changes no voxel, and ended a run
// "stuck" with frontiers left at its end): 20 s at 1 m/s with the map unchanged is not stuck; jitter
// within progress_travel is, stuck_timeout after the flight; with progress_travel 0 the flight counts
// for nothing.
constexpr double kStuckTimeout = 5.0;  // s, of stillManager()

// A manager with stuck_timeout kStuckTimeout and `progress_travel`, triggered at t = 0 at (0, 0, 0.5) with
// `in` (one frontier, the map never changing), ready for the next step.
std::unique_ptr<LayerManager> stillManager(double progress_travel, LayerInputs& in) {
  LayerManagerConfig c = config();
  c.stuck_timeout = kStuckTimeout;
  c.progress_travel = progress_travel;
  auto m = std::make_unique<LayerManager>(c, kBox, 0.5);
  in = frontiers({1}, {1}, 42);
  in.trigger = true;
  in.position = Vec3(0.0, 0.0, 0.5);
  m->step(in, 0.0);
  in.trigger = false;
  return m;
}

TEST(LayerManager, AFlightIsProgressJitterIsNot) {
  for (double travel : {1.0, 0.0}) {
    LayerInputs in;
    auto m = stillManager(travel, in);
    LayerOutputs out;
    double t = 0.0;
    for (int k = 1; k <= 40 && out.state != ExplorationState::kFinished; ++k) {  // 20 s, 0.5 m a step
      in.position = Vec3(0.5 * k, 0.0, 0.5);
      out = m->step(in, t += 0.5);
    }
    if (travel == 0.0) {
      EXPECT_EQ(out.reason, FinishReason::kStuck) << "the flight counted with progress_travel 0";
      EXPECT_NEAR(t, kStuckTimeout, 1e-9);
      continue;
    }
    ASSERT_EQ(out.state, ExplorationState::kExplore) << "stuck while flying, at " << t << " s";
    const double flown_until = t;
    for (int k = 0; k < 40 && out.state != ExplorationState::kFinished; ++k) {  // jitter of 0.9 m at most
      in.position = Vec3(20.0 + 0.45 * (k % 3 - 1), 0.0, 0.5);
      out = m->step(in, t += 0.5);
    }
    EXPECT_EQ(out.reason, FinishReason::kStuck);
    // Stuck stuck_timeout after the last metre's progress (the flight's last steps), not later.
    EXPECT_LE(t - flown_until, kStuckTimeout + 1e-9);
  }
}

// A position first known after the trigger is where progress is measured from: a flight of 1 m/s (2 m per
// stuck_timeout, progress_travel 1 m) that begins without a known position is progress all the same.
TEST(LayerManager, APositionFirstKnownAfterTheTriggerStartsTheProgressCount) {
  LayerManagerConfig c = config();
  c.stuck_timeout = kStuckTimeout;
  c.progress_travel = 1.0;
  LayerManager m(c, kBox, 0.5);
  LayerInputs in = frontiers({1}, {1}, 42);
  in.trigger = true;
  ASSERT_FALSE(in.position);
  m.step(in, 0.0);
  in.trigger = false;
  LayerOutputs out;
  double t = 0.0;
  for (int k = 1; k <= 40; ++k) {  // 20 s
    in.position = Vec3(0.5 * k, 0.0, 0.5);
    out = m.step(in, t += 0.5);
    ASSERT_EQ(out.state, ExplorationState::kExplore) << "stuck while flying, at " << t << " s";
  }
}

// An odometry that relocalises (jumps of 2 m, each reported) is no flight: with the map unchanged the run
// ends stuck stuck_timeout after the trigger, however often it jumps. Unreported, each jump counted as
// progress_travel flown, and the stuck check never fired.
TEST(LayerManager, ARelocalisationIsNoProgress) {
  for (bool reported : {true, false}) {
    LayerInputs in;
    auto m = stillManager(1.0, in);
    LayerOutputs out;
    double t = 0.0;
    for (int k = 1; k <= 40 && out.state != ExplorationState::kFinished; ++k) {  // 20 s, a jump every 1 s
      const bool jump = k % 2 == 0;
      in.position = Vec3(jump ? 2.0 * (k / 2 % 2) : in.position->x(), 0.0, 0.5);
      in.relocalised = reported && jump;
      out = m->step(in, t += 0.5);
    }
    if (reported) {
      EXPECT_EQ(out.reason, FinishReason::kStuck);
      EXPECT_NEAR(t, kStuckTimeout, 1e-9);
    } else {
      EXPECT_EQ(out.state, ExplorationState::kExplore) << "unreported jumps are taken for flight";
    }
  }
}

TEST(LayerManager, ValidateNamesKeys) {
  LayerManagerConfig c = config();
  c.layer_height = 0.0;
  EXPECT_NE(c.validate().message().find("layer_height"), std::string::npos);
  // One band over everything is a large finite height: an infinite one makes NaN band bounds.
  c.layer_height = std::numeric_limits<double>::infinity();
  EXPECT_NE(c.validate().message().find("layer_height"), std::string::npos);
  c.layer_height = 1e-12;  // 2.6e13 bands on a 26 m box overflowed the int count
  EXPECT_NE(c.validate().message().find("layer_height"), std::string::npos);
  c.layer_height = 0.5;
  EXPECT_TRUE(c.validate()) << c.validate().message();
  c.layer_height = 1000.0;
  EXPECT_TRUE(c.validate().ok());
  c.settle_time = std::numeric_limits<double>::infinity();
  EXPECT_NE(c.validate().message().find("settle_time"), std::string::npos);
  c = config();
  c.max_retries = 0;
  EXPECT_NE(c.validate().message().find("max_retries"), std::string::npos);
  for (double travel : {-1.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    c = config();
    c.progress_travel = travel;
    EXPECT_NE(c.validate().message().find("progress_travel"), std::string::npos) << travel;
  }
  // 0 ended every run at its trigger (stuck, or out of time); NaN never would.
  for (double bad : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()}) {
    c = config();
    c.stuck_timeout = bad;
    EXPECT_NE(c.validate().message().find("stuck_timeout"), std::string::npos) << bad;
    c = config();
    c.time_limit = bad;
    EXPECT_NE(c.validate().message().find("time_limit"), std::string::npos) << bad;
  }
  EXPECT_STREQ(toString(FinishReason::kStuck), "stuck");
  EXPECT_STREQ(toString(ExplorationState::kFinalPass), "FINAL_PASS");
  // .inf is "no limit": accepted, and a run that stops growing its map for a day is neither stuck nor late.
  c = config();
  c.time_limit = c.stuck_timeout = std::numeric_limits<double>::infinity();
  ASSERT_TRUE(c.validate()) << c.validate().message();
  LayerManager m(c, kBox, 0.5);
  LayerInputs trig = frontiers({1}, {1}, 0);
  trig.trigger = true;
  m.step(trig, 0.0);
  LayerOutputs out;
  for (double t = 0.5; t < 86400.0; t += 600.0) out = m.step(frontiers({1}, {1}, 7), t);
  EXPECT_EQ(out.state, ExplorationState::kExplore);
}

// A start facing a wall sees too little for a frontier: the band is not counted explored, and the chain
// is asked to turn in place, until the heading has been in every octant; then it settles as usual.
TEST(LayerManager, NothingIsExploredBeforeALookRound) {
  LayerManagerConfig c = config();
  c.layer_height = 10.0;  // one band
  LayerManager m(c, kBox, 1.0);
  LayerInputs in = frontiers({}, {}, 0);
  in.trigger = true;
  in.yaw = 3.0;  // octant 7 (and the wrap: 3.0 and -3.2 are one heading)
  LayerOutputs out = m.step(in, 0.0);
  ASSERT_EQ(out.state, ExplorationState::kExplore);
  EXPECT_FALSE(out.look_around);
  std::uint64_t p = 0;
  double t = 0.0;
  auto at = [&](double yaw, std::vector<std::uint32_t> ids = {}) {
    LayerInputs i = frontiers(ids, ids, ++p);
    i.yaw = yaw;
    return m.step(i, t += 0.5);
  };
  out = at(-3.2);
  EXPECT_FALSE(out.look_around);  // 0.5 s < settle_time
  for (int k = 0; k < 6; ++k) {
    out = at(3.0);
    EXPECT_EQ(out.state, ExplorationState::kExplore) << k;
    EXPECT_TRUE(out.transitions.empty()) << k;
    EXPECT_TRUE(out.look_around) << k;
  }
  // Turning: six more octants, still nothing to explore.
  for (double yaw : {-2.8, -2.0, -1.2, -0.4, 0.4, 1.2}) {
    out = at(yaw);
    EXPECT_TRUE(out.look_around) << yaw;
    EXPECT_EQ(out.state, ExplorationState::kExplore) << yaw;
  }
  EXPECT_FALSE(m.lookedAround());
  // A frontier comes into view: no look round is asked while there is one.
  out = at(1.2, {5});
  EXPECT_FALSE(out.look_around);
  // The last octant (2.0 rad): looked round. Empty again, the band settles after settle_time.
  out = at(2.0);
  EXPECT_TRUE(m.lookedAround());
  EXPECT_FALSE(out.look_around);
  EXPECT_EQ(out.state, ExplorationState::kExplore);
  for (int k = 0; k < 4 && out.state == ExplorationState::kExplore; ++k) out = at(2.0);
  // One band covers the box, so the box has settled with it: the final pass has nothing to find.
  EXPECT_EQ(out.state, ExplorationState::kFinished);
  EXPECT_EQ(out.reason, FinishReason::kComplete);
  EXPECT_FALSE(out.look_around);
}

// Headings seen before the trigger are no look round: a vehicle turned round while it waited (carried, or
// turning on the ground), then facing one way with nothing in view after the trigger, is asked to look round
// and its band does not end "complete".
TEST(LayerManager, HeadingsBeforeTheTriggerAreNoLookRound) {
  LayerManagerConfig c = config();
  c.layer_height = 10.0;  // one band
  LayerManager m(c, kBox, 1.0);
  double t = 0.0;
  for (int k = 0; k < 8; ++k) {
    LayerInputs waiting = frontiers({}, {}, 0);
    waiting.yaw = -M_PI + (k + 0.5) * M_PI / 4.0;
    ASSERT_EQ(m.step(waiting, t += 0.1).state, ExplorationState::kWaitTrigger);
  }
  EXPECT_FALSE(m.lookedAround());
  LayerInputs in = frontiers({}, {}, 0);
  in.trigger = true;
  in.yaw = 3.0;
  ASSERT_EQ(m.step(in, t += 0.1).state, ExplorationState::kExplore);
  in.trigger = false;
  LayerOutputs out;
  for (int k = 0; k < 6; ++k) {
    out = m.step(in, t += 0.5);
    EXPECT_EQ(out.state, ExplorationState::kExplore) << k;
  }
  EXPECT_TRUE(out.look_around);
  EXPECT_FALSE(m.lookedAround());
}

// The final pass waits out settle_time only when the box was not already settled as the last band was:
// with one band covering the box it would repeat the band's wait (about 1.2 s of every maze run).
TEST(LayerManager, FinalPassEndsAtOnceWhenTheBoxHasAlreadySettled) {
  LayerManagerConfig c = config();
  c.layer_height = 10.0;  // one band: the whole box
  LayerManager one(c, kBox, 1.0);
  LayerInputs trig = frontiers({}, {}, 0);
  trig.trigger = true;
  one.step(trig, 0.0);
  lookRound(one, 0.0);
  LayerOutputs out = one.step(frontiers({}, {}, 1), 0.5);  // empty since 0.5
  EXPECT_EQ(out.state, ExplorationState::kExplore);
  out = one.step(frontiers({}, {}, 2), 1.0);
  EXPECT_EQ(out.state, ExplorationState::kExplore);
  out = one.step(frontiers({}, {}, 3), 1.5);  // settled: band explored, and so the box
  ASSERT_EQ(out.state, ExplorationState::kFinished);
  EXPECT_EQ(out.reason, FinishReason::kComplete);
  ASSERT_EQ(out.transitions.size(), 2u);
  EXPECT_EQ(out.transitions[0].to, ExplorationState::kFinalPass);
  EXPECT_EQ(out.transitions[0].why, "every band explored");
  EXPECT_EQ(out.transitions[1].from, ExplorationState::kFinalPass);
  EXPECT_EQ(out.transitions[1].to, ExplorationState::kFinished);
  EXPECT_EQ(out.transitions[1].why, "no frontier left in the box");

  // Six bands, the last one (band 0) settling while a frontier elsewhere went only 0.5 s ago: the
  // final pass starts and waits out its own settle_time.
  LayerManager six(config(), kBox, 0.5);
  six.step(trig, 0.0);
  lookRound(six, 0.0);
  double t = 0.0;
  std::uint64_t p = 0;
  out = LayerOutputs();
  for (int guard = 0; guard < 100 && out.band.index != six.bandOrder().back(); ++guard)
    out = six.step(frontiers({}, {7}, ++p), t += 0.5);
  ASSERT_EQ(out.band.index, 5);  // the last band of the order 0..5
  ASSERT_EQ(out.state, ExplorationState::kExplore);
  out = six.step(frontiers({}, {7}, ++p), t += 0.5);  // band 5 empty since now
  out = six.step(frontiers({}, {}, ++p), t += 0.5);   // frontier 7 gone: the box empty since now
  EXPECT_EQ(out.state, ExplorationState::kExplore);
  out = six.step(frontiers({}, {}, ++p), t += 0.5);  // band 5 settled, the box only 0.5 s
  ASSERT_EQ(out.state, ExplorationState::kFinalPass);
  out = six.step(frontiers({}, {}, ++p), t += 0.5);  // the box 1.0 s
  EXPECT_EQ(out.state, ExplorationState::kFinished);
  EXPECT_EQ(out.reason, FinishReason::kComplete);
}

// A stop request ends the exploration at once, from any state but FINISHED, as FINISHED(aborted); a trigger
// after it (or with it) is ignored, and a finished run keeps its reason.
TEST(LayerManager, AStopRequestFinishesAsAbortedFromAnyState) {
  LayerInputs stop = frontiers({1}, {1}, 0);
  stop.abort = true;
  {  // waiting for the trigger; the trigger in the same step is void
    LayerManager m(config(), kBox, 0.5);
    LayerInputs both = stop;
    both.trigger = true;
    const LayerOutputs out = m.step(both, 1.0);
    EXPECT_EQ(out.state, ExplorationState::kFinished);
    EXPECT_EQ(out.reason, FinishReason::kAborted);
    EXPECT_STREQ(toString(out.reason), "aborted");
    ASSERT_EQ(out.transitions.size(), 1u);
    EXPECT_EQ(out.transitions[0].why, "stopped on request");
    EXPECT_TRUE(out.trigger_ignored);
    const LayerInputs trigger = triggerInput();
    EXPECT_EQ(m.step(trigger, 2.0).state, ExplorationState::kFinished);
  }
  {  // exploring a band, with frontiers left
    LayerManager m(config(), kBox, 0.5);
    const LayerInputs trigger = triggerInput();
    ASSERT_EQ(m.step(trigger, 0.0).state, ExplorationState::kExplore);
    EXPECT_EQ(m.step(frontiers({1}, {1}, 1), 1.0).state, ExplorationState::kExplore);
    const LayerOutputs out = m.step(stop, 2.0);
    EXPECT_EQ(out.state, ExplorationState::kFinished);
    EXPECT_EQ(out.reason, FinishReason::kAborted);
  }
  {  // already finished (time limit): the reason stays
    LayerManagerConfig c = config();
    c.time_limit = 1.0;
    LayerManager m(c, kBox, 0.5);
    const LayerInputs trigger = triggerInput();
    m.step(trigger, 0.0);
    ASSERT_EQ(m.step(frontiers({1}, {1}, 1), 2.0).reason, FinishReason::kTimeLimit);
    const LayerOutputs out = m.step(stop, 3.0);
    EXPECT_EQ(out.reason, FinishReason::kTimeLimit);
    EXPECT_TRUE(out.transitions.empty());
  }
}

// What the nodelet and the bench hand the manager: every frontier in all_frontiers, those whose average lies
// in the band (bounds included) in band_frontiers too.
TEST(LayerManager, AFrontierIsListedInTheBandThatHoldsItsAverage) {
  Band band;
  band.z_min = 1.0;
  band.z_max = 2.0;
  LayerInputs in;
  in.listFrontier(1, 0.99, band);
  in.listFrontier(2, 1.0, band);
  in.listFrontier(3, 1.5, band);
  in.listFrontier(4, 2.0, band);
  in.listFrontier(5, 2.01, band);
  EXPECT_EQ(in.all_frontiers, (std::vector<std::uint32_t>{1, 2, 3, 4, 5}));
  EXPECT_EQ(in.band_frontiers, (std::vector<std::uint32_t>{2, 3, 4}));
}
