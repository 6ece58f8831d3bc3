#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>

#include "go_feap/world/generators.h"
#include "go_feap/world/scene.h"
#include "go_feap/world/shapes.h"

namespace go_feap::world {

namespace {

// Whole cells of at least `cell` along `size` (a hair under a whole number of cells counts as that number:
// 6 / 2 need not be exactly 3 in floating point), at least `least`; bounded for any finite input.
int wholeCells(double size, double cell, int least) {
  const double n = std::floor(size / cell + 1e-9);
  return n >= least ? static_cast<int>(std::min(n, 1e6)) : least;
}

}  // namespace

int MazeConfig::cellsX() const { return wholeCells(size_x, cell_size, 2); }
int MazeConfig::cellsY() const { return wholeCells(size_y, cell_size, 1); }

common::Status MazeConfig::validate() const {
  auto err = [](const char* key, const char* why) {
    return common::Status::Error(std::string("maze: ") + key + " " + why);
  };
  if (!(resolution > 0.0)) return err("resolution", "must be > 0");
  if (!(cell_size > 0.0)) return err("cell_size", "must be > 0");
  if (!(wall_thickness >= resolution)) return err("wall_thickness", "must be at least one voxel");
  if (!(cell_size - 1.5 * wall_thickness >= 1.5))
    return err("cell_size", "leaves corridors narrower than 1.5 m after the walls");
  if (!(size_x >= 2.0 * cell_size) || !(size_y >= cell_size))
    return err("size_x/size_y", "must hold at least 2 x 1 cells");
  if (!(height > start_height) || !(start_height > wall_thickness))
    return err("height/start_height", "need 0 < start_height < height");
  if (extra_openings < 0) return err("extra_openings", "must be >= 0");
  if (!(margin >= 0.0)) return err("margin", "must be >= 0");
  // Bounded like a file scene's grid, and in cells (the generator's dead-end search grows with the square
  // of the cells: 400 x 400 m did not finish; 1e6 x 1e6 m overflowed the cell count and crashed).
  if (!(size_x <= 1e4 && size_y <= 1e4 && height <= 1e3)) return err("size_x/size_y/height", "must be at most 10 km x 10 km x 1 km");
  if (!(static_cast<double>(cellsX()) * cellsY() <= 2500.0))
    return err("size_x/size_y", "must hold at most 2500 cells");
  const double voxels = sceneVoxelCount({Vec3(-0.5 * size_x, -0.5 * size_y, 0.0), Vec3(0.5 * size_x, 0.5 * size_y, height)},
                                        resolution, margin);
  if (!(voxels <= kMaxSceneVoxels)) return err("size_x/size_y/height/resolution", "make a grid of more than 2^30 voxels");
  return common::Status::Ok();
}

int MazeLayout::degree(int cell) const {
  int d = 0;
  for (const auto& p : passages) d += (p.first == cell) + (p.second == cell);
  return d;
}

Vec3 MazeLayout::cellCentre(const MazeConfig& config, int cell, double z) const {
  const double x0 = -0.5 * config.size_x, y0 = -0.5 * config.size_y;
  const double px = config.size_x / cells_x, py = config.size_y / cells_y;
  return Vec3(x0 + (cell % cells_x + 0.5) * px, y0 + (cell / cells_x + 0.5) * py, z);
}

common::Result<Scene> generateMaze(const MazeConfig& config, std::uint64_t seed, MazeLayout* layout_out) {
  if (auto st = config.validate(); !st) return st;
  MazeLayout layout;
  // Whole cells no shorter than cell_size: rounded to the nearest count, a 3 m side of 2 m cells made two
  // cells of 1.5 m, corridors of 1.2 m along the outer walls.
  layout.cells_x = config.cellsX();
  layout.cells_y = config.cellsY();
  const int nx = layout.cells_x, ny = layout.cells_y, n = nx * ny;
  std::mt19937_64 rng(seed);

  // Spanning tree by randomised depth-first search (a perfect maze: many dead ends).
  std::vector<char> visited(n, 0);
  std::vector<int> stack{0};
  visited[0] = 1;
  std::set<std::pair<int, int>> open;
  auto neighbours = [&](int c) {
    std::vector<int> out;
    const int i = c % nx, j = c / nx;
    if (i > 0) out.push_back(c - 1);
    if (i + 1 < nx) out.push_back(c + 1);
    if (j > 0) out.push_back(c - nx);
    if (j + 1 < ny) out.push_back(c + nx);
    return out;
  };
  while (!stack.empty()) {
    const int cur = stack.back();
    std::vector<int> cand;
    for (int nb : neighbours(cur)) if (!visited[nb]) cand.push_back(nb);
    if (cand.empty()) {
      stack.pop_back();
      continue;
    }
    const int next = cand[std::uniform_int_distribution<int>(0, static_cast<int>(cand.size()) - 1)(rng)];
    visited[next] = 1;
    open.insert({std::min(cur, next), std::max(cur, next)});
    stack.push_back(next);
  }
  // Extra openings create loops; keep at least one dead end so the maze has one.
  std::vector<std::pair<int, int>> closed;
  for (int c = 0; c < n; ++c)
    for (int nb : neighbours(c))
      if (nb > c && !open.count({c, nb})) closed.push_back({c, nb});
  std::shuffle(closed.begin(), closed.end(), rng);
  auto degree = [&](int c) {
    int d = 0;
    for (const auto& p : open) d += (p.first == c) + (p.second == c);
    return d;
  };
  auto dead_ends = [&]() {
    int k = 0;
    for (int c = 0; c < n; ++c) k += degree(c) == 1;
    return k;
  };
  int added = 0;
  for (const auto& wall : closed) {
    if (added >= config.extra_openings) break;
    open.insert(wall);
    if (dead_ends() == 0) {
      open.erase(wall);
      continue;
    }
    ++added;
  }
  layout.passages.assign(open.begin(), open.end());

  // Rasterise: floor, outer walls, then every wall between cells that is not a passage.
  const Aabb box{Vec3(-0.5 * config.size_x, -0.5 * config.size_y, 0.0),
                 Vec3(0.5 * config.size_x, 0.5 * config.size_y, config.height)};
  Scene scene = makeEmptyScene("maze", box, config.resolution, config.margin);
  scene.seed = seed;
  scene.seeded = true;
  const double t = config.wall_thickness, h = config.height, r = config.resolution;
  const double px = config.size_x / nx, py = config.size_y / ny;
  fillBox(scene, {Vec3(box.min.x(), box.min.y(), 0.0), Vec3(box.max.x(), box.max.y(), 0.5 * r)});
  fillBox(scene, {box.min, Vec3(box.min.x() + t, box.max.y(), h)});
  fillBox(scene, {Vec3(box.max.x() - t, box.min.y(), 0.0), box.max});
  fillBox(scene, {box.min, Vec3(box.max.x(), box.min.y() + t, h)});
  fillBox(scene, {Vec3(box.min.x(), box.max.y() - t, 0.0), box.max});
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i < nx; ++i) {
      const int c = i + j * nx;
      const double x1 = box.min.x() + (i + 1) * px, y1 = box.min.y() + (j + 1) * py;
      const double xa = box.min.x() + i * px, ya = box.min.y() + j * py;
      if (i + 1 < nx && !open.count({c, c + 1}))
        fillBox(scene, {Vec3(x1 - 0.5 * t, ya - 0.5 * t, 0.0), Vec3(x1 + 0.5 * t, y1 + 0.5 * t, h)});
      if (j + 1 < ny && !open.count({c, c + nx}))
        fillBox(scene, {Vec3(xa - 0.5 * t, y1 - 0.5 * t, 0.0), Vec3(x1 + 0.5 * t, y1 + 0.5 * t, h)});
    }
  }
  scene.start.position = layout.cellCentre(config, 0, config.start_height);
  scene.start.yaw = 0.0;
  if (layout_out) *layout_out = layout;
  if (auto st = validateScene(scene); !st) return st;
  return scene;
}

}  // namespace go_feap::world
