#include "go_feap/ros/params.h"

#include <ros/console.h>

#include <stdexcept>

namespace go_feap::ros_params {

namespace {
bool readNumbers(const ros::NodeHandle& nh, const std::string& key, std::size_t n, std::vector<double>& out) {
  XmlRpc::XmlRpcValue v;
  if (!nh.getParam(key, v) || v.getType() != XmlRpc::XmlRpcValue::TypeArray || static_cast<std::size_t>(v.size()) != n)
    return false;
  out.clear();
  for (int i = 0; i < v.size(); ++i) {
    if (v[i].getType() == XmlRpc::XmlRpcValue::TypeDouble)
      out.push_back(static_cast<double>(v[i]));
    else if (v[i].getType() == XmlRpc::XmlRpcValue::TypeInt)
      out.push_back(static_cast<int>(v[i]));
    else
      return false;
  }
  return true;
}
}  // namespace

ParamReader& ParamReader::getFrame(const std::string& key, std::string& out) {
  std::string value;
  if (!nh_.hasParam(key))
    fail(key, "is missing");
  else if (!nh_.getParam(key, value))
    fail(key, "has the wrong type");
  else if (value.empty() || value.front() == '/')
    fail(key, "must be a TF frame id: not empty, no leading '/' (got '" + value + "')");
  else
    out = value;
  return *this;
}

ParamReader& ParamReader::getVec3(const std::string& key, Eigen::Vector3d& out) {
  std::vector<double> v;
  if (!nh_.hasParam(key)) {
    fail(key, "is missing");
  } else if (!readNumbers(nh_, key, 3, v)) {
    fail(key, "must be a list of 3 numbers");
  } else {
    out = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  return *this;
}

ParamReader& ParamReader::getMatrix4(const std::string& key, Eigen::Matrix4d& out) {
  std::vector<double> v;
  if (!nh_.hasParam(key)) {
    fail(key, "is missing");
  } else if (!readNumbers(nh_, key, 16, v)) {
    fail(key, "must be a list of 16 numbers (row-major 4x4)");
  } else {
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) out(r, c) = v[4 * r + c];
  }
  return *this;
}

void requireOrThrow(bool ok, const std::string& nodelet, const std::string& what) {
  if (ok) return;
  ROS_FATAL_STREAM(nodelet << ": " << what << "; not starting");
  throw std::runtime_error(nodelet + ": " + what);
}

void requireBox(const common::Aabb& box, const ParamReader& p, const std::string& nodelet) {
  requireOrThrow(box.valid() && box.min.allFinite() && box.max.allFinite(), nodelet,
                 "parameters '" + p.fullName("exploration_box/min") + "' and '" + p.fullName("exploration_box/max") +
                     "' must be finite, with min < max in every axis");
}

void stopManager(const std::string& nodelet, const std::string& what) {
  ROS_FATAL_STREAM(nodelet << ": " << what << "; the parameters of this nodelet and of the map's mapper conflict: "
                           << "stopping the nodelet manager");
  ros::WallDuration(0.5).sleep();  // the message leaves on /rosout first (its own thread sends it)
  ros::requestShutdown();
}

}  // namespace go_feap::ros_params

#include "go_feap/world/scene_files.h"

namespace go_feap::ros_params {

world::Scene loadScene(const ros::NodeHandle& private_nh, const std::string& nodelet) {
  ParamReader p(private_nh);
  std::string scene;
  int seed = 0;
  p.get("scene", scene).get("seed", seed);
  requireOrThrow(p.ok(), nodelet, p.error());
  requireOrThrow(seed >= 0, nodelet, "parameter '" + p.fullName("seed") + "' must be >= 0");
  auto result = world::makeScene(scene, static_cast<std::uint64_t>(seed));
  requireOrThrow(result.ok(), nodelet, result.ok() ? "" : result.message());
  return std::move(result).value();
}

}  // namespace go_feap::ros_params
