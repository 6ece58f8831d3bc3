// OctoMap .bt export and import of the occupancy map, and the checked reader of .bt files.
#include <octomap/OcTree.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <vector>

#include "go_feap/map/octomap_file.h"
#include "go_feap/map/voxel_map.h"

namespace go_feap::map {

namespace {

// OctoMap's reader recurses once per inner node it is told of, without a limit: garbage that marks every
// child "inner" made 100,000 nested calls and overflowed the stack. The tree's data is walked here first,
// without recursion: each node is two bytes of child codes (two bits per child, 11 = a node with children
// of its own, whose bytes follow depth first), and an OctoMap tree is 16 levels deep. "" when it fits.
std::string nestingProblem(const std::string& bytes, std::size_t data_start) {
  constexpr int kTreeDepth = 16;
  struct Level {
    int depth;
    int inner_left;  // children of this node with children, not yet read
  };
  std::vector<Level> stack;
  std::size_t at = data_start;
  auto read_node = [&](int depth) -> std::string {
    if (at + 2 > bytes.size()) return "truncated tree data";
    int inner = 0;
    for (int b = 0; b < 2; ++b) {
      const auto codes = static_cast<unsigned char>(bytes[at + b]);
      for (int i = 0; i < 4; ++i) inner += ((codes >> (2 * i)) & 3u) == 3u;
    }
    at += 2;
    if (inner > 0 && depth + 1 >= kTreeDepth)
      return "tree data nested deeper than " + std::to_string(kTreeDepth) + " levels";
    if (inner > 0) stack.push_back({depth + 1, inner});
    return "";
  };
  if (std::string e = read_node(0); !e.empty()) return e;
  while (!stack.empty()) {
    Level& top = stack.back();
    if (top.inner_left == 0) {
      stack.pop_back();
      continue;
    }
    --top.inner_left;
    if (std::string e = read_node(top.depth); !e.empty()) return e;
  }
  return "";
}

// Where the tree data begins, after the header lines that follow the first: each empty, a comment, 'id X',
// 'size N' or 'res R' (R > 0), and last a line 'data'. OctoMap reads the header word by word ('id' takes
// the next word, on the next line if need be), so a header outside these lines could make it start the
// data elsewhere than this check walked: 'id' alone on its line took the 'data' below as its value.
// Sets `problem` and returns npos on a line that is none of these. `empty` tells whether the header said
// 'size 0': OctoMap writes no tree data for an empty tree.
std::size_t treeDataStart(const std::string& bytes, std::string& problem, bool& empty) {
  empty = false;
  std::size_t at = bytes.find('\n');  // the first line was checked
  for (int number = 2; at != std::string::npos; ++number) {
    const std::size_t begin = at + 1;
    const std::size_t end = bytes.find('\n', begin);
    if (end == std::string::npos) break;
    std::string line = bytes.substr(begin, end - begin);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::vector<std::string> w;
    for (std::string word; words >> word;) w.push_back(word);
    at = end;
    if (w.empty() || w[0][0] == '#') continue;
    if (w.size() == 1 && w[0] == "data") return end + 1;
    const bool keyed = w.size() == 2 && (w[0] == "id" || w[0] == "size" || w[0] == "res");
    if (keyed && w[0] == "res") {
      char* rest = nullptr;
      const double res = std::strtod(w[1].c_str(), &rest);
      if (*rest != '\0' || !(res > 0.0) || !std::isfinite(res)) {
        problem = "res '" + w[1] + "' on header line " + std::to_string(number) + " is no resolution > 0";
        return std::string::npos;
      }
    }
    if (keyed && w[0] == "size") empty = w[1] == "0";
    if (!keyed) {
      problem = "header line " + std::to_string(number) + " '" + line.substr(0, 40) +
                "' is none of a comment, 'id X', 'size N', 'res R' or 'data'";
      return std::string::npos;
    }
  }
  problem = "no 'data' line";
  return std::string::npos;
}

}  // namespace

common::Result<std::unique_ptr<octomap::OcTree>> readOctree(const std::string& path) {
  using R = common::Result<std::unique_ptr<octomap::OcTree>>;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return R::Error(path + ": file not found");
  std::ifstream in(path, std::ios::binary);
  std::string first_line;
  std::getline(in, first_line);
  if (first_line.rfind("# Octomap OcTree binary file", 0) != 0)
    return R::Error(path + ": not an OctoMap binary (.bt) file (bad header)");
  in.seekg(0);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) return R::Error(path + ": read error");
  std::string header_problem;
  bool empty = false;
  const std::size_t data_start = treeDataStart(bytes, header_problem, empty);
  if (data_start == std::string::npos) return R::Error(path + ": corrupt OctoMap file (" + header_problem + ")");
  // An empty tree (a map saved before its first scan) has no data to walk.
  if (!(empty && data_start == bytes.size()))
    if (const std::string e = nestingProblem(bytes, data_start); !e.empty())
      return R::Error(path + ": corrupt OctoMap file (" + e + ")");
  // OctoMap's reader reports problems on std::cerr and returns false; read into a tree
  // first and check the stream, so truncated files are caught as well.
  std::istringstream data(bytes);
  auto tree = std::make_unique<octomap::OcTree>(0.1);
  if (!tree->readBinary(data)) return R::Error(path + ": corrupt or truncated OctoMap file");
  for (auto it = tree->begin_leafs(), end = tree->end_leafs(); it != end; ++it)
    if (!std::isfinite(it.getX()) || !std::isfinite(it.getY()) || !std::isfinite(it.getZ()))
      return R::Error(path + ": corrupt OctoMap file (non-finite leaf coordinate)");
  return tree;
}

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
  return writeOctree(tree, path);
}

common::Status writeOctree(const octomap::OcTree& tree, const std::string& path) {
  const std::string part = path + ".part";
  {
    std::ofstream out(part, std::ios::binary);
    if (!out || !tree.writeBinaryConst(out) || !out.flush()) {
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
  auto read = readOctree(path);
  if (!read) return read.status();
  const octomap::OcTree& tree = **read;
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
