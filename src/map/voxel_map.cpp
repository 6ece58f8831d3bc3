#include "go_feap/map/voxel_map.h"

#include <cstdint>
#include <iomanip>
#include <limits>
#include <sstream>

namespace go_feap::map {

common::Status MapConfig::validate() const {
  if (auto st = occupancy.validate(); !st) return st;
  // The ESDF's limits depend on the voxel size only, not on the grid's extent.
  if (auto st = esdf.validate(common::GridGeometry(Vec3::Zero(), occupancy.resolution, Index3::Ones())); !st)
    return st;
  return common::Status::Ok();
}

common::Status MapConfig::validate(const Aabb& box) const {
  if (auto st = validate(); !st) return st;
  if (!box.min.allFinite() || !box.max.allFinite() || !box.valid())
    return common::Status::Error("exploration_box: min and max must be finite, with min < max on every axis");
  const double voxels = common::GridGeometry::coveringCount(box.expanded(occupancy.margin), occupancy.resolution);
  if (voxels > static_cast<double>(std::numeric_limits<std::uint32_t>::max())) {
    std::ostringstream why;
    why << std::setprecision(3) << "exploration_box with occupancy/resolution " << occupancy.resolution
        << " m and margin " << occupancy.margin << " m needs about " << voxels
        << " voxels, more than the map's 2^32 - 1";
    return common::Status::Error(why.str());
  }
  return common::Status::Ok();
}

double MapConfig::estimatedBytes(const Aabb& box) const {
  return kBytesPerVoxel * common::GridGeometry::coveringCount(box.expanded(occupancy.margin), occupancy.resolution);
}

common::Status MapConfig::checkFits(const Aabb& box, double memory_bytes) const {
  const double bytes = estimatedBytes(box);
  if (bytes <= memory_bytes) return common::Status::Ok();
  constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
  std::ostringstream why;
  why << std::setprecision(3) << "exploration_box with occupancy/resolution " << occupancy.resolution
      << " m and margin " << occupancy.margin << " m needs a map of about " << bytes / kGiB
      << " GiB, more than this machine's " << memory_bytes / kGiB
      << " GiB of memory (a coarser resolution or a smaller box)";
  return common::Status::Error(why.str());
}

VoxelMap::VoxelMap(const MapConfig& config, const Aabb& box)
    : config_(config), occupancy_(config.occupancy, box), esdf_(occupancy_.geometry(), config.esdf) {}

common::Result<MapUpdateInfo> VoxelMap::integrate(const cv::Mat& depth, const DepthIntrinsics& K,
                                                  const Eigen::Isometry3d& T_W_C) {
  auto frame = occupancy_.integrate(depth, K, T_W_C);
  if (!frame) return frame.status();
  MapUpdateInfo info;
  info.frame = std::move(frame).value();
  if (!info.frame.became_occupied.empty() || !info.frame.stopped_occupied.empty())
    info.esdf_changed = esdf_.update(info.frame.became_occupied, info.frame.stopped_occupied);
  if (info.frame.any_change) {
    const auto& geo = occupancy_.geometry();
    const double h = 0.5 * geo.resolution();
    info.changed_box = {geo.indexToCoord(info.frame.changed_min) - Vec3::Constant(h),
                        geo.indexToCoord(info.frame.changed_max) + Vec3::Constant(h)};
  }
  return info;
}

}  // namespace go_feap::map
