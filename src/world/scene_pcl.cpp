// The only translation unit of the world module that includes PCL (slow headers).
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "go_feap/world/scene_files.h"

namespace go_feap::world {

namespace fs = std::filesystem;

namespace {

// One element of a PLY header (vertex, face, camera ...), in the order the data holds them.
struct PlyElement {
  std::string name;
  double count = 0.0;
  double bytes = 0.0;      ///< binary bytes of an instance: its scalars and each list's length field
  double values = 0.0;     ///< properties
  bool list = false;       ///< a list property: instances vary in length
  bool known = true;       ///< every property type is one PLY defines
  std::string face_list;   ///< face: its vertex_indices (or vertex_index) list's count and index types, "uchar int"
};

// What a point cloud's header declares, read without PCL (which allocates what a header declares before
// it reads a byte). `data` is empty for a header this parser does not recognise (PCL judges those).
struct CloudHeader {
  double points = 0.0;     ///< declared points (PLY: vertices)
  double per_point = 0.0;  ///< binary bytes per point (PLY: of a vertex, list contents not counted)
  double values = 0.0;     ///< values per point
  double room = 0.0;       ///< bytes after the header
  std::streamoff data_start = -1;  ///< where the data begins (-1: unknown)
  std::string data;        ///< PCD: ascii, binary, binary_compressed (as PCL reads data_word); PLY: ascii, binary_*
  std::string data_word;   ///< PCD: the word after DATA, as written
  bool data_line = false;  ///< PCD: a DATA line came
  bool fields = false;     ///< PCD: a FIELDS line came before DATA
  std::string bad_line;    ///< PCD: the first header line that is no PCD header line, with its number ("" if none)
  std::vector<std::pair<char, int>> columns;  ///< PCD: each value of a row's TYPE and SIZE (fields by COUNT)
  std::vector<PlyElement> elements;  ///< PLY
};

// Bytes of a PLY scalar type, 0 for a name PLY does not define.
double plyTypeBytes(const std::string& type) {
  for (const char* t : {"char", "uchar", "int8", "uint8"})
    if (type == t) return 1.0;
  for (const char* t : {"short", "ushort", "int16", "uint16"})
    if (type == t) return 2.0;
  for (const char* t : {"int", "uint", "float", "int32", "uint32", "float32"})
    if (type == t) return 4.0;
  if (type == "double" || type == "float64") return 8.0;
  return 0.0;
}

// How PCL's PCDReader reads the word after DATA: by its prefix, binary_compressed or binary (lower case), and
// every other word as ascii ("ASCII" and "foo" alike).
std::string pclDataKind(const std::string& word) {
  if (word.rfind("binary_compressed", 0) == 0) return "binary_compressed";
  if (word.rfind("binary", 0) == 0) return "binary";
  return "ascii";
}

// A DATA word that is none of PCL's three (ascii in any case, binary, binary_compressed): PCL would read
// "foo" or "Binary" data as ASCII text and "binary_lzf" as binary. "" for a known word.
std::string pcdDataWordProblem(const std::string& path, const CloudHeader& h) {
  if (asciiLower(h.data_word) == "ascii" || h.data_word == "binary" || h.data_word == "binary_compressed") return "";
  return path + ": corrupt PCD file (DATA '" + h.data_word + "': expected ascii, binary or binary_compressed)";
}

CloudHeader readCloudHeader(const std::string& path, const std::string& kind) {
  CloudHeader h;
  std::ifstream in(path, std::ios::binary);
  const double file_size = static_cast<double>(fs::file_size(path));
  std::string line;
  double width = 0.0, height = 1.0;
  std::vector<double> sizes, counts;
  std::vector<char> types;
  auto numbers = [](std::istringstream& s) {
    std::vector<double> out;
    double v = 0.0;
    while (s >> v) out.push_back(v);
    return out;
  };
  for (int i = 0; i < 4096 && std::getline(in, line); ++i) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream words(line);
    std::string key;
    words >> key;
    if (kind == "PCD") {
      // Every line before DATA empty, a comment or one of PCD's keywords, exactly. PCL's header reader stops
      // at any other line and reads the points from the file's first byte (a 'FOO bar' line gave points at
      // the origin), and it matches keys by their prefix ('POINTS_ 1e8' sized its buffer at 1.2 GB).
      static const std::set<std::string> kKeys = {"VERSION", "FIELDS", "SIZE",   "TYPE", "COUNT",
                                                  "WIDTH",   "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
      if (!line.empty() && key.rfind('#', 0) != 0 && kKeys.count(key) == 0) {
        h.bad_line = "line " + std::to_string(i + 1) + " '" + line.substr(0, 40) + "'";
        break;
      }
      if (key == "FIELDS") h.fields = true;
      else if (key == "TYPE") for (std::string t; words >> t;) types.push_back(t.size() == 1 ? t[0] : '?');
      else if (key == "SIZE") sizes = numbers(words);
      else if (key == "COUNT") counts = numbers(words);
      else if (key == "WIDTH") words >> width;
      else if (key == "HEIGHT") words >> height;
      else if (key == "POINTS") words >> h.points;
      else if (key == "DATA") {
        words >> h.data_word;
        h.data_line = true;
        h.data = pclDataKind(h.data_word);
        break;
      }
    } else {
      if (key == "format") words >> h.data;
      else if (key == "element") {
        PlyElement e;
        words >> e.name >> e.count;
        h.elements.push_back(e);
      } else if (key == "property" && !h.elements.empty()) {
        PlyElement& e = h.elements.back();
        std::string type, length_type;
        words >> type;
        if (type == "list") {
          std::string index_type, name;
          words >> length_type >> index_type >> name;
          e.list = true;
          if (e.name == "face" && (name == "vertex_indices" || name == "vertex_index"))
            e.face_list = length_type + " " + index_type;
          type = length_type;
        }
        const double bytes = plyTypeBytes(type);
        e.known = e.known && bytes > 0.0;
        e.bytes += bytes;
        e.values += 1.0;
      } else if (key == "end_header") break;
    }
  }
  for (const PlyElement& e : h.elements)
    if (e.name == "vertex") h.points = e.count, h.values = e.values, h.per_point = e.bytes;
  if (kind == "PCD") {
    h.points = std::max(h.points, width * height);
    for (std::size_t f = 0; f < sizes.size(); ++f) {
      const double count = f < counts.size() ? counts[f] : 1.0;
      h.per_point += sizes[f] * count;
      h.values += count;
      for (double c = 0.0; c < count && h.columns.size() < 4096; c += 1.0)  // (a row of more is refused anyway)
        h.columns.emplace_back(f < types.size() ? types[f] : '?',
                               sizes[f] >= 1.0 && sizes[f] <= 8.0 ? static_cast<int>(sizes[f]) : 0);
    }
  }
  const double header_end = in ? static_cast<double>(in.tellg()) : file_size;
  h.room = std::max(0.0, file_size - header_end);
  h.data_start = in ? static_cast<std::streamoff>(in.tellg()) : -1;
  return h;
}

// Whether the value `v` of a row's `column` fits its type: "" when it does, else why not. Nothing checked: "".
using ValueCheck = std::function<std::string(std::size_t column, double v)>;

// Walks the non-blank text rows from `start`, handing `row` each row's index, its number of words and its
// first word that is no number, or no value `check` takes, quoted with why ("" when all are good). Stops at
// the first problem `row` returns, and returns it; "" when every row passed, with their number in `rows`.
std::string scanRows(const std::string& path, std::streamoff start, std::size_t& rows,
                     const std::function<std::string(std::size_t, double, const std::string&)>& row,
                     const ValueCheck& check = nullptr) {
  std::ifstream in(path, std::ios::binary);
  in.seekg(start);
  std::string line, word;
  rows = 0;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.find_first_not_of(" \t") == std::string::npos) continue;
    std::istringstream words(line);
    double n = 0.0;
    std::string bad;
    while (words >> word) {
      char* end = nullptr;
      const double v = std::strtod(word.c_str(), &end);
      if (bad.empty() && end != word.c_str() + word.size()) bad = "'" + word + "', not a number";
      if (bad.empty() && check)
        if (const std::string why = check(static_cast<std::size_t>(n), v); !why.empty()) bad = "'" + word + "', " + why;
      n += 1.0;
    }
    if (std::string problem = row(rows, n, bad); !problem.empty()) return problem;
    ++rows;
  }
  return "";
}

