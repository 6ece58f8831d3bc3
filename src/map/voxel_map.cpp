#include "go_feap/map/voxel_map.h"

namespace go_feap::map {

common::Status MapConfig::validate() const {
  if (auto st = occupancy.validate(); !st) return st;
  // The ESDF's limits depend on the voxel size only, not on the grid's extent.
  if (auto st = esdf.validate(common::GridGeometry(Vec3::Zero(), occupancy.resolution, Index3::Ones())); !st)
    return st;
  return common::Status::Ok();
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
