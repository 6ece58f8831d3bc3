// File-based scenes: point clouds (.pcd/.ply), meshes (.stl), OctoMaps (.bt) and the scene
// YAML that places them in the world. Every loader returns an error naming the file and
// what is wrong instead of throwing.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "go_feap/world/scene.h"

namespace go_feap::world {

/// Triangles as consecutive vertex triples (file frame).
struct TriangleMesh {
  std::vector<Vec3> vertices;
  std::size_t triangleCount() const { return vertices.size() / 3; }
};

/// Occupied cubes of an OctoMap (leaf centre and edge length, file frame).
struct OccupiedCube {
  Vec3 centre;
  double size;
};

/// The extension of `path` in lower case (".pcd" for "UP.PCD"): every loader matches extensions this way.
std::string lowerExtension(const std::string& path);
/// `text` with its ASCII letters in lower case (file keywords compared in any case: SOLID, ASCII).
std::string asciiLower(std::string text);

/// A point cloud file's points and, for a PLY mesh, its faces as triangles of point indices.
struct PointCloudFile {
  std::vector<Vec3> points;
  std::size_t skipped_points = 0;  ///< points with x, y and z all NaN (PCL's "no point"), not in `points`
  std::vector<std::array<std::uint32_t, 3>> triangles;  ///< a convex face fanned round its first vertex, a concave one ear-clipped
};

/// Reads x, y, z of every point of a .pcd or .ply file (PCL readers), each in its own type (float32, float64
/// or an integer type, COUNT 1), and a PLY's faces (`vertex_indices` or `vertex_index` lists). A point whose
/// x, y and z are all NaN (PCL's "no point", as in an organised cloud from a depth camera) is skipped in a
/// file without faces. Fails on missing, truncated or corrupt files, other NaN/Inf points, clouds without a
/// point, and faces of fewer than 3 vertices or naming a vertex the file does not have.
common::Result<PointCloudFile> loadPointCloudFile(const std::string& path);

/// loadPointCloudFile's points.
common::Result<std::vector<Vec3>> loadPointCloud(const std::string& path);

/// Reads a binary or ASCII STL. A file is binary when its size equals 84 + 50 n for the
/// triangle count n in its header (binary files may start with "solid" too).
common::Result<TriangleMesh> loadStl(const std::string& path);

/// Reads the occupied leaves of an OctoMap binary (.bt) file.
common::Result<std::vector<OccupiedCube>> loadOctomap(const std::string& path);

/// A file-based scene as described by a scene YAML (see README, "Scene files").
struct SceneFileSpec {
  std::string name;
  std::string file;                                        ///< absolute, or relative to the YAML
  Eigen::Matrix4d T_world_file = Eigen::Matrix4d::Identity();  ///< p_world = T p_file
  double resolution = 0.1;                                 ///< voxel size (m)
  Aabb box;                                                ///< exploration box (world, m)
  StartPose start;
  bool ground_plane = false;  ///< optional: fill the voxel layer at the box's min z
  double margin = 1.0;        ///< optional: grid margin around the box (m)
};

/// Parses a scene YAML; `file` is resolved against the YAML's folder. A key the loader does not read, or one
/// given twice, is refused (at every level), naming it.
common::Result<SceneFileSpec> parseSceneYaml(const std::string& yaml_path);

/// Loads the geometry named by `spec` and voxelises it in the world frame: points mark
/// their voxel, triangles (STL, and a PLY's faces) every voxel they overlap, octree leaves every voxel they overlap
/// (voxelizeParallelepiped).
/// Geometry outside the grid (box + margin) is dropped.
common::Result<Scene> loadSceneFile(const SceneFileSpec& spec);

/// parseSceneYaml + loadSceneFile.
common::Result<Scene> loadSceneYaml(const std::string& yaml_path);

/// Whether triangle (a, b, c) marks voxel `idx` of `geo`: it overlaps the voxel's half-open cube
/// [lo, lo + res) (a face lying exactly on a voxel boundary marks the voxel on its positive side only).
bool triangleMarksVoxel(const common::GridGeometry& geo, const Index3& idx, const Vec3& a, const Vec3& b,
                        const Vec3& c);

/// Marks every voxel of `scene` that triangle (a, b, c) marks (world frame), testing only the voxels
/// of the grid columns the triangle crosses: the cost grows with the triangle's area, not with the
/// volume of its bounding box.
void voxelizeTriangle(Scene& scene, const Vec3& a, const Vec3& b, const Vec3& c);

/// Marks every voxel of `scene` that the solid parallelepiped centre + half * [-1, 1]^3 (world frame; the columns
/// of `half` are its half edges: an octree leaf placed by T_world_file) overlaps with a volume. A face lying on a
/// voxel face marks only the voxel on the solid's side: triangleMarksVoxel's half-open rule for a solid
/// [min, max), so a solid filling whole voxels marks just those. Faces within a millionth of a voxel (or of the
/// solid's shortest edge) of each other count as lying on each other (rounding).
void voxelizeParallelepiped(Scene& scene, const Vec3& centre, const Eigen::Matrix3d& half);

/// Writes the occupied voxel centres as a binary PCD (world frame).
common::Status saveScenePcd(const Scene& scene, const std::string& path);

/// Writes the occupied voxels as an OctoMap .bt at the scene's resolution.
common::Status saveSceneBt(const Scene& scene, const std::string& path);

/// Builds a scene from "maze", "powerplant" (with `seed`) or the path of a scene YAML.
common::Result<Scene> makeScene(const std::string& spec, std::uint64_t seed);

}  // namespace go_feap::world
