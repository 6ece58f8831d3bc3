// FrontierFinder: keeps the frontier clusters of the shared map up to date.
// In: map_handle, map_update (from EsdfMapper, same manager), layer (LayerBounds).
// Out: frontiers (go_feap/FrontierArray, after each map update and when the band changes),
// frontier_markers (one colour per cluster, xi as text).
// State on the parameter server: ~id_reserved, the ids reserved so far (see reserveIds()).
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/master.h>
#include <ros/ros.h>
#include <visualization_msgs/MarkerArray.h>

#include <limits>
#include <mutex>
#include <utility>

#include "go_feap/FrontierArray.h"
#include "go_feap/LayerBounds.h"
#include "go_feap/MapUpdate.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/message_checks.h"
#include "go_feap/common/config_groups.h"
#include "go_feap/common/monotonic_clock.h"
#include "go_feap/ros/compute_time.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/params.h"
#include "go_feap/ros/shared_map.h"

namespace go_feap {

class FrontierFinder : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
  ros_map::EmptyHandles empty_handles_{10.0};  ///< map_handles without a map, said only when they last
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros_params::ParamReader p(getPrivateNodeHandle());
    config::readFrontier(p, config_);
    config::readOmission(p, omission_);
    config::readBox(p, box_);
    p.getFrame("world_frame", world_frame_);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    for (const common::Status& st : {config_.validate(), omission_.validate()})
      ros_params::requireOrThrow(st.ok(), getName(), st.message());
    ros_params::requireBox(box_, p, getName());
    // A finder loaded before this one under the same name (the nodelet reloaded into a running system)
    // reserved the ids below ~id_reserved: this one's begin there.
    int reserved = 0;
    if (getPrivateNodeHandle().getParam("id_reserved", reserved)) {
      if (reserved >= 1) {
        first_id_ = id_reserved_ = static_cast<std::uint32_t>(reserved);
        NODELET_INFO_STREAM(getName() << ": frontier ids begin at " << reserved
                                      << " (~id_reserved: a finder before this one handed out ids below it)");
      } else {
        NODELET_WARN_STREAM(getName() << ": ~id_reserved " << reserved << " is no frontier id; ids begin at 1");
      }
    }
    compute_pub_ = nh.advertise<ComputeTime>("compute_time", 20);
    frontier_pub_ = nh.advertise<FrontierArray>("frontiers", 2);
    marker_pub_ = nh.advertise<visualization_msgs::MarkerArray>("frontier_markers", 2);
    handle_sub_ = ros_guard::subscribe(nh, getName(), "map_handle", 1, &FrontierFinder::onHandle, this);
    update_sub_ = ros_guard::subscribe(nh, getName(), "map_update", 20, &FrontierFinder::onUpdate, this);
    layer_sub_ = ros_guard::subscribe(nh, getName(), "layer", 1, &FrontierFinder::onLayer, this);
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
    shared_ = *map;
  }

  void onLayer(const LayerBounds::ConstPtr& msg) {
    const std::string bad = ros_check::layerBoundsProblem(*msg);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": layer refused: " << bad << "; the band stays as it was");
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    const bool changed = band_ != std::make_pair(msg->z_min, msg->z_max);
    band_ = {msg->z_min, msg->z_max};
    if (!finder_) return;
    finder_->setActiveBand(msg->z_min, msg->z_max);
    // The planners see the new band's active flags now, not at the next map update. The frontiers are those
    // of the last update, sent with its stamp (the layer manager sends the same band again while it looks round).
    if (changed) publish(last_stamp_, last_now_);
  }

  void onUpdate(const MapUpdate::ConstPtr& msg) {
    const std::string bad = ros_check::mapUpdateProblem(*msg);
    if (!bad.empty()) {
      // Not counted as received: the next update then shows a gap, and every frontier is recomputed.
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": map_update " << msg->sequence << " refused: " << bad);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (!shared_) {
      GO_FEAP_NODELET_THROTTLE(WARN, 5.0, getName() << ": map_update before map_handle; waiting for the map");
      return;
    }
    const auto t_compute = ros_conv::WallClock::now();
    // The frontiers' ages on a clock that never goes back: a ROS clock that did (a bag played again) made
    // every frontier's age 0 and dated a grown one before its neighbours for as long.
    const double now = clock_.at(msg->header.stamp.toSec());
    if (clock_.wentBack() > 0.0)
      NODELET_WARN_STREAM(getName() << ": the clock went back " << clock_.wentBack()
                                    << " s: the frontiers' ages pause for as long");
    reserveIds();  // before the ids are handed out, and outside the map lock (it asks the ROS master)
    {
      std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
      const map::OccupancyMap& occupancy = shared_->map->occupancy();
      if (!finder_) {  // the first update: everything from the map
        finder_ = std::make_unique<frontier::FrontierFinder>(config_, occupancy.geometry(), box_);
        finder_->continueIdsFrom(first_id_);
        finder_->setActiveBand(band_.first, band_.second);
        finder_->recomputeAll(occupancy, now);
      } else {
        if (frontier::applyMapUpdate(*finder_, occupancy, shared_->sequence, shared_->last_changed, last_sequence_,
                                     ros_conv::mapUpdateNote(*msg), now) == frontier::UpdatePath::kRecomputed)
          NODELET_WARN_STREAM(getName() << ": map updates " << last_sequence_ + 1 << ".." << msg->sequence - 1
                                        << " missed; recomputing all frontiers");
      }
    }
    ros_conv::publishComputeTime(compute_pub_, "frontier", t_compute);
    last_sequence_ = msg->sequence;
    last_stamp_ = msg->header.stamp;
    last_now_ = now;
    publish(msg->header.stamp, now);
    reserveIds();  // an update that used more than the margin (a recomputation of a huge map) is covered now
  }

  // Ids are handed out once while the ROS master runs, also across finders: around each update, while
  // fewer than half of kIdReserve ids are left of the reservation, ~id_reserved moves kIdReserve past the
  // next id (a write every 50000 ids or so; an update makes a few hundred at most). A finder loaded
  // later, after this one was unloaded or its manager died, begins at the reservation. The write asks the
  // master once and never waits for it (ros::param::set retries until it answers): with the master
  // gone the finder goes on, and tries again at the next update.
  void reserveIds() {
    static constexpr std::uint32_t kIdReserve = 100000;
    const std::uint32_t next = finder_ ? finder_->nextId() : first_id_;
    if (next <= id_reserved_ && id_reserved_ - next >= kIdReserve / 2) return;
    if (next > static_cast<std::uint32_t>(std::numeric_limits<int>::max()) - kIdReserve) {
      NODELET_WARN_STREAM_ONCE(getName() << ": frontier ids passed " << next
                                         << ": ~id_reserved can hold no more; a finder loaded later may reuse ids");
      return;
    }
    XmlRpc::XmlRpcValue params, result, payload;
    params[0] = ros::this_node::getName();
    params[1] = getPrivateNodeHandle().resolveName("id_reserved");
    params[2] = static_cast<int>(next + kIdReserve);
    if (ros::master::execute("setParam", params, result, payload, /*wait_for_master=*/false)) {
      id_reserved_ = next + kIdReserve;
    } else {
      GO_FEAP_NODELET_THROTTLE(WARN, 10.0, getName() << ": the ROS master did not take ~id_reserved " << next + kIdReserve
                                                   << "; a finder loaded after this one may hand out ids from "
                                                   << id_reserved_ << " again");
    }
  }

  void publish(const ros::Time& stamp, double now) {
    FrontierArray out;
    out.header.stamp = stamp;
    out.header.frame_id = world_frame_;
    visualization_msgs::MarkerArray markers;
    visualization_msgs::Marker clear;
    clear.action = visualization_msgs::Marker::DELETEALL;
    markers.markers.push_back(clear);
    const auto& geo = shared_->map->geometry();
    for (const frontier::Frontier& f : finder_->frontiers()) {
      go_feap::Frontier m;
      m.id = f.id;
      for (const common::Index3& c : f.cells) {
        m.cells.push_back(ros_conv::toPoint(geo.indexToCoord(c)));
      }
      m.average.x = f.average.x(), m.average.y = f.average.y(), m.average.z = f.average.z();
      m.aabb_min.x = f.box.min.x(), m.aabb_min.y = f.box.min.y(), m.aabb_min.z = f.box.min.z();
      m.aabb_max.x = f.box.max.x(), m.aabb_max.y = f.box.max.y(), m.aabb_max.z = f.box.max.z();
      m.n_near = static_cast<std::uint32_t>(f.n_near);
      m.duration = f.duration(now);
      m.omission_likelihood =
          planning::xi(omission_, static_cast<int>(f.cells.size()), f.duration(now), f.n_near);
      m.active = f.active;
      out.frontiers.push_back(m);

      visualization_msgs::Marker cubes;
      cubes.header = out.header;
      cubes.ns = "frontier_cells";
      cubes.id = static_cast<int>(f.id);
      cubes.type = visualization_msgs::Marker::CUBE_LIST;
      cubes.scale.x = cubes.scale.y = cubes.scale.z = geo.resolution();
      cubes.pose.orientation.w = 1.0;
      // Golden-ratio hues: neighbouring ids get distinct colours; inactive ones are grey.
      const double hue = std::fmod(f.id * 0.618033988749895, 1.0);
      cubes.color.r = f.active ? 0.5 + 0.5 * std::cos(2 * M_PI * hue) : 0.5;
      cubes.color.g = f.active ? 0.5 + 0.5 * std::cos(2 * M_PI * (hue - 1.0 / 3)) : 0.5;
      cubes.color.b = f.active ? 0.5 + 0.5 * std::cos(2 * M_PI * (hue - 2.0 / 3)) : 0.5;
      cubes.color.a = f.active ? 0.8 : 0.3;
      cubes.points = m.cells;
      markers.markers.push_back(cubes);
      visualization_msgs::Marker text;
      text.header = out.header;
      text.ns = "frontier_xi";
      text.id = static_cast<int>(f.id);
      text.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
      text.pose.position = m.average;
      text.pose.position.z += 0.3;
      text.pose.orientation.w = 1.0;
      text.scale.z = 0.25;
      text.color.r = text.color.g = text.color.b = text.color.a = 1.0;
      char buf[32];
      std::snprintf(buf, sizeof(buf), "xi %.2f", m.omission_likelihood);
      text.text = buf;
      markers.markers.push_back(text);
    }
    frontier_pub_.publish(out);
    marker_pub_.publish(markers);
  }

  frontier::FrontierConfig config_;
  planning::OmissionConfig omission_;
  common::Aabb box_;
  std::string world_frame_;
  std::mutex mutex_;
  std::shared_ptr<ros_map::SharedMap> shared_;
  std::unique_ptr<frontier::FrontierFinder> finder_;
  std::pair<double, double> band_{-1e18, 1e18};
  std::uint64_t last_sequence_ = 0;
  ros::Time last_stamp_;  ///< of the last map update the frontiers come from
  double last_now_ = 0.0;  ///< clock_ at that update
  common::MonotonicClock clock_;  ///< the frontiers' clock, from the map updates' stamps
  std::uint32_t first_id_ = 1;     ///< the first id this finder hands out (~id_reserved when it started)
  std::uint32_t id_reserved_ = 1;  ///< ids below it are handed out or reserved (~id_reserved)
  ros::Publisher compute_pub_;
  ros::Publisher frontier_pub_, marker_pub_;
  ros::Subscriber handle_sub_, update_sub_, layer_sub_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::FrontierFinder, nodelet::Nodelet)
