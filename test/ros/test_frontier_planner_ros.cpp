// rostest: simulator + EsdfMapper + FrontierFinder + GlobalPlanner + LocalPlanner + LayerManager. Before
// the trigger nothing is planned; after it and a turn in place at the maze start, a non-empty tour must
// come out whose first frontier exists and is reachable from the start through ground-truth free space.
#include <gtest/gtest.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/NodeletLoad.h>
#include <nodelet/NodeletUnload.h>
#include <ros/ros.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <vector>

#include <std_msgs/Bool.h>
#include <std_msgs/UInt32.h>
#include <std_srvs/Trigger.h>

#include "go_feap/ComputeTime.h"
#include "go_feap/ExplorationStatus.h"
#include "go_feap/FrontierArray.h"
#include "go_feap/LayerBounds.h"
#include "go_feap/ViewpointPath.h"
#include "go_feap/GlobalTour.h"
#include "go_feap/PositionCommand.h"
#include "ros_test_util.h"
#include "go_feap/world/scene_files.h"

namespace {

using go_feap::test::spinUntil;

using go_feap::common::Index3;
using go_feap::common::Vec3;

class FrontierPlannerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    frontier_sub_ = nh_.subscribe("frontiers", 20, &FrontierPlannerTest::onFrontiers, this);
    tour_sub_ = nh_.subscribe("global_tour", 2, &FrontierPlannerTest::onTour, this);
    odom_sub_ = nh_.subscribe("odom", 2, &FrontierPlannerTest::onOdom, this);
    status_sub_ = nh_.subscribe("status", 5, &FrontierPlannerTest::onStatus, this);
    layer_sub_ = nh_.subscribe("layer", 1, &FrontierPlannerTest::onLayer, this);
    target_sub_ = nh_.subscribe("local_target", 2, &FrontierPlannerTest::onTarget, this);
    cmd_pub_ = nh_.advertise<go_feap::PositionCommand>("position_cmd", 10);
  }
  void onFrontiers(const go_feap::FrontierArray::ConstPtr& m) {
    for (const auto& f : m->frontiers) highest_id_ = std::max(highest_id_, f.id);
    frontiers_ = m;
    recent_frontiers_.push_back(m);
    if (recent_frontiers_.size() > 30) recent_frontiers_.pop_front();
  }
  // A tour is paired with the frontier array it was planned from (the global planner stamps it with that
  // array's stamp): the tour may overtake the array on its own connection, and frontier ids change with
  // every update.
  void onTour(const go_feap::GlobalTour::ConstPtr& m) {
    if (m->frontier_ids.empty()) return;
    toursByStamp()[m->header.stamp] = m;
    for (const auto& f : recent_frontiers_)
      if (f->header.stamp == m->header.stamp) {
        tour_ = m;
        tour_frontiers_ = f;
      }
  }
  void onOdom(const nav_msgs::Odometry::ConstPtr& m) { odom_ = m; }
  void onStatus(const go_feap::ExplorationStatus::ConstPtr& m) { status_ = m; }
  void onLayer(const go_feap::LayerBounds::ConstPtr& m) { layer_ = m; }
  void onTarget(const go_feap::ViewpointPath::ConstPtr& m) {
    target_ = m;
    target_tour_ = tour_;
  }
  /// Publishes the tour `make()` gives on `pub` every 0.1 s of the clock, until `seconds` of it have passed
  /// or `done()`.
  template <class Make, class Done>
  bool sendTours(ros::Publisher& pub, Make make, double seconds, Done done) {
    const ros::Time start = ros::Time::now();
    ros::Time last;
    return spinUntil([&] {
      if (last.isZero() || (ros::Time::now() - last).toSec() >= 0.1) {
        pub.publish(make());
        last = ros::Time::now();
      }
      return (ros::Time::now() - start).toSec() >= seconds || done();
    }, 60.0);
  }
  /// sendTours() of the chain's latest tour (its frontiers exist), changed by `change`.
  template <class Change, class Done>
  bool feedTours(ros::Publisher& pub, Change change, double seconds, Done done) {
    return sendTours(pub, [&] {
      go_feap::GlobalTour tour = *tour_;
      change(tour);
      return tour;
    }, seconds, done);
  }

  ros::NodeHandle nh_;
  ros::Subscriber frontier_sub_, tour_sub_, odom_sub_, status_sub_, layer_sub_, target_sub_;
  go_feap::ViewpointPath::ConstPtr target_;
  go_feap::GlobalTour::ConstPtr target_tour_;
  go_feap::ExplorationStatus::ConstPtr status_;
  go_feap::LayerBounds::ConstPtr layer_;
  ros::Publisher cmd_pub_;
  go_feap::FrontierArray::ConstPtr frontiers_, tour_frontiers_;
  std::deque<go_feap::FrontierArray::ConstPtr> recent_frontiers_;
  /// Every tour with frontiers since the first test began: a kept target carries the stamp of a tour long
  /// past, chosen during an earlier test.
  static std::map<ros::Time, go_feap::GlobalTour::ConstPtr>& toursByStamp() {
    static std::map<ros::Time, go_feap::GlobalTour::ConstPtr> tours;
    return tours;
  }
  go_feap::GlobalTour::ConstPtr tour_;
  nav_msgs::Odometry::ConstPtr odom_;
  std::uint32_t highest_id_ = 0;  ///< of every frontier received
};

