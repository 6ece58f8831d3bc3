#include "go_feap/ros/tf_gaps.h"

#include <algorithm>

namespace go_feap::ros_tf {

void SampleLog::add(const std::string& child, const ros::Time& stamp) {
  if (stamp.isZero()) return;
  std::string key = child;
  if (!key.empty() && key.front() == '/') key.erase(0, 1);  // tf2 strips it too
  std::deque<ros::Time>& stamps = links_[key];
  // Stamps compared as seconds: ros::Time subtraction throws beyond 2^31 s.
  if (!stamps.empty() && stamp.toSec() < stamps.back().toSec() - keep_s_) stamps.clear();
  const auto at = std::lower_bound(stamps.begin(), stamps.end(), stamp);
  if (at != stamps.end() && *at == stamp) return;  // repeated
  stamps.insert(at, stamp);
  while (stamps.front().toSec() < stamps.back().toSec() - keep_s_) stamps.pop_front();
}

std::optional<SampleLog::Bracket> SampleLog::around(const std::string& child, const ros::Time& stamp) const {
  std::string key = child;
  if (!key.empty() && key.front() == '/') key.erase(0, 1);
  const auto link = links_.find(key);
  if (link == links_.end() || link->second.empty()) return std::nullopt;
  const std::deque<ros::Time>& stamps = link->second;
  const auto after = std::lower_bound(stamps.begin(), stamps.end(), stamp);
  if (after == stamps.end()) return std::nullopt;
  if (*after == stamp) return Bracket{stamp, stamp};
  if (after == stamps.begin()) return std::nullopt;
  return Bracket{*std::prev(after), *after};
}

}  // namespace go_feap::ros_tf