// A text row's problem: `bad` (its first bad word, quoted with why) or a count `n` of words other than
// `want`, named as `prefix` + `index`; "" for a good row (the message is built only for a bad one).
std::string rowProblem(const std::string& prefix, long long index, double n, const std::string& bad, double want) {
  if (bad.empty() && n == want) return "";
  const std::string where = prefix + std::to_string(index) + " has ";
  if (!bad.empty()) return where + bad + ")";
  return where + std::to_string(std::llround(n)) + " values, the header " + std::to_string(std::llround(want)) + ")";
}

// An ASCII PCD's rows, each with the header's number of values, each a whole number. PCL's reader takes
// rows with too few or too many values and words that are no numbers without a word (a file declaring 4
// points with "2 2", "3 3 3 3" and "foo bar baz" rows loaded as if whole). "" when every row is right.
std::string asciiRowsProblem(const std::string& path, const CloudHeader& h) {
  if (h.data != "ascii" || h.data_start < 0) return "";
  const std::string prefix = path + ": corrupt PCD file (row ";
  std::size_t rows = 0;
  // Integer fields take whole numbers in their range: PCL wrapped 300 in a U1 field to 44 and cut 2.7 to 2.
  const ValueCheck fits = [&](std::size_t column, double v) -> std::string {
    if (column >= h.columns.size()) return "";
    const auto [type, size] = h.columns[column];
    if ((type != 'U' && type != 'I') || size == 0) return "";
    const double bits = 8.0 * size;
    const double lo = type == 'U' ? 0.0 : -std::pow(2.0, bits - 1.0);
    const double hi = type == 'U' ? std::pow(2.0, bits) - 1.0 : std::pow(2.0, bits - 1.0) - 1.0;
    if (v == std::floor(v) && v >= lo && v <= hi) return "";
    return std::string("not a whole number in the range of its field's type ") + type + std::to_string(size);
  };
  const std::string problem = scanRows(
      path, h.data_start, rows,
      [&](std::size_t r, double n, const std::string& bad) {
        return rowProblem(prefix, static_cast<long long>(r) + 1, n, bad, h.values);
      },
      fits);
  if (!problem.empty()) return problem;
  if (static_cast<double>(rows) != h.points)
    return path + ": corrupt PCD file (its header declares " + std::to_string(std::llround(h.points)) + " points, it has " +
           std::to_string(rows) + " rows)";
  return "";
}

