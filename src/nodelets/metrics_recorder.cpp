// MetricsRecorder: measures a run of the chain. Coverage of the scene's observable set and
// collisions against ground truth (simulation: private `scene` and `seed`; with `scene` empty,
// onboard, both are unknown), explored volume and flight distance, the per-block compute
// times the nodelets report, and the layer manager's state. Logs a progress line, publishes a
// status text for rviz, and when exploration finishes writes summary.json, metrics.csv and
// coverage.png to `metrics/output_dir` (if set) and, with `metrics/shutdown_on_finish`, ends
// the process so a headless run returns. In: map_handle, odom, status, compute_time.
// Out: status_text (visualization_msgs/Marker), coverage (std_msgs/Float64), flown_path
// (nav_msgs/Path, one pose per sample, thinned to every other one whenever it reaches 4096).
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>
#include <ros/ros.h>
#include <std_msgs/Float64.h>
#include <visualization_msgs/Marker.h>

#include <unistd.h>

#include <filesystem>
#include <iomanip>
#include <mutex>
#include <optional>
#include <sstream>

#include "go_feap/ComputeTime.h"
#include "go_feap/ExplorationStatus.h"
#include "go_feap/metrics/metrics.h"
#include "go_feap/ros/conversions.h"
#include "go_feap/ros/log_throttle.h"
#include "go_feap/ros/message_checks.h"
#include "go_feap/ros/guarded.h"
#include "go_feap/ros/params.h"
#include "go_feap/ros/shared_map.h"
#include "go_feap/world/scene.h"

namespace go_feap {

class MetricsRecorder : public nodelet::Nodelet {
  // Declared first: it outlives whatever callback the other members' destruction still lets run.
  ros_log::Throttle log_throttle_;  ///< this nodelet's throttled messages
  ros_map::EmptyHandles empty_handles_{10.0};  ///< map_handles without a map, said only when they last
 public:
  // A run that began and did not finish (Ctrl-C, a launch that ended, a replayed bag's end, the hang
  // guard) still writes its figures so far, with finish_reason "stopped": before, output_dir stayed empty.
  ~MetricsRecorder() override {
    // No callback runs once these are shut down (a running one is waited for), so none races the write.
    timer_.stop();
    for (ros::Subscriber* sub : {&handle_sub_, &odom_sub_, &status_sub_, &compute_sub_}) sub->shutdown();
    std::lock_guard<std::mutex> lock(mutex_);
    if (started_ && !finished_)
      finishRun(kStopped, status_ ? status_->elapsed : 0.0, status_ ? static_cast<int>(status_->blacklisted_frontiers) : 0);
  }

 private:
  static constexpr const char* kStopped = "stopped";

