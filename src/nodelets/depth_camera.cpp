// DepthCamera: renders the ground-truth scene from the vehicle's pose. odom in; depth
// (32FC1 metres, REP 117's +inf / -inf / NaN where there is no return; or 16UC1 millimetres, 0 where
// there is none), camera_info, camera_pose (same stamp as the image) and
// the static TF body->camera out, at `rate` Hz of simulated time.
#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/PoseStamped.h>
#include <nav_msgs/Odometry.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_eigen/tf2_eigen.h>
#include <tf2_ros/static_transform_broadcaster.h>

#include <cmath>
#include <limits>
#include <random>

#include "go_feap/common/config_groups.h"
#include "go_feap/common/transform.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/params.h"
#include "go_feap/sim/depth_camera.h"
#include "go_feap/world/scene.h"

namespace go_feap {

class DepthCamera : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    const std::string me = getName();
    ros_params::ParamReader p(pnh);
    sim::DepthCameraConfig c;
    config::readDepthCamera(p, c);
    int seed = 0;
    Eigen::Matrix4d T_B_C;
    double odom_rate = 0.0;
    p.get("depth_camera/noise_seed", seed).get("depth_camera/rate", rate_).get("simulation/odom_rate", odom_rate);
    p.get("depth_camera/encoding", encoding_);
    p.getFrame("depth_camera/camera_frame", camera_frame_).getMatrix4("depth_camera/T_B_C", T_B_C);
    p.getFrame("simulation/world_frame", world_frame_).getFrame("simulation/body_frame", body_frame_);
    ros_params::requireOrThrow(p.ok(), me, p.error());
    ros_params::requireOrThrow(camera_frame_ != body_frame_ && camera_frame_ != world_frame_, me,
                               "parameter '" + p.fullName("depth_camera/camera_frame") +
                                   "' must differ from the body and world frames (its TF hangs off the body)");
    ros_params::requireOrThrow(encoding_ == "32FC1" || encoding_ == "16UC1", me,
                               "parameter '" + p.fullName("depth_camera/encoding") + "' must be 32FC1 or 16UC1");
    ros_params::requireOrThrow(c.validate().ok(), me, c.validate().message());
    // 16 bits of millimetres end at 65.535 m: a return beyond would be written as 65535 mm, a wall that is not there.
    ros_params::requireOrThrow(encoding_ != "16UC1" || c.max_range <= 65.535, me,
                               "parameter '" + p.fullName("depth_camera/max_range") +
                                   "' must be <= 65.535 m with encoding 16UC1 (millimetres in 16 bits)");
    ros_params::requireOrThrow(rate_ > 0.0 && rate_ <= 100.0, me,
                               "parameter '" + p.fullName("depth_camera/rate") + "' must be in (0, 100] Hz");
    // Frames are rendered at odometry stamps: a faster camera came at the odometry's rate, in silence.
    ros_params::requireOrThrow(rate_ <= odom_rate, me,
                               "parameter '" + p.fullName("depth_camera/rate") + "' (" + std::to_string(rate_) +
                                   " Hz) must be <= '" + p.fullName("simulation/odom_rate") + "' (" +
                                   std::to_string(odom_rate) + " Hz): frames are rendered at odometry stamps");
    ros_params::requireOrThrow(common::isCameraMount(T_B_C), me,
                               "parameter '" + p.fullName("depth_camera/T_B_C") + "' must be a rigid transform with a translation of at most " +
                                   std::to_string(common::kMaxMountOffset) + " m (a camera on the vehicle; metres, not millimetres)");
    T_B_C_.matrix() = T_B_C;
    rng_.seed(static_cast<std::uint64_t>(seed));
    config_ = c;
    intrinsics_ = c.intrinsics();

    scene_ = std::make_unique<world::Scene>(ros_params::loadScene(pnh, me));
    renderer_ = std::make_unique<sim::DepthRenderer>(c, *scene_);

    depth_pub_ = nh.advertise<sensor_msgs::Image>("depth", 2);
    info_pub_ = nh.advertise<sensor_msgs::CameraInfo>("camera_info", 2);
    pose_pub_ = nh.advertise<geometry_msgs::PoseStamped>("camera_pose", 2);
    odom_sub_ = ros_guard::subscribe(nh, getName(), "odom", 10, &DepthCamera::onOdom, this, ros::TransportHints().tcpNoDelay());