// Binary data with a whole point (PLY: vertex) or more after the `bytes` its header declares: data the header
// does not count. Less is padding (a trailing newline). "" when there is less.
std::string surplusProblem(const std::string& path, const std::string& kind, const CloudHeader& h, double bytes) {
  if (h.room - bytes < std::max(1.0, h.per_point)) return "";
  std::ostringstream why;
  why << path << ": corrupt " << kind << " file (" << h.room - bytes << " bytes after the " << bytes
      << " its header declares, " << h.points << (kind == "PLY" ? " vertices)" : " points)");
  return why.str();
}

// A PLY's data against its header. ASCII: one row per element instance, as many as declared in all (PCL
// read the declared vertices and dropped rows beyond them without a word), and every vertex row whole
// numbers, as many as the vertex has properties. Binary without list properties: the bytes the header
// declares, with less than a vertex's worth after them (a whole vertex more is a row the header does not
// count; a byte or two of padding is not). "" when the data matches.
std::string plyDataProblem(const std::string& path, const CloudHeader& h) {
  if (h.data_start < 0 || h.elements.empty()) return "";
  // PCL (1.13) reads a face's indices only from these lists: of any other types it hands back empty faces.
  for (const PlyElement& e : h.elements) {
    if (e.face_list.empty()) continue;
    std::istringstream types(e.face_list);
    std::string count, index;
    types >> count >> index;
    const bool wide = count == "int" || count == "uint" || count == "int32" || count == "uint32";
    const bool byte_count = count == "uchar" || count == "uint8";
    const bool int_index = index == "int" || index == "uint" || index == "int32" || index == "uint32";
    if (!(wide || (byte_count && int_index)))
      return path + ": PLY file's face list is 'list " + e.face_list +
             "', which cannot be read (faces are read as lists of int or uint indices counted by a uchar, or "
             "of any indices counted by an int or uint)";
  }
  // Every element's least bytes (a list's length field each; its entries may be none), against the file:
  // PCL reserves the faces a header declares before it reads one (1e9 faces declared in 200 bytes: 24 GB).
  if (h.data.rfind("binary", 0) == 0) {
    double least = 0.0;
    for (const PlyElement& e : h.elements) {
      // An element without properties takes no bytes, however many it declares: PCL loops over (and for faces
      // reserves) them all.
      if (e.count > 0.0 && e.values == 0.0)
        return path + ": corrupt PLY file (its element '" + e.name + "' declares " + std::to_string(std::llround(e.count)) +
               " instances but no property)";
      least += e.count * e.bytes;
    }
    if (least > h.room) {
      std::ostringstream why;
      why << path << ": corrupt or truncated PLY file (its header declares elements that need at least " << least
          << " bytes of data, but the file holds " << h.room << ")";
      return why.str();
    }
  }
  double declared = 0.0, bytes = 0.0;
  bool exact = true;
  for (const PlyElement& e : h.elements) {
    declared += e.count;
    bytes += e.count * e.bytes;
    exact = exact && e.known && !e.list;
  }
  if (h.data == "ascii") {
    const std::string prefix = path + ": corrupt PLY file (vertex ";
    std::size_t rows = 0;
    const std::string problem = scanRows(path, h.data_start, rows, [&](std::size_t r, double n, const std::string& bad) {
      double first = 0.0;  // the element row r belongs to
      for (const PlyElement& e : h.elements) {
        if (static_cast<double>(r) < first + e.count) {
          if (e.name != "vertex" || e.list) return std::string();
          return rowProblem(prefix, std::llround(r - first), n, bad, e.values);
        }
        first += e.count;
      }
      return std::string();
    });
    if (!problem.empty()) return problem;
    if (static_cast<double>(rows) != declared)
      return path + ": corrupt PLY file (its header declares " + std::to_string(std::llround(declared)) +
             " rows in all, " + std::to_string(std::llround(h.points)) + " of them vertices; it has " +
             std::to_string(rows) + ")";
  } else if (exact) {
    return surplusProblem(path, "PLY", h, bytes);
  }
  return "";
}

