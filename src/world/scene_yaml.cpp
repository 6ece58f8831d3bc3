#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <set>
#include <sstream>

#include "go_feap/world/generators.h"
#include "go_feap/world/scene_files.h"

namespace go_feap::world {

namespace fs = std::filesystem;

namespace {

// Thrown inside the parser only; converted to a Result at its boundary.
struct KeyError {
  std::string message;
};

YAML::Node require(const YAML::Node& parent, const std::string& key, const std::string& where) {
  const YAML::Node n = parent[key];
  if (!n) throw KeyError{"missing key '" + where + key + "'"};
  return n;
}

double number(const YAML::Node& n, const std::string& key) {
  if (!n.IsScalar()) throw KeyError{"key '" + key + "' must be a number"};
  try {
    const double v = n.as<double>();
    if (!std::isfinite(v)) throw KeyError{"key '" + key + "' must be finite"};
    return v;
  } catch (const YAML::Exception&) {
    throw KeyError{"key '" + key + "' must be a number, got '" + n.Scalar() + "'"};
  }
}

std::vector<double> numbers(const YAML::Node& n, const std::string& key, std::size_t count) {
  if (!n.IsSequence() || n.size() != count)
    throw KeyError{"key '" + key + "' must be a list of " + std::to_string(count) + " numbers"};
  std::vector<double> out;
  for (std::size_t i = 0; i < count; ++i) out.push_back(number(n[i], key + "[" + std::to_string(i) + "]"));
  return out;
}

Vec3 vec3(const YAML::Node& n, const std::string& key) {
  const auto v = numbers(n, key, 3);
  return Vec3(v[0], v[1], v[2]);
}

bool boolean(const YAML::Node& n, const std::string& key) {
  try {
    if (!n.IsScalar()) throw YAML::Exception(YAML::Mark(), "");
    return n.as<bool>();
  } catch (const YAML::Exception&) {
    throw KeyError{"key '" + key + "' must be true or false"};
  }
}

// Refuses a key of the map `node` (whose keys are named `where` + key) that is not in `allowed`, naming the
// allowed ones, and a key given twice (yaml-cpp keeps both and operator[] reads the first): a typo such as
// 'ground_plnae: true' was ignored in silence, and a repeated resolution took its first value.
void checkKeys(const YAML::Node& node, const std::string& where, std::initializer_list<const char*> allowed) {
  std::set<std::string> seen;
  for (const auto& entry : node) {
    const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : "(a key that is no string)";
    if (std::none_of(allowed.begin(), allowed.end(), [&](const char* a) { return key == a; })) {
      std::string list;
      for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
      const std::string parent = where.empty() ? "the file" : "'" + where.substr(0, where.size() - 1) + "'";
      throw KeyError{"unknown key '" + where + key + "' (" + parent + " takes " + list + ")"};
    }
    if (!seen.insert(key).second) throw KeyError{"key '" + where + key + "' is given more than once"};
  }
}

// Whether the columns of `m` are (nearly) linearly dependent, whatever their lengths: the determinant of the
// columns scaled to unit length is 1 for a rotation and 0 for dependent columns. An absolute |det| < 1e-9
// refused a millimetre mesh turned 45 degrees (|det| 1e-9) and passed dependent columns of large scale.
bool nearlySingular(Eigen::Matrix3d m) {
  for (int c = 0; c < 3; ++c) {
    const double length = m.col(c).stableNorm();  // no overflow for entries of 1e300
    if (!(length > 0.0)) return true;
    m.col(c) /= length;
  }
  return !(std::abs(m.determinant()) >= 1e-9);
}

// Whether `s` is UTF-8 text without control characters (bytes below 0x20, and 0x7f): a scene's name goes
// into JSON, table.md and the pictures' titles.
bool printableUtf8(const std::string& s) {
  for (std::size_t i = 0; i < s.size();) {
    const auto b = static_cast<unsigned char>(s[i]);
    if (b < 0x80) {
      if (b < 0x20 || b == 0x7f) return false;
      ++i;
      continue;
    }
    // The length of the sequence from its lead byte, and the least code point it may hold (no overlong form).
    const int len = b >= 0xf0 && b <= 0xf4 ? 4 : b >= 0xe0 ? 3 : b >= 0xc2 && b < 0xe0 ? 2 : 0;
    if (len == 0 || i + len > s.size()) return false;
    std::uint32_t code = b & (0x7f >> len);
    for (int k = 1; k < len; ++k) {
      const auto c = static_cast<unsigned char>(s[i + k]);
      if ((c & 0xc0) != 0x80) return false;
      code = (code << 6) | (c & 0x3f);
    }
    const std::uint32_t least = len == 2 ? 0x80 : len == 3 ? 0x800 : 0x10000;
    if (code < least || code > 0x10ffff || (code >= 0xd800 && code <= 0xdfff)) return false;
    i += len;
  }
  return true;
}

// The value of `scene.name`: a non-empty string of printable UTF-8 (a Latin-1 byte aborted go_feap_scene
// when it wrote scene.json).
std::string sceneName(const YAML::Node& n) {
  if (!n.IsScalar() || n.Scalar().empty()) throw KeyError{"key 'scene.name' must be a non-empty string"};
  if (!printableUtf8(n.Scalar()))
    throw KeyError{"key 'scene.name' must be UTF-8 text without control characters"};
  return n.Scalar();
}

// The map under `key` of `parent`, required.
YAML::Node requireMap(const YAML::Node& parent, const std::string& key, const std::string& where) {
  const YAML::Node n = require(parent, key, where);
  if (!n.IsMap()) throw KeyError{"key '" + where + key + "' must be a map"};
  return n;
}

// Whether any voxel of the index range [lo, hi) is occupied.
bool anyOccupied(const Scene& scene, const Index3& lo, const Index3& hi) {
  for (int z = lo.z(); z < hi.z(); ++z)
    for (int y = lo.y(); y < hi.y(); ++y)
      for (int x = lo.x(); x < hi.x(); ++x)
        if (scene.occupied.at(Index3(x, y, z))) return true;
  return false;
}

}  // namespace

std::string asciiLower(std::string text) {
  for (char& c : text)
    if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
  return text;
}

std::string lowerExtension(const std::string& path) { return asciiLower(fs::path(path).extension().string()); }

common::Result<SceneFileSpec> parseSceneYaml(const std::string& yaml_path) {
  using R = common::Result<SceneFileSpec>;
  std::error_code ec;
  if (!fs::is_regular_file(yaml_path, ec)) return R::Error(yaml_path + ": file not found");
  YAML::Node root;
  try {
    root = YAML::LoadFile(yaml_path);
  } catch (const YAML::Exception& e) {
    return R::Error(yaml_path + ": not valid YAML (" + e.what() + ")");
  }
  SceneFileSpec spec;
  try {
    if (!root.IsMap()) throw KeyError{"missing key 'scene'"};
    checkKeys(root, "", {"scene"});
    const YAML::Node s = require(root, "scene", "");
    if (!s.IsMap()) throw KeyError{"key 'scene' must be a mapping"};
    checkKeys(s, "scene.", {"name", "file", "T_world_file", "resolution", "box", "start", "ground_plane", "margin"});
    spec.name = sceneName(require(s, "name", "scene."));
    const YAML::Node file = require(s, "file", "scene.");
    if (!file.IsScalar() || file.Scalar().empty()) throw KeyError{"key 'scene.file' must be a file name"};
    fs::path fp(file.Scalar());
    // Joined, not normalised: '..' after a symlinked folder is the link target's parent, as the system
    // resolves it (lexically_normal() dropped the link: a checkout linked into a workspace lost its scenes).
    if (fp.is_relative()) fp = fs::path(yaml_path).parent_path() / fp;
    spec.file = fp.string();

    const auto t = numbers(require(s, "T_world_file", "scene."), "scene.T_world_file", 16);
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) spec.T_world_file(r, c) = t[4 * r + c];
    if (spec.T_world_file.row(3) != Eigen::RowVector4d(0, 0, 0, 1))
      throw KeyError{"key 'scene.T_world_file' must end with the row 0 0 0 1 (row-major 4x4)"};
    if (nearlySingular(spec.T_world_file.topLeftCorner<3, 3>()))
      throw KeyError{"key 'scene.T_world_file' has a singular rotation/scale part (its columns are (nearly) dependent)"};

    spec.resolution = number(require(s, "resolution", "scene."), "scene.resolution");
    if (!(spec.resolution > 0.0)) throw KeyError{"key 'scene.resolution' must be > 0"};

    const YAML::Node box = requireMap(s, "box", "scene.");
    checkKeys(box, "scene.box.", {"min", "max"});
    spec.box.min = vec3(require(box, "min", "scene.box."), "scene.box.min");
    spec.box.max = vec3(require(box, "max", "scene.box."), "scene.box.max");
    if (!spec.box.valid()) throw KeyError{"key 'scene.box' needs min < max on every axis"};

    const YAML::Node start = requireMap(s, "start", "scene.");
    checkKeys(start, "scene.start.", {"position", "yaw"});
    spec.start.position = vec3(require(start, "position", "scene.start."), "scene.start.position");
    spec.start.yaw = number(require(start, "yaw", "scene.start."), "scene.start.yaw");

    if (s["ground_plane"]) spec.ground_plane = boolean(s["ground_plane"], "scene.ground_plane");
    if (s["margin"]) {
      spec.margin = number(s["margin"], "scene.margin");
      if (!(spec.margin >= 0.0)) throw KeyError{"key 'scene.margin' must be >= 0"};
    }
    const double voxels = sceneVoxelCount(spec.box, spec.resolution, spec.margin);
    if (!(voxels <= kMaxSceneVoxels)) {
      std::ostringstream why;
      why << "keys 'scene.box', 'scene.margin' and 'scene.resolution' give a grid of " << voxels
          << " voxels, more than the " << kMaxSceneVoxels << " a scene may have (is the resolution in metres?)";
      throw KeyError{why.str()};
    }
  } catch (const KeyError& e) {
    return R::Error(yaml_path + ": " + e.message);
  } catch (const YAML::Exception& e) {
    return R::Error(yaml_path + ": malformed scene description (" + e.what() + ")");
  }
  return spec;
}

