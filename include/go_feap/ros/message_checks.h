// Checks on the chain's own messages (frontiers, global_tour, layer, map_update, status, position_cmd) and
// on depth images, as they arrive. Each topic can also be fed from outside the chain (a bag, a tool, another planner), and a value that is not
// finite or a count that does not match would reach the core as a voxel index cast from NaN or a read
// past an array's end. Each function says what is wrong (naming the field, and the frontier's id where
// there is one), or returns an empty string; the nodelet then refuses the message whole and keeps what
// it had.
#pragma once

#include <sensor_msgs/Image.h>

#include <string>
#include <utility>

#include "go_feap/ExplorationStatus.h"
#include "go_feap/FrontierArray.h"
#include "go_feap/GlobalTour.h"
#include "go_feap/LayerBounds.h"
#include "go_feap/MapUpdate.h"
#include "go_feap/PositionCommand.h"
#include "go_feap/common/grid.h"
#include "go_feap/ros/log_throttle.h"

namespace go_feap::ros_check {

/// A depth image the chain can read: encoding 32FC1 (m), 16UC1 or mono16 (mm); width and height above
/// 0; a row step of at least width pixels and a whole number of them; and exactly height x step bytes of
/// data, counted in 64 bits (cv_bridge compares them in 32, so a step whose product wraps round passes
/// there and the image is read far past its buffer).
std::string depthImageProblem(const sensor_msgs::Image& msg);

/// Every frontier: an id other than 0 (0 means "no frontier" in a local_target) and unique in the array;
/// at least one cell; cells, P_avg and box finite, the box not inverted; T and xi finite and >= 0; as
/// many viewpoint yaws and visible counts as viewpoint positions, all finite.
std::string frontierArrayProblem(const FrontierArray& msg);

/// The same array against a map: every frontier's cells and P_avg inside `bounds` (the map's extent,
/// faces included), where a voxel index exists. Call it on an array frontierArrayProblem() passed.
std::string frontierOutside(const FrontierArray& msg, const common::Aabb& bounds);

/// As many waypoints as frontier ids, every waypoint finite.
std::string globalTourProblem(const GlobalTour& msg);

/// z_min and z_max finite with z_min < z_max; count >= 1 and index < count.
std::string layerBoundsProblem(const LayerBounds& msg);

/// With changed voxels: the changed box finite and not inverted.
std::string mapUpdateProblem(const MapUpdate& msg);

/// A known state (WAIT_TRIGGER .. FINISHED); elapsed and distance finite and >= 0, elapsed under a
/// year (it becomes a ros::Duration, which throws beyond 2^31 s); coverage finite.
std::string explorationStatusProblem(const ExplorationStatus& msg);

/// Whether a planner may act, following the layer manager's status: open only while the exploration is
/// under way (EXPLORE or FINAL_PASS). Before the trigger and once FINISHED the planners plan nothing and
/// send no target. A status that explorationStatusProblem() refuses changes nothing; refusals, openings
/// and closings are logged under the node's name ("<node>: exploration FINISHED: <closed_says>").
class ExplorationGate {
 public:
  ExplorationGate(std::string open_says, std::string closed_says)
      : open_says_(std::move(open_says)), closed_says_(std::move(closed_says)) {}
  /// Takes a status message for the nodelet `node`; true when it closed the gate (the caller drops what
  /// it holds).
  bool update(const ExplorationStatus& msg, const std::string& node);
  bool open() const { return open_; }

 private:
  std::string open_says_, closed_says_;
  bool open_ = false;
  ros_log::Throttle throttle_;  ///< of the refusals
};

/// In `world_frame`, with position, velocity, acceleration, yaw and yaw rate all finite (the trajectory
/// planner starts its next plan from the command; the simulator flies it).
std::string positionCommandProblem(const PositionCommand& msg, const std::string& world_frame);

}  // namespace go_feap::ros_check
