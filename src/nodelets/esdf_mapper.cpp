// EsdfMapper: integrates depth images into the occupancy map and the incremental ESDF.
// In: depth (+ camera_info) and camera_pose (exact or approximate sync) or TF. Out:
// map_update (go_feap/MapUpdate), map_handle (in-process map pointer, see
// go_feap/ros/shared_map.h), throttled occupied_cloud and esdf_slice, service save_map.
#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/PoseStamped.h>
#include <message_filters/subscriber.h>
#include <message_filters/sync_policies/approximate_time.h>
#include <message_filters/sync_policies/exact_time.h>
#include <message_filters/synchronizer.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/image_encodings.h>
#include <sensor_msgs/point_cloud2_iterator.h>
#include <Eigen/Geometry>
#include <tf2_ros/buffer.h>
#include <tf2_ros/message_filter.h>
#include <tf2_ros/transform_listener.h>
#include <tf2_msgs/TFMessage.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <iomanip>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "go_feap/MapUpdate.h"
#include "go_feap/SaveMap.h"
#include "go_feap/common/config_groups.h"
#include "go_feap/common/machine.h"
#include "go_feap/ros/compute_time.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/message_checks.h"
#include "go_feap/ros/params.h"
#include "go_feap/ros/shared_map.h"
#include "go_feap/ros/tf_gaps.h"

namespace go_feap {

class EsdfMapper : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
  using ExactPolicy = message_filters::sync_policies::ExactTime<sensor_msgs::Image, geometry_msgs::PoseStamped>;
  using ApproxPolicy = message_filters::sync_policies::ApproximateTime<sensor_msgs::Image, geometry_msgs::PoseStamped>;

 private:
  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    const std::string me = getName();
    ros_params::ParamReader p(pnh);
    map::MapConfig c;
    config::readMap(p, c);
    p.get("mapper/sync_mode", sync_mode_).get("mapper/pose_tolerance", pose_tolerance_);
    p.get("mapper/max_pose_jump", max_pose_jump_).getFrame("mapper/world_frame", world_frame_);
    p.get("mapper/max_rotation_jump", max_rotation_jump_);
    p.get("mapper/cloud_period", cloud_period_).get("mapper/esdf_slice_height", slice_height_);
    p.get("mapper/warn_period", warn_period_).get("mapper/tf_queue", tf_queue_).get("mapper/max_tf_gap", max_tf_gap_);
    common::Aabb box;
    config::readBox(p, box);
    ros_params::requireOrThrow(p.ok(), me, p.error());
    const common::Status map_ok = c.validate(box);
    ros_params::requireOrThrow(map_ok.ok(), me, map_ok.message());
    ros_params::requireOrThrow(sync_mode_ == "exact" || sync_mode_ == "approximate" || sync_mode_ == "tf", me,
                               "parameter '" + p.fullName("mapper/sync_mode") + "' must be exact, approximate or tf");
    ros_params::requireOrThrow(pose_tolerance_ >= 0.0 && pose_tolerance_ <= 1.0, me,
                               "parameter '" + p.fullName("mapper/pose_tolerance") + "' must be in [0, 1] s");
    ros_params::requireOrThrow(std::isfinite(max_pose_jump_) && max_pose_jump_ > 0.0, me,
                               "parameter '" + p.fullName("mapper/max_pose_jump") + "' must be finite and > 0");
    ros_params::requireOrThrow(max_rotation_jump_ > 0.0 && max_rotation_jump_ <= M_PI, me,
                               "parameter '" + p.fullName("mapper/max_rotation_jump") + "' must be in (0, pi] rad");
    ros_params::requireOrThrow(std::isfinite(cloud_period_) && cloud_period_ >= 0.0, me,
                               "parameter '" + p.fullName("mapper/cloud_period") + "' must be finite and >= 0");
    ros_params::requireOrThrow(tf_queue_ >= 1 && tf_queue_ <= 1000, me,
                               "parameter '" + p.fullName("mapper/tf_queue") + "' must be in [1, 1000] frames");
    ros_params::requireOrThrow(std::isfinite(max_tf_gap_) && max_tf_gap_ > 0.0, me,
                               "parameter '" + p.fullName("mapper/max_tf_gap") + "' must be finite and > 0");
    // At most an hour: after the first warning, a longer period leaves a flight's bad input unsaid.
    ros_params::requireOrThrow(warn_period_ > 0.0 && warn_period_ <= 3600.0, me,
                               "parameter '" + p.fullName("mapper/warn_period") + "' must be in (0, 3600] s");
    ros_params::requireOrThrow(std::isfinite(slice_height_), me,
                               "parameter '" + p.fullName("mapper/esdf_slice_height") + "' must be finite");

