// Reading required ROS parameters: every key must be present and of the right type; the
// first problem is remembered with the key's full name.
#pragma once

#include <ros/node_handle.h>

#include <Eigen/Core>
#include <string>
#include <vector>

#include "go_feap/common/grid.h"

namespace go_feap::ros_params {

class ParamReader {
 public:
  explicit ParamReader(const ros::NodeHandle& nh) : nh_(nh) {}

  /// Reads `key` into `out`; on a missing or wrongly typed key records an error.
  template <typename T>
  ParamReader& get(const std::string& key, T& out) {
    T value{};
    if (!nh_.hasParam(key)) {
      fail(key, "is missing");
    } else if (!nh_.getParam(key, value)) {
      fail(key, "has the wrong type");
    } else {
      out = value;
    }
    return *this;
  }
  /// Reads a TF frame id: one that is empty or starts with '/' (tf2 refuses such ids, and every message
  /// stamped with it would be dropped downstream) is recorded as an error.
  ParamReader& getFrame(const std::string& key, std::string& out);
  ParamReader& getVec3(const std::string& key, Eigen::Vector3d& out);
  ParamReader& getMatrix4(const std::string& key, Eigen::Matrix4d& out);

  bool ok() const { return error_.empty(); }
  /// "parameter '/ns/key' is missing" (the first problem found), or empty.
  const std::string& error() const { return error_; }
  std::string fullName(const std::string& key) const { return nh_.resolveName(key); }

 private:
  void fail(const std::string& key, const std::string& why) {
    if (error_.empty()) error_ = "parameter '" + fullName(key) + "' " + why;
  }
  ros::NodeHandle nh_;
  std::string error_;
};

/// Throws std::runtime_error with `what` (after logging it as fatal) when `ok` is false:
/// a nodelet whose parameters are wrong does not start.
void requireOrThrow(bool ok, const std::string& nodelet, const std::string& what);

/// requireOrThrow() for the exploration box read by `p`: finite, with min < max in every axis. An infinite
/// one passed min < max, and the layer manager's bands came out NaN, which every nodelet refused.
void requireBox(const common::Aabb& box, const ParamReader& p, const std::string& nodelet);

/// For a parameter found wrong only when another nodelet's values come (a reader's clearance past the
/// mapper's esdf/max_distance, known once the map arrives): logs `what` as fatal and shuts this process's
/// nodelet manager down, which ends a launch as a nodelet refusing to start does. The nodelet is still
/// in its callback: it returns and does nothing more.
void stopManager(const std::string& nodelet, const std::string& what);

}  // namespace go_feap::ros_params

namespace go_feap::world {
struct Scene;
}

namespace go_feap::ros_params {

/// Builds the scene named by the private parameters `scene` (maze, powerplant or the path
/// of a scene YAML) and `seed`; throws (after logging) when they are wrong.
world::Scene loadScene(const ros::NodeHandle& private_nh, const std::string& nodelet);

}  // namespace go_feap::ros_params