// First: before the trigger, with frontiers in view, neither mode's planners send a tour or a target (they
// used to plan and send targets at once: only the layer manager waited for the trigger). The local planner
// waits for it on its own too: the probe local planner, fed a tour of the frontiers in view by this test
// (the global planners send none yet), sends no target before the trigger, and does after it. Then the
// trigger starts the start band, once.
TEST_F(FrontierPlannerTest, NothingIsPlannedBeforeTheTriggerWhichStartsTheStartBandOnce) {
  auto scene = go_feap::test::sceneFromParams();
  ASSERT_TRUE(scene) << scene.message();
  ASSERT_TRUE(spinUntil([&] { return status_ && layer_ && odom_; }, 60.0)) << "no status, layer or odometry";
  EXPECT_EQ(status_->state, go_feap::ExplorationStatus::WAIT_TRIGGER);
  int sent = 0;
  const auto tour_seen = [&](const go_feap::GlobalTour::ConstPtr&) { ++sent; };
  const auto target_seen = [&](const go_feap::ViewpointPath::ConstPtr&) { ++sent; };
  const ros::Subscriber counted[] = {nh_.subscribe<go_feap::GlobalTour>("global_tour", 10, tour_seen),
                                     nh_.subscribe<go_feap::GlobalTour>("fuel/global_tour", 10, tour_seen),
                                     nh_.subscribe<go_feap::ViewpointPath>("local_target", 10, target_seen),
                                     nh_.subscribe<go_feap::ViewpointPath>("fuel/local_target", 10, target_seen)};
  int probe_targets = 0;
  go_feap::ViewpointPath::ConstPtr probe_target;
  const ros::Subscriber probe_target_sub = nh_.subscribe<go_feap::ViewpointPath>(
      "probe/local_target", 10, [&](const go_feap::ViewpointPath::ConstPtr& m) {
        ++probe_targets;
        probe_target = m;
      });
  ros::Publisher probe_tour_pub = nh_.advertise<go_feap::GlobalTour>("probe/global_tour", 10);
  ros::Publisher probe_failed_pub = nh_.advertise<std_msgs::UInt32>("probe/frontier_failed", 10);
  ASSERT_TRUE(spinUntil(
      [&] {
        return std::all_of(std::begin(counted), std::end(counted),
                           [](const ros::Subscriber& c) { return c.getNumPublishers() > 0; }) &&
               probe_target_sub.getNumPublishers() > 0 && probe_tour_pub.getNumSubscribers() > 0 &&
               probe_failed_pub.getNumSubscribers() > 0;
      },
      30.0))
      << "the planners' outputs are not connected";
  // A tour of the active frontiers in view, in the order they come.
  const auto ownTour = [&] {
    go_feap::GlobalTour tour;
    tour.header.stamp = ros::Time::now();
    tour.header.frame_id = frontiers_->header.frame_id;
    for (const go_feap::Frontier& f : frontiers_->frontiers)
      if (f.active) {
        tour.frontier_ids.push_back(f.id);
        tour.waypoints.push_back(f.average);
      }
    return tour;
  };
  // A turn in place until active frontiers are in view, then 3 s more (30 global planner periods).
  ASSERT_TRUE(go_feap::test::turnInPlace(
      cmd_pub_, scene->start.position,
      [&] {
        return frontiers_ && std::any_of(frontiers_->frontiers.begin(), frontiers_->frontiers.end(),
                                          [](const go_feap::Frontier& f) { return f.active; });
      },
      150.0))
      << "no active frontier in view";
  spinUntil([] { return false; }, 3.0);
  sendTours(probe_tour_pub, ownTour, 2.0, [] { return false; });
  spinUntil([] { return false; }, 0.5);
  EXPECT_EQ(status_->state, go_feap::ExplorationStatus::WAIT_TRIGGER);
  EXPECT_EQ(sent, 0) << "tours or targets before the trigger";
  EXPECT_EQ(probe_targets, 0) << "the probe local planner sent targets before the trigger, from a tour it was fed";
  std_srvs::Trigger trigger;
  ASSERT_TRUE(ros::service::waitForService("trigger", ros::Duration(10.0)));
  ASSERT_TRUE(ros::service::call("trigger", trigger));
  EXPECT_TRUE(trigger.response.success) << trigger.response.message;
  ASSERT_TRUE(spinUntil([&] { return status_->state == go_feap::ExplorationStatus::EXPLORE; }, 30.0));
  EXPECT_TRUE(sendTours(probe_tour_pub, ownTour, 30.0, [&] { return probe_targets > 0; }) && probe_targets > 0)
      << "the probe local planner sent no target from the same kind of tour after the trigger";
  // Its target dropped again (reported failed), so that the probe holds nothing for the tests below.
  if (probe_target && !probe_target->frontier_ids.empty()) {
    std_msgs::UInt32 drop;
    drop.data = probe_target->frontier_ids.front();
    probe_failed_pub.publish(drop);
    spinUntil([] { return false; }, 0.5);
  }
  // The maze start is at z = 1.0: band 1 of 1 m bands, [1, 2].
  ASSERT_TRUE(spinUntil([&] { return layer_->index == 1; }, 10.0));
  EXPECT_DOUBLE_EQ(layer_->z_min, 1.0);
  EXPECT_DOUBLE_EQ(layer_->z_max, 2.0);
  EXPECT_EQ(layer_->count, 3u);
  ASSERT_TRUE(ros::service::call("trigger", trigger));
  EXPECT_FALSE(trigger.response.success) << "a second trigger must be ignored";
  // Frontiers published after the band change carry the band's active flags.
  const ros::Time after = ros::Time::now() + ros::Duration(0.5);
  ASSERT_TRUE(spinUntil([&] { return frontiers_->header.stamp > after && !frontiers_->frontiers.empty(); }, 60.0));
  for (const auto& f : frontiers_->frontiers)
    EXPECT_EQ(f.active, f.average.z >= 1.0 && f.average.z <= 2.0) << "frontier " << f.id << " z " << f.average.z;
  // The status names the band flown (not the number of bands).
  EXPECT_TRUE(spinUntil([&] { return status_->layer == layer_->index; }, 10.0))
      << "status band " << status_->layer << ", layer topic band " << layer_->index << " of " << layer_->count;
}

// Runs after the trigger test (EXPLORE), as every test below.
TEST_F(FrontierPlannerTest, TourStartsAtAReachableFrontier) {
  auto scene = go_feap::test::sceneFromParams();
  ASSERT_TRUE(scene) << scene.message();
  const auto observable = go_feap::world::computeObservableSet(*scene);
  ASSERT_TRUE(spinUntil([&] { return odom_ != nullptr && status_ != nullptr; }, 60.0));
  ASSERT_EQ(status_->state, go_feap::ExplorationStatus::EXPLORE);

  ASSERT_TRUE(go_feap::test::turnInPlace(cmd_pub_, scene->start.position, [&] { return tour_ != nullptr; }, 150.0))
      << "no non-empty global_tour";

  ASSERT_FALSE(tour_->frontier_ids.empty());
  EXPECT_EQ(tour_->frontier_ids.size(), tour_->waypoints.size());
  EXPECT_TRUE(tour_->exact);
  const go_feap::Frontier* first = nullptr;
  for (const auto& f : tour_frontiers_->frontiers)
    if (f.id == tour_->frontier_ids.front()) first = &f;
  ASSERT_NE(first, nullptr) << "the tour's first frontier is not among the frontiers";
  EXPECT_TRUE(first->active);
  // Reachable: some cell of it lies in the ground-truth observable set (free space
  // connected to the start).
  const auto& geo = observable.mask.geometry();
  std::size_t reachable = 0;
  for (const auto& p : first->cells) {
    const Index3 idx = geo.coordToIndex(Vec3(p.x, p.y, p.z));
    reachable += geo.inside(idx) && observable.mask.at(idx) && !scene->isOccupied(idx);
  }
  EXPECT_GT(reachable, first->cells.size() / 2);
  // Every frontier cell is known free in truth too (not inside a wall).
  std::size_t in_wall = 0, cells = 0;
  for (const auto& f : tour_frontiers_->frontiers)
    for (const auto& p : f.cells) {
      ++cells;
      in_wall += scene->isOccupied(Vec3(p.x, p.y, p.z));
    }
  EXPECT_LT(in_wall, cells / 50 + 1);
}

