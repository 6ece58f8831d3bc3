// GlobalPlanner: orders the frontiers near the UAV with the omission-aware objective.
// In: frontiers (go_feap/FrontierArray), odom, map_handle, blacklist, tour_wanted (std_msgs/Bool from
// the local planner: false while it holds its target, planning::planDue()). Out: global_tour
// (go_feap/GlobalTour) and global_tour_marker (line strip from the UAV through the tour). While no
// tour is wanted the last one is sent again at the same rate, marked `repeated`, without planning
// (the fuel mode's cadence, as go_feap_bench skips both planners then); when a tour is wanted again,
// it is planned at once from the last frontiers, as go_feap_bench plans it in the same tick.
// The planning step itself is the core's TourPlanner (A* path lengths on the shared map,
// cached per frontier pair). Nothing is planned except while the layer manager's status says the
// exploration is under way (EXPLORE, FINAL_PASS): not before the trigger, not once FINISHED.
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <visualization_msgs/Marker.h>

#include <chrono>
#include <mutex>
#include <optional>
#include <set>
#include <std_msgs/Bool.h>
#include <std_msgs/UInt32MultiArray.h>

#include "go_feap/ExplorationStatus.h"
#include "go_feap/FrontierArray.h"
#include "go_feap/GlobalTour.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/message_checks.h"
#include "go_feap/common/config_groups.h"
#include "go_feap/ros/compute_time.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/params.h"
#include "go_feap/planning/tour_planner.h"
#include "go_feap/ros/shared_map.h"