    // Said, and checked against the machine, before it is allocated: too large a map ended in the OOM killer
    // taking the whole nodelet manager.
    const double estimate = c.estimatedBytes(box);
    NODELET_INFO_STREAM(me << ": allocating a map of about " << static_cast<long long>(estimate / (1024 * 1024))
                           << " MiB");
    const common::Status fits = c.checkFits(box, common::physicalMemoryBytes());
    ros_params::requireOrThrow(fits.ok(), me, fits.message());
    shared_ = std::make_shared<ros_map::SharedMap>(std::make_unique<map::VoxelMap>(c, box));
    // Said before the first subscription: a frame integrated beside onInit would grow what this reads.
    const auto& geo = shared_->map->geometry();
    NODELET_INFO_STREAM(me << ": map " << geo.dims().transpose() << " voxels at " << geo.resolution() << " m ("
                           << shared_->map->memoryBytes() / (1024 * 1024) << " MiB), sync " << sync_mode_);
    compute_pub_ = nh.advertise<ComputeTime>("compute_time", 20);
    update_pub_ = nh.advertise<MapUpdate>("map_update", 10);
    handle_pub_ = nh.advertise<ros_map::MapHandle>("map_handle", 1, /*latch=*/true);
    cloud_pub_ = nh.advertise<sensor_msgs::PointCloud2>("occupied_cloud", 1);
    slice_pub_ = nh.advertise<sensor_msgs::PointCloud2>("esdf_slice", 1);
    // On the manager's worker threads, not the queue that integrates depth: a save of a large map takes
    // seconds, and frames went on arriving (and were dropped) while the vehicle flew on a frozen map.
    save_srv_ = ros_guard::service(getMTNodeHandle(), getName(), "save_map", &EsdfMapper::onSave, this);
    info_sub_ = ros_guard::subscribe(nh, getName(), "camera_info", 1, &EsdfMapper::onInfo, this);
    depth_sub_.subscribe(nh, "depth", 5);
    if (sync_mode_ == "tf") {
      // The listener fills the buffer on its own thread. A frame waits in the filter, never blocking this
      // nodelet's queue, until its transform has come (VIO lags the camera) or tf_queue newer frames push
      // it out; a wait inside the callback stalled it, and save_map, for ever once the clock stopped.
      tf_buffer_ = std::make_unique<tf2_ros::Buffer>();
      tf_listener_ = std::make_unique<tf2_ros::TransformListener>(*tf_buffer_, nh);
      // The stamps of the moving links' samples, heard beside the listener (mapper/max_tf_gap). /tf is
      // global, as the listener's own subscription.
      tf_samples_sub_ = ros_guard::subscribe(nh, getName(), "/tf", 200, &EsdfMapper::onTfSamples, this);
      tf_filter_ = std::make_unique<tf2_ros::MessageFilter<sensor_msgs::Image>>(
          depth_sub_, *tf_buffer_, world_frame_, static_cast<std::uint32_t>(tf_queue_), nh);
      tf_filter_->registerCallback(&EsdfMapper::onDepthTransformable, this);
      tf_filter_->registerFailureCallback(
          [this](const sensor_msgs::Image::ConstPtr& depth, tf2_ros::filter_failure_reasons::FilterFailureReason why) {
            ros_guard::run(getName(), "the TF filter's drop callback", log_throttle_, [&] { onDepthDropped(depth, why); });
          });
    } else {
      pose_sub_.subscribe(nh, "camera_pose", 20);
      // A pair is the only callback: count the images, so that frames that never pair (poses stamped
      // otherwise, or none) are said, not dropped in silence.
      depth_sub_.registerCallback([this](const sensor_msgs::Image::ConstPtr&) {
        ros_guard::run(getName(), "the depth counter", log_throttle_, [&] { onDepthArrived(); });
      });
      if (sync_mode_ == "exact") {
        exact_sync_ = std::make_unique<message_filters::Synchronizer<ExactPolicy>>(ExactPolicy(kSyncQueue), depth_sub_, pose_sub_);
        exact_sync_->registerCallback(&EsdfMapper::onDepthPair, this);
      } else {
        // ApproximateTime subtracts the stamps it holds as ros::Time, which throws past 2^31 s: one message
        // stamped 4e9 s (a sender's clock gone wrong) took the nodelet manager down, outside any callback
        // of ours. Each message reaches it through a guarded callback that refuses such stamps first.
        approx_sync_ = std::make_unique<message_filters::Synchronizer<ApproxPolicy>>(ApproxPolicy(kSyncQueue));
        approx_sync_->registerCallback(&EsdfMapper::onDepthPair, this);
        depth_sub_.registerCallback([this](const sensor_msgs::Image::ConstPtr& m) {
          ros_guard::run(getName(), "the depth synchroniser", log_throttle_, [&] {
            if (pairableStamp("depth image", m->header.stamp)) approx_sync_->add<0>(m);
          });
        });
        pose_sub_.registerCallback([this](const geometry_msgs::PoseStamped::ConstPtr& m) {
          ros_guard::run(getName(), "the camera_pose synchroniser", log_throttle_, [&] {
            if (pairableStamp("camera_pose", m->header.stamp)) approx_sync_->add<1>(m);
          });
        });
      }
    }
    publishHandle();
  }

  // A camera_info that cannot describe the images (a driver restarting, a zero K) is refused: the frames
  // go on with the last valid intrinsics instead of all being skipped until a valid one comes.
  void onInfo(const sensor_msgs::CameraInfo::ConstPtr& info) {
    const map::DepthIntrinsics K = ros_conv::depthIntrinsics(*info);
    const common::Status st = K.validate();
    std::lock_guard<std::mutex> lock(input_mutex_);
    if (!st.ok()) {
      GO_FEAP_NODELET_THROTTLE(WARN, warn_period_, getName() << ": camera_info refused: " << st.message() << "; "
                                                           << (intrinsics_ ? "the last valid intrinsics stay"
                                                                           : "no frame is integrated until a valid one"));
      return;
    }
    intrinsics_ = K;
    intrinsics_frame_ = info->header.frame_id;
    if (ros_conv::hasDistortion(*info))
      GO_FEAP_NODELET_THROTTLE(WARN, warn_period_, getName() << ": camera_info gives lens distortion (D of model '"
                                                           << info->distortion_model << "' is not 0): the depth images "
                                                              "are taken as rectified, distortion not undone; feed "
                                                              "the rectified image (image_rect) and its camera_info");
  }

  // The synchroniser's callback, under ros_guard like every other.
  void onDepthPair(const sensor_msgs::Image::ConstPtr& depth, const geometry_msgs::PoseStamped::ConstPtr& pose) {
    ros_guard::run(getName(), "the depth and camera_pose callback", log_throttle_, [&] { onDepthPose(depth, pose); });
  }

  /// Whether a message stamped `stamp` may enter the approximate synchroniser (ros_conv::pairableStamp():
  /// within 2^30 s, 34 years, of now); said and skipped otherwise.
  bool pairableStamp(const char* what, const ros::Time& stamp) {
    const double now = ros::Time::now().toSec();
    if (ros_conv::pairableStamp(stamp.toSec(), now)) return true;
    skip("stamp", std::string(what) + " stamped " + std::to_string(stamp.toSec()) + " s, " +
                      std::to_string(stamp.toSec() - now) + " s from now: too far to pair (mapper/sync_mode approximate)");
    return false;
  }

  // More images than the synchroniser keeps since the last pair: none of them found its camera_pose.
  void onDepthArrived() {
    if (++unpaired_ <= kSyncQueue) return;
    skip("pose_sync", std::to_string(unpaired_ - 1) + " depth images in a row found no camera_pose " +
                          (sync_mode_ == "exact" ? "stamped alike (mapper/sync_mode exact)"
                                                 : "to pair with (mapper/sync_mode approximate)") +
                          ": is camera_pose published, and stamped with the image's stamp?");
  }

  void onDepthPose(const sensor_msgs::Image::ConstPtr& depth, const geometry_msgs::PoseStamped::ConstPtr& pose) {
    unpaired_ = 0;
    // Stamps are the map's clock (a frontier's age counts from the frame that found it): a frame stamped 0
    // would date its frontiers to the epoch for good.
    if (depth->header.stamp.isZero()) return skip("stamp", "depth image stamped 0");
    // In seconds as doubles: ros::Time subtraction throws beyond 2^31 s, and a stamp is the sender's.
    const double dt = std::abs(depth->header.stamp.toSec() - pose->header.stamp.toSec());
    if (dt > pose_tolerance_ + 1e-9) return skip("pose_time", "camera_pose is " + std::to_string(dt) + " s from the image");
    // A pose in another frame (odom, the body) would put the frame in the wrong place of the map, and an
    // unset (all-zero) quaternion would be read as no rotation at all.
    if (pose->header.frame_id != world_frame_)
      return skip("pose_frame", "camera_pose is in frame '" + pose->header.frame_id + "', not the map's '" +
                                    world_frame_ + "'");
    const std::string bad = ros_conv::odometryPoseProblem(pose->pose);
    if (!bad.empty()) return skip("pose", "camera_pose refused: " + bad);
    const auto& p = pose->pose.position;
    integrate(depth, ros_conv::rigidPose(p.x, p.y, p.z, pose->pose.orientation));
  }

  // The TF filter's callback, under ros_guard like every other.
  void onDepthTransformable(const sensor_msgs::Image::ConstPtr& depth) {
    ros_guard::run(getName(), "the depth callback (TF)", log_throttle_, [&] { onDepthTf(depth); });
  }

  void onDepthDropped(const sensor_msgs::Image::ConstPtr& depth, tf2_ros::filter_failure_reasons::FilterFailureReason why) {
    namespace reasons = tf2_ros::filter_failure_reasons;
    const std::string pair = world_frame_ + " <- '" + depth->header.frame_id + "'";
    if (why == reasons::EmptyFrameID) return skip("tf", "depth image without a frame_id: its camera pose cannot be looked up");
    if (why == reasons::OutTheBack)
      return skip("tf", "depth image stamped " + std::to_string(depth->header.stamp.toSec()) +
                            " s, older than the TF buffer holds for " + pair);
    // Unknown: pushed out of the queue by newer frames, or left behind by a TF buffer that moved on (a
    // time jump clears it) while the frame waited.
    skip("tf", "no transform " + pair + " at the image's stamp " + std::to_string(depth->header.stamp.toSec()) +
                   " s while it waited (" + std::to_string(tf_queue_) +
                   " newer frames came, mapper/tf_queue, or the TF buffer moved on)");
  }

  void onDepthTf(const sensor_msgs::Image::ConstPtr& depth) {
    // Time 0 asks tf2 for the latest transform, which is not the image's pose.
    if (depth->header.stamp.isZero()) return skip("stamp", "depth image stamped 0: its camera pose cannot be looked up");
    geometry_msgs::TransformStamped tf;
    try {  // the filter passed it: no waiting
      tf = tf_buffer_->lookupTransform(world_frame_, depth->header.frame_id, depth->header.stamp);
    } catch (const tf2::TransformException& e) {
      return skip("tf", std::string("no transform ") + world_frame_ + " <- " + depth->header.frame_id + ": " + e.what());
    }
    if (const std::string gap = interpolatedAcrossGap(depth->header.frame_id, depth->header.stamp); !gap.empty())
      return skip("tf_gap", gap);
    const auto& t = tf.transform.translation;
    integrate(depth, ros_conv::rigidPose(t.x, t.y, t.z, tf.transform.rotation));
  }

  void onTfSamples(const tf2_msgs::TFMessage::ConstPtr& msg) {
    std::lock_guard<std::mutex> lock(tf_samples_mutex_);
    for (const geometry_msgs::TransformStamped& t : msg->transforms)
      tf_samples_.add(t.child_frame_id, t.header.stamp, t.transform);
  }

  /// Why the pose of `frame` at `stamp` is not to be trusted, or "": a link of the chain world <- frame
  /// that moved between its samples round the stamp, more than mapper/max_tf_gap apart, between which tf2
  /// put the pose on a straight line (an odometry gap). With no sample after the stamp logged yet (the one
  /// that let tf2 answer is still on its way here), the last before it more than max_tf_gap back is a gap
  /// as long at least.
  std::string interpolatedAcrossGap(const std::string& frame, const ros::Time& stamp) {
    std::vector<std::string> chain;
    try {
      tf_buffer_->_chainAsVector(world_frame_, stamp, frame, stamp, world_frame_, chain);
    } catch (const tf2::TransformException&) {
      return "";  // the lookup just passed; a chain tf2 cannot name now is left to it
    }
    std::lock_guard<std::mutex> lock(tf_samples_mutex_);
    for (const std::string& link : chain) {
      if (link == world_frame_) continue;  // its own parent link is not in the chain
      const auto bracket = tf_samples_.around(link, stamp);
      if (!bracket) continue;
      const double span = (bracket->after ? bracket->after->toSec() : stamp.toSec()) - bracket->before.toSec();
      if (!(span > max_tf_gap_) || (bracket->after && !bracket->moved)) continue;
      std::ostringstream why;
      why << "the pose at " << std::fixed << std::setprecision(3) << stamp.toSec() << " s is interpolated between '"
          << link << "' samples at " << bracket->before.toSec() << " s and ";
      if (bracket->after)
        why << bracket->after->toSec() << " s, " << span;
      else
        why << "a later one, at least " << span;
      why << " s apart (more than mapper/max_tf_gap, " << max_tf_gap_ << " s): a gap in the odometry";
      return why.str();
    }
    return "";
  }

  void integrate(const sensor_msgs::Image::ConstPtr& msg, const Eigen::Isometry3d& T_W_C) {
    std::optional<map::DepthIntrinsics> K;
    std::string K_frame;
    {
      std::lock_guard<std::mutex> lock(input_mutex_);
      K = intrinsics_;
      K_frame = intrinsics_frame_;
    }
    if (!K) return skip("camera_info", "no camera_info received yet");
    // Intrinsics of another camera with the same image size (the depth camera's camera_info beside a depth
    // image aligned to the colour camera) would project every ray wrongly: said, not refused, as a driver
    // may name the two frames differently for the same camera.
    if (!K_frame.empty() && !msg->header.frame_id.empty() && K_frame != msg->header.frame_id)
      GO_FEAP_NODELET_THROTTLE(WARN, warn_period_, getName() << ": camera_info is in frame '" << K_frame
                                                           << "' but the depth image in '" << msg->header.frame_id
                                                           << "': are the intrinsics this camera's? (integrated)");
    if (!T_W_C.matrix().allFinite() ||
        !T_W_C.linear().isApprox(Eigen::Quaterniond(T_W_C.linear()).normalized().toRotationMatrix(), 1e-3))
      return skip("pose", "camera pose is not finite or not a rotation");
    // A jump between integrated frames, farther than mapper/max_pose_jump or turned more than
    // mapper/max_rotation_jump (a VIO restarted at its own origin resets the heading), is a relocalisation:
    // the frame is skipped and its pose is the reference from now on.
    if (reference_) {
      const double moved = (T_W_C.translation() - reference_->translation()).norm();
      const double turned = Eigen::AngleAxisd(reference_->linear().transpose() * T_W_C.linear()).angle();
      if (moved > max_pose_jump_ || turned > max_rotation_jump_) {
        reference_ = T_W_C;
        std::ostringstream why;
        why << "camera pose moved " << moved << " m and turned " << turned << " rad since the last frame (more than "
            << "mapper/max_pose_jump, " << max_pose_jump_ << " m, or mapper/max_rotation_jump, " << max_rotation_jump_
            << " rad): relocalisation?";
        return skip("pose_jump", why.str());
      }
    }
    const std::string bad = ros_check::depthImageProblem(*msg);
    if (!bad.empty()) return skip("image", "depth image refused: " + bad);
    cv_bridge::CvImageConstPtr image;
    try {
      image = cv_bridge::toCvShare(msg);
    } catch (const std::exception& e) {  // cv_bridge::Exception, or cv::Exception from OpenCV under it
      return skip("image", std::string("cannot read the depth image: ") + e.what());
    }
    const auto t0 = std::chrono::steady_clock::now();
    common::Result<map::MapUpdateInfo> info = common::Result<map::MapUpdateInfo>::Error("");
    std::uint64_t sequence = 0;
    {
      std::unique_lock<std::shared_mutex> lock(shared_->mutex);
      info = shared_->map->integrate(image->image, *K, T_W_C);
      if (info) {
        sequence = ++shared_->sequence;
        shared_->last_changed = info->frame.changed;
      }
    }
    if (!info) return skip("frame", info.message());
    reference_ = T_W_C;
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ros_conv::publishComputeTime(compute_pub_, "mapping", t0);
    if (info->frame.pixels_used == 0)  // a covered lens, an emitter off, the wrong topic: mapping has stopped
      GO_FEAP_NODELET_THROTTLE(WARN, warn_period_, getName() << ": no usable depth pixel in the frame stamped "
                                                           << msg->header.stamp.toSec() << " s (all "
                                                           << info->frame.pixels_invalid
                                                           << " sampled were 0, NaN or nearer than min_range): nothing mapped");
    else if (info->frame.rays == 0) {  // every ray misses the map: odometry in another frame, or far off
      const common::Aabb bounds = shared_->map->geometry().bounds();  // fixed at construction
      auto point = [](const common::Vec3& v) {
        std::ostringstream s;
        s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
        return s.str();
      };
      GO_FEAP_NODELET_THROTTLE(WARN, warn_period_, getName() << ": the camera at " << point(T_W_C.translation())
                                                           << " m sees nothing of the map, which spans "
                                                           << point(bounds.min) << " to " << point(bounds.max)
                                                           << " m in '" << world_frame_
                                                           << "' (exploration_box and occupancy/margin): nothing "
                                                              "mapped. Is the camera pose in the map's frame?");
    } else if (info->frame.pixels_invalid > 0)
      GO_FEAP_NODELET_THROTTLE(DEBUG, warn_period_, getName() << ": " << info->frame.pixels_invalid
                                                            << " invalid depth pixels in the latest frame");

    MapUpdate update;
    update.header.stamp = msg->header.stamp;
    update.header.frame_id = world_frame_;
    update.sequence = sequence;
    update.changed_voxels = static_cast<std::uint32_t>(info->frame.changed_voxels);
    update.resolution = shared_->map->geometry().resolution();
    if (info->frame.any_change) {
      update.changed_min.x = info->changed_box.min.x();
      update.changed_min.y = info->changed_box.min.y();
      update.changed_min.z = info->changed_box.min.z();
      update.changed_max.x = info->changed_box.max.x();
      update.changed_max.y = info->changed_box.max.y();
      update.changed_max.z = info->changed_box.max.z();
    }
    publishHandle();
    update_pub_.publish(update);
    NODELET_DEBUG_STREAM(getName() << ": frame " << sequence << " integrated in " << ms << " ms, "
                                   << info->frame.changed_voxels << " voxels changed");
    // Either way round: a frame stamped far ahead (or time going back, as a bag played again) must not
    // stop the clouds for good.
    if (cloud_period_ > 0.0 &&
        (last_cloud_.isZero() || std::abs(msg->header.stamp.toSec() - last_cloud_.toSec()) >= cloud_period_)) {
      last_cloud_ = msg->header.stamp;
      publishClouds(msg->header.stamp);
    }
  }

  void publishHandle() {
    auto handle = boost::make_shared<ros_map::MapHandle>();
    handle->shared = shared_;
    handle_pub_.publish(handle);
  }

  void publishClouds(const ros::Time& stamp) {
    if (cloud_pub_.getNumSubscribers() == 0 && slice_pub_.getNumSubscribers() == 0) return;
    std::vector<Eigen::Vector4f> occupied, slice;
    {
      // On the thread that integrates depth: each cloud only when heard, the slice from its own layer, and
      // coordinates only for the voxels sent (a pass over all of them took the powerplant's 29M voxels
      // through a division each).
      std::shared_lock<std::shared_mutex> lock(shared_->mutex);
      const map::VoxelMap& m = *shared_->map;
      const auto& geo = m.geometry();
      if (cloud_pub_.getNumSubscribers() > 0)
        for (std::size_t l = 0; l < geo.size(); ++l)
          if (m.occupancy().stateAt(l) == map::VoxelState::kOccupied) {
            const common::Vec3 c = geo.indexToCoord(geo.unlinear(l));
            occupied.emplace_back(c.x(), c.y(), c.z(), c.z());
          }
      const int kz = geo.clampedIndex(common::Vec3(0, 0, slice_height_)).z();  // the nearest layer
      if (slice_pub_.getNumSubscribers() > 0)
        for (int y = 0; y < geo.dims().y(); ++y)
          for (int x = 0; x < geo.dims().x(); ++x) {
            const common::Index3 idx(x, y, kz);
            if (m.occupancy().stateAt(geo.linear(idx)) == map::VoxelState::kUnknown) continue;
            const common::Vec3 c = geo.indexToCoord(idx);
            slice.emplace_back(c.x(), c.y(), c.z(), static_cast<float>(m.esdf().distance(idx)));
          }
    }
    cloud_pub_.publish(toCloud(occupied, "height", stamp));
    slice_pub_.publish(toCloud(slice, "distance", stamp));
  }

  sensor_msgs::PointCloud2 toCloud(const std::vector<Eigen::Vector4f>& pts, const std::string& field,
                                   const ros::Time& stamp) const {
    sensor_msgs::PointCloud2 cloud;
    cloud.header.stamp = stamp;
    cloud.header.frame_id = world_frame_;
    sensor_msgs::PointCloud2Modifier mod(cloud);
    mod.setPointCloud2Fields(4, "x", 1, sensor_msgs::PointField::FLOAT32, "y", 1, sensor_msgs::PointField::FLOAT32,
                             "z", 1, sensor_msgs::PointField::FLOAT32, field.c_str(), 1,
                             sensor_msgs::PointField::FLOAT32);
    mod.resize(pts.size());
    sensor_msgs::PointCloud2Iterator<float> it(cloud, "x");
    for (const auto& p : pts) {
      it[0] = p[0];
      it[1] = p[1];
      it[2] = p[2];
      it[3] = p[3];
      ++it;
    }
    return cloud;
  }

  bool onSave(SaveMap::Request& req, SaveMap::Response& res) {
    if (req.path.empty()) {
      res.success = false;
      res.message = "path is empty";
      return true;
    }
    std::lock_guard<std::mutex> one_at_a_time(save_mutex_);  // two at once would share a .part file
    map::OccupancySnapshot snapshot;
    {
      std::shared_lock<std::shared_mutex> lock(shared_->mutex);  // a copy, a byte a voxel: mapping waits a moment
      snapshot = shared_->map->occupancy().snapshot();
    }
    const common::Status st = map::saveBt(snapshot, req.path);
    res.success = st.ok();
    res.message = st.ok() ? "wrote " + req.path : st.message();
    NODELET_INFO_STREAM(getName() << ": save_map: " << res.message);
    return true;
  }

  // Counts bad input per reason and logs at most once per warn_period.
  void skip(const std::string& reason, const std::string& what) {
    std::lock_guard<std::mutex> lock(input_mutex_);
    const std::size_t n = ++skipped_[reason];
    const ros::WallTime now = ros::WallTime::now();
    ros::WallTime& last = last_warn_[reason];
    if (last.isZero() || (now - last).toSec() >= warn_period_) {
      last = now;
      NODELET_WARN_STREAM(getName() << ": frame skipped (" << reason << "): " << what << " [" << n
                                    << " skipped for this reason so far]");
    }
  }

  std::shared_ptr<ros_map::SharedMap> shared_;
  std::string sync_mode_, world_frame_;
  double pose_tolerance_ = 0.02, max_pose_jump_ = 1.0, cloud_period_ = 1.0, slice_height_ = 1.0, warn_period_ = 2.0;
  int tf_queue_ = 10;
  double max_tf_gap_ = 0.5, max_rotation_jump_ = 0.5;
  std::mutex tf_samples_mutex_;
  ros_tf::SampleLog tf_samples_;
  ros::Subscriber tf_samples_sub_;
  static constexpr int kSyncQueue = 20;  // frames the synchroniser keeps waiting for their pair
  int unpaired_ = 0;                     // depth images since the last pair
  std::mutex input_mutex_;
  std::mutex save_mutex_;  ///< save_map calls, one at a time
  std::optional<map::DepthIntrinsics> intrinsics_;
  std::string intrinsics_frame_;  // frame_id of the camera_info intrinsics_ came from
  std::map<std::string, std::size_t> skipped_;
  std::map<std::string, ros::WallTime> last_warn_;
  std::optional<Eigen::Isometry3d> reference_;  ///< camera pose of the last integrated frame (or the last jump's)
  ros::Time last_cloud_;
  ros::Publisher compute_pub_;
  ros::Publisher update_pub_, handle_pub_, cloud_pub_, slice_pub_;
  ros::ServiceServer save_srv_;
  ros::Subscriber info_sub_;
  message_filters::Subscriber<sensor_msgs::Image> depth_sub_;
  message_filters::Subscriber<geometry_msgs::PoseStamped> pose_sub_;
  std::unique_ptr<message_filters::Synchronizer<ExactPolicy>> exact_sync_;
  std::unique_ptr<message_filters::Synchronizer<ApproxPolicy>> approx_sync_;
  std::unique_ptr<tf2_ros::Buffer> tf_buffer_;
  std::unique_ptr<tf2_ros::TransformListener> tf_listener_;
  std::unique_ptr<tf2_ros::MessageFilter<sensor_msgs::Image>> tf_filter_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::EsdfMapper, nodelet::Nodelet)