TEST_F(FrontierPlannerTest, LocalTargetIsAFreeViewpointOfATourFrontier) {
  auto scene = go_feap::test::sceneFromParams();
  ASSERT_TRUE(scene) << scene.message();
  ASSERT_TRUE(spinUntil([&] { return target_ && target_tour_ && !target_->positions.empty(); }, 90.0))
      << "no local_target";
  EXPECT_EQ(target_->positions.size(), target_->yaws.size());
  EXPECT_EQ(target_->positions.size(), target_->frontier_ids.size());
  EXPECT_LE(target_->positions.size(), 3u);
  // Viewpoints lie in ground-truth free space with clearance (0.4 m requested; checked at
  // 0.25 m, one voxel less than the mapped clearance plus a voxel of map error).
  for (const auto& p : target_->positions) {
    const Vec3 v(p.x, p.y, p.z);
    for (double dx = -0.25; dx <= 0.25; dx += 0.05)
      for (double dy = -0.25; dy <= 0.25; dy += 0.05)
        for (double dz = -0.25; dz <= 0.25; dz += 0.05)
          ASSERT_FALSE(scene->isOccupied(Vec3(v + Vec3(dx, dy, dz)))) << "viewpoint " << v.transpose();
    EXPECT_TRUE(scene->box.contains(v));
  }
  // Of a tour frontier: the target carries the stamp of the tour it was chosen from, each viewpoint one of
  // that tour's first local/k_frontiers frontiers (not 0, a turn in place where none was found), on a
  // ring round its P_avg (the tour's waypoint): within the largest of viewpoints/ring_radii across.
  go_feap::ViewpointPath::ConstPtr target;
  go_feap::GlobalTour::ConstPtr tour;
  ASSERT_TRUE(spinUntil(
      [&] {
        target = target_;
        const auto it = target ? toursByStamp().find(target->header.stamp) : toursByStamp().end();
        if (it != toursByStamp().end()) tour = it->second;
        return tour != nullptr;
      },
      30.0))
      << "no local_target with the stamp of a tour";
  int k_frontiers = 0;
  std::vector<double> radii;
  ASSERT_TRUE(ros::param::get("/local_planner/local/k_frontiers", k_frontiers));
  ASSERT_TRUE(ros::param::get("/local_planner/viewpoints/ring_radii", radii) && !radii.empty());
  const double reach = *std::max_element(radii.begin(), radii.end());
  for (std::size_t i = 0; i < target->positions.size(); ++i) {
    const std::uint32_t id = target->frontier_ids[i];
    ASSERT_NE(id, 0u) << "viewpoint " << i << " belongs to no frontier (a turn in place)";
    const auto first = tour->frontier_ids.begin();
    const auto last = first + std::min<std::ptrdiff_t>(k_frontiers, static_cast<std::ptrdiff_t>(tour->frontier_ids.size()));
    const auto it = std::find(first, last, id);
    ASSERT_NE(it, last) << "viewpoint " << i << " observes frontier " << id << ", not one of the tour's first " << k_frontiers;
    const auto& w = tour->waypoints[static_cast<std::size_t>(it - first)];
    const auto& p = target->positions[i];
    EXPECT_LE(std::hypot(p.x - w.x, p.y - w.y), reach + 1e-6) << "viewpoint " << i << " of frontier " << id;
  }
}

// A failed attempt reported on frontier_failed for the local target's frontier (the trajectory planner
// found no way there) drops that target: the local planner chooses again on the next tour instead of
// repeating the kept target (same tour stamp) for ever. Runs after the trigger test (EXPLORE).
TEST_F(FrontierPlannerTest, AFailedTargetIsDroppedAndChosenAgain) {
  ASSERT_TRUE(spinUntil([&] { return status_ != nullptr; }, 60.0)) << "no status";
  if (status_->state == go_feap::ExplorationStatus::WAIT_TRIGGER) {
    std_srvs::Trigger trigger;
    ASSERT_TRUE(ros::service::waitForService("trigger", ros::Duration(10.0)));
    ASSERT_TRUE(ros::service::call("trigger", trigger));
  }
  // A kept target: the same message (tour stamp) repeated.
  go_feap::ViewpointPath::ConstPtr kept;
  ASSERT_TRUE(spinUntil(
      [&] {
        if (!target_ || target_->frontier_ids.empty() || target_->frontier_ids.front() == 0) return false;
        if (kept && kept != target_ && kept->header.stamp == target_->header.stamp &&
            kept->frontier_ids.front() == target_->frontier_ids.front())
          return true;
        kept = target_;
        return false;
      },
      90.0))
      << "no kept local_target";
  ros::Publisher failed_pub = nh_.advertise<std_msgs::UInt32>("frontier_failed", 10);
  // The layer manager and the local planner share one manager: one connection.
  ASSERT_TRUE(spinUntil([&] { return failed_pub.getNumSubscribers() >= 1; }, 10.0));
  std_msgs::UInt32 failed;
  // Another frontier's failure leaves the target as it is (the local planner reports failures of its own).
  failed.data = kept->frontier_ids.front() + 1000000;
  failed_pub.publish(failed);
  spinUntil([] { return false; }, 1.5);
  EXPECT_EQ(target_->target_seq, kept->target_seq) << "another frontier's failure dropped the target";
  EXPECT_EQ(target_->frontier_ids.front(), kept->frontier_ids.front());
  failed.data = kept->frontier_ids.front();
  failed_pub.publish(failed);
  EXPECT_TRUE(spinUntil([&] { return target_->header.stamp > kept->header.stamp; }, 5.0))
      << "the local planner kept its target for frontier " << failed.data << " after it failed";
  EXPECT_NE(target_->target_seq, kept->target_seq) << "the target chosen again kept its number";
}