    geometry_msgs::TransformStamped tf = tf2::eigenToTransform(T_B_C_);
    tf.header.stamp = ros::Time::now();
    tf.header.frame_id = body_frame_;
    tf.child_frame_id = camera_frame_;
    static_tf_.sendTransform(tf);
    NODELET_INFO_STREAM(me << ": " << c.width << "x" << c.height << " depth at " << rate_ << " Hz, range "
                           << c.min_range << "-" << c.max_range << " m");
  }

  // Renders when the odometry stamp reaches the next frame time, so that the image, its
  // camera pose and the odometry share one exact stamp.
  void onOdom(const nav_msgs::Odometry::ConstPtr& odom) {
    // A refused message is as if it never came: it takes no frame's turn and no part in the stamp checks.
    const std::string bad = ros_conv::odometryPoseProblem(*odom, world_frame_);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": odometry refused: " << bad);
      return;
    }
    const ros::Time stamp = odom->header.stamp;
    // Odometry whose stamp stands still (a source stamping every message alike, or a stalled clock
    // relayed): frames are timed by the stamps, so none comes until it moves on. Said once the stamp has
    // come kStallMessages times in a row, and again every 5 s while it lasts.
    if (stamp == last_stamp_) {
      if (++repeats_ >= kStallMessages)
        GO_FEAP_NODELET_THROTTLE(WARN, 5.0, getName() << ": odometry stamp " << stamp.toSec() << " s repeated in "
                                                    << repeats_ + 1 << " messages in a row: no depth frame until it advances");
      return;
    }
    if (repeats_ >= kStallMessages)
      NODELET_INFO_STREAM(getName() << ": odometry stamps advance again after " << repeats_ + 1 << " messages stamped "
                                    << last_stamp_.toSec() << " s");
    repeats_ = 0;
    last_stamp_ = stamp;
    const double period = 1.0 / rate_;
    const double now = stamp.toSec();
    const double ahead = std::isnan(next_frame_) ? 0.0 : next_frame_ - now;  // s to the next frame
    // Not yet. Within a microsecond counts as due: stamps are whole nanoseconds and the schedule a sum of
    // periods, so a frame due with this stamp came out 1e-12 s ahead of it, and waited for the next odometry
    // (a 50 Hz camera on 100 Hz odometry sent frames 0.03 s apart, and dropped some).
    constexpr double kDue = 1e-6;
    if (ahead > kDue && ahead <= period) return;
    // On time: the next frame one period on. More than a period late, or more than a period early (a
    // clock that went back, or one odometry stamp far ahead, which would otherwise hold every frame
    // back until that time): the frames start again from this stamp. In seconds as a double: a
    // ros::Time one period past a stamp near 2^32 s would throw.
    next_frame_ = (std::isnan(next_frame_) || ahead < -period || ahead > period) ? now + period : next_frame_ + period;
    // The orientation normalised: odometry may be up to 1e-3 off unit length (it passes the pose checks).
    const auto& p = odom->pose.pose.position;
    const Eigen::Isometry3d T_W_B = ros_conv::rigidPose(p.x, p.y, p.z, odom->pose.pose.orientation);
    const Eigen::Isometry3d T_W_C = T_W_B * T_B_C_;

    cv_bridge::CvImage image;
    image.header.stamp = stamp;
    image.header.frame_id = camera_frame_;
    image.encoding = sensor_msgs::image_encodings::TYPE_32FC1;
    renderer_->render(T_W_C, image.image);
    if (config_.noise_stddev_per_m > 0.0 || config_.dropout_probability > 0.0) renderer_->addNoise(image.image, rng_);
    if (encoding_ == "16UC1") {  // as a RealSense publishes it: millimetres, 0 = no return (near or far)
      cv::Mat mm;
      sim::toMillimetres(image.image, mm);
      image.image = mm;
      image.encoding = sensor_msgs::image_encodings::TYPE_16UC1;
    }

    sensor_msgs::CameraInfo info;
    info.header = image.header;
    info.width = intrinsics_.width;
    info.height = intrinsics_.height;
    info.distortion_model = "plumb_bob";
    info.D.assign(5, 0.0);
    info.K = {intrinsics_.fx, 0, intrinsics_.cx, 0, intrinsics_.fy, intrinsics_.cy, 0, 0, 1};
    info.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    info.P = {intrinsics_.fx, 0, intrinsics_.cx, 0, 0, intrinsics_.fy, intrinsics_.cy, 0, 0, 0, 1, 0};

    geometry_msgs::PoseStamped pose;
    pose.header.stamp = stamp;
    pose.header.frame_id = world_frame_;
    pose.pose = tf2::toMsg(T_W_C);

    pose_pub_.publish(pose);
    info_pub_.publish(info);
    depth_pub_.publish(image.toImageMsg());
  }

  sim::DepthCameraConfig config_;
  sim::CameraIntrinsics intrinsics_;
  double rate_ = 15.0;
  std::string world_frame_, body_frame_, camera_frame_, encoding_;
  Eigen::Isometry3d T_B_C_ = Eigen::Isometry3d::Identity();
  std::unique_ptr<world::Scene> scene_;
  std::unique_ptr<sim::DepthRenderer> renderer_;
  std::mt19937_64 rng_;
  static constexpr int kStallMessages = 10;  ///< repeats of one odometry stamp before it is reported
  ros::Time last_stamp_;                      ///< of the last odometry message
  int repeats_ = 0;                           ///< messages since then with the same stamp
  double next_frame_ = std::numeric_limits<double>::quiet_NaN();  // stamp of the next frame, s; NaN before the first
  ros::Publisher depth_pub_, info_pub_, pose_pub_;
  ros::Subscriber odom_sub_;
  tf2_ros::StaticTransformBroadcaster static_tf_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::DepthCamera, nodelet::Nodelet)
