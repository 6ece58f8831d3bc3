#include "go_feap/world/scene.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>
#include <sstream>
#include <vector>

namespace go_feap::world {

std::size_t Scene::occupiedCount() const {
  std::size_t n = 0;
  for (std::uint8_t v : occupied.data()) n += (v != 0);
  return n;
}

double sceneVoxelCount(const Aabb& box, double resolution, double margin) {
  double n = 1.0;
  for (int a = 0; a < 3; ++a) n *= std::max(1.0, std::ceil((box.max[a] - box.min[a] + 2.0 * margin) / resolution) + 1.0);
  return n;
}

Scene makeEmptyScene(const std::string& name, const Aabb& box, double resolution, double margin) {
  Scene scene;
  scene.name = name;
  scene.box = box;
  scene.occupied =
      common::DenseGrid<std::uint8_t>(common::GridGeometry::covering(box.expanded(margin), resolution), 0);
  return scene;
}

bool markOccupied(Scene& scene, const Vec3& p) {
  const Index3 idx = scene.geometry().clampedIndex(p);  // a point far outside (or NaN) must not overflow
  if (!scene.geometry().inside(idx)) return false;
  scene.occupied.at(idx) = 1;
  return true;
}

namespace {

std::string fmt(const Vec3& v) {
  std::ostringstream os;
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

}  // namespace

common::Status validateScene(const Scene& scene) {
  const std::string who = "scene '" + scene.name + "': ";
  if (!(scene.resolution() > 0.0)) return common::Status::Error(who + "resolution must be > 0");
  if (!scene.box.valid()) {
    return common::Status::Error(who + "exploration box min " + fmt(scene.box.min) +
                                 " must be below max " + fmt(scene.box.max) + " on every axis");
  }
  if (!scene.start.position.allFinite() || !std::isfinite(scene.start.yaw)) {
    return common::Status::Error(who + "start pose is not finite");
  }
  if (!scene.box.contains(scene.start.position)) {
    return common::Status::Error(who + "start " + fmt(scene.start.position) +
                                 " lies outside the exploration box " + fmt(scene.box.min) + " .. " +
                                 fmt(scene.box.max));
  }
  if (scene.isOccupied(scene.start.position)) {
    return common::Status::Error(who + "start " + fmt(scene.start.position) + " lies inside an obstacle");
  }
  return common::Status::Ok();
}

ObservableSet computeObservableSet(const Scene& scene) {
  const auto& geo = scene.geometry();
  ObservableSet result;
  result.mask = common::DenseGrid<std::uint8_t>(geo, 0);
  Index3 lo, hi;
  geo.centreRange(scene.box, lo, hi);
  auto in_box = [&](const Index3& i) { return (i.array() >= lo.array()).all() && (i.array() < hi.array()).all(); };

  const Index3 start = geo.coordToIndex(scene.start.position);
  if (!in_box(start) || scene.occupied.at(start) != 0) return result;

  // Breadth-first flood fill through free voxels of the box. The queue holds the wave front only (a
  // deque frees what was taken): it used to keep every free voxel, 4 bytes each, 4 GB in a scene of
  // 1e9 voxels; a wave front is about a cross-section. 32-bit indices halve it again.
  constexpr std::uint8_t kFree = 1, kOccupied = 2;
  std::deque<std::uint32_t> queue;
  if (geo.size() > std::numeric_limits<std::uint32_t>::max()) return result;
  queue.push_back(static_cast<std::uint32_t>(geo.linear(start)));
  result.mask[queue.front()] = kFree;
  result.free_count = 1;
  while (!queue.empty()) {
    const Index3 cur = geo.unlinear(queue.front());
    queue.pop_front();
    for (const Index3& off : common::faceNeighbours()) {
      const Index3 nb = cur + off;
      if (!in_box(nb)) continue;
      const std::size_t l = geo.linear(nb);
      if (result.mask[l] != 0) continue;
      if (scene.occupied[l] != 0) {
        result.mask[l] = kOccupied;
        ++result.occupied_count;
      } else {
        result.mask[l] = kFree;
        ++result.free_count;
        queue.push_back(static_cast<std::uint32_t>(l));
      }
    }
  }
  for (auto& v : result.mask.data()) v = v != 0;
  return result;
}

}  // namespace go_feap::world
