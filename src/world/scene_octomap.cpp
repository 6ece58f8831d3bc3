#include <octomap/OcTree.h>

#include <filesystem>
#include <fstream>
#include <memory>

#include "go_feap/world/scene_files.h"

namespace go_feap::world {

common::Result<std::vector<OccupiedCube>> loadOctomap(const std::string& path) {
  using R = common::Result<std::vector<OccupiedCube>>;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return R::Error(path + ": file not found");
  std::ifstream in(path, std::ios::binary);
  std::string first_line;
  std::getline(in, first_line);
  if (first_line.rfind("# Octomap OcTree binary file", 0) != 0)
    return R::Error(path + ": not an OctoMap binary (.bt) file (bad header)");
  in.seekg(0);
  // OctoMap's reader reports problems on std::cerr and returns false; read into a tree
  // first and check the stream, so truncated files are caught as well.
  octomap::OcTree tree(0.1);
  if (!tree.readBinary(in)) return R::Error(path + ": corrupt or truncated OctoMap file");
  if (in.bad()) return R::Error(path + ": read error");
  std::vector<OccupiedCube> cubes;
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const octomap::point3d c = it.getCoordinate();
    if (!std::isfinite(c.x()) || !std::isfinite(c.y()) || !std::isfinite(c.z()))
      return R::Error(path + ": corrupt OctoMap file (non-finite leaf coordinate)");
    cubes.push_back({Vec3(c.x(), c.y(), c.z()), it.getSize()});
  }
  if (cubes.empty()) return R::Error(path + ": the OctoMap holds no occupied voxels");
  return cubes;
}

common::Status saveSceneBt(const Scene& scene, const std::string& path) {
  octomap::OcTree tree(scene.resolution());
  const auto& geo = scene.geometry();
  std::size_t n = 0;
  for (std::size_t l = 0; l < scene.occupied.size(); ++l) {
    if (!scene.occupied[l]) continue;
    const Vec3 c = geo.indexToCoord(geo.unlinear(l));
    tree.updateNode(octomap::point3d(c.x(), c.y(), c.z()), true, /*lazy_eval=*/true);
    ++n;
  }
  if (n == 0) return common::Status::Error(path + ": scene '" + scene.name + "' has no occupied voxels to write");
  tree.updateInnerOccupancy();
  tree.prune();
  std::ofstream out(path, std::ios::binary);
  if (!out || !tree.writeBinary(out) || !out.flush())
    return common::Status::Error(path + ": cannot write OctoMap file");
  return common::Status::Ok();
}

}  // namespace go_feap::world