// The least number of bytes the data needs by its header, against the file's size: a 154-byte ASCII PCD
// declaring 3e8 points took 3.6 GB and 20 s in PCL; COUNT 1e9 asked for 12 GB. ASCII values take at least
// two characters (a digit and a separator), binary ones their SIZE (PLY: a byte at least), and LZF expands
// data at most about 100-fold. "" when the declared count fits.
std::string declaredSizeProblem(const std::string& path, const std::string& kind, const CloudHeader& h) {
  if (h.data.empty() || !(h.points > 0.0)) return "";
  double least = 0.0;
  if (h.data == "ascii") least = h.points * 2.0 * h.values;
  else if (h.data == "binary_compressed") least = h.points * h.per_point / 100.0;
  else least = h.points * h.per_point;
  if (least <= h.room) return "";
  std::ostringstream why;
  why << path << ": corrupt or truncated " << kind << " file (its header declares " << h.points
      << " points, which need at least " << least << " bytes of data, but the file holds " << h.room << ")";
  return why.str();
}

common::Status checkPcdSize(pcl::PCDReader& reader, const std::string& path) {
  pcl::PCLPointCloud2 header;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0, data_type = 0;
  unsigned int data_idx = 0;
  if (reader.readHeader(path, header, origin, orientation, version, data_type, data_idx) < 0 ||
      header.fields.empty() || header.point_step == 0)
    return common::Status::Error(path + ": corrupt PCD file (unreadable header)");
  // Binary data shorter than declared is refused before (declaredSizeProblem()).
  const std::uintmax_t size = fs::file_size(path);
  const std::uintmax_t points = static_cast<std::uintmax_t>(header.width) * header.height;
  if (data_type == 2) {
    std::uint32_t sizes[2] = {0, 0};
    std::ifstream in(path, std::ios::binary);
    in.seekg(data_idx);
    in.read(reinterpret_cast<char*>(sizes), sizeof(sizes));
    if (!in || size < data_idx + 8 + static_cast<std::uintmax_t>(sizes[0]) ||
        sizes[1] != points * header.point_step)
      return common::Status::Error(path + ": truncated or corrupt compressed PCD file");
  }
  return common::Status::Ok();
}

