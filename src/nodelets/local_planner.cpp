// LocalPlanner: picks the next viewpoint. Samples candidate viewpoints around the first
// frontiers of the global tour, filters them by frontier type (near or cluttered: steering
// rate; open: N_view) and runs the viewpoint DAG. In: global_tour, frontiers, odom, depth
// (obstacle-ratio window), camera_info (the viewpoints' FOV checked against the camera's), layer, map_handle, map_update (forgets the cached viewpoints of the frontiers
// a change reaches), frontier_failed (drops a failed target). Out:
// local_target (go_feap/ViewpointPath, numbered: a kept target is repeated with its number),
// frontier_failed, viewpoint_markers, tour_wanted (std_msgs/Bool, with each tour: planning::planDue() for
// the state that tour leaves, so after a plan for the target it chose or kept; the global planner sends
// its last tour again, `repeated`, instead of planning while it is false, and plans at once when it turns
// true; a repeated tour is never planned against). Targets are chosen and sent only while the layer
// manager's status says the exploration is under way (EXPLORE, FINAL_PASS): before the trigger nothing
// flies, and once FINISHED no new target is sent (the trajectory planner ends the flight it is on).
// An empty tour (nothing to visit: a band just changed and settling) sends nothing, as go_feap_bench.
#include <cv_bridge/cv_bridge.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <visualization_msgs/MarkerArray.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <mutex>
#include <shared_mutex>
#include <std_msgs/Bool.h>
#include <std_msgs/UInt32.h>
#include <optional>
#include <vector>

#include "go_feap/ExplorationStatus.h"
#include "go_feap/FrontierArray.h"
#include "go_feap/GlobalTour.h"
#include "go_feap/LayerBounds.h"
#include "go_feap/MapUpdate.h"
#include "go_feap/ViewpointPath.h"
#include "go_feap/planning/local_planner.h"
#include "go_feap/planning/viewpoints.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/message_checks.h"
#include "go_feap/common/config_groups.h"
#include "go_feap/ros/compute_time.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/params.h"
#include "go_feap/ros/shared_map.h"

namespace go_feap {

class LocalPlanner : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
  ros_map::EmptyHandles empty_handles_{10.0};  ///< map_handles without a map, said only when they last
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros_params::ParamReader p(getPrivateNodeHandle());
    auto& v = viewpoint_config_;
    auto& l = local_config_;
    config::readViewpoints(p, v);
    config::readLocal(p, l);
    p.get("frontier/max_cluster_extent", frontier_extent_).get("local/max_input_speed", max_input_speed_);
    p.get("local/odom_timeout", odom_timeout_);
    config::readAstar(p, astar_config_, "distance_astar");
    p.getFrame("world_frame", world_frame_);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    for (const common::Status& st : {v.validate(), l.validate(), astar_config_.validate()})
      ros_params::requireOrThrow(st.ok(), getName(), st.message());
    ros_params::requireOrThrow(frontier_extent_ > 0.0 && std::isfinite(frontier_extent_), getName(),
                               "parameter '" + p.fullName("frontier/max_cluster_extent") + "' must be finite and > 0");
    ros_params::requireOrThrow(std::isfinite(max_input_speed_) && max_input_speed_ > 0.0, getName(),
                               "parameter '" + p.fullName("local/max_input_speed") + "' must be > 0");
    speed_limit_name_ = p.fullName("local/max_input_speed");
    ros_params::requireOrThrow(std::isfinite(odom_timeout_) && odom_timeout_ > 0.0, getName(),
                               "parameter '" + p.fullName("local/odom_timeout") + "' must be finite and > 0");
    window_ = std::make_unique<planning::ObstacleWindow>(l.window_size, l.clutter_threshold);

