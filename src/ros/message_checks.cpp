#include "go_feap/ros/message_checks.h"

#include <ros/console.h>
#include <sensor_msgs/image_encodings.h>

#include <cmath>
#include <cstdint>
#include <sstream>
#include <unordered_set>

namespace go_feap::ros_check {
namespace {

bool finite(const geometry_msgs::Point& p) { return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z); }
bool finite(const geometry_msgs::Vector3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }
bool inverted(const geometry_msgs::Point& lo, const geometry_msgs::Point& hi) {
  return lo.x > hi.x || lo.y > hi.y || lo.z > hi.z;
}

std::string point(const geometry_msgs::Point& p) {
  std::ostringstream s;
  s << "(" << p.x << ", " << p.y << ", " << p.z << ")";
  return s.str();
}

/// "frontier 7 (index 2)": how every problem with one frontier starts.
std::string frontierName(const Frontier& f, std::size_t index) {
  return "frontier " + std::to_string(f.id) + " (index " + std::to_string(index) + ")";
}

}  // namespace

std::string frontierArrayProblem(const FrontierArray& msg) {
  std::unordered_set<std::uint32_t> ids;
  for (std::size_t i = 0; i < msg.frontiers.size(); ++i) {
    const Frontier& f = msg.frontiers[i];
    const auto name = [&] { return frontierName(f, i); };  // built only for a refusal: every frontier, 15 Hz
    if (f.id == 0) return name() + ": id 0 is reserved for no frontier";
    if (!ids.insert(f.id).second) return name() + ": id " + std::to_string(f.id) + " appears twice";
    if (f.cells.empty()) return name() + ": no cells";
    for (std::size_t c = 0; c < f.cells.size(); ++c)
      if (!finite(f.cells[c])) return name() + ": cell " + std::to_string(c) + " " + point(f.cells[c]) + " is not finite";
    if (!finite(f.average)) return name() + ": average " + point(f.average) + " is not finite";
    if (!finite(f.aabb_min) || !finite(f.aabb_max))
      return name() + ": box " + point(f.aabb_min) + " .. " + point(f.aabb_max) + " is not finite";
    if (inverted(f.aabb_min, f.aabb_max))
      return name() + ": box " + point(f.aabb_min) + " .. " + point(f.aabb_max) + " is inverted";
    if (!(f.duration >= 0.0) || !std::isfinite(f.duration))
      return name() + ": duration " + std::to_string(f.duration) + " is not finite and >= 0";
    if (!(f.omission_likelihood >= 0.0) || !std::isfinite(f.omission_likelihood))
      return name() + ": omission_likelihood " + std::to_string(f.omission_likelihood) + " is not finite and >= 0";
    const std::size_t n = f.viewpoint_positions.size();
    if (f.viewpoint_yaws.size() != n || f.viewpoint_visible.size() != n)
      return name() + ": " + std::to_string(n) + " viewpoint positions but " + std::to_string(f.viewpoint_yaws.size()) +
             " yaws and " + std::to_string(f.viewpoint_visible.size()) + " visible counts";
    for (std::size_t v = 0; v < n; ++v)
      if (!finite(f.viewpoint_positions[v]) || !std::isfinite(f.viewpoint_yaws[v]))
        return name() + ": viewpoint " + std::to_string(v) + " " + point(f.viewpoint_positions[v]) + " yaw " +
               std::to_string(f.viewpoint_yaws[v]) + " is not finite";
  }
  return std::string();
}

std::string frontierOutside(const FrontierArray& msg, const common::Aabb& bounds) {
  auto in = [&](const geometry_msgs::Point& q) {
    const common::Vec3 p(q.x, q.y, q.z);
    return (p.array() >= bounds.min.array()).all() && (p.array() <= bounds.max.array()).all();
  };
  auto outside = [&](const Frontier& f, std::size_t i, const std::string& what, const geometry_msgs::Point& q) {
    std::ostringstream s;
    s << frontierName(f, i) << ": " << what << " " << point(q) << " lies outside the map (" << bounds.min.transpose()
      << " .. " << bounds.max.transpose() << ")";
    return s.str();
  };
  for (std::size_t i = 0; i < msg.frontiers.size(); ++i) {
    const Frontier& f = msg.frontiers[i];
    if (!in(f.average)) return outside(f, i, "average", f.average);
    for (std::size_t c = 0; c < f.cells.size(); ++c)
      if (!in(f.cells[c])) return outside(f, i, "cell " + std::to_string(c), f.cells[c]);
  }
  return std::string();
}

std::string globalTourProblem(const GlobalTour& msg) {
  if (msg.waypoints.size() != msg.frontier_ids.size())
    return std::to_string(msg.frontier_ids.size()) + " frontier ids but " + std::to_string(msg.waypoints.size()) +
           " waypoints";
  for (std::size_t i = 0; i < msg.waypoints.size(); ++i)
    if (!finite(msg.waypoints[i]))
      return "waypoint " + std::to_string(i) + " " + point(msg.waypoints[i]) + " (frontier " +
             std::to_string(msg.frontier_ids[i]) + ") is not finite";
  // A tour visits each frontier once; the local planner copies each listed frontier (cells and all), so a
  // million repeats of one id would take gigabytes.
  std::unordered_set<std::uint32_t> ids;
  for (std::size_t i = 0; i < msg.frontier_ids.size(); ++i)
    if (!ids.insert(msg.frontier_ids[i]).second)
      return "frontier " + std::to_string(msg.frontier_ids[i]) + " appears twice (at " + std::to_string(i) + ")";
  return std::string();
}