namespace go_feap {

class GlobalPlanner : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
  ros_map::EmptyHandles empty_handles_{10.0};  ///< map_handles without a map, said only when they last
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros_params::ParamReader p(getPrivateNodeHandle());
    config::readGlobalPlanner(p, config_);
    p.get("global/rate", rate_);
    config::readAstar(p, astar_config_, "distance_astar");
    p.getFrame("world_frame", world_frame_);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    ros_params::requireOrThrow(rate_ > 0.0 && rate_ <= 1000.0, getName(),
                               "parameter '" + p.fullName("global/rate") + "' must be in (0, 1000] Hz");
    for (const common::Status& st : {config_.validate(), astar_config_.validate()})
      ros_params::requireOrThrow(st.ok(), getName(), st.message());
    compute_pub_ = nh.advertise<ComputeTime>("compute_time", 20);
    tour_pub_ = nh.advertise<GlobalTour>("global_tour", 2);
    marker_pub_ = nh.advertise<visualization_msgs::Marker>("global_tour_marker", 2);
    handle_sub_ = ros_guard::subscribe(nh, getName(), "map_handle", 1, &GlobalPlanner::onHandle, this);
    odom_sub_ = ros_guard::subscribe(nh, getName(), "odom", 5, &GlobalPlanner::onOdom, this);
    frontier_sub_ = ros_guard::subscribe(nh, getName(), "frontiers", 2, &GlobalPlanner::onFrontiers, this);
    blacklist_sub_ = ros_guard::subscribe(nh, getName(), "blacklist", 1, &GlobalPlanner::onBlacklist, this);
    wanted_sub_ = ros_guard::subscribe(nh, getName(), "tour_wanted", 2, &GlobalPlanner::onWanted, this);
    status_sub_ = ros_guard::subscribe(nh, getName(), "status", 2, &GlobalPlanner::onStatus, this);
  }

  void onStatus(const ExplorationStatus::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (gate_.update(*msg, getName())) last_tour_.reset();  // not to be sent again once it starts anew
  }

  void onWanted(const std_msgs::Bool::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    const bool again = !wanted_ && msg->data;
    wanted_ = msg->data;
    // Wanted again (the target was reached, seen out or is due for its periodic replan): plan now rather
    // than at the next frontier message past global/rate, which would hold the vehicle up to a period.
    if (again && last_frontiers_ && shared_ && uav_ && gate_.open()) {
      last_plan_ = ros::Time::now();
      plan(*last_frontiers_);
    }
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
    if (const common::Status st = astar_config_.validate((*map)->map->config().esdf); !st) {
      ros_params::stopManager(getName(), st.message());  // Astar's constructor would throw
      return;
    }
    // Built before anything is kept: a constructor that threw would leave the map taken and no planner
    // (the next frontiers would reach a null one, and the handle would never be taken again).
    auto astar = std::make_unique<planning::Astar>((*map)->map->occupancy(), (*map)->map->esdf(), astar_config_);
    auto planner = std::make_unique<planning::TourPlanner>(config_, *astar);
    shared_ = *map;
    astar_ = std::move(astar);
    planner_ = std::move(planner);
  }

  void onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
    const std::string bad = ros_conv::odometryPoseProblem(*msg, world_frame_);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": odometry refused: " << bad);
      return;
    }
    const auto& p = msg->pose.pose.position;
    std::lock_guard<std::mutex> lock(mutex_);
    uav_ = common::Vec3(p.x, p.y, p.z);
  }

  void onBlacklist(const std_msgs::UInt32MultiArray::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(mutex_);
    blacklist_.clear();
    blacklist_.insert(msg->data.begin(), msg->data.end());
  }

  void onFrontiers(const FrontierArray::ConstPtr& msg) {
    const std::string bad = ros_check::frontierArrayProblem(*msg);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": frontiers refused: " << bad);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    last_frontiers_ = msg;
    if (!gate_.open()) return;  // before the trigger, or FINISHED
    if (!shared_ || !uav_) {
      GO_FEAP_NODELET_THROTTLE(WARN, 5.0, getName() << ": waiting for " << (!shared_ ? "map_handle" : "odom"));
      return;
    }
    // Plan at most at global/rate (frontiers arrive with every depth frame).
    const ros::Time now = ros::Time::now();
    if (now < last_plan_) {  // a clock that went back (a bag played again): plan from now on, not from then
      NODELET_WARN_STREAM(getName() << ": the clock went back " << last_plan_.toSec() - now.toSec()
                                    << " s: planning again from now");
      last_plan_ = ros::Time();
    }
    if (!last_plan_.isZero() && (now - last_plan_).toSec() < 1.0 / rate_ - 1e-6) return;
    last_plan_ = now;
    if (!wanted_ && last_tour_) {
      GlobalTour again = *last_tour_;
      again.header.stamp = msg->header.stamp;
      again.repeated = true;
      tour_pub_.publish(again);
      return;
    }
    plan(*msg);
  }

  /// Plans a tour over `msg`'s frontiers and publishes it (mutex_ held; shared_ and uav_ set).
  void plan(const FrontierArray& msg) {
    const std::string outside = ros_check::frontierOutside(msg, shared_->map->geometry().bounds());
    if (!outside.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": frontiers refused: " << outside);
      return;
    }
    std::vector<planning::FrontierSummary> frontiers;
    for (const auto& f : msg.frontiers) {
      if (blacklist_.count(f.id)) continue;  // the layer manager gave up on it
      planning::FrontierSummary s;
      s.id = f.id;
      s.average = common::Vec3(f.average.x, f.average.y, f.average.z);
      s.cell_count = static_cast<int>(f.cells.size());
      s.duration = f.duration;
      s.n_near = static_cast<int>(f.n_near);
      s.active = f.active;
      frontiers.push_back(s);
    }
    const auto t0 = ros_conv::WallClock::now();
    std::size_t fallbacks = 0;
    common::Result<planning::GlobalTour> tour = common::Result<planning::GlobalTour>::Error("");
    {
      std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
      tour = planner_->plan(frontiers, *uav_, ros::Time::now().toSec(), &fallbacks);
    }
    ros_conv::publishComputeTime(compute_pub_, "global", t0);
    const double ms = std::chrono::duration<double, std::milli>(ros_conv::WallClock::now() - t0).count();
    if (!tour) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": no tour: " << tour.message());
      return;
    }
    NODELET_DEBUG_STREAM(getName() << ": tour of " << tour->frontier_ids.size() << " frontiers in " << ms << " ms ("
                                   << fallbacks << " Euclidean fallbacks)");
    GlobalTour out;
    out.header.stamp = msg.header.stamp;
    out.header.frame_id = world_frame_;
    out.frontier_ids.assign(tour->frontier_ids.begin(), tour->frontier_ids.end());
    out.cost = tour->cost;
    out.lambda = tour->lambda;
    out.exact = tour->exact;
    visualization_msgs::Marker line;
    line.header = out.header;
    line.ns = "global_tour";
    line.type = visualization_msgs::Marker::LINE_STRIP;
    line.action = tour->waypoints.empty() ? visualization_msgs::Marker::DELETE : visualization_msgs::Marker::ADD;
    line.pose.orientation.w = 1.0;
    line.scale.x = 0.08;
    line.color.r = 1.0, line.color.g = 0.55, line.color.a = 1.0;
    line.points.push_back(ros_conv::toPoint(*uav_));
    for (const common::Vec3& w : tour->waypoints) {
      out.waypoints.push_back(ros_conv::toPoint(w));
      line.points.push_back(out.waypoints.back());
    }
    tour_pub_.publish(out);
    last_tour_ = out;
    marker_pub_.publish(line);
  }

  planning::GlobalPlannerConfig config_;
  planning::AstarConfig astar_config_;
  std::string world_frame_;
  std::mutex mutex_;
  ros_check::ExplorationGate gate_{"planning tours", "no tours planned"};  ///< from the status
  std::shared_ptr<ros_map::SharedMap> shared_;
  std::unique_ptr<planning::Astar> astar_;
  std::optional<common::Vec3> uav_;
  std::unique_ptr<planning::TourPlanner> planner_;
  bool wanted_ = true;                  ///< the local planner's last tour_wanted (none yet: plan)
  std::optional<GlobalTour> last_tour_;  ///< sent again while no tour is wanted
  FrontierArray::ConstPtr last_frontiers_;  ///< planned from at once when a tour is wanted again
  std::set<std::uint32_t> blacklist_;
  double rate_ = 5.0;
  ros::Time last_plan_;
  ros::Publisher compute_pub_;
  ros::Publisher tour_pub_, marker_pub_;
  ros::Subscriber handle_sub_, odom_sub_, frontier_sub_, blacklist_sub_, wanted_sub_, status_sub_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::GlobalPlanner, nodelet::Nodelet)