  void onInit() override {
    ros::NodeHandle& nh = getNodeHandle();
    ros::NodeHandle& pnh = getPrivateNodeHandle();
    ros_params::ParamReader p(pnh);
    std::string scene_spec;
    p.get("scene", scene_spec).get("metrics/sample_rate", sample_rate_);
    p.get("metrics/collision_distance", collision_distance_).get("metrics/output_dir", output_dir_);
    p.get("metrics/max_odom_step", max_odom_step_);
    p.get("metrics/planner", planner_).get("metrics/shutdown_on_finish", shutdown_on_finish_);
    p.get("metrics/progress_period", progress_period_).getFrame("world_frame", world_frame_);
    ros_params::requireOrThrow(p.ok(), getName(), p.error());
    ros_params::requireOrThrow(sample_rate_ > 0.0 && sample_rate_ <= 1000.0, getName(),
                               "parameter '" + p.fullName("metrics/sample_rate") + "' must be in (0, 1000] Hz");
    ros_params::requireOrThrow(metrics::CollisionMonitor::validDistance(collision_distance_), getName(),
                               "parameter '" + p.fullName("metrics/collision_distance") + "' must be in (0, 0.5] m");
    ros_params::requireOrThrow(std::isfinite(max_odom_step_) && max_odom_step_ > 0.0, getName(),
                               "parameter '" + p.fullName("metrics/max_odom_step") + "' must be finite and > 0");
    ros_params::requireOrThrow(std::isfinite(progress_period_) && progress_period_ > 0.0, getName(),
                               "parameter '" + p.fullName("metrics/progress_period") + "' must be > 0");
    ros_params::requireOrThrow(!planner_.empty(), getName(),
                               "parameter '" + p.fullName("metrics/planner") + "' must name the planner (summary.json's)");
    // The results folder made (or found) writable now, not when the run is over: a folder that cannot be
    // made would lose the whole run's figures at its end, with only an error logged.
    if (!output_dir_.empty()) {
      std::error_code ec;
      std::filesystem::create_directories(output_dir_, ec);
      ros_params::requireOrThrow(!ec && std::filesystem::is_directory(output_dir_, ec) && ::access(output_dir_.c_str(), W_OK) == 0,
                                 getName(), "parameter '" + p.fullName("metrics/output_dir") + "': '" + output_dir_ +
                                                "' cannot be made a writable folder" + (ec ? " (" + ec.message() + ")" : ""));
    }
    metrics::Summary& s = recorder_.summary();
    s.planner = planner_;
    s.coverage = -1.0;
    if (!scene_spec.empty()) {
      scene_ = std::make_unique<world::Scene>(ros_params::loadScene(pnh, getName()));
      const common::Status start = metrics::checkStartClearance(*scene_, collision_distance_);
      ros_params::requireOrThrow(start.ok(), getName(), start.message());
      s.scene = scene_->name;
      s.seed = scene_->seed;
      s.min_obstacle_distance_m = metrics::CollisionMonitor::kHorizon;
      collisions_ = std::make_unique<metrics::CollisionMonitor>(*scene_, collision_distance_);
    } else {
      s.scene = "onboard";
      s.ground_truth = false;
    }
    text_pub_ = nh.advertise<visualization_msgs::Marker>("status_text", 2);
    coverage_pub_ = nh.advertise<std_msgs::Float64>("coverage", 2);
    path_pub_ = nh.advertise<nav_msgs::Path>("flown_path", 1);
    path_.header.frame_id = world_frame_;
    handle_sub_ = ros_guard::subscribe(nh, getName(), "map_handle", 1, &MetricsRecorder::onHandle, this);
    odom_sub_ = ros_guard::subscribe(nh, getName(), "odom", 20, &MetricsRecorder::onOdom, this);
    status_sub_ = ros_guard::subscribe(nh, getName(), "status", 5, &MetricsRecorder::onStatus, this);
    compute_sub_ = ros_guard::subscribe(nh, getName(), "compute_time", 50, &MetricsRecorder::onCompute, this);
    timer_ = ros_guard::timer(nh, getName(), ros::Duration(1.0 / sample_rate_), &MetricsRecorder::onTimer, this);
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
    if (scene_) coverage_ = std::make_unique<metrics::CoverageTracker>(*scene_, shared_->map->geometry());
  }

