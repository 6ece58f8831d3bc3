// OdometryTf: republishes an odometry stream (e.g. VINS-Fusion's) as the TF world -> body, and the
// camera extrinsic (config/d435i.yaml T_B_C) as the static TF body -> camera, so the mapper can look
// up the camera pose at each depth stamp (mapper/sync_mode: tf) on a real drone. Odometry with a
// non-finite pose or a non-unit orientation is refused (counted, logged once per warn period). Odometry
// whose body z axis lies more than max_body_tilt from the world's up is said (and still sent): the planners
// take the body frame as FLU (x forward, y left, z up), and a VIO reporting its camera IMU's frame (x right,
// y down, z forward, as VINS-Fusion's stock D435i set-up does) turns the heading and the depth rays.
// In: odom. Out: TF `world_frame` -> `body_frame`, static TF `body_frame` -> `camera_frame`.
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>
#include <tf2_ros/transform_broadcaster.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

#include "go_feap/common/transform.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/params.h"

namespace go_feap {

class OdometryTf : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
 private:
  void onInit() override {
    ros_params::ParamReader p(getPrivateNodeHandle());
    std::string camera_frame;
    Eigen::Matrix4d T_B_C;
    p.getFrame("world_frame", world_frame_).getFrame("body_frame", body_frame_).get("warn_period", warn_period_);
    p.get("max_body_tilt", max_body_tilt_);
    p.getFrame("camera_frame", camera_frame).getMatrix4("T_B_C", T_B_C);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    ros_params::requireOrThrow(common::isCameraMount(T_B_C), getName(),
                               "parameter '" + p.fullName("T_B_C") + "' must be a rigid transform with a translation of at most " +
                                   std::to_string(common::kMaxMountOffset) + " m (a camera on the vehicle; metres, not millimetres)");
    ros_params::requireOrThrow(camera_frame != body_frame_, getName(),  // getFrame refused empty ones
                               "parameter '" + p.fullName("camera_frame") + "' must name a frame other than the body");
    ros_params::requireOrThrow(camera_frame != world_frame_, getName(),  // world -> body -> world: a loop
                               "parameter '" + p.fullName("camera_frame") + "' must name a frame other than the world");
    ros_params::requireOrThrow(world_frame_ != body_frame_, getName(),
                               "parameters 'world_frame' and 'body_frame' must name two different frames");
    // At most an hour: after the first warning, a longer period leaves a flight's bad input unsaid.
    ros_params::requireOrThrow(warn_period_ > 0.0 && warn_period_ <= 3600.0, getName(),
                               "parameter '" + p.fullName("warn_period") + "' must be in (0, 3600] s");
    // Below pi: at pi no pose would ever be said (an upside-down z axis is pi from up).
    ros_params::requireOrThrow(max_body_tilt_ > 0.0 && max_body_tilt_ < M_PI, getName(),
                               "parameter '" + p.fullName("max_body_tilt") + "' must be in (0, pi) rad");
    min_up_ = std::cos(max_body_tilt_);
    // Sent once every parameter has passed: a nodelet that does not start leaves no TF behind.
    Eigen::Isometry3d extrinsic;
    extrinsic.matrix() = T_B_C;
    geometry_msgs::TransformStamped camera = tf2::eigenToTransform(extrinsic);
    camera.header.stamp = ros::Time::now();
    camera.header.frame_id = body_frame_;
    camera.child_frame_id = camera_frame;
    static_broadcaster_.sendTransform(camera);
    broadcaster_ = std::make_unique<tf2_ros::TransformBroadcaster>();
    odom_sub_ = ros_guard::subscribe(getNodeHandle(), getName(), "odom", 20, &OdometryTf::onOdom, this);
  }

  void onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
    const std::string bad = ros_conv::odometryPoseProblem(*msg, world_frame_);
    if (!bad.empty()) {
      ++refused_;
      GO_FEAP_NODELET_THROTTLE(WARN, warn_period_, getName() << ": odometry refused: " << bad << " (" << refused_
                                                           << " refused so far)");
      return;
    }
    if (msg->header.stamp.isZero()) {  // (it equalled the unset last_stamp_: "stamp 0 s repeated", no TF ever)
      ++refused_;
      GO_FEAP_NODELET_THROTTLE(WARN, warn_period_, getName() << ": odometry refused: header.stamp is unset (0): a TF "
                                                           << "at time 0 dates no depth frame (" << refused_
                                                           << " refused so far)");
      return;
    }
    const auto& p = msg->pose.pose.position;
    const auto& q = msg->pose.pose.orientation;
    const Eigen::Vector3d position(p.x, p.y, p.z);
    if (msg->header.stamp == last_stamp_) {  // TF refuses repeated stamps: the first pose of a stamp stands
      // A copy is harmless; another pose under the same stamp is a source stamping alike, and is said.
      const double apart = (position - last_position_).norm();
      if (apart > 1e-6)
        GO_FEAP_NODELET_THROTTLE(WARN, warn_period_, getName() << ": odometry stamp " << last_stamp_.toSec()
                                                             << " s repeated with a pose " << apart
                                                             << " m from the first: dropped, the TF keeps the first");
      return;
    }
    last_stamp_ = msg->header.stamp;
    last_position_ = position;
    // The body's z axis in the world, R e_z: its z component is cos(tilt) for a unit quaternion.
    const double up = 1.0 - 2.0 * (q.x * q.x + q.y * q.y) / (q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
    if (up < min_up_)
      GO_FEAP_NODELET_THROTTLE(WARN, warn_period_,
                               getName() << ": the odometry's body z axis lies "
                                         << std::acos(std::clamp(up, -1.0, 1.0)) * 180.0 / M_PI
                                         << " deg from the world's up (more than max_body_tilt "
                                         << max_body_tilt_ << " rad): the body frame must be FLU "
                                         << "(x forward, y left, z up); a VIO reporting its camera IMU's "
                                         << "frame (x right, y down, z forward) turns the heading and "
                                         << "the depth rays: relay its odometry rotated into an FLU body");
    geometry_msgs::TransformStamped t;
    t.header.stamp = msg->header.stamp;
    t.header.frame_id = world_frame_;
    t.child_frame_id = body_frame_;
    t.transform.translation.x = p.x, t.transform.translation.y = p.y, t.transform.translation.z = p.z;
    t.transform.rotation = q;
    broadcaster_->sendTransform(t);
  }

  std::string world_frame_, body_frame_;
  double warn_period_ = 2.0;
  double max_body_tilt_ = 1.0;  ///< rad
  double min_up_ = 0.0;         ///< cos(max_body_tilt_): the least z component of the body's z axis
  std::uint64_t refused_ = 0;
  ros::Time last_stamp_;
  Eigen::Vector3d last_position_ = Eigen::Vector3d::Zero();  ///< of the odometry stamped last_stamp_
  std::unique_ptr<tf2_ros::TransformBroadcaster> broadcaster_;
  tf2_ros::StaticTransformBroadcaster static_broadcaster_;
  ros::Subscriber odom_sub_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::OdometryTf, nodelet::Nodelet)
