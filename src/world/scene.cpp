#include "go_feap/world/scene.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

namespace go_feap::world {

std::size_t Scene::occupiedCount() const {
  std::size_t n = 0;
  for (std::uint8_t v : occupied.data()) n += (v != 0);
  return n;
}

double sceneVoxelCount(const Aabb& box, double resolution, double margin) {
  return common::GridGeometry::coveringCount(box.expanded(margin), resolution);
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
  // The box's voxels are those whose centres it holds (computeObservableSet, the tools' counts): a box
  // between two layers of centres holds none, and nothing in it could be explored.
  const auto& geo = scene.geometry();
  Index3 lo, hi;
  geo.centreRange(scene.box, lo, hi);
  for (int a = 0; a < 3; ++a) {
    if (hi[a] <= lo[a]) {
      std::ostringstream why;
      why << who << "exploration box " << fmt(scene.box.min) << " .. " << fmt(scene.box.max)
          << " holds no voxel centre along " << "xyz"[a] << " (voxel centres lie at " << geo.origin()[a]
          << " + (k + 0.5) x " << scene.resolution() << " m): make it at least one voxel wide";
      return common::Status::Error(why.str());
    }
  }
  if (!scene.start.position.allFinite() || !std::isfinite(scene.start.yaw)) {
    return common::Status::Error(who + "start pose is not finite");
  }
  if (!scene.box.contains(scene.start.position)) {
    return common::Status::Error(who + "start " + fmt(scene.start.position) +
                                 " lies outside the exploration box " + fmt(scene.box.min) + " .. " +
                                 fmt(scene.box.max));
  }
  // A start on the box's face can lie in a voxel of the margin, from which nothing is observable.
  const Index3 start = geo.coordToIndex(scene.start.position);
  if ((start.array() < lo.array()).any() || (start.array() >= hi.array()).any()) {
    return common::Status::Error(who + "start " + fmt(scene.start.position) + " lies in the voxel centred at " +
                                 fmt(geo.indexToCoord(start)) + ", outside the exploration box " +
                                 fmt(scene.box.min) + " .. " + fmt(scene.box.max) +
                                 ": nothing would be observable (move the start half a voxel into the box)");
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

  // Scan-line flood fill through the free voxels of the box: a seed's row is filled to both sides as far
  // as it is free (a span), and each of the four rows beside the span (y +- 1, z +- 1) is scanned along it,
  // marking the occupied voxels met and leaving one seed per run of free ones. Rows are read in memory
  // order: a voxel-by-voxel breadth-first fill jumped a whole plane between neighbours, which took 215 s
  // through a 1e9-voxel scene, and its queue once held every free voxel.
  constexpr std::uint8_t kFree = 1, kOccupied = 2;
  auto& mask = result.mask;
  auto rowStart = [&](int y, int z) { return geo.linear(Index3(0, y, z)); };
  auto markOccupied = [&](std::size_t l) {
    if (mask[l] != 0) return;
    mask[l] = kOccupied;
    ++result.occupied_count;
  };
  auto open = [&](std::size_t l) { return mask[l] == 0 && scene.occupied[l] == 0; };
  std::vector<Index3> seeds{start};
  while (!seeds.empty()) {
    const Index3 seed = seeds.back();
    seeds.pop_back();
    const std::size_t row = rowStart(seed.y(), seed.z());
    if (!open(row + seed.x())) continue;  // a span from another seed filled it
    int x0 = seed.x(), x1 = seed.x();
    while (x0 > lo.x() && open(row + x0 - 1)) --x0;
    while (x1 + 1 < hi.x() && open(row + x1 + 1)) ++x1;
    for (int x = x0; x <= x1; ++x) mask[row + x] = kFree;
    result.free_count += static_cast<std::size_t>(x1 - x0 + 1);
    if (x0 > lo.x() && scene.occupied[row + x0 - 1] != 0) markOccupied(row + x0 - 1);
    if (x1 + 1 < hi.x() && scene.occupied[row + x1 + 1] != 0) markOccupied(row + x1 + 1);
    const int side_y[4] = {seed.y() - 1, seed.y() + 1, seed.y(), seed.y()};
    const int side_z[4] = {seed.z(), seed.z(), seed.z() - 1, seed.z() + 1};
    for (int k = 0; k < 4; ++k) {
      if (side_y[k] < lo.y() || side_y[k] >= hi.y() || side_z[k] < lo.z() || side_z[k] >= hi.z()) continue;
      const std::size_t side = rowStart(side_y[k], side_z[k]);
      bool in_run = false;
      for (int x = x0; x <= x1; ++x) {
        const std::size_t l = side + x;
        if (scene.occupied[l] != 0) markOccupied(l);
        const bool free = open(l);
        if (free && !in_run) seeds.emplace_back(x, side_y[k], side_z[k]);
        in_run = free;
      }
    }
  }
  for (auto& v : result.mask.data()) v = v != 0;
  return result;
}

}  // namespace go_feap::world
