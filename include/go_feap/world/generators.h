// Seeded, deterministic procedural scenes: same seed -> identical grid.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "go_feap/world/scene.h"

namespace go_feap::world {

/// Maze of full-height walls on a regular grid of cells (DESIGN §3.1).
struct MazeConfig {
  double size_x = 20.0;          ///< box length along x (m); box is centred on x = 0
  double size_y = 10.0;          ///< box width along y (m); centred on y = 0
  double height = 3.0;           ///< box height (m), floor at z = 0
  double cell_size = 2.0;        ///< least pitch of the maze cells (m): each side is split into whole cells this long or longer
  double wall_thickness = 0.2;   ///< wall thickness (m); corridors are the pitch - wall wide (- 1.5 walls along the outer walls)
  int extra_openings = 3;        ///< walls removed after the spanning tree, creating loops
  double resolution = 0.1;       ///< voxel size (m)
  double margin = 0.5;           ///< grid margin around the box (m)
  double start_height = 1.0;     ///< start altitude (m)

  common::Status validate() const;
  /// Cells along x and y: as many whole cells of at least cell_size as fit (2 x 1 at least).
  int cellsX() const;
  int cellsY() const;
};

/// The maze's cell graph: cells (i, j), i along x, j along y; an open passage joins two
/// neighbouring cells. Kept so tests can check topology (dead ends, loops) directly.
struct MazeLayout {
  int cells_x = 0;
  int cells_y = 0;
  std::vector<std::pair<int, int>> passages;  ///< pairs of linear cell ids i + j * cells_x
  int degree(int cell) const;
  Vec3 cellCentre(const MazeConfig& config, int cell, double z) const;
};

common::Result<Scene> generateMaze(const MazeConfig& config, std::uint64_t seed,
                                   MazeLayout* layout = nullptr);

/// Industrial plant (DESIGN §3.1): boiler hall with open intermediate floors, chimney,
/// tanks, pipe racks at several heights, stair towers, platforms and overhangs.
struct PowerplantConfig {
  double size_x = 33.0;       ///< box length (m), centred on x = 0
  double size_y = 31.0;       ///< box width (m), centred on y = 0
  double height = 26.0;       ///< box height (m), floor at z = 0
  double resolution = 0.1;    ///< voxel size (m)
  double margin = 0.5;        ///< grid margin around the box (m)

  common::Status validate() const;
};

common::Result<Scene> generatePowerplant(const PowerplantConfig& config, std::uint64_t seed);

}  // namespace go_feap::world