common::Result<Scene> loadSceneFile(const SceneFileSpec& spec) {
  using R = common::Result<Scene>;
  Scene scene = makeEmptyScene(spec.name, spec.box, spec.resolution, spec.margin);
  scene.start = spec.start;
  const Eigen::Affine3d T(spec.T_world_file);
  const std::string ext = lowerExtension(spec.file);
  if (ext == ".pcd" || ext == ".ply") {
    auto cloud = loadPointCloudFile(spec.file);
    if (!cloud) return cloud.status();
    std::vector<Vec3>& placed = cloud->points;
    for (std::size_t i = 0; i < placed.size(); ++i) {
      placed[i] = T * placed[i];
      if (!placed[i].allFinite())
        return R::Error(spec.file + ": point " + std::to_string(i) + " is not finite once placed by T_world_file");
    }
    // A PLY mesh's faces mark every voxel they overlap, as an STL's triangles do (its vertices alone left
    // the walls between them open); a vertex no face uses is left out (meshes keep such strays after editing).
    // A cloud without faces marks its points.
    if (cloud->triangles.empty()) {
      for (const Vec3& p : placed) markOccupied(scene, p);
    } else {
      for (const auto& [a, b, c] : cloud->triangles) voxelizeTriangle(scene, placed[a], placed[b], placed[c]);
    }
  } else if (ext == ".stl") {
    auto mesh = loadStl(spec.file);
    if (!mesh) return mesh.status();
    const auto& v = mesh->vertices;
    for (std::size_t i = 0; i + 2 < v.size(); i += 3) {
      const Vec3 a = T * v[i], b = T * v[i + 1], c = T * v[i + 2];
      if (!(a.allFinite() && b.allFinite() && c.allFinite()))
        return R::Error(spec.file + ": triangle " + std::to_string(i / 3) + " is not finite once placed by T_world_file");
      voxelizeTriangle(scene, a, b, c);
    }
  } else if (ext == ".bt") {
    auto cubes = loadOctomap(spec.file);
    if (!cubes) return cubes.status();
    // A leaf marks every grid voxel its cube, placed by T_world_file (turned, scaled), overlaps: marking
    // only the voxels whose centres it covered lost a 0.03 m wall on a 0.1 m grid. Only the voxels within the
    // placed cube's bounds are looked at, so a large leaf costs no more than the grid.
    for (std::size_t i = 0; i < cubes->size(); ++i) {
      const OccupiedCube& cube = (*cubes)[i];
      const Vec3 centre = T * cube.centre;
      const Eigen::Matrix3d half = 0.5 * cube.size * T.linear();
      if (!(centre.allFinite() && half.allFinite()))
        return R::Error(spec.file + ": leaf " + std::to_string(i) + " is not finite once placed by T_world_file");
      voxelizeParallelepiped(scene, centre, half);
    }
  } else {
    return R::Error(spec.file + ": unknown scene file extension '" + fs::path(spec.file).extension().string() +
                    "' (expected .pcd, .ply, .stl or .bt, in any case)");
  }
  // The file's own geometry is counted before the floor is added: a floor would hide a file that
  // T_world_file placed wholly outside the box. (A box holding no voxel centre is validateScene's to name.)
  Index3 lo, hi;
  scene.geometry().centreRange(spec.box, lo, hi);
  if ((hi.array() > lo.array()).all() && !anyOccupied(scene, lo, hi))
    return R::Error(spec.file + ": no geometry falls inside the exploration box (check T_world_file and box)");
  if (spec.ground_plane) {
    const auto& geo = scene.geometry();
    const int kz = geo.coordToIndex(spec.box.min + Vec3::Constant(1e-6 * spec.resolution)).z();
    if (kz >= 0 && kz < geo.dims().z())
      for (int y = 0; y < geo.dims().y(); ++y)
        for (int x = 0; x < geo.dims().x(); ++x) scene.occupied.at(Index3(x, y, kz)) = 1;
  }
  if (auto st = validateScene(scene); !st) return st;
  return scene;
}

