// Small message <-> Eigen conversions shared by the nodelets.
#pragma once

#include <geometry_msgs/Point.h>
#include <geometry_msgs/Pose.h>
#include <geometry_msgs/Quaternion.h>
#include <geometry_msgs/Vector3.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/CameraInfo.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <string>

#include "go_feap/MapUpdate.h"
#include "go_feap/common/grid.h"
#include "go_feap/frontier/frontier_finder.h"
#include "go_feap/map/occupancy_map.h"

namespace go_feap::ros_conv {

inline geometry_msgs::Point toPoint(const common::Vec3& v) {
  geometry_msgs::Point p;
  p.x = v.x();
  p.y = v.y();
  p.z = v.z();
  return p;
}

inline common::Vec3 toVec3(const geometry_msgs::Point& p) { return common::Vec3(p.x, p.y, p.z); }

/// What the frontier finder and the local planner take of a map_update (its sequence, change count and box).
inline frontier::MapUpdateNote mapUpdateNote(const MapUpdate& msg) {
  frontier::MapUpdateNote note;
  note.sequence = msg.sequence;
  note.changed_voxels = msg.changed_voxels;
  note.changed_min = toVec3(msg.changed_min);
  note.changed_max = toVec3(msg.changed_max);
  return note;
}

/// The pinhole intrinsics of the rectified image a camera_info describes: P's fx, fy, cx, cy (P[0], P[5],
/// P[2], P[6]), which sensor_msgs/CameraInfo gives for rectified images (a depth camera's image_rect_raw, as
/// depth_image_proc reads it), or K's where P is unset (its fx or fy 0: a driver filling K alone); its sides
/// clamped to int (an image's sides are ints; DepthIntrinsics::validate() judges the rest).
inline map::DepthIntrinsics depthIntrinsics(const sensor_msgs::CameraInfo& info) {
  const auto side = [](std::uint32_t n) {
    return static_cast<int>(std::min<std::uint32_t>(n, static_cast<std::uint32_t>(std::numeric_limits<int>::max())));
  };
  if (info.P[0] != 0.0 && info.P[5] != 0.0)
    return {side(info.width), side(info.height), info.P[0], info.P[5], info.P[2], info.P[6]};
  return {side(info.width), side(info.height), info.K[0], info.K[4], info.K[2], info.K[5]};
}

/// Whether a camera_info gives lens distortion (a coefficient of D not 0): its image is then not the
/// rectified one the mapper takes.
inline bool hasDistortion(const sensor_msgs::CameraInfo& info) {
  return std::any_of(info.D.begin(), info.D.end(), [](double d) { return d != 0.0; });
}

/// Heading (rad, about world z) of an orientation; a quaternion of any nonzero length gives the heading of
/// its rotation.
inline double yawOf(const geometry_msgs::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), q.w * q.w + q.x * q.x - q.y * q.y - q.z * q.z);
}

/// Why an odometry pose cannot be used, or an empty string: a position that is not finite, or an
/// orientation that is not a rotation (not finite, or a length more than 1e-3 from 1, which tf2 refuses
/// too; an all-zero quaternion is an orientation left unset). Every nodelet that takes odometry refuses
/// such a message whole, as if it had not come.
inline std::string odometryPoseProblem(const geometry_msgs::Pose& pose) {
  const auto& p = pose.position;
  const auto& q = pose.orientation;
  const bool position_ok = std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  const double norm = std::sqrt(q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w);
  if (position_ok && std::abs(norm - 1.0) <= 1e-3) return std::string();  // every message at 100 Hz: no stream
  std::ostringstream why;
  if (!position_ok)
    why << "position (" << p.x << ", " << p.y << ", " << p.z << ") is not finite";
  else
    why << "orientation (x " << q.x << ", y " << q.y << ", z " << q.z << ", w " << q.w << ") is not a unit quaternion";
  return why.str();
}

/// Whether a message stamped `stamp` (s) may meet others in message_filters' ApproximateTime, which
/// subtracts stamps as ros::Time and throws past 2^31 s: within 2^30 s of `now` (s), so that any two it
/// holds are less than 2^31 s apart; with no clock yet (now 0: use_sim_time before the first /clock),
/// below 2^31 s, which keeps any two of them less than 2^31 s apart too.
inline bool pairableStamp(double stamp, double now) {
  constexpr double k30 = 1073741824.0, k31 = 2147483648.0;
  return now > 0.0 ? std::abs(stamp - now) < k30 : stamp < k31;
}

