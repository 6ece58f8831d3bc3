// Where tf2 interpolates a pose across a gap in the samples of a moving link. tf2 interpolates between the
// two samples round a stamp however far apart they are: after an odometry gap (a VIO that lost track and
// came back), a depth frame stamped inside the gap gets a pose on the straight line between the last
// sample before and the first after, and would be mapped there. The mapper in sync_mode tf keeps the
// stamps of every dynamic transform it hears (/tf) and asks, for each moving link of a frame's chain, how
// far apart the samples round the frame's stamp are.
#pragma once

#include <ros/time.h>

#include <deque>
#include <map>
#include <optional>
#include <string>

namespace go_feap::ros_tf {

/// The stamps of the samples of each moving link, by child frame (tf2's names, no leading '/'), kept for
/// `keep` seconds behind the newest of the link.
class SampleLog {
 public:
  explicit SampleLog(double keep_s = 10.0) : keep_s_(keep_s) {}

  /// A sample of the link to `child` at `stamp`. A stamp older than the link's newest by more than
  /// keep_s (a clock that went back: a bag played again) starts the link's log afresh; a slightly older
  /// one (out of order) is put in its place.
  void add(const std::string& child, const ros::Time& stamp);

  /// The samples round `stamp` of the link to `child`, as {before, after} (equal for a sample at the
  /// stamp); none when the link is unknown here (static, or never heard) or the stamp is outside the
  /// stamps kept.
  struct Bracket {
    ros::Time before, after;
    double span() const { return after.toSec() - before.toSec(); }
  };
  std::optional<Bracket> around(const std::string& child, const ros::Time& stamp) const;

  void clear() { links_.clear(); }

 private:
  double keep_s_;
  std::map<std::string, std::deque<ros::Time>> links_;
};

}  // namespace go_feap::ros_tf