// Bytes of a PCLPointField datatype that holds a number, 0 for any other (BOOL, or a value no type has).
std::size_t fieldBytes(std::uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8:
    case pcl::PCLPointField::UINT8: return 1;
    case pcl::PCLPointField::INT16:
    case pcl::PCLPointField::UINT16: return 2;
    case pcl::PCLPointField::INT32:
    case pcl::PCLPointField::UINT32:
    case pcl::PCLPointField::FLOAT32: return 4;
    case pcl::PCLPointField::INT64:
    case pcl::PCLPointField::UINT64:
    case pcl::PCLPointField::FLOAT64: return 8;
    default: return 0;
  }
}

template <typename T>
double valueAt(const std::uint8_t* at) {
  T v;
  std::memcpy(&v, at, sizeof(v));  // the blob's points need not be aligned for T
  return static_cast<double>(v);
}

// The number of a type fieldBytes() accepts, stored at `at` (host byte order, as PCL's readers leave it).
double readNumber(const std::uint8_t* at, std::uint8_t datatype) {
  switch (datatype) {
    case pcl::PCLPointField::INT8: return valueAt<std::int8_t>(at);
    case pcl::PCLPointField::UINT8: return valueAt<std::uint8_t>(at);
    case pcl::PCLPointField::INT16: return valueAt<std::int16_t>(at);
    case pcl::PCLPointField::UINT16: return valueAt<std::uint16_t>(at);
    case pcl::PCLPointField::INT32: return valueAt<std::int32_t>(at);
    case pcl::PCLPointField::UINT32: return valueAt<std::uint32_t>(at);
    case pcl::PCLPointField::INT64: return valueAt<std::int64_t>(at);
    case pcl::PCLPointField::UINT64: return valueAt<std::uint64_t>(at);
    case pcl::PCLPointField::FLOAT32: return valueAt<float>(at);
    default: return valueAt<double>(at);
  }
}

}  // namespace

namespace {

// Appends the triangles of the face `polygon` (indices into `points`): its fan round the first vertex when every
// fan triangle turns the way the face does (the fan then covers the face exactly), else ear clipping in the
// plane of the face's Newell normal. A degenerate face (no normal) is fanned.
void triangulateFace(const std::vector<Vec3>& points, const std::vector<std::uint32_t>& polygon,
                     std::vector<std::array<std::uint32_t, 3>>& triangles) {
  const std::size_t n = polygon.size();
  // Newell's normal (twice the face's vector area), from the first vertex: far from the origin (a georeferenced
  // mesh) absolute coordinates would drown a small face's area in rounding.
  const Vec3 o = points[polygon[0]];
  Vec3 normal = Vec3::Zero();
  for (std::size_t i = 0; i < n; ++i) normal += (points[polygon[i]] - o).cross(points[polygon[(i + 1) % n]] - o);
  const auto turn = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    return (points[b] - points[a]).cross(points[c] - points[a]).dot(normal);
  };
  bool fan = normal.squaredNorm() == 0.0;
  if (!fan) {
    fan = true;
    for (std::size_t k = 1; k + 1 < n && fan; ++k) fan = turn(polygon[0], polygon[k], polygon[k + 1]) >= 0.0;
  }
  if (fan) {
    for (std::size_t k = 1; k + 1 < n; ++k) triangles.push_back({polygon[0], polygon[k], polygon[k + 1]});
    return;
  }
  // Ear clipping: a corner that turns the face's way and holds no other remaining vertex is cut off.
  std::vector<std::uint32_t> rest = polygon;
  const auto inside = [&](std::uint32_t p, std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    return turn(a, b, p) >= 0.0 && turn(b, c, p) >= 0.0 && turn(c, a, p) >= 0.0;
  };
  std::size_t from = 0;  // where the search for the next ear starts: beside the last one cut, not at the start
  while (rest.size() > 3) {
    const std::size_t m = rest.size();
    bool cut = false;
    for (std::size_t step = 0; step < m && !cut; ++step) {
      const std::size_t i = (from + step) % m;
      const std::uint32_t a = rest[(i + m - 1) % m], b = rest[i], c = rest[(i + 1) % m];
      if (!(turn(a, b, c) > 0.0)) continue;
      bool empty = true;
      for (std::size_t j = 0; j < m && empty; ++j) {
        const std::uint32_t p = rest[j];
        if (p != a && p != b && p != c && points[p] != points[a] && points[p] != points[b] && points[p] != points[c])
          empty = !inside(p, a, b, c);
      }
      if (!empty) continue;
      triangles.push_back({a, b, c});
      rest.erase(rest.begin() + static_cast<std::ptrdiff_t>(i));
      from = i == 0 ? 0 : i - 1;
      cut = true;
    }
    if (!cut) break;  // no ear (a self-crossing face): the rest is fanned
  }
  for (std::size_t k = 1; k + 1 < rest.size(); ++k) triangles.push_back({rest[0], rest[k], rest[k + 1]});
}