std::string layerBoundsProblem(const LayerBounds& msg) {
  if (!std::isfinite(msg.z_min) || !std::isfinite(msg.z_max) || !(msg.z_min < msg.z_max)) {
    std::ostringstream s;
    s << "band z " << msg.z_min << " .. " << msg.z_max << " is not finite with z_min < z_max";
    return s.str();
  }
  if (msg.count < 1 || msg.index >= msg.count)
    return "band index " + std::to_string(msg.index) + " is not below the count " + std::to_string(msg.count);
  return std::string();
}

std::string depthImageProblem(const sensor_msgs::Image& msg) {
  std::uint64_t bytes_per_pixel = 0;
  if (msg.encoding == sensor_msgs::image_encodings::TYPE_32FC1) bytes_per_pixel = 4;
  if (msg.encoding == sensor_msgs::image_encodings::TYPE_16UC1 || msg.encoding == sensor_msgs::image_encodings::MONO16)
    bytes_per_pixel = 2;
  if (bytes_per_pixel == 0) return "encoding '" + msg.encoding + "' is neither 32FC1 (m) nor 16UC1 / mono16 (mm)";
  const std::string size = std::to_string(msg.width) + "x" + std::to_string(msg.height);
  if (msg.width == 0 || msg.height == 0) return "the image is " + size;
  if (msg.step < msg.width * bytes_per_pixel || msg.step % bytes_per_pixel != 0)
    return "step " + std::to_string(msg.step) + " is not a whole number of " + std::to_string(bytes_per_pixel) +
           "-byte pixels at least " + std::to_string(msg.width) + " wide";
  const std::uint64_t expected = std::uint64_t{msg.height} * msg.step;
  if (msg.data.size() != expected)
    return std::to_string(msg.data.size()) + " bytes of data, where " + size + " with step " +
           std::to_string(msg.step) + " needs " + std::to_string(expected);
  // cv_bridge reads any other byte order as the wrong type (CV_8UC4 for 32FC1) instead of swapping it.
  constexpr bool kHostBigEndian = __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__;
  if ((msg.is_bigendian != 0) != kHostBigEndian)
    return std::string("is_bigendian ") + (msg.is_bigendian ? "1 (big-endian)" : "0 (little-endian)") +
           ": not this machine's byte order, which the depth image is read in";
  return std::string();
}

std::string mapUpdateProblem(const MapUpdate& msg) {
  if (msg.changed_voxels == 0) return std::string();
  if (!finite(msg.changed_min) || !finite(msg.changed_max))
    return "changed box " + point(msg.changed_min) + " .. " + point(msg.changed_max) + " is not finite";
  if (inverted(msg.changed_min, msg.changed_max))
    return "changed box " + point(msg.changed_min) + " .. " + point(msg.changed_max) + " is inverted";
  return std::string();
}

std::string explorationStatusProblem(const ExplorationStatus& msg) {
  if (msg.state > ExplorationStatus::FINISHED) return "state " + std::to_string(msg.state) + " is not a known state";
  if (!(msg.elapsed >= 0.0) || !(msg.elapsed < 365.0 * 86400.0))
    return "elapsed " + std::to_string(msg.elapsed) + " s is not finite, >= 0 and under a year";
  if (!(msg.distance >= 0.0) || !std::isfinite(msg.distance))
    return "distance " + std::to_string(msg.distance) + " m is not finite and >= 0";
  if (!std::isfinite(msg.coverage)) return "coverage is not finite";
  return std::string();
}

bool ExplorationGate::update(const ExplorationStatus& msg, const std::string& node) {
  const std::string bad = explorationStatusProblem(msg);
  if (!bad.empty()) {
    if (throttle_.pass("status refused", 2.0, ros::Time::now().toSec())) ROS_WARN_STREAM(node << ": status refused: " << bad);
    return false;
  }
  const bool open = msg.state == ExplorationStatus::EXPLORE || msg.state == ExplorationStatus::FINAL_PASS;
  if (open == open_) return false;
  open_ = open;
  ROS_INFO_STREAM(node << ": exploration " << msg.state_name << ": " << (open ? open_says_ : closed_says_));
  return !open;
}

std::string positionCommandProblem(const PositionCommand& msg, const std::string& world_frame) {
  if (msg.header.frame_id != world_frame)
    return "the command is in frame '" + msg.header.frame_id + "', not '" + world_frame + "' (world_frame)";
  if (!finite(msg.position)) return "position " + point(msg.position) + " is not finite";
  if (!finite(msg.velocity) || !finite(msg.acceleration)) return "velocity or acceleration is not finite";
  if (!std::isfinite(msg.yaw) || !std::isfinite(msg.yaw_dot)) return "yaw or yaw_dot is not finite";
  return std::string();
}

}  // namespace go_feap::ros_check