    compute_pub_ = nh.advertise<ComputeTime>("compute_time", 20);
    target_pub_ = nh.advertise<ViewpointPath>("local_target", 2);
    marker_pub_ = nh.advertise<visualization_msgs::MarkerArray>("viewpoint_markers", 2);
    // Every publisher before the first subscription: onInit runs beside this nodelet's callbacks (a tour
    // heard at once, by a planner loaded into a running exploration, used them while they were assigned).
    failed_pub_ = nh.advertise<std_msgs::UInt32>("frontier_failed", 100);
    wanted_pub_ = nh.advertise<std_msgs::Bool>("tour_wanted", 2);
    handle_sub_ = ros_guard::subscribe(nh, getName(), "map_handle", 1, &LocalPlanner::onHandle, this);
    odom_sub_ = ros_guard::subscribe(nh, getName(), "odom", 5, &LocalPlanner::onOdom, this);
    depth_sub_ = ros_guard::subscribe(nh, getName(), "depth", 2, &LocalPlanner::onDepth, this);
    info_sub_ = ros_guard::subscribe(nh, getName(), "camera_info", 2, &LocalPlanner::onInfo, this);
    layer_sub_ = ros_guard::subscribe(nh, getName(), "layer", 1, &LocalPlanner::onLayer, this);
    frontier_sub_ = ros_guard::subscribe(nh, getName(), "frontiers", 2, &LocalPlanner::onFrontiers, this);
    tour_sub_ = ros_guard::subscribe(nh, getName(), "global_tour", 2, &LocalPlanner::onTour, this);
    update_sub_ = ros_guard::subscribe(nh, getName(), "map_update", 20, &LocalPlanner::onMapUpdate, this);
    failed_sub_ = ros_guard::subscribe(nh, getName(), "frontier_failed", 100, &LocalPlanner::onFailed, this);
    status_sub_ = ros_guard::subscribe(nh, getName(), "status", 2, &LocalPlanner::onStatus, this);
  }

  void onStatus(const ExplorationStatus::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!gate_.update(*msg, getName())) return;
    target_.reset();  // nothing in hand is repeated
    last_out_.reset();
    target_quicker_ = false;
  }

  void onHandle(const boost::shared_ptr<const ros_map::MapHandle>& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (shared_) {
      if (const std::string other = ros_map::otherMapProblem(*msg, shared_); !other.empty())
        GO_FEAP_NODELET_THROTTLE(ERROR, 10.0, getName() << ": " << other);
      return;
    }
    auto map = ros_map::acceptHandle(*msg);
    if (!map) {
      if (empty_handles_.due(ros::Time::now().toSec()))
        NODELET_ERROR_STREAM(getName() << ": for " << empty_handles_.patience() << " s: " << map.message());
      return;
    }
    // Astar's constructor throws otherwise; a viewpoint clearance past max_distance passes no viewpoint, and a
    // sensor_range past the mapper's scores viewpoints on cells never mapped from them.
    const map::EsdfConfig& esdf = (*map)->map->config().esdf;
    for (const common::Status& st : {astar_config_.validate(esdf), viewpoint_config_.validate(esdf),
                                     viewpoint_config_.fitsMapper((*map)->map->config().occupancy)})
      if (!st) {
        ros_params::stopManager(getName(), st.message());
        return;
      }
    // Built before the map is kept: a constructor that threw would leave the map taken and no A* (the
    // next tour would reach a null one, and the handle would never be taken again).
    auto astar = std::make_unique<planning::Astar>((*map)->map->occupancy(), (*map)->map->esdf(), astar_config_);
    shared_ = *map;
    astar_ = std::move(astar);
  }
  // The viewpoints cached for frontiers a change of the map reaches are forgotten (a frontier keeps its id
  // while its cells stay the same): by the changed voxels while the map is still at this update, by the
  // update's box after, and all of them when updates were missed.
  void onMapUpdate(const MapUpdate::ConstPtr& msg) {
    if (!ros_check::mapUpdateProblem(*msg).empty()) {  // the frontier finder names it
      std::lock_guard<std::mutex> lock(mutex_);
      cache_.retain({});
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    const std::uint64_t last = last_update_;
    last_update_ = msg->sequence;
    if (!shared_) return;  // no map yet: nothing sampled, nothing cached
    std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
    cache_.forgetFor(ros_conv::mapUpdateNote(*msg), last, shared_->sequence, shared_->map->occupancy().geometry(), shared_->last_changed);
  }

  void onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
    // The velocity prices every leg from the vehicle: one not finite (it used to be taken as rest) or
    // faster than local/max_input_speed refuses the message whole.
    common::Vec3 v_world;
    const std::string bad =
        ros_conv::odometryProblem(*msg, world_frame_, max_input_speed_, speed_limit_name_, v_world);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": odometry refused: " << bad);
      return;
    }
    const auto& p = msg->pose.pose.position;
    const auto& q = msg->pose.pose.orientation;
    std::lock_guard<std::mutex> lock(mutex_);
    position_ = common::Vec3(p.x, p.y, p.z);
    yaw_ = ros_conv::yawOf(q);
    tilt_ = planning::tiltOf(Eigen::Quaterniond(q.w, q.x, q.y, q.z));
    velocity_ = v_world;
    speed_ = velocity_.norm();
    odom_arrival_ = ros::Time::now();
  }
  // The odometry is current: it came within local/odom_timeout (a clock that went back counts as current).
  // A pose frozen by a VIO dropout would be taken for the vehicle at rest where it stopped: a target there
  // judged reached and settled at every tour, in vain, and its frontier blacklisted.
  bool odometryCurrent() {
    const double age = (ros::Time::now() - odom_arrival_).toSec();
    if (age <= odom_timeout_) return true;
    GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": no odometry for " << age << " s (local/odom_timeout "
                                                  << odom_timeout_ << " s): nothing planned nor judged until it comes");
    return false;
  }
  void onDepth(const sensor_msgs::Image::ConstPtr& msg) {
    const std::string bad = ros_check::depthImageProblem(*msg);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 5.0, getName() << ": depth image refused: " << bad << "; frame not counted");
      return;
    }
    cv_bridge::CvImageConstPtr image;
    try {
      image = cv_bridge::toCvShare(msg);
    } catch (const std::exception& e) {  // cv_bridge::Exception, or cv::Exception from OpenCV under it
      GO_FEAP_NODELET_THROTTLE(WARN, 5.0, getName() << ": depth image unreadable (" << e.what() << "); skipped");
      return;
    }
    const auto ratio = planning::obstacleRatio(image->image, local_config_.max_range);
    std::lock_guard<std::mutex> lock(mutex_);
    if (!ratio) {
      GO_FEAP_NODELET_THROTTLE(WARN, 5.0, getName() << ": " << ratio.message() << "; frame not counted");
      return;
    }
    window_->push(*ratio);
  }
  // The viewpoints' field of view against the depth camera's, once for each camera_info not checked before: a
  // wider model scores viewpoints on cells the camera does not see (their flights clear nothing, and the
  // frontiers go on until blacklisted). Said, not refused: a camera whose driver restarted with a narrower
  // image must not stop a flight. Not throttled: a throttle on the simulated clock swallows what comes in its
  // first period. One the mapper cannot take is left to the mapper to name.
  void onInfo(const sensor_msgs::CameraInfo::ConstPtr& info) {
    const map::DepthIntrinsics K = ros_conv::depthIntrinsics(*info);
    if (!K.validate()) return;
    std::lock_guard<std::mutex> lock(mutex_);
    if (std::find(checked_cameras_.begin(), checked_cameras_.end(), K) != checked_cameras_.end()) return;
    if (checked_cameras_.size() >= 16) checked_cameras_.erase(checked_cameras_.begin());  // a camera re-calibrating
    checked_cameras_.push_back(K);
    if (const common::Status st = viewpoint_config_.fitsCamera(K); !st)
      NODELET_WARN_STREAM(getName() << ": " << st.message() << " (camera_info " << K.width << "x" << K.height << ", fx "
                                    << K.fx << ", fy " << K.fy << ", cx " << K.cx << ", cy " << K.cy
                                    << "); set the viewpoints' hfov and vfov to at most the camera's");
  }
  void onLayer(const LayerBounds::ConstPtr& msg) {
    const std::string bad = ros_check::layerBoundsProblem(*msg);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": layer refused: " << bad << "; the band stays as it was");
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    band_ = {msg->z_min, msg->z_max};
    // No frontier in view and no look round yet (the layer manager repeats this while it holds): turn in
    // place, unless already flying somewhere or turning. The target in hand is repeated, with its number:
    // no tour comes while nothing is a frontier, and a target published before the trajectory planner
    // had subscribed (a start under load) was otherwise lost, and the vehicle never turned.
    if (!msg->look_around || !position_ || !gate_.open() || !odometryCurrent()) return;
    if (idle()) {
      GO_FEAP_NODELET_THROTTLE(INFO, 2.0, getName() << ": no frontier in view before a look round: turning in place");
      turnInPlace(msg->header.stamp);
    } else {
      repeatTarget();
    }
  }
  /// The target in hand again, with its number (the trajectory planner keeps it as the same target): a
  /// subscriber that started late or missed it still gets it.
  void repeatTarget() {
    if (last_out_) target_pub_.publish(*last_out_);
  }
  bool idle() const { return !target_ || planning::targetReached(*position_, yaw_, speed_, *target_, local_config_); }
  /// Targets a turn in place by scan_step (a frontier id of 0: no frontier).
  void turnInPlace(const ros::Time& stamp) {
    target_ = planning::scanTarget(*position_, yaw_, local_config_);
    target_frontier_ = 0;
    target_quicker_ = false;
    committed_at_ = ros::Time::now().toSec();
    ViewpointPath out;
    out.header.stamp = stamp;
    out.header.frame_id = world_frame_;
    out.target_seq = ++target_seq_;
    out.positions.push_back(ros_conv::toPoint(target_->position));
    out.yaws.push_back(target_->yaw);
    out.frontier_ids.push_back(0);
    target_pub_.publish(out);
    last_out_ = out;
  }
  // A failed attempt on the current target's frontier (the trajectory planner found no way there): drop
  // the target, as go_feap_bench does, so that the next tour chooses again. Kept, it was repeated for
  // ever, and each repeat failed again (the frontier, blacklisted, was no longer in any tour). A turn in
  // place (frontier id 0) that failed is dropped too: kept, it was repeated at every tour and look round
  // request, and the tours' frontiers, reported only when idle, were never blacklisted.
  void onFailed(const std_msgs::UInt32::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!target_ || msg->data != target_frontier_) return;
    target_.reset();
    last_out_.reset();
    target_quicker_ = false;
  }
  void publishWanted(bool wanted) {
    std_msgs::Bool msg;
    msg.data = wanted;
    wanted_pub_.publish(msg);
  }
  /// planning::planDue() right after a plan at `now`: a target that is still there was just chosen or kept
  /// (not reached, something left to see from it); none wants a tour.
  bool wantedAfterPlan(double now) const {
    if (!target_) return planning::planDue(nullptr, now, last_plan_, viewpoint_config_.min_visible, local_config_);
    planning::CurrentTarget held;
    held.viewpoint = *target_;
    held.committed_at = committed_at_;
    held.remaining_visible = viewpoint_config_.min_visible;
    held.quicker = target_quicker_;
    return planning::planDue(&held, now, last_plan_, viewpoint_config_.min_visible, local_config_);
  }
  void onFrontiers(const FrontierArray::ConstPtr& msg) {
    const std::string bad = ros_check::frontierArrayProblem(*msg);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": frontiers refused: " << bad);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    frontiers_ = msg;
  }

  void onTour(const GlobalTour::ConstPtr& tour) {
    const std::string bad = ros_check::globalTourProblem(*tour);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": global_tour refused: " << bad);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (!gate_.open() || !shared_ || !position_ || !frontiers_ || !odometryCurrent()) return;
    const std::string outside = ros_check::frontierOutside(*frontiers_, shared_->map->geometry().bounds());
    if (!outside.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": frontiers refused: " << outside);
      return;
    }
    const auto t_compute = ros_conv::WallClock::now();
    std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
    const map::VoxelMap& m = *shared_->map;
    const auto& geo = m.geometry();
    std::vector<frontier::Frontier> all, tour_frontiers;
    for (const auto& msg : frontiers_->frontiers) {
      frontier::Frontier f;
      f.id = msg.id;
      f.average = common::Vec3(msg.average.x, msg.average.y, msg.average.z);
      for (const auto& c : msg.cells) f.cells.push_back(geo.coordToIndex(common::Vec3(c.x, c.y, c.z)));
      all.push_back(std::move(f));
    }
    for (unsigned id : tour->frontier_ids) {
      const auto it = std::find_if(all.begin(), all.end(), [&](const frontier::Frontier& f) { return f.id == id; });
      if (it != all.end()) tour_frontiers.push_back(*it);  // else: it changed since the tour was planned
    }
    // The current target first: while planning could not replace it (planning::planDue()), repeat it.
    const double now = ros::Time::now().toSec();
    if (now < last_plan_) {  // a clock that went back (a bag played again): plan from now on, not from then
      NODELET_WARN_STREAM(getName() << ": the clock went back " << last_plan_ - now << " s: planning again from now");
      last_plan_ = -1e9;
      committed_at_ = std::min(committed_at_, now);
    }
    std::optional<planning::CurrentTarget> current;
    if (target_)
      current = planning::assessTarget(*target_, committed_at_, *position_, yaw_, speed_, tilt_, all,
                                       m.occupancy(), viewpoint_config_, frontier_extent_, local_config_);
    if (current) current->quicker = target_quicker_;
    const bool due = planning::planDue(current ? &*current : nullptr, now, last_plan_, viewpoint_config_.min_visible,
                                       local_config_);
    if (!due || tour->repeated) {
      map_lock.unlock();  // no compute time: nothing was planned (as in go_feap_bench)
      publishWanted(due);  // nothing changed: the next tour is wanted when this one was
      repeatTarget();
      return;
    }
    // A tour planned on an older frontier list, none of whose frontiers is in this one (the finder moved on
    // while the global planner worked): nothing is evaluated, so no attempt fails and no look round starts
    // (each of its frontiers was reported failed and the vehicle turned in place). The next tour is wanted.
    if (!tour->frontier_ids.empty() && tour_frontiers.empty()) {
      map_lock.unlock();
      NODELET_DEBUG_STREAM(getName() << ": no frontier of the tour is in the latest frontier list: waiting for the next");
      publishWanted(true);
      repeatTarget();
      return;
    }
    last_plan_ = now;
    // Planned against: tour_wanted answers for the state the plan leaves (a target just chosen or kept is
    // held), or the global planner would plan one more tour before it heard that none is wanted.
    struct OnExit {
      std::function<void()> run;
      ~OnExit() { run(); }
    } wanted_after{[&] { publishWanted(wantedAfterPlan(now)); }};
    // Nothing to visit (every frontier blacklisted, or none in reach): no look round and no failed
    // attempt, as go_feap_bench; the layer manager decides what comes next. It used to turn the vehicle
    // in place again after every turn, for ever once FINISHED(complete).
    if (tour->frontier_ids.empty()) return;
    std::vector<std::uint32_t> ids;
    for (const auto& f : frontiers_->frontiers) ids.push_back(f.id);
    cache_.retain(ids);
    auto plan = planning::chooseLocalTarget(*position_, velocity_, yaw_, std::move(tour_frontiers), band_.first, band_.second,
                                            m.occupancy(), m.esdf(), *astar_, *window_, viewpoint_config_,
                                            local_config_, &cache_, &visited_);
    if (!plan) {
      ros_conv::publishComputeTime(compute_pub_, "local", t_compute);
      map_lock.unlock();
      // Nothing to fly to: look around, unless already flying somewhere or turning.
      if (idle()) {
        GO_FEAP_NODELET_THROTTLE(INFO, 2.0, getName() << ": no local plan (" << plan.message()
                                                    << "): turning in place to look around");
        // Each look around is a failed attempt for the tour's frontiers (none had a viewpoint): a
        // frontier that stays unchanged through max_retries of them is blacklisted, not scanned for ever.
        for (unsigned id : tour->frontier_ids) {
          std_msgs::UInt32 failed;
          failed.data = id;
          failed_pub_.publish(failed);
        }
        turnInPlace(tour->header.stamp);
      } else {
        repeatTarget();
      }
      return;
    }
    // Target hysteresis (the same rule as go_feap_bench): keep the current viewpoint while it is
    // worth flying to; report a frontier that its reached viewpoint does not clear.
    const frontier::Viewpoint& proposal = plan->path.front();
    // Targets are compared by path, not straight line (pathCost()): under the map lock.
    const planning::TargetStep step = planning::stepTarget(
        current ? &*current : nullptr, proposal,
        [&](const frontier::Viewpoint& v) { return planning::pathCost(*astar_, *position_, velocity_, yaw_, v, local_config_); },
        now, viewpoint_config_.min_visible, local_config_, visited_);
    const planning::TargetDecision decision = step.decision;
    ros_conv::publishComputeTime(compute_pub_, "local", t_compute);
    map_lock.unlock();
    if (decision == planning::TargetDecision::kKeep) {
      repeatTarget();  // the kept target
      return;
    }
    if (decision == planning::TargetDecision::kReachedInVain) {
      // The frontier the same target is proposed for now: the target's own may have been regrown under a new
      // id meanwhile, and a failure of an id that is gone is forgotten (it was never blacklisted).
      const std::uint32_t frontier = plan->frontier_ids.front();
      NODELET_INFO_STREAM(getName() << ": frontier " << frontier
                                    << " not cleared from its reached viewpoint: failed attempt");
      std_msgs::UInt32 failed;
      failed.data = frontier;
      failed_pub_.publish(failed);
      target_.reset();
      last_out_.reset();
      return;
    }
    if (step.exhausted)
      NODELET_INFO_STREAM(getName() << ": the place of the target for frontier " << plan->frontier_ids.front()
                                    << " was chosen " << local_config_.max_choices << " times within "
                                    << local_config_.choice_window << " s: it is not proposed again");
    target_ = proposal;
    target_quicker_ = decision == planning::TargetDecision::kSwitchQuicker;
    target_frontier_ = plan->frontier_ids.front();
    committed_at_ = now;
    ViewpointPath out;
    out.header.stamp = tour->header.stamp;
    out.header.frame_id = world_frame_;
    out.target_seq = ++target_seq_;  // a new target, even one near the last: the trajectory goes exactly there
    out.cost = plan->cost;
    visualization_msgs::MarkerArray markers;
    visualization_msgs::Marker candidates, chosen;
    candidates.header = chosen.header = out.header;
    candidates.ns = "candidate_viewpoints";
    chosen.ns = "chosen_viewpoints";
    candidates.type = visualization_msgs::Marker::SPHERE_LIST;
    chosen.type = visualization_msgs::Marker::LINE_STRIP;
    candidates.pose.orientation.w = chosen.pose.orientation.w = 1.0;
    candidates.scale.x = candidates.scale.y = candidates.scale.z = 0.12;
    candidates.color.g = candidates.color.b = 0.8, candidates.color.a = 0.6;
    chosen.scale.x = 0.06;
    chosen.color.g = 1.0, chosen.color.a = 1.0;
    chosen.points.push_back(ros_conv::toPoint(*position_));
    for (std::size_t i = 0; i < plan->path.size(); ++i) {
      out.positions.push_back(ros_conv::toPoint(plan->path[i].position));
      out.yaws.push_back(plan->path[i].yaw);
      out.frontier_ids.push_back(plan->frontier_ids[i]);
      chosen.points.push_back(ros_conv::toPoint(plan->path[i].position));
    }
    for (const auto& layer : plan->layers)
      for (const auto& vp : layer) candidates.points.push_back(ros_conv::toPoint(vp.position));
    markers.markers = {candidates, chosen};
    target_pub_.publish(out);
    last_out_ = out;
    marker_pub_.publish(markers);
  }

  planning::ViewpointConfig viewpoint_config_;
  planning::LocalPlannerConfig local_config_;
  planning::AstarConfig astar_config_;
  std::string world_frame_;
  std::mutex mutex_;
  std::shared_ptr<ros_map::SharedMap> shared_;
  std::unique_ptr<planning::Astar> astar_;
  std::unique_ptr<planning::ObstacleWindow> window_;
  std::optional<common::Vec3> position_;
  double yaw_ = 0.0;
  double tilt_ = 0.0;                             ///< rad from level, of the last odometry
  common::Vec3 velocity_ = common::Vec3::Zero();  ///< world frame
  std::pair<double, double> band_{-1e18, 1e18};
  FrontierArray::ConstPtr frontiers_;
  ros::Publisher compute_pub_;
  ros::Publisher target_pub_, marker_pub_, failed_pub_, wanted_pub_;
  std::optional<frontier::Viewpoint> target_;
  std::optional<ViewpointPath> last_out_;
  planning::ViewpointCache cache_;
  planning::VisitedViewpoints visited_;
  std::uint32_t target_frontier_ = 0;
  std::uint32_t target_seq_ = 0;  ///< ViewpointPath::target_seq of the last new target
  bool target_quicker_ = false;  ///< the target won on cost (planning::CurrentTarget::quicker)
  ros_check::ExplorationGate gate_{"choosing targets", "no targets sent"};  ///< from the status
  double committed_at_ = 0.0, speed_ = 0.0, frontier_extent_ = 2.0, max_input_speed_ = 20.0, odom_timeout_ = 0.5;
  ros::Time odom_arrival_;  ///< when the last accepted odometry came (ROS clock)
  std::string speed_limit_name_;  ///< local/max_input_speed's full name, for the messages
  double last_plan_ = -1e9;  ///< s (ROS time), when a tour was last planned against (planning::planDue())
  ros::Subscriber handle_sub_, odom_sub_, depth_sub_, info_sub_, layer_sub_, frontier_sub_, tour_sub_, failed_sub_,
      status_sub_, update_sub_;
  std::vector<map::DepthIntrinsics> checked_cameras_;  ///< the last 16 camera_infos the FOV was checked against
  std::uint64_t last_update_ = 0;  ///< sequence of the last map_update
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::LocalPlanner, nodelet::Nodelet)