// The fuel mode's planners (beside the go_feap ones, on fuel/...): while the local planner holds its
// target (planning::planDue() false) the global planner sends its last tour again, marked repeated,
// instead of planning one at global/rate 10 Hz; a planned tour costs a compute_time message, a repeated
// one none. When the target is dropped (a failed attempt on its frontier) a tour is due: the local
// planner wants one, the global planner plans it, and a new target follows.
TEST_F(FrontierPlannerTest, FuelModeGlobalPlannerPlansOnlyWhenTheLocalPlannerWantsATour) {
  int planned = 0, repeated = 0, computed = 0, not_wanted = 0;
  bool counting = false;
  go_feap::ViewpointPath::ConstPtr fuel_target;
  ros::Subscriber tours = nh_.subscribe<go_feap::GlobalTour>("fuel/global_tour", 50, [&](const go_feap::GlobalTour::ConstPtr& m) {
    if (counting) (m->repeated ? repeated : planned) += 1;
  });
  ros::Subscriber times = nh_.subscribe<go_feap::ComputeTime>("fuel/compute_time", 50, [&](const go_feap::ComputeTime::ConstPtr& m) {
    if (counting && m->block == "global") ++computed;
  });
  ros::Subscriber want = nh_.subscribe<std_msgs::Bool>("fuel/tour_wanted", 50, [&](const std_msgs::Bool::ConstPtr& m) {
    if (counting && !m->data) ++not_wanted;
  });
  ros::Subscriber targets = nh_.subscribe<go_feap::ViewpointPath>(
      "fuel/local_target", 5, [&](const go_feap::ViewpointPath::ConstPtr& m) { fuel_target = m; });
  ASSERT_TRUE(spinUntil([&] { return fuel_target && !fuel_target->frontier_ids.empty() && fuel_target->frontier_ids.front() != 0; }, 90.0))
      << "no fuel/local_target at a frontier";
  // Held: the vehicle does not fly here, so nothing reaches or clears the target within commit_time.
  // Counted until five repeated tours and five answers wanting none (at 10 Hz, about 0.5 s; longer when
  // frames are lost under load), over a window of `held` seconds: at most one plan at its start and one
  // every replan_period (1.5 s) after, where planning at global/rate would give one per repeat.
  counting = true;
  const ros::Time start = ros::Time::now();
  ASSERT_TRUE(spinUntil([&] { return repeated >= 5 && not_wanted >= 5; }, 30.0))
      << repeated << " repeated tours and " << not_wanted << " answers wanting none while the target was held";
  counting = false;
  const double held = (ros::Time::now() - start).toSec();
  const int allowed = 2 + static_cast<int>(held / 1.5);
  EXPECT_LE(planned, allowed) << "the global planner planned " << planned << " tours in " << held
                              << " s while the target was held";
  // Planning calls while held (a failed plan sends no tour, and a call at the window's edge may have its
  // tour outside it, so they are not matched one to one with planned tours): a repeat that planned would
  // count as many calls as repeats.
  EXPECT_LE(computed, allowed) << computed << " planning calls in " << held << " s while the target was held ("
                               << repeated << " repeated tours)";

  // Dropped: a tour is due, planned, and a new target chosen from it.
  const std::uint32_t seq = fuel_target->target_seq;
  ros::Publisher failed_pub = nh_.advertise<std_msgs::UInt32>("fuel/frontier_failed", 10);
  ASSERT_TRUE(spinUntil([&] { return failed_pub.getNumSubscribers() >= 1; }, 10.0));
  planned = 0;
  counting = true;
  std_msgs::UInt32 failed;
  failed.data = fuel_target->frontier_ids.front();
  failed_pub.publish(failed);
  EXPECT_TRUE(spinUntil([&] { return planned >= 1 && fuel_target->target_seq > seq; }, 20.0))
      << "no tour was planned and no new target chosen after the target was dropped (" << planned << " planned)";
  counting = false;
}

// A local planner never plans against a repeated tour (the global planner's last tour sent again while
// no tour was wanted): fed the chain's own tour marked repeated, the probe planner (go_feap mode, so it
// always wants a tour) answers each with tour_wanted but chooses no target and spends no compute time;
// fed the same tour unmarked, it plans and chooses a target.
TEST_F(FrontierPlannerTest, LocalPlannerNeverPlansAgainstARepeatedTour) {
  int wanted = 0, computed = 0;
  go_feap::ViewpointPath::ConstPtr probe_target;
  ros::Subscriber want = nh_.subscribe<std_msgs::Bool>("probe/tour_wanted", 50, [&](const std_msgs::Bool::ConstPtr& m) {
    if (m->data) ++wanted;
  });
  ros::Subscriber times = nh_.subscribe<go_feap::ComputeTime>("probe/compute_time", 50, [&](const go_feap::ComputeTime::ConstPtr& m) {
    if (m->block == "local") ++computed;
  });
  ros::Subscriber targets = nh_.subscribe<go_feap::ViewpointPath>(
      "probe/local_target", 5, [&](const go_feap::ViewpointPath::ConstPtr& m) { probe_target = m; });
  ros::Publisher tour_pub = nh_.advertise<go_feap::GlobalTour>("probe/global_tour", 10);
  // This node's subscriptions connected too: an answer sent before would be lost (1.5 s of the clock is
  // 0.75 s of wall time at the simulator's rate factor 2).
  ASSERT_TRUE(spinUntil([&] {
    return tour_ && tour_pub.getNumSubscribers() >= 1 && want.getNumPublishers() >= 1 && times.getNumPublishers() >= 1;
  }, 90.0)) << "no tour to feed the probe";
  auto feed = [&](bool repeated, double seconds) {
    return feedTours(
        tour_pub, [&](go_feap::GlobalTour& tour) { tour.repeated = repeated; }, seconds,
        [&] { return !repeated && probe_target; });
  };
  ASSERT_TRUE(feed(true, 1.5));
  EXPECT_GE(wanted, 5) << "the probe did not take up the repeated tours";
  EXPECT_FALSE(probe_target) << "a target was chosen from a repeated tour";
  EXPECT_EQ(computed, 0) << "planning against a repeated tour";

  // Unmarked, the same tour is planned against: a target follows (a viewpoint of its frontiers, or a
  // look around should none have one from here; either way a plan was made).
  ASSERT_TRUE(feed(false, 10.0));
  ASSERT_TRUE(probe_target) << "no target from the same tour unmarked";
  EXPECT_GE(computed, 1);
}

