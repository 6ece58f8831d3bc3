// Helpers shared by the rostest nodes.
#pragma once

#include <gtest/gtest.h>
#include <ros/master.h>
#include <ros/network.h>
#include <ros/ros.h>
#include <xmlrpcpp/XmlRpcClient.h>

#include <rosgraph_msgs/Log.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <sstream>
#include <string>
#include <vector>

#include "go_feap/PositionCommand.h"
#include "go_feap/world/scene.h"
#include "go_feap/world/scene_files.h"

namespace go_feap::test {

/// The nodes the ROS master lists as publishing `topic` (getSystemState); empty when it does not answer.
inline std::vector<std::string> publishersOf(const std::string& topic) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  std::vector<std::string> nodes;
  if (!ros::master::execute("getSystemState", args, result, payload, false)) return nodes;
  XmlRpc::XmlRpcValue& publishers = payload[0];
  for (int i = 0; i < publishers.size(); ++i)
    if (static_cast<std::string>(publishers[i][0]) == topic)
      for (int j = 0; j < publishers[i][1].size(); ++j) nodes.push_back(static_cast<std::string>(publishers[i][1][j]));
  return nodes;
}

/// Where every thread of the node `node` (a nodelet manager) stands, for a failure message: gdb's
/// `thread apply all bt` of its process (the pid from the node's getPid): for each thread its first three
/// frames above the C library's waits and sleeps, and every go_feap frame, each cut at 200 characters,
/// the threads in go_feap code first, at most `max_chars` in all. A nodelet that went silent shows why: a
/// callback that never returns holds its worker thread, and every nodelet queued on that thread waits
/// with it. Without gdb, or a node the master does not know, the text says so instead.
inline std::string threadStacks(const std::string& node, std::size_t max_chars = 16000) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  args[1] = node;
  if (!ros::master::execute("lookupNode", args, result, payload, false))
    return "(no thread stacks: the master does not know " + node + ")\n";
  std::string host;
  std::uint32_t port = 0;
  if (!ros::network::splitURI(static_cast<std::string>(payload), host, port))
    return "(no thread stacks: " + node + " has the URI " + static_cast<std::string>(payload) + ")\n";
  XmlRpc::XmlRpcClient client(host.c_str(), static_cast<int>(port), "/");
  XmlRpc::XmlRpcValue pid_args, pid_result;
  pid_args[0] = ros::this_node::getName();
  if (!client.execute("getPid", pid_args, pid_result) || pid_result.getType() != XmlRpc::XmlRpcValue::TypeArray ||
      pid_result.size() < 3 || pid_result[2].getType() != XmlRpc::XmlRpcValue::TypeInt)
    return "(no thread stacks: " + node + " did not give its pid)\n";
  const int pid = static_cast<int>(pid_result[2]);
  const std::string command = "timeout 60 gdb -nx -batch -iex 'set debuginfod enabled off' -p " + std::to_string(pid) +
                              " -ex 'thread apply all bt' 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return "(no thread stacks: could not run gdb)\n";
  // One block per thread; those with a go_feap frame first (a stuck callback is among them).
  std::vector<std::string> ours, others;
  std::string block, said;
  bool block_ours = false;
  int frame_count = 0;
  auto flush = [&] {
    if (!block.empty()) (block_ours ? ours : others).push_back(block);
    block.clear();
    block_ours = false;
  };
  char buffer[4096];
  while (fgets(buffer, sizeof buffer, pipe)) {
    const std::string line(buffer);
    said += line;
    if (line.rfind("Thread ", 0) == 0) {
      flush();
      frame_count = 0;
      block = line;
    } else if (line.rfind("#", 0) == 0 && !block.empty()) {
      const bool in_go_feap = line.find("go_feap") != std::string::npos;
      const bool libc_wait = line.find("futex") != std::string::npos || line.find("nptl") != std::string::npos ||
                             line.find("nanosleep") != std::string::npos || line.find("poll") != std::string::npos;
      block_ours = block_ours || in_go_feap;
      if (in_go_feap || (!libc_wait && frame_count++ < 3))
        block += "  " + (line.size() > 200 ? line.substr(0, 200) + "...\n" : line);
    }
  }
  flush();
  pclose(pipe);
  if (ours.empty() && others.empty())
    return "(no thread stacks from gdb: " + said.substr(said.size() > 600 ? said.size() - 600 : 0) + ")\n";
  std::string text = "threads of " + node + " (pid " + std::to_string(pid) + "), those in go_feap code first:\n";
  for (const auto* list : {&ours, &others})
    for (const std::string& b : *list) text += b;
  if (text.size() > max_chars) text = text.substr(0, max_chars) + "\n(cut at " + std::to_string(max_chars) + " characters)\n";
  return text;
}

/// Spins until pred() holds or `wall_timeout` wall seconds pass; returns pred().
template <typename Pred>
bool spinUntil(Pred pred, double wall_timeout) {
  const ros::WallTime end = ros::WallTime::now() + ros::WallDuration(wall_timeout);
  while (ros::ok() && ros::WallTime::now() < end) {
    ros::spinOnce();
    if (pred()) return true;
    ros::WallDuration(0.005).sleep();
  }
  return pred();
}

