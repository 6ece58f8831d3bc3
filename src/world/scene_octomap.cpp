#include <octomap/OcTree.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "go_feap/map/octomap_file.h"
#include "go_feap/world/scene_files.h"

namespace go_feap::world {

common::Result<std::vector<OccupiedCube>> loadOctomap(const std::string& path) {
  using R = common::Result<std::vector<OccupiedCube>>;
  auto tree = map::readOctree(path);
  if (!tree) return tree.status();
  std::vector<OccupiedCube> cubes;
  for (auto it = (*tree)->begin_leafs(), end = (*tree)->end_leafs(); it != end; ++it) {
    if (!(*tree)->isNodeOccupied(*it)) continue;
    // In double: a float centre is off by up to 1e-6 m at 30 m, which moves a leaf's faces off the voxel
    // faces they lie on and would mark the next voxel.
    cubes.push_back({Vec3(it.getX(), it.getY(), it.getZ()), it.getSize()});
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
    // OctoMap's keys reach 2^15 voxels either side of the origin (3.3 km at 0.1 m): updateNode() dropped a
    // voxel beyond, in silence, and an empty tree was written.
    octomap::OcTreeKey key;
    if (!tree.coordToKeyChecked(octomap::point3d(c.x(), c.y(), c.z()), key)) {
      std::ostringstream why;
      why << path << ": scene '" << scene.name << "' has an occupied voxel at (" << c.transpose()
          << "), beyond OctoMap's reach of " << 32768 * scene.resolution() << " m from the origin at "
          << scene.resolution() << " m";
      return common::Status::Error(why.str());
    }
    tree.updateNode(key, true, /*lazy_eval=*/true);
    ++n;
  }
  if (n == 0) return common::Status::Error(path + ": scene '" + scene.name + "' has no occupied voxels to write");
  tree.updateInnerOccupancy();
  tree.prune();
  return map::writeOctree(tree, path);
}

}  // namespace go_feap::world