// A tour none of whose frontiers is in the latest frontier list (planned on an older one) is skipped: no
// attempt fails and no look round starts (each of its frontiers was reported failed, and the vehicle turned
// in place), and the next tour is wanted. So is an empty tour. The chain's own tour is then planned against.
TEST_F(FrontierPlannerTest, LocalPlannerSkipsATourWhoseFrontiersAreAllGone) {
  int wanted = 0, computed = 0, failed = 0;
  go_feap::ViewpointPath::ConstPtr probe_target;
  ros::Subscriber want = nh_.subscribe<std_msgs::Bool>("probe/tour_wanted", 50, [&](const std_msgs::Bool::ConstPtr& m) {
    if (m->data) ++wanted;
  });
  ros::Subscriber times = nh_.subscribe<go_feap::ComputeTime>("probe/compute_time", 50, [&](const go_feap::ComputeTime::ConstPtr& m) {
    if (m->block == "local") ++computed;
  });
  ros::Subscriber fails = nh_.subscribe<std_msgs::UInt32>("probe/frontier_failed", 50,
                                                          [&](const std_msgs::UInt32::ConstPtr&) { ++failed; });
  ros::Subscriber targets = nh_.subscribe<go_feap::ViewpointPath>(
      "probe/local_target", 5, [&](const go_feap::ViewpointPath::ConstPtr& m) { probe_target = m; });
  ros::Publisher tour_pub = nh_.advertise<go_feap::GlobalTour>("probe/global_tour", 10);
  ASSERT_TRUE(spinUntil([&] {
    return tour_ && tour_pub.getNumSubscribers() >= 1 && want.getNumPublishers() >= 1 &&
           times.getNumPublishers() >= 1 && fails.getNumPublishers() >= 1;
  }, 90.0)) << "no tour to feed the probe";
  auto feed = [&](bool gone, double seconds) {
    return feedTours(
        tour_pub,
        [&](go_feap::GlobalTour& tour) {
          if (gone)
            for (std::uint32_t& id : tour.frontier_ids) id += 4000000000u;  // ids no frontier has had
        },
        seconds, [&] { return !gone && probe_target; });
  };
  ASSERT_FALSE(tour_->frontier_ids.empty());
  // A target the probe holds (from an earlier test, or chosen now from the chain's tour) is dropped first,
  // reported failed, so that the stale tours meet a probe with nothing in hand.
  ros::Publisher failed_pub = nh_.advertise<std_msgs::UInt32>("probe/frontier_failed", 10);
  ASSERT_TRUE(feed(false, 10.0));
  ASSERT_TRUE(probe_target) << "no target from the chain's tour";
  ASSERT_TRUE(spinUntil([&] { return failed_pub.getNumSubscribers() >= 2; }, 10.0));  // the probe, and `fails`
  std_msgs::UInt32 drop;
  drop.data = probe_target->frontier_ids.at(0);
  failed_pub.publish(drop);
  spinUntil([] { return false; }, 0.5);
  probe_target.reset();
  wanted = computed = failed = 0;
  ASSERT_TRUE(feed(true, 1.5));
  EXPECT_GE(wanted, 5) << "the probe did not ask again for a tour";
  EXPECT_EQ(failed, 0) << "frontiers of a stale tour reported failed";
  EXPECT_FALSE(probe_target) << "a target (a look round) from a stale tour";
  EXPECT_EQ(computed, 0) << "planning against a stale tour";
  // An empty tour (nothing to visit: every frontier blacklisted, or none in reach) is no attempt either:
  // no look round and no failed frontier; the layer manager decides what comes next.
  computed = failed = 0;
  ASSERT_TRUE(feedTours(
      tour_pub,
      [](go_feap::GlobalTour& tour) {
        tour.frontier_ids.clear();
        tour.waypoints.clear();
      },
      1.5, [] { return false; }));
  EXPECT_EQ(failed, 0) << "frontiers failed on an empty tour";
  EXPECT_FALSE(probe_target) << "a target (a look round) from an empty tour";
  EXPECT_EQ(computed, 0) << "planning against an empty tour";
  ASSERT_TRUE(feed(false, 10.0));
  ASSERT_TRUE(probe_target) << "no target from the chain's tour";
  EXPECT_GE(computed, 1);
}

// When a tour is wanted again, the fuel-mode global planner plans it at once from the last frontiers
// (go_feap_bench plans it in the same tick), not at the next frontier message past global/rate. The
// probe planner, fed by the test: a frontier message gives a planned tour; told no tour is wanted, it
// answers the next frontier message with that tour repeated; told a tour is wanted again, it plans one
// with no frontier message after.
TEST_F(FrontierPlannerTest, FuelModeGlobalPlannerPlansAtOnceWhenATourIsWantedAgain) {
  int planned = 0, repeated = 0;
  ros::Subscriber tours = nh_.subscribe<go_feap::GlobalTour>("probe/fuel_tour", 20, [&](const go_feap::GlobalTour::ConstPtr& m) {
    (m->repeated ? repeated : planned) += 1;
  });
  ros::Publisher frontier_pub = nh_.advertise<go_feap::FrontierArray>("probe/frontiers", 2);
  ros::Publisher wanted_pub = nh_.advertise<std_msgs::Bool>("probe/fuel_tour_wanted", 2);
  ASSERT_TRUE(spinUntil([&] {
    return frontiers_ && !frontiers_->frontiers.empty() && frontier_pub.getNumSubscribers() >= 1 &&
           wanted_pub.getNumSubscribers() >= 1 && tours.getNumPublishers() >= 1;
  }, 90.0)) << "no frontiers to feed the probe";
  const go_feap::FrontierArray frontiers = *frontiers_;
  // Frontier messages 0.15 s apart (global/rate 10 Hz lets one through per 0.1 s) until `done`.
  auto feed = [&](const std::function<bool()>& done) {
    ros::Time last;
    return spinUntil([&] {
      if (last.isZero() || (ros::Time::now() - last).toSec() >= 0.15) {
        frontier_pub.publish(frontiers);
        last = ros::Time::now();
      }
      return done();
    }, 30.0);
  };
  auto pause = [&](double seconds) {
    const ros::Time start = ros::Time::now();
    spinUntil([&] { return (ros::Time::now() - start).toSec() >= seconds; }, 30.0);
  };
  ASSERT_TRUE(feed([&] { return planned >= 1; })) << "the probe planned no tour";
  std_msgs::Bool wanted;
  wanted.data = false;
  wanted_pub.publish(wanted);
  // Tours come in order on one connection: from the first repeated one on, "no tour wanted" is in force
  // (it travels on another connection, so a tour may still be planned before it arrives).
  int before = -1;  // planned tours when the first repeated one came
  ASSERT_TRUE(feed([&] {
    if (repeated >= 1 && before < 0) before = planned;
    return repeated >= 3;
  })) << "no repeated tours while no tour was wanted";
  EXPECT_EQ(planned, before) << "a tour was planned while none was wanted";
  pause(0.3);  // the last frontier message's tour, if any, is in
  const int held = planned;
  wanted.data = true;
  wanted_pub.publish(wanted);
  EXPECT_TRUE(spinUntil([&] { return planned > held; }, 10.0))
      << "no tour planned when one was wanted again without a new frontier message";
}