  void onOdom(const nav_msgs::Odometry::ConstPtr& msg) {
    const std::string bad = ros_conv::odometryPoseProblem(*msg, world_frame_);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": odometry refused: " << bad);
      return;
    }
    const auto& q = msg->pose.pose.position;
    const common::Vec3 p(q.x, q.y, q.z);
    std::lock_guard<std::mutex> lock(mutex_);
    position_ = p;
    if (!started() || finished_) return;
    if (const std::optional<double> step = ros_conv::flownStep(last_position_, p, max_odom_step_))
      distance_ += *step;
    else
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": " << ros_conv::odometryJump(*last_position_, p));
    last_position_ = p;
    if (!collisions_) return;
    if (collisions_->update(p))
      NODELET_WARN_STREAM(getName() << ": collision at " << p.transpose() << " (" << collisions_->lastClearance()
                                    << " m from a ground-truth obstacle)");
    metrics::Summary& s = recorder_.summary();
    s.collisions = collisions_->collisions();
    s.min_obstacle_distance_m = collisions_->closestApproach();
  }

  void onCompute(const ComputeTime::ConstPtr& msg) {
    // The chain's blocks only: another name (from a tool, or bytes that are not text) would be a key of
    // summary.json of its own, and "total" would clash with the sum.
    if (!metrics::isComputeBlock(msg->block) || !std::isfinite(msg->ms) || msg->ms < 0.0) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": compute_time refused: block '" << msg->block << "' ("
                                                  << msg->block.size() << " bytes), " << msg->ms
                                                  << " ms; blocks are mapping, frontier, global, local and trajectory, "
                                                     "times finite and >= 0");
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (started() && !finished_) recorder_.addTime(msg->block, msg->ms);
  }

  void onStatus(const ExplorationStatus::ConstPtr& msg) {
    const std::string bad = ros_check::explorationStatusProblem(*msg);
    if (!bad.empty()) {
      GO_FEAP_NODELET_THROTTLE(WARN, 2.0, getName() << ": status refused: " << bad);
      return;
    }
    std::lock_guard<std::mutex> lock(mutex_);
    status_ = msg;
    if (msg->state == ExplorationStatus::FINISHED && !finished_ && started_) {
      finishRun(msg->finish_reason, msg->elapsed, static_cast<int>(msg->blacklisted_frontiers));
      if (shutdown_on_finish_) ros::requestShutdown();
    }
    // Only whether the run has begun: its time is the layer manager's elapsed. (This was the clock minus
    // elapsed as a ros::Time, which threw, ending the whole nodelet manager, for an elapsed beyond the
    // clock: a status from a tool or another run early in a simulation.)
    if (msg->state == ExplorationStatus::WAIT_TRIGGER) heard_waiting_ = true;
    if (msg->state != ExplorationStatus::WAIT_TRIGGER && !started_) {
      if (msg->state == ExplorationStatus::FINISHED) {
        if (heard_waiting_) {  // stopped before the trigger, with this recorder there: a run of nothing, said so
          started_ = true;
          wall_start_ = ros::WallTime::now();
          finishRun(msg->finish_reason, msg->elapsed, static_cast<int>(msg->blacklisted_frontiers));
        } else if (!said_missed_) {
          // A recorder that first hears the exploration finished records nothing: started there, its next status
          // wrote a summary of a run it never saw (no flight, no samples, the run's whole time).
          said_missed_ = true;
          NODELET_WARN_STREAM(getName() << ": the exploration had finished (" << msg->finish_reason
                                        << ") before this recorder heard it: nothing is recorded");
        }
        // The run is over all the same: a launch waiting for the recorder to end it is not left hanging.
        if (shutdown_on_finish_) ros::requestShutdown();
        return;
      }
      started_ = true;
      wall_start_ = ros::WallTime::now();  // the run's wall time counts from the trigger, as the bench's
      // Joined late (loaded after the trigger, or its status subscription slow to connect): the figures count
      // from here, which the summary alone would not tell.
      if (msg->elapsed > 1.0 / sample_rate_ + 1.0)
        NODELET_WARN_STREAM(getName() << ": joined the exploration " << msg->elapsed
                                      << " s after its trigger: flight distance, samples and compute times count from "
                                         "here, not from the trigger");
    }
  }

  bool started() const { return started_; }

  double currentCoverage() const {
    if (!coverage_ || !shared_) return -1.0;
    std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
    return coverage_->coverage(shared_->map->occupancy());
  }

  void addSample() {
    metrics::Sample s;
    s.t = status_ ? status_->elapsed : 0.0;
    s.coverage = currentCoverage();
    if (shared_) {
      std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
      const double res = shared_->map->geometry().resolution();
      s.explored_m3 = static_cast<double>(shared_->map->occupancy().knownCount()) * res * res * res;
    }
    s.distance = distance_;
    s.layer = status_ ? static_cast<int>(status_->layer) : 0;
    s.frontiers = status_ ? static_cast<int>(status_->frontier_count) : 0;
    if (position_) s.position = *position_;
    recorder_.addSample(s);
    last_sample_ = s;
  }

  void onTimer(const ros::TimerEvent&) {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!started() || finished_) {
      publishText();
      return;
    }
    addSample();
    if (position_) {
      geometry_msgs::PoseStamped pose;
      pose.header.stamp = ros::Time::now();
      pose.header.frame_id = world_frame_;
      pose.pose.position.x = position_->x(), pose.pose.position.y = position_->y(), pose.pose.position.z = position_->z();
      pose.pose.orientation.w = 1.0;
      // Sent whole at every sample, to a subscriber: at most kMaxPathPoses poses, evenly over the run, ending
      // at the latest (copied into the message only when it is sent).
      trail_.add(pose);
      if (path_pub_.getNumSubscribers() > 0) {
        path_.poses = trail_.items();
        path_.header.stamp = pose.header.stamp;
        path_pub_.publish(path_);
      }
    }
    std_msgs::Float64 c;
    c.data = last_sample_.coverage;
    coverage_pub_.publish(c);
    publishText();
    if (last_sample_.t >= next_progress_) {
      next_progress_ = last_sample_.t + progress_period_;
      NODELET_INFO_STREAM(getName() << ": [progress] " << progressLine());
    }
  }

  std::string progressLine() const {
    std::ostringstream line;
    line << std::fixed << std::setprecision(1);
    line << (status_ ? status_->state_name : std::string("WAIT_TRIGGER"));
    if (status_) line << " band " << status_->layer;
    line << " coverage ";
    if (last_sample_.coverage >= 0.0)
      line << 100.0 * last_sample_.coverage << " %";
    else
      line << "n/a";
    line << " t " << last_sample_.t << " s distance " << distance_ << " m";
    if (scene_) line << " collisions " << recorder_.summary().collisions;
    return line.str();
  }

  void publishText() {
    if (!position_) return;
    visualization_msgs::Marker text;
    text.header.stamp = ros::Time::now();
    text.header.frame_id = world_frame_;
    text.ns = "status";
    text.type = visualization_msgs::Marker::TEXT_VIEW_FACING;
    text.pose.position.x = position_->x();
    text.pose.position.y = position_->y();
    text.pose.position.z = position_->z() + 1.0;
    text.pose.orientation.w = 1.0;
    text.scale.z = 0.35;
    text.color.r = text.color.g = text.color.b = 1.0;
    text.color.a = 1.0;
    text.text = progressLine();
    text_pub_.publish(text);
  }

  /// Takes the last sample, fills the summary and writes the results (caller holds mutex_).
  void finishRun(const std::string& reason, double elapsed, int blacklisted) {
    finished_ = true;
    addSample();
    metrics::Summary& s = recorder_.summary();
    s.finish_reason = reason;
    s.blacklisted_frontiers = blacklisted;
    s.exploration_time_s = elapsed;
    s.flight_distance_m = distance_;
    s.coverage = last_sample_.coverage;
    s.wall_time_s = (ros::WallTime::now() - wall_start_).toSec();
    if (shared_) {  // under the map's lock: the mapper grows the map's vectors while it integrates
      std::shared_lock<std::shared_mutex> map_lock(shared_->mutex);
      s.extra["map_memory_mb"] = static_cast<double>(shared_->map->memoryBytes()) / (1024.0 * 1024.0);
    }
    NODELET_INFO_STREAM(getName() << ": finished (" << s.finish_reason << "): " << progressLine());
    if (!output_dir_.empty()) {
      const common::Status st = recorder_.writeAll(output_dir_);
      if (st.ok())
        NODELET_INFO_STREAM(getName() << ": results written to " << output_dir_);
      else
        NODELET_ERROR_STREAM(getName() << ": " << st.message());
    }
    NODELET_INFO_STREAM(getName() << ": [summary] " << metrics::summaryJson(s));
  }

  double sample_rate_ = 2.0, collision_distance_ = 0.1, progress_period_ = 5.0, max_odom_step_ = 1.0;
  std::string output_dir_, planner_, world_frame_;
  bool shutdown_on_finish_ = false;
  std::mutex mutex_;
  std::unique_ptr<world::Scene> scene_;
  std::shared_ptr<ros_map::SharedMap> shared_;
  std::unique_ptr<metrics::CoverageTracker> coverage_;
  metrics::Recorder recorder_;
  metrics::Sample last_sample_;
  ExplorationStatus::ConstPtr status_;
  bool started_ = false;  ///< a status past WAIT_TRIGGER has come
  std::optional<common::Vec3> position_, last_position_;
  double distance_ = 0.0, next_progress_ = 0.0;
  bool heard_waiting_ = false;  ///< a WAIT_TRIGGER status came: the recorder was there before the run
  bool said_missed_ = false;    ///< the "finished before this recorder heard it" warning was given
  std::unique_ptr<metrics::CollisionMonitor> collisions_;
  bool finished_ = false;
  ros::WallTime wall_start_ = ros::WallTime::now();  ///< reset when the run starts
  ros::Publisher text_pub_, coverage_pub_, path_pub_;
  nav_msgs::Path path_;
  static constexpr std::size_t kMaxPathPoses = 4096;  // flown_path for rviz
  metrics::BoundedTrail<geometry_msgs::PoseStamped> trail_{kMaxPathPoses};
  ros::Subscriber handle_sub_, odom_sub_, status_sub_, compute_sub_;
  ros::Timer timer_;
};

}  // namespace go_feap

PLUGINLIB_EXPORT_CLASS(go_feap::MetricsRecorder, nodelet::Nodelet)
