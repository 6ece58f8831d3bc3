// Sharing the mapper's map with the planning nodelets of the same nodelet manager.
//
// The EsdfMapper owns a SharedMap and publishes a MapHandle (a shared pointer to it) on
// `map_handle` with every map update. Nodelets in the same manager receive the pointer
// itself through roscpp's intra-process delivery (no copy, no serialisation); they keep
// it and read the map under a shared lock (`std::shared_lock lock(shared->mutex)`), while
// the mapper integrates each frame under the exclusive lock. A subscriber in another
// process receives an empty handle (nothing crosses the wire) and must say so.
#pragma once

#include <ros/message_traits.h>
#include <ros/serialization.h>

#include <memory>
#include <optional>
#include <shared_mutex>
#include <string>

#include "go_feap/map/voxel_map.h"

namespace go_feap::ros_map {

struct SharedMap {
  explicit SharedMap(std::unique_ptr<map::VoxelMap> m) : map(std::move(m)) {}
  mutable std::shared_mutex mutex;
  std::unique_ptr<map::VoxelMap> map;
  std::uint64_t sequence = 0;  ///< frames integrated (under the lock)
  std::vector<std::size_t> last_changed;  ///< voxels whose state changed in frame `sequence`
};

struct MapHandle {
  std::shared_ptr<SharedMap> shared;
};

/// The map a received handle points to, or an error when it carries none: it came from another process,
/// where no pointer can travel, or it is the latched copy a nodelet subscribing after the mapper's start
/// gets (roscpp keeps a latched message serialised when no subscriber in the process took it; the mapper
/// sends its handle again with every frame). A reader checks the map's ESDF against its own
/// clearances next (ros_params::stopManager when they conflict).
inline common::Result<std::shared_ptr<SharedMap>> acceptHandle(const MapHandle& handle) {
  using R = common::Result<std::shared_ptr<SharedMap>>;
  if (!handle.shared) return R::Error("map_handle carries no map: a copy latched before this nodelet subscribed (the mapper sends "
                                         "its map with its next frame), or a mapper outside this nodelet's manager (run "
                                         "it in the EsdfMapper's manager)");
  return handle.shared;
}

/// When to say that the handles coming carry no map. At start-up that is normal (a copy latched before the
/// nodelet subscribed; the mapper's next frame brings the map), so it is said only once handles without a
/// map have come for `patience` s, then every `patience` s: a mapper outside this nodelet's manager.
class EmptyHandles {
 public:
  explicit EmptyHandles(double patience) : patience_(patience) {}
  /// An empty handle came at time `now` (s): true when that is to be said. A clock that went back (a
  /// simulation restarted) starts the wait again.
  bool due(double now) {
    if (!first_ || now < *first_ || (said_ && now < *said_)) {
      first_ = now;
      said_.reset();
      return false;
    }
    if (now - *first_ < patience_ || (said_ && now - *said_ < patience_)) return false;
    said_ = now;
    return true;
  }
  double patience() const { return patience_; }

 private:
  double patience_;
  std::optional<double> first_, said_;
};

/// What to log when a handle to another map than the one `held` comes (the mapper was reloaded into the
/// manager): a reader keeps the map it planned on, whose state it holds; "" for the same map (the mapper
/// sends its handle with every update).
inline std::string otherMapProblem(const MapHandle& handle, const std::shared_ptr<SharedMap>& held) {
  if (!handle.shared || handle.shared == held) return std::string();
  return "map_handle points to another map (the mapper was restarted?): this nodelet keeps planning on the "
         "first one; restart it too";
}

}  // namespace go_feap::ros_map

namespace ros {
namespace message_traits {
template <>
struct MD5Sum<go_feap::ros_map::MapHandle> {
  static const char* value() { return "6f0e1d2c3b4a59687766554433221100"; }
  static const char* value(const go_feap::ros_map::MapHandle&) { return value(); }
};
template <>
struct DataType<go_feap::ros_map::MapHandle> {
  static const char* value() { return "go_feap/MapHandle"; }
  static const char* value(const go_feap::ros_map::MapHandle&) { return value(); }
};
template <>
struct Definition<go_feap::ros_map::MapHandle> {
  static const char* value() { return "# In-process handle to the mapper's map; carries nothing between processes.\n"; }
  static const char* value(const go_feap::ros_map::MapHandle&) { return value(); }
};
}  // namespace message_traits

namespace serialization {
template <>
struct Serializer<go_feap::ros_map::MapHandle> {
  template <typename Stream, typename T>
  inline static void allInOne(Stream&, T) {}
  ROS_DECLARE_ALLINONE_SERIALIZER
};
}  // namespace serialization
}  // namespace ros