// tour_wanted answers each tour for the state it leaves: the fuel-mode probe local planner, fed the
// chain's tour, chooses a target from the first one it takes up and, holding that target for
// commit_time, wants no further tour (answering for the state before the plan, it said it wanted one,
// and the global planner planned a tour more than FUEL's cadence asks).
TEST_F(FrontierPlannerTest, FuelModeLocalPlannerWantsNoTourRightAfterChoosingATarget) {
  std::vector<bool> answers;
  go_feap::ViewpointPath::ConstPtr probe_target;
  ros::Subscriber want = nh_.subscribe<std_msgs::Bool>("probe/fuel_local/tour_wanted", 50,
                                                       [&](const std_msgs::Bool::ConstPtr& m) { answers.push_back(m->data); });
  ros::Subscriber targets = nh_.subscribe<go_feap::ViewpointPath>(
      "probe/fuel_local/local_target", 5, [&](const go_feap::ViewpointPath::ConstPtr& m) { probe_target = m; });
  ros::Publisher tour_pub = nh_.advertise<go_feap::GlobalTour>("probe/fuel_local/global_tour", 10);
  ASSERT_TRUE(spinUntil([&] { return tour_ && tour_pub.getNumSubscribers() >= 1 && want.getNumPublishers() >= 1; }, 90.0))
      << "no tour to feed the probe";
  // Tours marked repeated, one a second, until the probe answers one (before it has the map and odometry
  // it answers none; a repeated tour it answers without planning): then it is ready.
  go_feap::GlobalTour tour = *tour_;
  tour.repeated = true;
  ros::WallTime last;
  ASSERT_TRUE(spinUntil([&] {
    if (answers.empty() && (last.isZero() || (ros::WallTime::now() - last).toSec() >= 1.0)) {
      tour_pub.publish(tour);
      last = ros::WallTime::now();
    }
    return !answers.empty();
  }, 30.0)) << "the probe took up no tour";
  spinUntil([] { return false; }, 0.5);
  ASSERT_FALSE(probe_target) << "a target chosen from a repeated tour";
  // Then one tour to plan against: one answer, with the target.
  answers.clear();
  tour.repeated = false;
  tour_pub.publish(tour);
  ASSERT_TRUE(spinUntil([&] { return !answers.empty() && probe_target; }, 30.0)) << "no answer and target for the tour";
  spinUntil([] { return false; }, 0.5);
  EXPECT_EQ(answers.size(), 1u);
  EXPECT_FALSE(answers.front()) << "a tour was wanted right after a target was chosen from the last one";
}

// The omission term orders through the nodelet. The go_feap-mode probe global planner (lambda 0.5, the
// shipped omission weights) gets two frontiers straight above and below the UAV: A 0.5 m up, B 0.6 m
// down, in plain sight (paths of 0.5, 0.6 and 1.1 m). Brute force of J = travel time + lambda * sum xi t
// (v_max 2 m/s): with xi 0 on both, A comes first (J 0.55 s against 0.55 s + 0.05 s); with xi 2 s on B
// (|C| <= c_small, T < t_max, 0 < N_near < n_max) and A's xi taken away by any one factor (|C| 3000: xi
// 0.02 s; T 30 s; N_near 0; N_near 5), B comes first (0.61 s against 0.66 s, lambda 0.1 too; 0.85 s
// against 1.10 s here). Each factor alone turns the order, so a nodelet that dropped one of them on the
// way (cells, duration or n_near from the message) or the weight would keep A first and fail.
TEST_F(FrontierPlannerTest, OmissionLikelyFrontierComesFirstThroughTheNodelet) {
  std::map<ros::Time, go_feap::GlobalTour::ConstPtr> tours;
  ros::Subscriber tour_sub = nh_.subscribe<go_feap::GlobalTour>(
      "probe/feap/global_tour", 20, [&](const go_feap::GlobalTour::ConstPtr& m) { tours[m->header.stamp] = m; });
  ros::Publisher frontier_pub = nh_.advertise<go_feap::FrontierArray>("probe/feap/frontiers", 2);
  ASSERT_TRUE(spinUntil([&] {
    return odom_ && frontier_pub.getNumSubscribers() >= 1 && tour_sub.getNumPublishers() >= 1;
  }, 90.0)) << "no odometry, or the probe is not connected";
  const auto& p = odom_->pose.pose.position;
  const Vec3 uav(p.x, p.y, p.z);
  ASSERT_GT(uav.z(), 0.6 + 0.3) << "the UAV is too low for a frontier 0.6 m below it";
  struct Omission {
    int cells;
    double duration;
    std::uint32_t n_near;
  };
  const Omission likely{10, 1.0, 2};  // xi = 1 * 2 * 1 = 2 s
  const std::uint32_t id_a = 4000000001u, id_b = 4000000002u;  // far above the finder's ids
  auto frontier = [](std::uint32_t id, const Vec3& at, const Omission& o) {
    go_feap::Frontier f;
    f.id = id;
    geometry_msgs::Point c;
    c.x = at.x(), c.y = at.y(), c.z = at.z();
    f.cells.assign(static_cast<std::size_t>(o.cells), c);  // |C| is the cell count
    f.average = f.aabb_min = f.aabb_max = c;
    f.duration = o.duration;
    f.n_near = o.n_near;
    f.active = true;
    return f;
  };
  // Publishes A and B with these attributes (0.15 s apart: global/rate lets one through per 0.1 s) until
  // the tour planned from one of them comes; returns its order. Each call's stamps come after every stamp
  // of the calls before (the clock ticks in 10 ms: a call's first message could share the last stamp of
  // the one before, whose tour, planned from the other attributes, was then taken for this call's).
  ros::Time last_sent;
  auto orderFor = [&](const Omission& a, const Omission& b) {
    spinUntil([&] { return ros::Time::now() > last_sent; }, 10.0);
    tours.clear();
    go_feap::FrontierArray msg;
    msg.header.frame_id = "world";
    msg.frontiers = {frontier(id_a, uav + Vec3(0.0, 0.0, 0.5), a), frontier(id_b, uav + Vec3(0.0, 0.0, -0.6), b)};
    std::vector<std::uint32_t> order;
    ros::WallTime last;
    spinUntil([&] {
      for (const auto& [stamp, tour] : tours)
        if (stamp == msg.header.stamp && !msg.header.stamp.isZero()) {
          order.assign(tour->frontier_ids.begin(), tour->frontier_ids.end());
          return true;
        }
      if (last.isZero() || (ros::WallTime::now() - last).toSec() >= 0.15) {
        msg.header.stamp = ros::Time::now();
        if (msg.header.stamp <= last_sent) return false;  // the clock has not ticked since
        frontier_pub.publish(msg);
        last_sent = msg.header.stamp;
        last = ros::WallTime::now();
      }
      return false;
    }, 30.0);
    return order;
  };
  const std::vector<std::uint32_t> a_first = {id_a, id_b}, b_first = {id_b, id_a};
  const Omission unlikely{10, 30.0, 2};  // T >= t_max: xi 0
  EXPECT_EQ(orderFor(unlikely, unlikely), a_first) << "with no omission term, the nearer frontier first";
  const struct {
    Omission a;
    const char* what;
  } cases[] = {{{3000, 1.0, 2}, "A's cell count (3000: alpha 0.01)"},
               {{10, 30.0, 2}, "A's duration (30 s: omega 0)"},
               {{10, 1.0, 0}, "A's n_near (0: beta 0)"},
               {{10, 1.0, 5}, "A's n_near (5: beta 0)"}};
  for (const auto& c : cases) {
    EXPECT_EQ(orderFor(c.a, likely), b_first) << "B, likely omitted, not first with only " << c.what << " telling them apart";
    EXPECT_EQ(orderFor(likely, c.a), a_first) << "A not first with " << c.what << " given to B";
  }
}