common::Result<Scene> loadSceneYaml(const std::string& yaml_path) {
  auto spec = parseSceneYaml(yaml_path);
  if (!spec) return spec.status();
  auto scene = loadSceneFile(*spec);
  if (!scene) return common::Result<Scene>::Error(yaml_path + ": " + scene.message());
  return scene;
}

namespace {

// A scene YAML whose `scene.generator` is `maze`: the procedural maze with the sizes given under
// `scene.maze` (size_x, size_y, height, cell_size; each optional, the defaults otherwise) and an optional
// name; no other key.
common::Result<Scene> loadGeneratedYaml(const std::string& yaml_path, const YAML::Node& root, std::uint64_t seed) {
  using R = common::Result<Scene>;
  try {
    checkKeys(root, "", {"scene"});
    const YAML::Node s = root["scene"];
    checkKeys(s, "scene.", {"name", "generator", "maze"});
    const YAML::Node generator = require(s, "generator", "scene.");
    if (!generator.IsScalar() || generator.Scalar() != "maze")
      throw KeyError{"key 'scene.generator' must be 'maze' (the only generator a YAML can size)"};
    MazeConfig config;
    if (const YAML::Node m = s["maze"]) {
      if (!m.IsMap()) throw KeyError{"key 'scene.maze' must be a map"};
      checkKeys(m, "scene.maze.", {"size_x", "size_y", "height", "cell_size"});
      if (m["size_x"]) config.size_x = number(m["size_x"], "scene.maze.size_x");
      if (m["size_y"]) config.size_y = number(m["size_y"], "scene.maze.size_y");
      if (m["height"]) config.height = number(m["height"], "scene.maze.height");
      if (m["cell_size"]) config.cell_size = number(m["cell_size"], "scene.maze.cell_size");
    }
    if (auto st = config.validate(); !st) throw KeyError{st.message()};
    auto scene = generateMaze(config, seed);
    if (!scene) return R::Error(yaml_path + ": " + scene.message());
    if (s["name"]) scene->name = sceneName(s["name"]);
    return scene;
  } catch (const KeyError& e) {
    return R::Error(yaml_path + ": " + e.message);
  } catch (const YAML::Exception& e) {
    return R::Error(yaml_path + ": malformed scene description (" + e.what() + ")");
  }
}

}  // namespace

common::Result<Scene> makeScene(const std::string& spec, std::uint64_t seed) {
  if (spec == "maze") return generateMaze(MazeConfig(), seed);
  if (spec == "powerplant") return generatePowerplant(PowerplantConfig(), seed);
  const std::string ext = lowerExtension(spec);
  if (ext == ".yaml" || ext == ".yml") {
    std::error_code ec;
    if (!fs::is_regular_file(spec, ec)) return common::Result<Scene>::Error(spec + ": file not found");
    YAML::Node root;
    try {
      root = YAML::LoadFile(spec);
    } catch (const std::exception& e) {
      return common::Result<Scene>::Error(spec + ": cannot be read as YAML (" + e.what() + ")");
    }
    if (root.IsMap() && root["scene"] && root["scene"].IsMap() && root["scene"]["generator"])
      return loadGeneratedYaml(spec, root, seed);
    return loadSceneYaml(spec);
  }
  return common::Result<Scene>::Error("unknown scene '" + spec +
                                      "': expected maze, powerplant or the path of a scene .yaml");
}

}  // namespace go_feap::world
