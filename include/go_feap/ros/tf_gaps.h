// Where tf2 interpolates a pose across a gap in the samples of a moving link. tf2 interpolates between the
// two samples round a stamp however far apart they are: after an odometry gap (a VIO that lost track and
// came back), a depth frame stamped inside the gap gets a pose on the straight line between the last
// sample before and the first after, and would be mapped there. The mapper in sync_mode tf keeps the
// samples of every transform it hears on /tf and asks, for each link of a frame's chain, how far apart the
// samples round the frame's stamp are, and whether the link moved between them (a link that holds still,
// as a fixed mount sent on /tf at 1 Hz, interpolates exactly however slowly it comes).
#pragma once

#include <geometry_msgs/Transform.h>
#include <ros/time.h>

#include <Eigen/Geometry>
#include <deque>
#include <map>
#include <optional>
#include <string>

namespace go_feap::ros_tf {

/// The samples of each link, by child frame (tf2's names, no leading '/'), kept for `keep` seconds behind
/// the newest of the link.
class SampleLog {
 public:
  explicit SampleLog(double keep_s = 10.0) : keep_s_(keep_s) {}

  /// A sample of the link to `child` at `stamp`. A stamp older than the link's newest by more than
  /// keep_s (a clock that went back: a bag played again) starts the link's log afresh; a slightly older
  /// one (out of order) is put in its place.
  void add(const std::string& child, const ros::Time& stamp, const geometry_msgs::Transform& pose);

  /// The samples round `stamp` of the link to `child`: the last at or before it, and the first at or
  /// after it when one is logged (none yet: the sample that let tf2 answer may be on its way here).
  /// `moved`: the two differ in pose (1 mm or 1 mrad). None when the link is unknown here or the stamp
  /// is before every sample kept.
  struct Bracket {
    ros::Time before;
    std::optional<ros::Time> after;
    bool moved = false;
  };
  std::optional<Bracket> around(const std::string& child, const ros::Time& stamp) const;

  void clear() { links_.clear(); }

 private:
  struct Sample {
    ros::Time stamp;
    Eigen::Vector3d t;
    Eigen::Quaterniond q;
  };
  static std::deque<Sample>::const_iterator firstFrom(const std::deque<Sample>& samples, const ros::Time& stamp);
  double keep_s_;
  std::map<std::string, std::deque<Sample>> links_;
};

}  // namespace go_feap::ros_tf