/// A periodic action in simulated time: due() holds at `first` (at once by default) and then once every
/// `period` seconds, as the test plays a sensor or a planner at a fixed rate.
class Every {
 public:
  explicit Every(double period, ros::Time first = ros::Time()) : period_(period), next_(first) {}
  bool due() {
    if (ros::Time::now() < next_) return false;
    next_ = ros::Time::now() + ros::Duration(period_);
    return true;
  }

 private:
  double period_;
  ros::Time next_;
};

/// Spins, calling tick() each time round (to publish what is due), until until() holds or `sim_seconds`
/// of simulated time pass (at most `wall_timeout` wall seconds); returns until().
template <typename Tick, typename Until>
bool spinSimUntil(double sim_seconds, Tick tick, Until until, double wall_timeout = 60.0) {
  const ros::Time end = ros::Time::now() + ros::Duration(sim_seconds);
  spinUntil(
      [&] {
        tick();
        return until() || ros::Time::now() >= end;
      },
      wall_timeout);
  return until();
}

/// The scene named by the test node's private parameters `scene` and `seed`.
inline common::Result<world::Scene> sceneFromParams() {
  ros::NodeHandle pnh("~");
  std::string name;
  int seed = 0;
  if (!pnh.getParam("scene", name) || !pnh.getParam("seed", seed))
    return common::Result<world::Scene>::Error("the test node needs the private parameters scene and seed");
  return world::makeScene(name, static_cast<std::uint64_t>(seed));
}

/// Smallest distance (m) from p to an occupied ground-truth voxel, sampled on a 2.5 cm lattice up to
/// `limit` (a brute-force oracle for the metrics' obstacle distance).
inline double latticeClearance(const world::Scene& scene, const Eigen::Vector3d& p, double limit) {
  double best = limit;
  for (double dx = -limit; dx <= limit + 1e-9; dx += 0.025)
    for (double dy = -limit; dy <= limit + 1e-9; dy += 0.025)
      for (double dz = -limit; dz <= limit + 1e-9; dz += 0.025) {
        const Eigen::Vector3d d(dx, dy, dz);
        if (d.norm() < best && scene.isOccupied(Eigen::Vector3d(p + d))) best = d.norm();
      }
  return best;
}

/// A command holding `position` with heading `yaw` (rad) turning at `yaw_dot` (rad/s).
inline PositionCommand holdCommand(const Eigen::Vector3d& position, double yaw, double yaw_dot = 0.0) {
  PositionCommand c;
  c.header.stamp = ros::Time::now();
  c.header.frame_id = "world";
  c.position.x = position.x();
  c.position.y = position.y();
  c.position.z = position.z();
  c.yaw = std::atan2(std::sin(yaw), std::cos(yaw));
  c.yaw_dot = yaw_dot;
  c.trajectory_flag = PositionCommand::TRAJECTORY_STATUS_READY;
  return c;
}

/// Turns the vehicle in place at `centre` through a full circle at 0.8 rad/s (simulated
/// time), then keeps spinning until `done()` holds; false on wall-time out.
template <typename Done>
bool turnInPlace(ros::Publisher& cmd_pub, const Eigen::Vector3d& centre, Done done, double wall_timeout) {
  const ros::Time t0 = ros::Time::now();
  return spinUntil(
      [&] {
        const double t = (ros::Time::now() - t0).toSec();
        cmd_pub.publish(holdCommand(centre, 0.8 * t, 0.8));
        return t > 2 * M_PI / 0.8 + 1.0 && done();
      },
      wall_timeout);
}

/// What the nodes said: the last `keep` messages at INFO or above on /rosout, for a failure
/// message (rostest keeps no node output).
class NodeLog {
 public:
  explicit NodeLog(ros::NodeHandle& nh, std::size_t keep = 40) : keep_(keep) {
    sub_ = nh.subscribe<rosgraph_msgs::Log>("/rosout", 200, [this](const rosgraph_msgs::Log::ConstPtr& m) {
      if (m->level < rosgraph_msgs::Log::INFO) return;
      lines_.push_back(std::to_string(m->header.stamp.toSec()) + " [" + m->name + "] " + m->msg);
      if (lines_.size() > keep_) lines_.pop_front();
    });
  }
  std::string str() const {
    std::ostringstream out;
    out << "last " << lines_.size() << " node messages:\n";
    for (const std::string& l : lines_) out << "  " << l << "\n";
    return out.str();
  }

 private:
  std::size_t keep_;
  std::deque<std::string> lines_;
  ros::Subscriber sub_;
};

}  // namespace go_feap::test

/// gtest main for a rostest node.
#define GO_FEAP_ROSTEST_MAIN(node_name)               \
  int main(int argc, char** argv) {                   \
    ::testing::InitGoogleTest(&argc, argv);           \
    ros::init(argc, argv, node_name);                 \
    ros::NodeHandle nh;                               \
    return RUN_ALL_TESTS();                           \
  }