/// Why a velocity (odometry's, or a command's) cannot be planned from: not finite, or faster than
/// `max_speed` m/s (the parameter `limit_name`), which no vehicle flies and a planner must not brake from
/// (a braking plan from 1e7 m/s took gigabytes). "" when usable.
inline std::string velocityProblem(const common::Vec3& v, double max_speed, const std::string& limit_name) {
  if (!v.allFinite()) {
    std::ostringstream why;
    why << "velocity (" << v.x() << ", " << v.y() << ", " << v.z() << ") is not finite";
    return why.str();
  }
  const double speed = v.stableNorm();  // stableNorm: the square of 1e200 m/s would overflow
  if (speed <= max_speed) return std::string();
  std::ostringstream why;
  why << "speed " << speed << " m/s is above " << limit_name << " (" << max_speed << " m/s)";
  return why.str();
}

/// The step from the last odometry position to `p` as flown distance: 0 without a last position, and
/// nothing when it is longer than `max_step` (a jump: a relocalisation, or a gap in the odometry).
inline std::optional<double> flownStep(const std::optional<common::Vec3>& last, const common::Vec3& p, double max_step) {
  if (!last) return 0.0;
  const double step = (p - *last).norm();
  if (step > max_step) return std::nullopt;
  return step;
}

/// What flownStep() refused, for the log.
inline std::string odometryJump(const common::Vec3& last, const common::Vec3& p) {
  return "odometry jumped " + std::to_string((p - last).norm()) +
         " m (more than metrics/max_odom_step): not counted as flown";
}

/// The pose (x, y, z, q) with its quaternion normalised: one accepted as a unit quaternion (within 1e-3) but
/// not quite one gives a rotation matrix scaled off rigid (the mapper refused such a camera pose as no
/// rotation at all; a camera scaled every ray of its frame).
inline Eigen::Isometry3d rigidPose(double x, double y, double z, const geometry_msgs::Quaternion& q) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, z);
  return T;
}

/// A velocity given in the body frame of `orientation` (nav_msgs/Odometry's twist, which is in the
/// child frame) turned into the world frame. The quaternion is normalised first.
inline common::Vec3 worldVelocity(const geometry_msgs::Quaternion& orientation, const geometry_msgs::Vector3& body) {
  const Eigen::Quaterniond q(orientation.w, orientation.x, orientation.y, orientation.z);
  return q.normalized() * common::Vec3(body.x, body.y, body.z);
}

/// Why odometry cannot be used in the map's `world_frame`: its header names another frame (an odom or
/// VIO frame the map is not in: the pose would land elsewhere in the map), or its pose is unusable
/// (odometryPoseProblem()). "" when usable.
inline std::string odometryPoseProblem(const nav_msgs::Odometry& odom, const std::string& world_frame) {
  if (odom.header.frame_id != world_frame)
    return "odometry is in frame '" + odom.header.frame_id + "', not the map's '" + world_frame + "' (world_frame)";
  return odometryPoseProblem(odom.pose.pose);
}

/// The odometry's linear velocity in its header's (world) frame. nav_msgs/Odometry gives the twist in
/// child_frame_id, the body (the simulator, most flight stacks): it is turned by the orientation. A
/// child_frame_id equal to the header's frame (VINS-Mono and VINS-Fusion write "world" for both) means the
/// twist is in the world frame already, and is taken as it is.
inline common::Vec3 odometryVelocity(const nav_msgs::Odometry& odom) {
  const geometry_msgs::Vector3& v = odom.twist.twist.linear;
  if (odom.child_frame_id == odom.header.frame_id) return common::Vec3(v.x, v.y, v.z);
  return worldVelocity(odom.pose.pose.orientation, v);
}

/// Why odometry cannot be planned from (odometryPoseProblem() in `world_frame`, then velocityProblem() of
/// odometryVelocity(), which goes to `v_world`): "" when usable.
inline std::string odometryProblem(const nav_msgs::Odometry& odom, const std::string& world_frame, double max_speed,
                                   const std::string& limit_name, common::Vec3& v_world) {
  if (std::string bad = odometryPoseProblem(odom, world_frame); !bad.empty()) return bad;
  v_world = odometryVelocity(odom);
  return velocityProblem(v_world, max_speed, limit_name);
}

}  // namespace go_feap::ros_conv
