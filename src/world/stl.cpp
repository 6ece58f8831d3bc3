#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

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

// The words of an ASCII STL, each with the number of the line it stands on. STL separates its
// words by any white space, so a facet may span lines or share one; some writers put its keywords in upper
// case (SOLID, FACET NORMAL): keywords are compared in lower case.
class StlWords {
 public:
  explicit StlWords(const std::string& text) : text_(text) {}
  /// The next word into `word`; false at the end of the text.
  bool next(std::string& word) {
    if (!pending_.empty()) {
      word = std::move(pending_);
      pending_.clear();
      return true;
    }
    while (!(words_ >> word)) {
      if (!std::getline(text_, line_text_)) return false;
      ++line_;
      words_.clear();
      words_.str(line_text_);
    }
    return true;
  }
  /// Skips a solid's name: the rest of the current line, up to a word `stop` on it (some writers put the
  /// first 'facet' on the 'solid' line, or the next 'solid' after an 'endsolid'), which is read next; true
  /// when it met `stop`.
  bool skipName(const char* stop) {
    std::string word;
    while (words_ >> word)
      if (asciiLower(word) == stop) {
        pending_ = stop;
        return true;  // the rest of the line follows it
      }
    return false;
  }
  std::size_t line() const { return line_; }

 private:
  std::istringstream text_, words_;
  std::string line_text_, pending_;
  std::size_t line_ = 0;
};

// A whole word read as a number into `v`: "" when it is one, else what is wrong with it. Every word must be
// whole (std::stod alone read "2abc" as 2); 1e999 overflows (a value too small for a double is read as ~0).
std::string numberProblem(const std::string& word, double& v) {
  errno = 0;
  char* end = nullptr;
  v = std::strtod(word.c_str(), &end);
  if (end == word.c_str() || *end != '\0') return "a non-numeric coordinate '" + word + "'";
  if (errno == ERANGE && std::isinf(v)) return "a coordinate '" + word + "' out of range";
  return "";
}

// Every `solid ... endsolid` block of an ASCII STL, facet by facet: facet normal n n n, outer loop, three
// vertex x y z, endloop, endfacet. A word out of place is refused with its line (a fourth coordinate, words
// between facets were skipped; a second solid was dropped).
R parseAscii(const std::string& path, const std::string& text) {
  StlWords words(text);
  TriangleMesh mesh;
  std::string word;
  auto corrupt = [&](const std::string& what) {
    return R::Error(path + ": corrupt ASCII STL (line " + std::to_string(words.line()) + ": " + what + ")");
  };
  auto truncated = [&]() {
    return R::Error(path + ": truncated ASCII STL (it ends inside facet " + std::to_string(mesh.triangleCount()) +
                    " or before 'endsolid')");
  };
  auto is = [&](const std::string& keyword) { return asciiLower(word) == keyword; };  // SOLID as solid
  auto got = [&](const std::string& want) { return "expected " + want + ", got '" + word + "'"; };
  bool on_endsolid_line = false;  // this 'solid' followed an 'endsolid' on its line
  while (words.next(word)) {
    if (!is("solid")) return corrupt(got(mesh.vertices.empty() ? "'solid'" : "'solid' or the end of the file"));
    words.skipName("facet");
    const std::size_t first_facet = mesh.triangleCount();
    while (true) {
      if (!words.next(word)) {
        // The file ends with the line of the last 'endsolid': its 'solid' was part of a name
        // ("endsolid Solid Body 1", as some CAD tools write), not a solid of its own.
        if (on_endsolid_line && mesh.triangleCount() == first_facet) return mesh;
        return truncated();
      }
      if (on_endsolid_line && mesh.triangleCount() == first_facet && is("solid")) {  // so was that one
        on_endsolid_line = false;
        words.skipName("facet");
        continue;
      }
      if (is("endsolid")) break;
      if (!is("facet")) return corrupt(got("'facet' or 'endsolid'"));
      const std::size_t facet = mesh.triangleCount();
      double normal = 0.0;  // not used: the triangle's winding is what the voxelizer needs, not its normal
      for (const std::string want : {"normal", "", "", "", "outer", "loop"}) {
        if (!words.next(word)) return truncated();
        if (want.empty()) {
          if (std::string e = numberProblem(word, normal); !e.empty()) return corrupt("facet " + std::to_string(facet) + " has " + e);
        } else if (!is(want)) {
          return corrupt(got("'" + want + "'"));
        }
      }
      for (int k = 0; k < 3; ++k) {
        if (!words.next(word)) return truncated();
        if (is("endloop"))
          return corrupt("facet " + std::to_string(facet) + " has " + std::to_string(k) + " vertices, expected 3");
        if (!is("vertex")) return corrupt(got("'vertex'"));
        Vec3 p;
        for (int a = 0; a < 3; ++a) {
          if (!words.next(word)) return truncated();
          if (std::string e = numberProblem(word, p[a]); !e.empty())
            return corrupt("vertex " + std::to_string(mesh.vertices.size()) + " has " + e);
        }
        if (!p.allFinite())
          return R::Error(path + ": vertex " + std::to_string(mesh.vertices.size()) + " (line " +
                          std::to_string(words.line()) + ") is NaN or Inf");
        mesh.vertices.push_back(p);
      }
      for (const char* want : {"endloop", "endfacet"}) {
        if (!words.next(word)) return truncated();
        if (is("vertex") && std::string(want) == "endloop")
          return corrupt("facet " + std::to_string(facet) + " has more than 3 vertices, expected 3");
        if (!is(want)) return corrupt(got("'" + std::string(want) + "'"));
      }
    }
    on_endsolid_line = words.skipName("solid");
  }
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
  // Not a well-formed binary file: ASCII if it says so and is text (no control bytes but white space), else a
  // broken binary file. (A binary file's 80-byte header may start with 'solid' too; an ASCII one was
  // recognised by 'facet' in it, so an empty solid was "too short" and a binary header saying 'solid ...
  // facet' gave "truncated ASCII STL".)
  const auto first = bytes.find_first_not_of(" \t\r\n");
  const std::size_t text_end = bytes.find_last_not_of('\0') + 1;  // NUL padding after the text is no binary sign
  const bool text = std::none_of(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(text_end), [](char c) {
    const auto b = static_cast<unsigned char>(c);
    return (b < 0x20 && !std::isspace(b)) || b == 0x7f;
  });
  if (first != std::string::npos && asciiLower(bytes.substr(first, 5)) == "solid" && text) {
    result = parseAscii(path, bytes.substr(0, text_end));
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
