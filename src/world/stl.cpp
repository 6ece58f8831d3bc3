#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "go_feap/world/scene_files.h"

namespace go_feap::world {

namespace {

using R = common::Result<TriangleMesh>;

R parseBinary(const std::string& path, const std::string& bytes, std::uint32_t count) {
  TriangleMesh mesh;
  mesh.vertices.reserve(3 * static_cast<std::size_t>(count));
  for (std::uint32_t t = 0; t < count; ++t) {
    const char* rec = bytes.data() + 84 + 50 * static_cast<std::size_t>(t);
    float v[12];
    std::memcpy(v, rec, sizeof(v));  // normal, then three vertices (little endian)
    for (int k = 0; k < 3; ++k) {
      const Vec3 p(v[3 + 3 * k], v[4 + 3 * k], v[5 + 3 * k]);
      if (!p.allFinite())
        return R::Error(path + ": triangle " + std::to_string(t) + " has a NaN or Inf vertex");
      mesh.vertices.push_back(p);
    }
  }
  return mesh;
}

R parseAscii(const std::string& path, const std::string& text) {
  std::istringstream in(text);
  std::string word;
  TriangleMesh mesh;
  bool ended = false;
  std::size_t line_vertices = 0;
  while (in >> word) {
    if (word == "vertex") {
      std::string xs, ys, zs;
      if (!(in >> xs >> ys >> zs))
        return R::Error(path + ": truncated ASCII STL (vertex " + std::to_string(mesh.vertices.size()) +
                        " has fewer than 3 coordinates)");
      Vec3 p;
      // Whole words only: std::stod alone read "2abc" as 2.
      auto whole = [](const std::string& s) {
        std::size_t used = 0;
        const double v = std::stod(s, &used);
        if (used != s.size()) throw std::invalid_argument(s);
        return v;
      };
      try {
        p = Vec3(whole(xs), whole(ys), whole(zs));
      } catch (const std::exception&) {
        return R::Error(path + ": corrupt ASCII STL (vertex " + std::to_string(mesh.vertices.size()) +
                        " has a non-numeric coordinate)");
      }
      if (!p.allFinite())
        return R::Error(path + ": vertex " + std::to_string(mesh.vertices.size()) + " is NaN or Inf");
      mesh.vertices.push_back(p);
      ++line_vertices;
    } else if (word == "endloop") {
      if (line_vertices != 3)
        return R::Error(path + ": corrupt ASCII STL (facet " + std::to_string(mesh.triangleCount()) +
                        " has " + std::to_string(line_vertices) + " vertices, expected 3)");
      line_vertices = 0;
    } else if (word == "endsolid") {
      ended = true;
      break;
    }
  }
  if (!ended) return R::Error(path + ": truncated ASCII STL (no 'endsolid')");
  if (line_vertices != 0 || mesh.vertices.size() % 3 != 0)
    return R::Error(path + ": truncated ASCII STL (last facet incomplete)");
  return mesh;
}

}  // namespace

common::Result<TriangleMesh> loadStl(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) return R::Error(path + ": file not found");
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (!in.good() && !in.eof()) return R::Error(path + ": read error");

  R result = R::Error("");
  if (bytes.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);
    if (bytes.size() == 84 + 50 * static_cast<std::size_t>(count)) {
      result = parseBinary(path, bytes, count);
      if (result && result->vertices.empty()) return R::Error(path + ": the mesh has no triangles");
      return result;
    }
  }
  // Not a well-formed binary file: ASCII if it says so, else a broken binary file.
  const auto first = bytes.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && bytes.compare(first, 5, "solid") == 0 &&
      bytes.find("facet") != std::string::npos) {
    result = parseAscii(path, bytes);
  } else if (bytes.size() >= 84) {
    std::uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);
    return R::Error(path + ": truncated or corrupt binary STL (header declares " + std::to_string(count) +
                    " triangles, i.e. " + std::to_string(84 + 50 * static_cast<std::size_t>(count)) +
                    " bytes, but the file has " + std::to_string(bytes.size()) + ")");
  } else {
    return R::Error(path + ": too short for an STL file (" + std::to_string(bytes.size()) + " bytes)");
  }
  if (result && result->vertices.empty()) return R::Error(path + ": the mesh has no triangles");
  return result;
}

}  // namespace go_feap::world
