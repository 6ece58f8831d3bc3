#include "go_feap/ros/tf_gaps.h"

#include <algorithm>

namespace go_feap::ros_tf {

namespace {

std::string keyOf(const std::string& child) {
  return !child.empty() && child.front() == '/' ? child.substr(1) : child;  // tf2 strips it too
}

}  // namespace

// The first of `samples` (in stamp order) at or after `stamp`.
std::deque<SampleLog::Sample>::const_iterator SampleLog::firstFrom(const std::deque<Sample>& samples,
                                                                  const ros::Time& stamp) {
  return std::lower_bound(samples.begin(), samples.end(), stamp,
                          [](const Sample& s, const ros::Time& t) { return s.stamp < t; });
}

void SampleLog::add(const std::string& child, const ros::Time& stamp, const geometry_msgs::Transform& pose) {
  if (stamp.isZero()) return;
  std::deque<Sample>& samples = links_[keyOf(child)];
  // Stamps compared as seconds: ros::Time subtraction throws beyond 2^31 s.
  if (!samples.empty() && stamp.toSec() < samples.back().stamp.toSec() - keep_s_) samples.clear();
  const auto at = firstFrom(samples, stamp);
  if (at != samples.end() && at->stamp == stamp) return;  // repeated
  const Eigen::Quaterniond q(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z);
  samples.insert(at, Sample{stamp, Eigen::Vector3d(pose.translation.x, pose.translation.y, pose.translation.z), q});
  while (samples.front().stamp.toSec() < samples.back().stamp.toSec() - keep_s_) samples.pop_front();
}

std::optional<SampleLog::Bracket> SampleLog::around(const std::string& child, const ros::Time& stamp) const {
  const auto link = links_.find(keyOf(child));
  if (link == links_.end() || link->second.empty()) return std::nullopt;
  const std::deque<Sample>& samples = link->second;
  const auto after = firstFrom(samples, stamp);
  if (after != samples.end() && after->stamp == stamp) return Bracket{stamp, stamp, false};
  if (after == samples.begin()) return std::nullopt;
  const Sample& b = *std::prev(after);
  if (after == samples.end()) return Bracket{b.stamp, std::nullopt, false};
  const bool moved = (after->t - b.t).norm() > 1e-3 || b.q.angularDistance(after->q) > 1e-3;
  return Bracket{b.stamp, after->stamp, moved};
}

}  // namespace go_feap::ros_tf