// PCL's verbosity is the process's: quiet while a file is read or written here (its diagnostics become one
// message of ours), then back to what it was, for the other users of PCL in a nodelet manager.
class QuietPcl {
 public:
  QuietPcl() : level_(pcl::console::getVerbosityLevel()) { pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS); }
  ~QuietPcl() { pcl::console::setVerbosityLevel(level_); }
  QuietPcl(const QuietPcl&) = delete;
  QuietPcl& operator=(const QuietPcl&) = delete;

 private:
  pcl::console::VERBOSITY_LEVEL level_;
};

}  // namespace

common::Result<PointCloudFile> loadPointCloudFile(const std::string& path) {
  using R = common::Result<PointCloudFile>;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return R::Error(path + ": file not found");
  const std::string ext = lowerExtension(path);
  const QuietPcl quiet;
  pcl::PCLPointCloud2 blob;
  std::vector<pcl::Vertices> faces;  // PLY
  CloudHeader header;
  int rc = -1;
  std::string kind;
  try {
    if (ext == ".pcd") {
      kind = "PCD";
      pcl::PCDReader reader;
      // PCL's binary reader maps the file and trusts the header (a truncated file
      // crashes it), so check the header against the file size first.
      header = readCloudHeader(path, kind);
      if (!header.bad_line.empty())
        return R::Error(path + ": corrupt PCD file (header " + header.bad_line +
                        " is no PCD header line: expected a comment or VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, "
                        "HEIGHT, VIEWPOINT, POINTS or DATA)");
      // PCL's header parser accepts text that is no PCD header at all; require the keywords.
      if (!header.fields || !header.data_line) return R::Error(path + ": corrupt PCD file (no FIELDS/DATA header)");
      if (const std::string e = pcdDataWordProblem(path, header); !e.empty()) return R::Error(e);
      if (const std::string e = declaredSizeProblem(path, kind, header); !e.empty()) return R::Error(e);
      if (header.data == "binary")
        if (const std::string e = surplusProblem(path, kind, header, header.points * header.per_point); !e.empty())
          return R::Error(e);
      if (const std::string e = asciiRowsProblem(path, header); !e.empty()) return R::Error(e);
      if (auto st = checkPcdSize(reader, path); !st) return st;
      rc = reader.read(path, blob);
    } else if (ext == ".ply") {
      kind = "PLY";
      pcl::PLYReader reader;
      header = readCloudHeader(path, kind);
      if (const std::string e = declaredSizeProblem(path, kind, header); !e.empty()) return R::Error(e);
      if (const std::string e = plyDataProblem(path, header); !e.empty()) return R::Error(e);
      // Read as a mesh: its faces (none for a plain cloud) come with the vertices.
      pcl::PolygonMesh mesh;
      rc = reader.read(path, mesh);
      blob = std::move(mesh.cloud);
      faces = std::move(mesh.polygons);
    } else {
      return R::Error(path + ": unknown point cloud extension '" + fs::path(path).extension().string() +
                      "' (expected .pcd or .ply, in any case)");
    }
  } catch (const std::exception& e) {
    return R::Error(path + ": corrupt " + kind + " file (" + e.what() + ")");
  }
  if (rc < 0) return R::Error(path + ": corrupt or truncated " + kind + " file (the PCL reader refused it)");
  // x, y and z are read at their offsets in their own types: converting to PointXYZ matched the names only,
  // and PCL left a field of another type (float64, an integer) at 0, so every point became (0, 0, 0).
  const char* const axes[3] = {"x", "y", "z"};
  const pcl::PCLPointField* xyz[3] = {nullptr, nullptr, nullptr};
  for (const auto& f : blob.fields)
    for (int a = 0; a < 3; ++a)
      if (f.name == axes[a]) {
        if (xyz[a]) return R::Error(path + ": " + kind + " file has the field '" + f.name + "' twice");
        xyz[a] = &f;
      }
  for (int a = 0; a < 3; ++a) {
    if (!xyz[a]) return R::Error(path + ": " + kind + " file has no x, y, z fields (no '" + axes[a] + "')");
    const pcl::PCLPointField& f = *xyz[a];
    const std::string field = path + ": " + kind + " file's field '" + f.name + "'";
    if (f.count != 1)
      return R::Error(field + " has COUNT " + std::to_string(f.count) + " (a coordinate must be one value)");
    const std::size_t bytes = fieldBytes(f.datatype);
    if (bytes == 0) return R::Error(field + " has type " + std::to_string(f.datatype) + ", which is no number");
    if (f.offset + bytes > blob.point_step)
      return R::Error(field + " lies past the end of a point (corrupt " + kind + " file)");
  }
  const std::size_t width = blob.width, height = blob.height;
  if (width * height == 0) return R::Error(path + ": the cloud is empty");
  if (blob.row_step < width * blob.point_step || blob.data.size() < (height - 1) * blob.row_step + width * blob.point_step)
    return R::Error(path + ": truncated " + kind + " file (header declares " + std::to_string(width * height) +
                    " points, data holds fewer)");
  PointCloudFile out;
  std::vector<Vec3>& points = out.points;
  points.reserve(width * height);
  for (std::size_t r = 0; r < height; ++r)
    for (std::size_t c = 0; c < width; ++c) {
      const std::uint8_t* point = blob.data.data() + r * blob.row_step + c * blob.point_step;
      Vec3 p;
      for (int a = 0; a < 3; ++a) p[a] = readNumber(point + xyz[a]->offset, xyz[a]->datatype);
      // x, y and z all NaN is PCL's "no point" (an organised cloud's pixel without a return): skipped,
      // where no face can name it. Anything else not finite is corrupt.
      if (p.array().isNaN().all() && faces.empty()) {
        ++out.skipped_points;
        continue;
      }
      if (!p.allFinite())
        return R::Error(path + ": point " + std::to_string(points.size() + out.skipped_points) + " is NaN or Inf");
      points.push_back(p);
    }
  if (points.empty())
    return R::Error(path + ": the cloud has no point (all " + std::to_string(out.skipped_points) +
                    " are NaN, PCL's mark of no point)");
  // Each face as triangles: a fan round its first vertex where that covers it (a convex face), else by ear
  // clipping in its plane (a concave one: a fan would fill in a doorway cut into a wall face).
  for (std::size_t f = 0; f < faces.size(); ++f) {
    const pcl::Indices& v = faces[f].vertices;
    const std::string face = path + ": PLY file's face " + std::to_string(f);
    if (v.size() < 3)
      return R::Error(face + " has " + std::to_string(v.size()) + " vertices (a face needs 3 at least)");
    for (const auto i : v)
      if (i < 0 || static_cast<std::size_t>(i) >= points.size())
        return R::Error(face + " names vertex " + std::to_string(i) + ", but the file has " +
                        std::to_string(points.size()) + " vertices (indices count from 0)");
    std::vector<std::uint32_t> polygon(v.begin(), v.end());
    triangulateFace(points, polygon, out.triangles);
  }
  return out;
}

common::Result<std::vector<Vec3>> loadPointCloud(const std::string& path) {
  auto file = loadPointCloudFile(path);
  if (!file) return file.status();
  return std::move(file->points);
}

common::Status saveScenePcd(const Scene& scene, const std::string& path) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  const auto& geo = scene.geometry();
  for (std::size_t l = 0; l < scene.occupied.size(); ++l) {
    if (!scene.occupied[l]) continue;
    const Vec3 c = geo.indexToCoord(geo.unlinear(l));
    cloud.push_back(pcl::PointXYZ(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z())));
  }
  if (cloud.empty()) return common::Status::Error(path + ": scene '" + scene.name + "' has no occupied voxels to write");
  const QuietPcl quiet;
  pcl::PCDWriter writer;
  if (writer.writeBinary(path, cloud) < 0) return common::Status::Error(path + ": cannot write PCD file");
  return common::Status::Ok();
}

}  // namespace go_feap::world