// The chain's own messages, fed malformed from outside (a bag, a tool), are refused whole and the
// nodelets go on with what they had (go_feap/ros/message_checks.h). Last in the file: it publishes on
// the chain's layer topic.
//  * The probe global planner, wanting a tour, plans none from frontier arrays with a NaN P_avg, a cell
//    far outside the map (a voxel index cast from it does not exist) or one id twice, then plans from the
//    same array unbroken.
//  * The probe local planner answers no tour whose waypoints do not match its ids or are not finite (it
//    answers every tour it takes up with tour_wanted), then answers the same tour unbroken.
//  * The frontier finder keeps its band through a layer with a NaN floor and an inverted one: the
//    frontiers published after still carry the real band's active flags (a NaN or inverted band made
//    every frontier inactive).
TEST_F(FrontierPlannerTest, MalformedChainMessagesAreRefusedAndTheNodeletsKeepWorking) {
  int planned = 0, answers = 0;
  ros::Subscriber tours = nh_.subscribe<go_feap::GlobalTour>("probe/fuel_tour", 20, [&](const go_feap::GlobalTour::ConstPtr& m) {
    if (!m->repeated) ++planned;
  });
  ros::Subscriber want = nh_.subscribe<std_msgs::Bool>("probe/tour_wanted", 50, [&](const std_msgs::Bool::ConstPtr&) { ++answers; });
  go_feap::LayerBounds::ConstPtr band;  // the layer manager's last band (the test's own layers not counted)
  ros::Subscriber layers = nh_.subscribe<go_feap::LayerBounds>("layer", 5, [&](const go_feap::LayerBounds::ConstPtr& m) {
    if (std::isfinite(m->z_min) && m->z_min < m->z_max) band = m;
  });
  ros::Publisher frontier_pub = nh_.advertise<go_feap::FrontierArray>("probe/frontiers", 2);
  ros::Publisher fuel_wanted_pub = nh_.advertise<std_msgs::Bool>("probe/fuel_tour_wanted", 2, true);
  ros::Publisher tour_pub = nh_.advertise<go_feap::GlobalTour>("probe/global_tour", 10);
  ros::Publisher layer_pub = nh_.advertise<go_feap::LayerBounds>("layer", 2);
  ASSERT_TRUE(spinUntil([&] {
    return frontiers_ && !frontiers_->frontiers.empty() && tour_ && band && frontier_pub.getNumSubscribers() >= 1 &&
           fuel_wanted_pub.getNumSubscribers() >= 1 && tour_pub.getNumSubscribers() >= 1 &&
           layer_pub.getNumSubscribers() >= 2 &&  // the manager, and this test itself
           tours.getNumPublishers() >= 1 && want.getNumPublishers() >= 1;
  }, 90.0)) << "no frontiers, tour or band to feed the probes (" << frontier_pub.getNumSubscribers() << " "
             << fuel_wanted_pub.getNumSubscribers() << " " << tour_pub.getNumSubscribers() << " "
             << layer_pub.getNumSubscribers() << " " << tours.getNumPublishers() << " " << want.getNumPublishers() << " "
             << (band != nullptr) << (tour_ != nullptr) << ")";
  std_msgs::Bool yes;
  yes.data = true;
  fuel_wanted_pub.publish(yes);
  auto pause = [&](double seconds) {
    const ros::Time start = ros::Time::now();
    spinUntil([&] { return (ros::Time::now() - start).toSec() >= seconds; }, 30.0);
  };
  // One message every 0.15 s (global/rate lets one through per 0.1 s), in turn, until `done` or `seconds`.
  auto feed = [&](const ros::Publisher& pub, const auto& messages, double seconds, const std::function<bool()>& done) {
    const ros::Time start = ros::Time::now();
    ros::Time last;
    std::size_t i = 0;
    spinUntil([&] {
      if (last.isZero() || (ros::Time::now() - last).toSec() >= 0.15) {
        pub.publish(messages[i++ % messages.size()]);
        last = ros::Time::now();
      }
      return done() || (ros::Time::now() - start).toSec() >= seconds;
    }, 60.0);
  };
  pause(0.5);

  const go_feap::FrontierArray good = *frontiers_;
  std::vector<go_feap::FrontierArray> broken(3, good);
  broken[0].frontiers[0].average.x = std::nan("");
  broken[1].frontiers[0].cells[0].y = 1e300;
  broken[2].frontiers.push_back(good.frontiers[0]);
  planned = 0;
  feed(frontier_pub, broken, 1.5, [] { return false; });
  EXPECT_EQ(planned, 0) << "the probe global planner planned a tour from malformed frontiers";
  feed(frontier_pub, std::vector<go_feap::FrontierArray>{good}, 10.0, [&] { return planned >= 1; });
  EXPECT_GE(planned, 1) << "the probe global planner planned no tour from the same frontiers unbroken";

  go_feap::GlobalTour tour = *tour_;
  std::vector<go_feap::GlobalTour> bad_tours(2, tour);
  bad_tours[0].waypoints.pop_back();
  bad_tours[1].waypoints.back().z = std::numeric_limits<double>::infinity();
  pause(0.3);
  answers = 0;
  feed(tour_pub, bad_tours, 1.5, [] { return false; });
  EXPECT_EQ(answers, 0) << "the probe local planner took up a malformed tour";
  feed(tour_pub, std::vector<go_feap::GlobalTour>{tour}, 10.0, [&] { return answers >= 1; });
  EXPECT_GE(answers, 1) << "the probe local planner took up no tour unbroken";

  std::vector<go_feap::LayerBounds> bad_layers(2, *band);
  bad_layers[0].z_min = std::nan("");
  bad_layers[1].z_min = band->z_max + 1.0;
  bad_layers[1].z_max = band->z_max + 0.5;
  feed(layer_pub, bad_layers, 1.0, [] { return false; });
  const ros::Time after = ros::Time::now() + ros::Duration(0.3);
  ASSERT_TRUE(spinUntil([&] { return frontiers_->header.stamp > after && !frontiers_->frontiers.empty(); }, 30.0));
  std::size_t active = 0;
  for (const auto& f : frontiers_->frontiers) {
    const bool in_band = f.average.z >= band->z_min && f.average.z <= band->z_max;
    active += in_band;
    EXPECT_EQ(f.active, in_band) << "frontier " << f.id << " z " << f.average.z << ", band " << band->z_min << " .. "
                                 << band->z_max;
  }
  EXPECT_GT(active, 0u) << "no frontier in the band: the check shows nothing";

  // A new band reaches the planners at once: the finder sends its frontiers again with the new band's active
  // flags and the stamp of the map update they come from (they used to wait for the next update, whose
  // stamp is always a new one). Then the manager's band again.
  std::vector<go_feap::FrontierArray::ConstPtr> seen;
  ros::Subscriber all = nh_.subscribe<go_feap::FrontierArray>(
      "frontiers", 100, [&](const go_feap::FrontierArray::ConstPtr& m) { seen.push_back(m); });
  ASSERT_TRUE(spinUntil([&] { return !seen.empty(); }, 30.0)) << "no frontiers";
  go_feap::LayerBounds other = *band;
  other.z_min = band->z_max;
  other.z_max = band->z_max + 1.0;
  const std::size_t before = seen.size();
  layer_pub.publish(other);
  std::size_t again = 0;
  ASSERT_TRUE(spinUntil([&] {
    for (std::size_t k = std::max<std::size_t>(before, 1); k < seen.size() && again == 0; ++k)
      if (seen[k]->header.stamp == seen[k - 1]->header.stamp) again = k;
    return again != 0;
  }, 10.0)) << "the frontiers were not sent again on a band change (" << seen.size() - before << " updates since)";
  for (const auto& f : seen[again]->frontiers)
    EXPECT_EQ(f.active, f.average.z >= other.z_min && f.average.z <= other.z_max) << "frontier " << f.id << " z " << f.average.z;
  EXPECT_EQ(seen[again]->frontiers.size(), seen[again - 1]->frontiers.size()) << "the same frontiers, sent again";
  layer_pub.publish(*band);
  const std::size_t restored = seen.size();
  ASSERT_TRUE(spinUntil([&] {
    return seen.size() > restored && std::all_of(seen.back()->frontiers.begin(), seen.back()->frontiers.end(), [&](const auto& f) {
             return f.active == (f.average.z >= band->z_min && f.average.z <= band->z_max);
           });
  }, 10.0)) << "the manager's band did not come back";
}

