// OctoMap .bt export and import of the occupancy map.
#include <octomap/OcTree.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "go_feap/map/voxel_map.h"

namespace go_feap::map {

common::Status VoxelMap::saveBt(const std::string& path) const { return map::saveBt(occupancy_.snapshot(), path); }

common::Status saveBt(const OccupancySnapshot& map, const std::string& path) {
  const auto& geo = map.geometry;
  octomap::OcTree tree(geo.resolution());
  const float occ = tree.getClampingThresMaxLog(), fre = tree.getClampingThresMinLog();
  for (int z = 0; z < geo.dims().z(); ++z) {
    for (int y = 0; y < geo.dims().y(); ++y)
      for (int x = 0; x < geo.dims().x(); ++x) {
        const Index3 idx(x, y, z);
        const VoxelState s = map.states[geo.linear(idx)];
        if (s == VoxelState::kUnknown) continue;
        const Vec3 c = geo.indexToCoord(idx);
        // OctoMap's keys reach 2^15 voxels either side of the origin (3.3 km at 0.1 m): a voxel beyond was
        // dropped and the file written as if whole.
        octomap::OcTreeKey key;
        if (!tree.coordToKeyChecked(octomap::point3d(c.x(), c.y(), c.z()), key)) {
          std::ostringstream why;
          why << path << ": the map's voxel at (" << c.transpose() << ") lies beyond OctoMap's reach of "
              << 32768 * geo.resolution() << " m from the origin; nothing written";
          return common::Status::Error(why.str());
        }
        tree.setNodeValue(key, s == VoxelState::kOccupied ? occ : fre, /*lazy_eval=*/true);
      }
    if (z % 16 == 15) tree.prune();  // keeps memory bounded on large maps
  }
  tree.updateInnerOccupancy();
  tree.prune();
  // Written beside and renamed over: a write that fails half way leaves an earlier file whole.
  const std::string part = path + ".part";
  {
    std::ofstream out(part, std::ios::binary);
    if (!out || !tree.writeBinary(out) || !out.flush()) {
      std::error_code ec;
      std::filesystem::remove(part, ec);
      return common::Status::Error(path + ": cannot write OctoMap file");
    }
  }
  std::error_code ec;
  std::filesystem::rename(part, path, ec);
  if (ec) {
    std::filesystem::remove(part, ec);
    return common::Status::Error(path + ": cannot write OctoMap file (" + ec.message() + ")");
  }
  return common::Status::Ok();
}

common::Status VoxelMap::loadBt(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return common::Status::Error(path + ": file not found");
  std::ifstream in(path, std::ios::binary);
  octomap::OcTree tree(0.1);
  if (!tree.readBinary(in)) return common::Status::Error(path + ": corrupt or truncated OctoMap file");
  const auto& geo = occupancy_.geometry();
  // A voxel centre on the face between two leaves lies in both (centreRange is closed), as when
  // the file's resolution is half the grid's: occupied wins there. The ESDF gets the voxels whose
  // occupancy differs once the whole file is read, so none is both inserted and removed.
  std::vector<bool> touched(geo.size(), false);
  std::vector<std::size_t> order;
  std::vector<bool> was_occupied;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    const VoxelState s = tree.isNodeOccupied(*it) ? VoxelState::kOccupied : VoxelState::kFree;
    const double size = it.getSize();
    const Vec3 lo = Vec3(it.getX(), it.getY(), it.getZ()) - Vec3::Constant(0.5 * size);
    Index3 i0, i1;
    geo.centreRange({lo, lo + Vec3::Constant(size)}, i0, i1);
    for (int z = i0.z(); z < i1.z(); ++z)
      for (int y = i0.y(); y < i1.y(); ++y)
        for (int x = i0.x(); x < i1.x(); ++x) {
          const Index3 idx(x, y, z);
          const std::size_t l = geo.linear(idx);
          const bool occupied = occupancy_.state(idx) == VoxelState::kOccupied;
          if (!touched[l]) {
            touched[l] = true;
            order.push_back(l);
            was_occupied.push_back(occupied);
          } else if (occupied) {
            continue;
          }
          occupancy_.setState(idx, s);
        }
  }
  std::vector<std::size_t> inserted, removed;
  for (std::size_t k = 0; k < order.size(); ++k) {
    const bool is = occupancy_.stateAt(order[k]) == VoxelState::kOccupied;
    if (is && !was_occupied[k]) inserted.push_back(order[k]);
    if (was_occupied[k] && !is) removed.push_back(order[k]);
  }
  esdf_.update(inserted, removed);
  return common::Status::Ok();
}

}  // namespace go_feap::map