// The frontier finder unloaded and loaded again into the running manager (a nodelet restarted): its ids
// go on from those handed out before (~id_reserved), so that the layer manager's blacklist and the
// planners' records of old ids name none of the new frontiers. Last: the finder is replaced.
TEST_F(FrontierPlannerTest, AFinderLoadedAgainHandsOutNoIdTwice) {
  ASSERT_TRUE(spinUntil([&] { return frontiers_ && !frontiers_->frontiers.empty(); }, 60.0)) << "no frontiers";
  int reserved = 0;
  ASSERT_TRUE(ros::param::get("frontier_finder/id_reserved", reserved)) << "the finder reserved no ids";
  EXPECT_GT(static_cast<std::int64_t>(reserved), static_cast<std::int64_t>(highest_id_));
  nodelet::NodeletUnload unload;
  unload.request.name = "/frontier_finder";
  ASSERT_TRUE(ros::service::call("go_feap_manager/unload_nodelet", unload) && unload.response.success);
  // Its loader process follows (the bond broke); a message still under way arrives meanwhile.
  spinUntil(
      [] {
        std::vector<std::string> nodes;
        return ros::master::getNodes(nodes) && std::find(nodes.begin(), nodes.end(), "/frontier_finder") == nodes.end();
      },
      10.0);
  spinUntil([] { return false; }, 1.0);
  const std::uint32_t before = highest_id_;
  ASSERT_GT(before, 0u);
  nodelet::NodeletLoad load;
  load.request.name = "/frontier_finder";
  load.request.type = "go_feap/FrontierFinder";
  const ros::Time loaded = ros::Time::now();
  ASSERT_TRUE(ros::service::call("go_feap_manager/load_nodelet", load) && load.response.success);
  ASSERT_TRUE(spinUntil([&] { return frontiers_->header.stamp > loaded && !frontiers_->frontiers.empty(); }, 60.0))
      << "the finder loaded again sends no frontiers";
  for (const auto& f : frontiers_->frontiers)
    EXPECT_GT(f.id, before) << "frontier id " << f.id << " was handed out before the finder was loaded again";
  ASSERT_TRUE(ros::param::get("frontier_finder/id_reserved", reserved));
  EXPECT_GT(static_cast<std::int64_t>(reserved), static_cast<std::int64_t>(highest_id_));
}

}  // namespace

GO_FEAP_ROSTEST_MAIN("test_frontier_planner_ros")
