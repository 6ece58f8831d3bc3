// Loaders (PCD, PLY, STL binary/ASCII, OctoMap .bt, scene YAML), round trips, the real
// scenes in ../shared/scenes, and every kind of bad input.
#include <gtest/gtest.h>
#include <octomap/OcTree.h>
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <tuple>

#include "go_feap/world/generators.h"
#include "go_feap/world/scene_files.h"
#include "go_feap/world/scene_image.h"

using namespace go_feap::world;
using go_feap::common::Index3;
namespace fs = std::filesystem;

namespace {

class TempDir {
 public:
  TempDir() {
    path_ = fs::temp_directory_path() / ("go_feap_test_" + std::to_string(::getpid()) + "_" +
                                         ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(path_);
  }
  ~TempDir() { fs::remove_all(path_); }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  fs::path path_;
};

void writeText(const std::string& path, const std::string& text) { std::ofstream(path, std::ios::binary) << text; }

// Closed cube [lo, hi]^3 as 12 triangles.
std::vector<Vec3> cubeTriangles(double lo, double hi) {
  std::vector<Vec3> c;
  for (int i = 0; i < 8; ++i) c.emplace_back(i & 1 ? hi : lo, i & 2 ? hi : lo, i & 4 ? hi : lo);
  const int f[12][3] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5}, {0, 4, 5}, {0, 5, 1},
                        {2, 3, 7}, {2, 7, 6}, {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
  std::vector<Vec3> v;
  for (const auto& t : f)
    for (int k : t) v.push_back(c[k]);
  return v;
}

void writeBinaryStl(const std::string& path, const std::vector<Vec3>& v, const std::string& header = "solid cube") {
  std::string bytes(80, '\0');
  std::memcpy(bytes.data(), header.data(), std::min<std::size_t>(80, header.size()));
  const std::uint32_t n = v.size() / 3;
  bytes.append(reinterpret_cast<const char*>(&n), 4);
  for (std::size_t t = 0; t < n; ++t) {
    float rec[12] = {0, 0, 0};
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) rec[3 + 3 * k + a] = static_cast<float>(v[3 * t + k][a]);
    bytes.append(reinterpret_cast<const char*>(rec), sizeof(rec));
    bytes.append(2, '\0');
  }
  writeText(path, bytes);
}

std::string asciiStl(const std::vector<Vec3>& v) {
  std::ostringstream os;
  os << "solid cube\n";
  for (std::size_t t = 0; t < v.size() / 3; ++t) {
    os << " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k) os << "   vertex " << v[3 * t + k].x() << " " << v[3 * t + k].y() << " " << v[3 * t + k].z() << "\n";
    os << "  endloop\n endfacet\n";
  }
  os << "endsolid cube\n";
  return os.str();
}

std::string sceneYaml(const std::string& file, const std::string& extra = "ground_plane: false",
                      const std::string& start = "[0.05, 0.05, 0.05]") {
  return "scene:\n  name: t\n  file: " + file +
         "\n  T_world_file: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n  resolution: 0.1\n"
         "  box: {min: [-1, -1, -1], max: [2, 2, 2]}\n  start: {position: " + start + ", yaw: 0}\n  " + extra + "\n";
}

// Loads `file` (in `d`) through a scene YAML of its own, with the start in the grid's corner.
go_feap::common::Result<Scene> loadWithCornerStart(const TempDir& d, const std::string& file) {
  writeText(d.file(file + ".yaml"), sceneYaml(file, "ground_plane: false", "[-0.55, -0.55, -0.55]"));
  return loadSceneYaml(d.file(file + ".yaml"));
}

// True when no 6-connected path of free voxels links the grid's outside layer to `inside`.
bool sealed(const Scene& s, const Index3& inside) {
  const auto& g = s.geometry();
  std::vector<char> seen(g.size(), 0);
  std::vector<Index3> st{Index3::Zero()};
  seen[0] = 1;
  while (!st.empty()) {
    const Index3 c = st.back();
    st.pop_back();
    if (c == inside) return false;
    for (const Index3& o : go_feap::common::faceNeighbours()) {
      const Index3 nb = c + o;
      if (!g.inside(nb) || seen[g.linear(nb)] || s.occupied.at(nb)) continue;
      seen[g.linear(nb)] = 1;
      st.push_back(nb);
    }
  }
  return true;
}

std::vector<std::size_t> occupiedSet(const Scene& s) {
  std::vector<std::size_t> v;
  for (std::size_t l = 0; l < s.occupied.size(); ++l)
    if (s.occupied[l]) v.push_back(l);
  return v;
}

// The whole of the file at `path`.
std::string fileBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void expectErrorMentions(const std::string& message, const std::vector<std::string>& words) {
  for (const auto& w : words) EXPECT_NE(message.find(w), std::string::npos) << "'" << w << "' not in: " << message;
}

// Writes `bytes` to `path` and expects loadStl to refuse it with a message naming the file and each of `words`.
void expectStlRefused(const std::string& path, const std::string& bytes, const std::vector<std::string>& words) {
  writeText(path, bytes);
  auto r = loadStl(path);
  ASSERT_FALSE(r) << path << ": " << r->triangleCount() << " triangles";
  std::vector<std::string> all{path};
  all.insert(all.end(), words.begin(), words.end());
  expectErrorMentions(r.message(), all);
}

}  // namespace

TEST(PointCloud, PcdBinaryAndAsciiAndPly) {
  TempDir d;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int i = 0; i < 50; ++i) cloud.push_back(pcl::PointXYZ(0.1f * i, -0.05f * i, 1.0f));
  pcl::io::savePCDFileBinary(d.file("a.pcd"), cloud);
  pcl::io::savePCDFileASCII(d.file("b.pcd"), cloud);
  pcl::io::savePCDFileBinaryCompressed(d.file("z.pcd"), cloud);  // PCL's own choice for large clouds
  std::ostringstream ply;
  ply << "ply\nformat ascii 1.0\nelement vertex " << cloud.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (const auto& p : cloud) ply << p.x << " " << p.y << " " << p.z << "\n";
  writeText(d.file("c.ply"), ply.str());
  pcl::console::setVerbosityLevel(pcl::console::L_WARN);
  for (const char* f : {"a.pcd", "b.pcd", "z.pcd", "c.ply"}) {
    auto pts = loadPointCloud(d.file(f));
    EXPECT_EQ(pcl::console::getVerbosityLevel(), pcl::console::L_WARN) << "PCL's verbosity, the process's, changed";
    ASSERT_TRUE(pts) << pts.message();
    ASSERT_EQ(pts->size(), cloud.size()) << f;
    for (std::size_t i = 0; i < cloud.size(); ++i)
      EXPECT_LT(((*pts)[i] - Vec3(cloud[i].x, cloud[i].y, cloud[i].z)).norm(), 1e-5) << f;
  }
  // A compressed file cut short, or whose uncompressed size is not the header's points, is refused.
  const std::string compressed = fileBytes(d.file("z.pcd"));
  writeText(d.file("z_cut.pcd"), compressed.substr(0, compressed.size() - 10));
  std::string resized = compressed;
  const std::size_t data = resized.find("DATA binary_compressed\n") + 23;
  std::uint32_t raw = 0;
  std::memcpy(&raw, resized.data() + data + 4, 4);
  ASSERT_EQ(raw, cloud.size() * 12u);  // x y z, 12 bytes a point
  raw += 12;
  std::memcpy(resized.data() + data + 4, &raw, 4);
  writeText(d.file("z_size.pcd"), resized);
  for (const char* f : {"z_cut.pcd", "z_size.pcd"}) {
    auto r = loadPointCloud(d.file(f));
    ASSERT_FALSE(r) << f;
    expectErrorMentions(r.message(), {f, "truncated or corrupt compressed PCD file"});
  }
}

// An organised cloud (WIDTH 3, HEIGHT 2, as a depth camera saves one) is read row after row: every point once.
TEST(PointCloud, OrganisedPcdIsReadRowAfterRow) {
  TempDir d;
  pcl::PointCloud<pcl::PointXYZ> cloud(3, 2);
  for (std::size_t i = 0; i < cloud.size(); ++i) cloud[i] = pcl::PointXYZ(1.0f + i, 0.5f * i, 2.0f);
  ASSERT_TRUE(cloud.isOrganized());
  pcl::io::savePCDFileBinary(d.file("organised_binary.pcd"), cloud);
  pcl::io::savePCDFileASCII(d.file("organised_ascii.pcd"), cloud);
  for (const char* f : {"organised_binary.pcd", "organised_ascii.pcd"}) {
    auto pts = loadPointCloud(d.file(f));
    ASSERT_TRUE(pts) << pts.message();
    ASSERT_EQ(pts->size(), 6u) << f;
    for (std::size_t i = 0; i < 6; ++i)
      EXPECT_LT(((*pts)[i] - Vec3(1.0 + i, 0.5 * i, 2.0)).norm(), 1e-6) << f << " point " << i;
  }
  // A pixel without a return is a point of NaN x, y and z (PCL's "no point", is_dense false): skipped, the
  // rest read (the whole cloud was refused); a cloud of nothing else has no point.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud[2] = pcl::PointXYZ(nan, nan, nan);
  cloud.is_dense = false;
  pcl::io::savePCDFileBinary(d.file("holes.pcd"), cloud);
  auto file = loadPointCloudFile(d.file("holes.pcd"));
  ASSERT_TRUE(file) << file.message();
  EXPECT_EQ(file->skipped_points, 1u);
  ASSERT_EQ(file->points.size(), 5u);
  EXPECT_LT((file->points[2] - Vec3(4.0, 1.5, 2.0)).norm(), 1e-6);
  for (auto& p : cloud) p = pcl::PointXYZ(nan, nan, nan);
  pcl::io::savePCDFileBinary(d.file("blind.pcd"), cloud);
  auto blind = loadPointCloudFile(d.file("blind.pcd"));
  ASSERT_FALSE(blind);
  expectErrorMentions(blind.message(), {"blind.pcd", "no point (all 6 are NaN"});
}

TEST(Stl, BinaryStartingWithSolidAndAsciiGiveTheSameWatertightShell) {
  TempDir d;
  const auto tri = cubeTriangles(0.23, 1.37);
  writeBinaryStl(d.file("bin.stl"), tri, "solid but binary");
  writeText(d.file("ascii.stl"), asciiStl(tri));
  auto b = loadStl(d.file("bin.stl"));
  auto a = loadStl(d.file("ascii.stl"));
  ASSERT_TRUE(b) << b.message();
  ASSERT_TRUE(a) << a.message();
  EXPECT_EQ(b->triangleCount(), 12u);
  EXPECT_EQ(a->triangleCount(), 12u);

  auto sb = loadWithCornerStart(d, "bin.stl");
  auto sa = loadWithCornerStart(d, "ascii.stl");
  ASSERT_TRUE(sb) << sb.message();
  ASSERT_TRUE(sa) << sa.message();
  EXPECT_EQ(occupiedSet(*sb), occupiedSet(*sa));
  // Surface voxels only: the centre is free but cannot be reached from outside.
  const Index3 centre = sb->geometry().coordToIndex(Vec3::Constant(0.8));
  EXPECT_FALSE(sb->occupied.at(centre));
  EXPECT_TRUE(sealed(*sb, centre));
  // Every voxel the surface passes through is marked; voxels well away from it are not.
  EXPECT_TRUE(sb->isOccupied(Vec3(0.25, 0.8, 0.8)));
  EXPECT_TRUE(sb->isOccupied(Vec3(1.35, 0.8, 0.8)));
  EXPECT_FALSE(sb->isOccupied(Vec3(0.05, 0.8, 0.8)));
  EXPECT_FALSE(sb->isOccupied(Vec3(0.45, 0.8, 0.8)));
}

// A PLY mesh's faces mark the voxels they overlap, as the same surface in an STL does: the cube [0.23, 1.37]^3
// as 8 vertices and 6 quads (ASCII, fanned into triangles; a ninth vertex no face uses, a stray, marks
// nothing) and as 12 triangles (PCL's binary writer) gives the STL's sealed shell. Its vertices alone mark 8
// voxels.
TEST(PlyMesh, FacesMarkTheVoxelsTheyOverlapAsAnStlDoes) {
  TempDir d;
  const double lo = 0.23, hi = 1.37;
  writeBinaryStl(d.file("cube.stl"), cubeTriangles(lo, hi));
  std::ostringstream quads;
  quads << "ply\nformat ascii 1.0\nelement vertex 9\nproperty double x\nproperty double y\nproperty double z\n"
           "element face 6\nproperty list uchar int vertex_indices\nend_header\n";
  for (int i = 0; i < 8; ++i) quads << (i & 1 ? hi : lo) << " " << (i & 2 ? hi : lo) << " " << (i & 4 ? hi : lo) << "\n";
  quads << "-0.55 -0.55 1.75\n";  // the stray
  quads << "4 0 1 3 2\n4 4 5 7 6\n4 0 1 5 4\n4 2 3 7 6\n4 0 2 6 4\n4 1 3 7 5\n";
  writeText(d.file("quads.ply"), quads.str());
  pcl::PolygonMesh mesh;
  pcl::PointCloud<pcl::PointXYZ> corners;
  const std::vector<Vec3> tri = cubeTriangles(lo, hi);
  for (const Vec3& v : tri) corners.push_back(pcl::PointXYZ(v.x(), v.y(), v.z()));  // 36 vertices, 3 a face
  pcl::toPCLPointCloud2(corners, mesh.cloud);
  for (int t = 0; t < 12; ++t) {
    pcl::Vertices f;
    f.vertices = {3 * t, 3 * t + 1, 3 * t + 2};
    mesh.polygons.push_back(f);
  }
  pcl::io::savePLYFileBinary(d.file("triangles.ply"), mesh);

  auto stl = loadWithCornerStart(d, "cube.stl");
  ASSERT_TRUE(stl) << stl.message();
  for (const char* f : {"quads.ply", "triangles.ply"}) {
    auto file = loadPointCloudFile(d.file(f));
    ASSERT_TRUE(file) << f << ": " << file.message();
    EXPECT_EQ(file->triangles.size(), 12u) << f;
    auto ply = loadWithCornerStart(d, f);
    ASSERT_TRUE(ply) << f << ": " << ply.message();
    EXPECT_EQ(occupiedSet(*ply), occupiedSet(*stl)) << f;
    EXPECT_TRUE(sealed(*ply, ply->geometry().coordToIndex(Vec3::Constant(0.8)))) << f;
    EXPECT_TRUE(ply->isOccupied(Vec3(0.25, 0.8, 0.8))) << f;  // the middle of a face, far from any vertex
  }
  EXPECT_GT(occupiedSet(*stl).size(), 500u);

  // Faces that are no faces are refused by number; so are rows a face list does not fill.
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
                           "0 0 0\n1 0 0\n0 1 0\n";
  auto refused = [&](const std::string& name, const std::string& text, const std::vector<std::string>& words) {
    writeText(d.file(name), text);
    auto r = loadPointCloudFile(d.file(name));
    ASSERT_FALSE(r) << name << ": " << r->triangles.size() << " triangles";
    std::vector<std::string> all{name};
    all.insert(all.end(), words.begin(), words.end());
    expectErrorMentions(r.message(), all);
  };
  refused("edge.ply", head + "2 0 1\n", {"face 0 has 2 vertices"});
  refused("beyond.ply", head + "3 0 1 3\n", {"face 0 names vertex 3", "has 3 vertices"});
  refused("negative.ply", head + "3 0 -1 2\n", {"face 0 names vertex -1"});
  // A vertex of NaN x, y and z (PCL's "no point", skipped in a cloud) is corrupt in a mesh, whose faces name it.
  std::string nan_vertex = head + "3 0 1 2\n";
  nan_vertex.replace(nan_vertex.find("\n1 0 0\n"), 7, "\nnan nan nan\n");
  refused("nanvertex.ply", nan_vertex, {"point 1 is NaN or Inf"});
  refused("short.ply", head + "3 0 1\n", {"PLY"});
  refused("long.ply", head + "3 0 1 2 1\n", {"PLY"});
  const std::string binary = fileBytes(d.file("triangles.ply"));
  refused("cut.ply", binary.substr(0, binary.size() - 20), {"PLY"});
  // PCL reads no indices from these lists (it hands back empty faces): refused by their types, before it reads.
  refused("ushort.ply", std::regex_replace(head, std::regex("uchar int"), "uchar ushort") + "3 0 1 2\n",
          {"face list is 'list uchar ushort'"});
  for (const char* types : {"uchar uint", "uint ushort", "int int"}) {
    const std::string name = std::string("ok_") + types[1] + ".ply";
    writeText(d.file(name), std::regex_replace(head, std::regex("uchar int"), types) + "3 0 1 2\n");
    auto r = loadPointCloudFile(d.file(name));
    ASSERT_TRUE(r) << types << ": " << r.message();
    EXPECT_EQ(r->triangles.size(), 1u) << types;
  }
  // A binary header declaring more faces than the file can hold (a length byte each at least): PCL would
  // reserve them all first.
  refused("many.ply", std::regex_replace(binary, std::regex("element face 12"), "element face 1000000000"),
          {"need at least 1e+09 bytes"});
  // Faces declared with no property take no bytes however many: refused as such.
  refused("bare.ply",
          std::regex_replace(binary, std::regex("element face 12\nproperty list uchar int vertex_indices"),
                             "element face 1000000000"),
          {"element 'face' declares 1000000000 instances but no property"});
}

// A concave face (a wall with a doorway cut into it, one 8-sided face) is cut into triangles that keep the
// doorway open, either way round: the same voxels as the wall written as six triangles. A fan round the
// first vertex filled the doorway in.
TEST(PlyMesh, AConcaveFaceKeepsItsOpening) {
  TempDir d;
  const double x = 0.55;
  const double u[8][2] = {{0, 0}, {1.5, 0}, {1.5, 1.5}, {1.0, 1.5}, {1.0, 0.5}, {0.5, 0.5}, {0.5, 1.5}, {0, 1.5}};
  for (const bool reversed : {false, true}) {
    std::ostringstream ply;
    ply << "ply\nformat ascii 1.0\nelement vertex 8\nproperty double x\nproperty double y\nproperty double z\n"
           "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    for (const auto& p : u) ply << x << " " << p[0] << " " << p[1] << "\n";
    ply << (reversed ? "8 7 6 5 4 3 2 1 0\n" : "8 0 1 2 3 4 5 6 7\n");
    writeText(d.file("door.ply"), ply.str());
    auto at = [&](double y, double z) { return Vec3(x, y, z); };
    // Bottom strip, left and right posts, as triangles.
    const std::vector<Vec3> pieces = {at(0, 0),   at(1.5, 0),   at(1.5, 0.5), at(0, 0),   at(1.5, 0.5), at(0, 0.5),
                                      at(0, 0.5), at(0.5, 0.5), at(0.5, 1.5), at(0, 0.5), at(0.5, 1.5), at(0, 1.5),
                                      at(1.0, 0.5), at(1.5, 0.5), at(1.5, 1.5), at(1.0, 0.5), at(1.5, 1.5), at(1.0, 1.5)};
    writeBinaryStl(d.file("door.stl"), pieces);
    auto ply_scene = loadWithCornerStart(d, "door.ply");
    auto stl_scene = loadWithCornerStart(d, "door.stl");
    ASSERT_TRUE(ply_scene) << ply_scene.message();
    ASSERT_TRUE(stl_scene) << stl_scene.message();
    EXPECT_FALSE(ply_scene->isOccupied(at(0.75, 1.0))) << "the doorway is filled in (reversed " << reversed << ")";
    EXPECT_TRUE(ply_scene->isOccupied(at(0.25, 1.0)));
    EXPECT_TRUE(ply_scene->isOccupied(at(1.25, 1.0)));
    EXPECT_TRUE(ply_scene->isOccupied(at(0.75, 0.25)));
    EXPECT_EQ(occupiedSet(*ply_scene), occupiedSet(*stl_scene)) << "reversed " << reversed;
  }
}

TEST(Stl, ThinTiltedWallHasNoHoles) {
  TempDir d;
  // A single-sided quad, tilted about two axes, spanning the whole grid cross-section.
  const Vec3 p0(-1.5, -1.5, -0.8), p1(2.5, -1.5, 0.0), p2(2.5, 2.5, 1.5), p3(-1.5, 2.5, 0.7);
  writeBinaryStl(d.file("wall.stl"), {p0, p1, p2, p0, p2, p3});
  writeText(d.file("wall.yaml"), sceneYaml("wall.stl", "margin: 0.0", "[0.55, 0.55, 1.85]"));
  auto s = loadSceneYaml(d.file("wall.yaml"));
  ASSERT_TRUE(s) << s.message();
  // Every column of the grid is cut by the wall: no free path leads from above to below.
  const auto& g = s->geometry();
  for (int y = 0; y < g.dims().y(); ++y)
    for (int x = 0; x < g.dims().x(); ++x) {
      int hits = 0;
      for (int z = 0; z < g.dims().z(); ++z) hits += s->occupied.at({x, y, z});
      ASSERT_GE(hits, 1) << "column " << x << ", " << y;
    }
  std::vector<char> seen(g.size(), 0);
  std::vector<Index3> st{Index3(0, 0, g.dims().z() - 1)};
  bool leaked = false;
  while (!st.empty() && !leaked) {
    const Index3 c = st.back();
    st.pop_back();
    leaked = c.z() == 0;
    for (const Index3& o : go_feap::common::faceNeighbours()) {
      const Index3 nb = c + o;
      if (!g.inside(nb) || seen[g.linear(nb)] || s->occupied.at(nb)) continue;
      seen[g.linear(nb)] = 1;
      st.push_back(nb);
    }
  }
  EXPECT_FALSE(leaked);
}

TEST(Stl, FaceOnAVoxelBoundaryMarksOneLayer) {
  TempDir d;
  // Square at z = 0.5 exactly (a voxel boundary): one voxel layer, the one above.
  writeBinaryStl(d.file("q.stl"), {Vec3(0, 0, 0.5), Vec3(1, 0, 0.5), Vec3(1, 1, 0.5), Vec3(0, 0, 0.5),
                                   Vec3(1, 1, 0.5), Vec3(0, 1, 0.5)});
  writeText(d.file("q.yaml"), sceneYaml("q.stl"));
  auto s = loadSceneYaml(d.file("q.yaml"));
  ASSERT_TRUE(s) << s.message();
  EXPECT_TRUE(s->isOccupied(Vec3(0.45, 0.45, 0.55)));
  EXPECT_FALSE(s->isOccupied(Vec3(0.45, 0.45, 0.45)));
}

// Distance from p to triangle (a, b, c): to its plane where p projects inside it, else to its edges (a
// collinear triangle has only its edges).
double pointTriangleDistance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  auto segment = [&](const Vec3& u, const Vec3& w) {
    const Vec3 d = w - u;
    const double t = d.squaredNorm() > 0.0 ? std::clamp((p - u).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
    return (p - (u + t * d)).norm();
  };
  double best = std::min({segment(a, b), segment(b, c), segment(c, a)});
  const Vec3 n = (b - a).cross(c - a);
  if (n.norm() > 1e-9 * (b - a).norm() * (c - a).norm()) {
    const double off = n.normalized().dot(p - a);
    const Vec3 q = p - off * n.normalized();
    if ((b - a).cross(q - a).dot(n) >= 0.0 && (c - b).cross(q - b).dot(n) >= 0.0 && (a - c).cross(q - c).dot(n) >= 0.0)
      best = std::min(best, std::abs(off));
  }
  return best;
}

// The column-by-column voxeliser marks exactly the voxels an exhaustive test of every grid voxel marks,
// for triangles of every kind: random, slivers, long and diagonal, degenerate (a segment, a point), on
// voxel faces, partly or wholly outside the grid. No point of a triangle lies in an unmarked voxel, and
// no marked voxel's centre lies farther from the triangle than half a voxel diagonal (a cube the
// triangle touches is that close), which the exhaustive test's own rule cannot show.
TEST(Stl, ColumnVoxeliserMarksWhatAnExhaustiveTestMarks) {
  const Scene empty = makeEmptyScene("t", {Vec3(-0.73, -0.41, 0.17), Vec3(1.31, 1.12, 1.93)}, 0.1, 0.2);
  const auto& g = empty.geometry();
  const Vec3 o = g.origin();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(-1.2, 1.8), y(-0.9, 1.6), z(-0.3, 2.4), unit(0.0, 1.0);
  std::uniform_int_distribution<int> cell(0, 20);
  auto random = [&] { return Vec3(x(rng), y(rng), z(rng)); };
  auto onBoundary = [&]() -> Vec3 { return o + 0.1 * Vec3(cell(rng), cell(rng), cell(rng)); };
  std::vector<std::array<Vec3, 3>> tris;
  for (int i = 0; i < 300; ++i) tris.push_back({random(), random(), random()});
  for (int i = 0; i < 60; ++i) {  // slivers: two vertices within 1 mm
    const Vec3 p = random(), q = random();
    tris.push_back({p, q, p + 1e-3 * Vec3(unit(rng), unit(rng), unit(rng))});
  }
  for (int i = 0; i < 60; ++i) tris.push_back({onBoundary(), onBoundary(), onBoundary()});
  for (int i = 0; i < 30; ++i) {  // in a voxel-boundary plane of each axis
    std::array<Vec3, 3> t{onBoundary(), onBoundary(), onBoundary()};
    for (auto& p : t) p[i % 3] = t[0][i % 3];
    tris.push_back(t);
  }
  for (int i = 0; i < 30; ++i) {  // degenerate: a segment, then a point
    const Vec3 p = random(), q = random();
    tris.push_back({p, q, p + 0.3 * (q - p)});
    tris.push_back({p, p, p});
  }
  tris.push_back({Vec3(-0.7, -0.4, 0.2), Vec3(1.3, 1.1, 1.9), Vec3(1.29, 1.1, 1.9)});  // corner to corner
  tris.push_back({Vec3(5, 5, 5), Vec3(6, 5, 5), Vec3(5, 6, 5)});                          // outside
  tris.push_back({Vec3(-1e30, 0.5, 1.0), Vec3(1e30, 0.5, 1.0), Vec3(0.0, 0.6, 1.2)});     // far outside
  std::size_t marked_total = 0;
  for (std::size_t t = 0; t < tris.size(); ++t) {
    const auto& [a, b, c] = tris[t];
    Scene fast = empty;
    voxelizeTriangle(fast, a, b, c);
    std::size_t marked = 0;
    for (int k = 0; k < g.dims().z(); ++k)
      for (int j = 0; j < g.dims().y(); ++j)
        for (int i = 0; i < g.dims().x(); ++i) {
          const Index3 idx(i, j, k);
          const bool want = triangleMarksVoxel(g, idx, a, b, c);
          marked += want;
          if (want && a.cwiseAbs().maxCoeff() < 1e3 && b.cwiseAbs().maxCoeff() < 1e3 && c.cwiseAbs().maxCoeff() < 1e3) {
            ASSERT_LE(pointTriangleDistance(g.indexToCoord(idx), a, b, c), 0.5 * std::sqrt(3.0) * 0.1 + 2e-4)
                << "triangle " << t << " marks voxel " << idx.transpose() << ", which it does not touch";
          }
          ASSERT_EQ(fast.occupied.at(idx) != 0, want)
              << "triangle " << t << " (" << a.transpose() << " | " << b.transpose() << " | " << c.transpose()
              << ") voxel " << idx.transpose();
        }
    marked_total += marked;
    // Points of the triangle strictly inside a voxel mark it.
    for (int s = 0; s < 200; ++s) {
      double r1 = unit(rng), r2 = unit(rng);
      if (r1 + r2 > 1.0) r1 = 1.0 - r1, r2 = 1.0 - r2;
      const Vec3 p = a + r1 * (b - a) + r2 * (c - a);
      const Index3 idx = g.coordToIndex(p);
      const Vec3 f = (p - g.indexToCoord(idx)) / 0.1;
      if (!g.inside(idx) || f.cwiseAbs().maxCoeff() > 0.499) continue;
      ASSERT_TRUE(fast.occupied.at(idx)) << "triangle " << t << " point " << p.transpose();
    }
  }
  EXPECT_GT(marked_total, 20000u);  // the triangles are not all outside
}

TEST(Octomap, LoadsOccupiedLeavesIncludingPrunedOnes) {
  TempDir d;
  octomap::OcTree tree(0.1);
  // A 0.8 m cube of occupied voxels aligned to the octree prunes into bigger leaves.
  for (double x = 0.05; x < 0.8; x += 0.1)
    for (double y = 0.05; y < 0.8; y += 0.1)
      for (double z = 0.05; z < 0.8; z += 0.1) tree.updateNode(octomap::point3d(x, y, z), true);
  tree.updateNode(octomap::point3d(-0.55, 1.45, 0.05), true);
  tree.updateNode(octomap::point3d(1.55, 1.55, 1.55), false);  // free: must stay free
  tree.prune();
  ASSERT_TRUE(tree.writeBinary(d.file("t.bt")));
  writeText(d.file("t.yaml"), sceneYaml("t.bt", "ground_plane: false", "[1.55, 1.55, 1.55]"));
  auto s = loadSceneYaml(d.file("t.yaml"));
  ASSERT_TRUE(s) << s.message();
  EXPECT_EQ(s->occupiedCount(), 8u * 8 * 8 + 1);
  EXPECT_TRUE(s->isOccupied(Vec3(0.75, 0.05, 0.45)));
  EXPECT_TRUE(s->isOccupied(Vec3(-0.55, 1.45, 0.05)));
  EXPECT_FALSE(s->isOccupied(Vec3(0.85, 0.05, 0.45)));
  // A tree of free space only is refused by name, not loaded as nothing.
  octomap::OcTree free_only(0.1);
  free_only.updateNode(octomap::point3d(0.05, 0.05, 0.05), false);
  ASSERT_TRUE(free_only.writeBinary(d.file("free.bt")));
  auto none = loadOctomap(d.file("free.bt"));
  ASSERT_FALSE(none);
  expectErrorMentions(none.message(), {"free.bt", "no occupied voxels"});
  // So is an empty tree (a map saved before its first scan), whose file has no tree data at all (it was
  // called truncated); one that says it has nodes and has no data is.
  ASSERT_TRUE(octomap::OcTree(0.1).writeBinary(d.file("empty.bt")));
  auto empty = loadOctomap(d.file("empty.bt"));
  ASSERT_FALSE(empty);
  expectErrorMentions(empty.message(), {"empty.bt", "no occupied voxels"});
  std::ifstream in(d.file("empty.bt"), std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t size_at = text.find("\nsize 0\n");
  ASSERT_NE(size_at, std::string::npos) << text;
  std::ofstream(d.file("claims.bt"), std::ios::binary) << text.substr(0, size_at) << "\nsize 9\n"
                                                        << text.substr(size_at + 8);
  auto claims = loadOctomap(d.file("claims.bt"));
  ASSERT_FALSE(claims);
  expectErrorMentions(claims.message(), {"claims.bt", "truncated"});
}

// T_world_file turns and moves points (PCD, PLY) and triangles (STL) alike: a quarter turn round z and a
// shift of (0.31, 0.2, 0) m put each file point in the voxel of T * p, and nothing else is marked (every
// other file test places by the identity or without a shift).
TEST(SceneYaml, TWorldFileTurnsAndMovesPointsAndTriangles) {
  TempDir d;
  const std::vector<Vec3> points{Vec3(0.05, 0.05, 0.05), Vec3(0.25, 0.05, 0.15), Vec3(0.05, 0.35, 0.45), Vec3(0.55, -0.35, 0.25)};
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (const Vec3& p : points) cloud.push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  pcl::io::savePCDFileBinary(d.file("p.pcd"), cloud);
  std::ostringstream ply;
  ply << "ply\nformat ascii 1.0\nelement vertex " << points.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  for (const Vec3& p : points) ply << p.x() << " " << p.y() << " " << p.z() << "\n";
  writeText(d.file("p.ply"), ply.str());
  std::vector<Vec3> triangles;  // a small triangle round each point (1 cm: inside its voxel)
  for (const Vec3& p : points)
    for (const Vec3& corner : {Vec3(-0.01, -0.01, 0.0), Vec3(0.01, -0.01, 0.0), Vec3(0.0, 0.01, 0.01)}) triangles.push_back(p + corner);
  writeBinaryStl(d.file("p.stl"), triangles, "triangles");
  Eigen::Matrix4d T;
  T << 0, -1, 0, 0.31, 1, 0, 0, 0.2, 0, 0, 1, 0, 0, 0, 0, 1;
  for (const char* file : {"p.pcd", "p.ply", "p.stl"}) {
    SCOPED_TRACE(file);
    std::string yaml = sceneYaml(file);
    const std::string identity = "[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]";
    yaml.replace(yaml.find(identity), identity.size(), "[0,-1,0,0.31, 1,0,0,0.2, 0,0,1,0, 0,0,0,1]");
    writeText(d.file(std::string(file) + ".yaml"), yaml);
    auto s = loadSceneYaml(d.file(std::string(file) + ".yaml"));
    ASSERT_TRUE(s) << s.message();
    std::set<std::size_t> expected;
    for (const Vec3& p : points) {
      const Vec3 w = (T * p.homogeneous()).head<3>();
      EXPECT_TRUE(s->isOccupied(w)) << "file point " << p.transpose() << " placed at " << w.transpose();
      expected.insert(s->geometry().linear(s->geometry().coordToIndex(w)));
    }
    EXPECT_EQ(s->occupiedCount(), expected.size());
  }
}

// Placed by a T_world_file that scales by 4 and turns a quarter round z, each 0.1 m leaf covers a 0.4 m
// cube of the scene: every scene voxel whose centre lies in a placed cube is marked, and no other (the
// oracle maps each voxel centre back into the file). Sampling the leaves in file units left 7 of each 8
// voxels of a wall unmarked. A leaf far outside the scene (pruned to a large cube there) costs nothing.
TEST(Octomap, ScaledAndTurnedLeavesMarkEveryVoxelTheyCover) {
  TempDir d;
  octomap::OcTree tree(0.1);
  std::vector<Vec3> leaves;
  for (double y = -0.15; y < 0.2; y += 0.1)
    for (double z = 0.05; z < 0.3; z += 0.1) leaves.emplace_back(0.05, y, z);
  for (const Vec3& c : leaves) tree.updateNode(octomap::point3d(c.x(), c.y(), c.z()), true);
  for (double x = 400.05; x < 401.6; x += 0.1)
    for (double y = 400.05; y < 401.6; y += 0.1)
      for (double z = 0.05; z < 1.6; z += 0.1) tree.updateNode(octomap::point3d(x, y, z), true);
  tree.prune();
  ASSERT_TRUE(tree.writeBinary(d.file("s.bt")));
  std::string yaml = sceneYaml("s.bt", "ground_plane: false", "[-0.95, -0.95, 1.55]");
  const std::string identity = "[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]";
  yaml.replace(yaml.find(identity), identity.size(), "[0,-4,0,0, 4,0,0,0, 0,0,4,0, 0,0,0,1]");
  writeText(d.file("s.yaml"), yaml);
  auto s = loadSceneYaml(d.file("s.yaml"));
  ASSERT_TRUE(s) << s.message();
  Eigen::Matrix4d T;
  T << 0, -4, 0, 0, 4, 0, 0, 0, 0, 0, 4, 0, 0, 0, 0, 1;
  const Eigen::Affine3d to_file(T.inverse());
  const auto& g = s->geometry();
  std::size_t expected = 0, wrong = 0;
  for (int z = 0; z < g.dims().z(); ++z)
    for (int y = 0; y < g.dims().y(); ++y)
      for (int x = 0; x < g.dims().x(); ++x) {
        const Index3 idx(x, y, z);
        const Vec3 f = to_file * g.indexToCoord(idx);
        bool in = false;
        for (const Vec3& c : leaves) in = in || (f - c).cwiseAbs().maxCoeff() <= 0.05;
        expected += in;
        wrong += in != (s->occupied.at(idx) != 0);
      }
  EXPECT_EQ(expected, 4u * 3 * 64);  // 12 leaves of 4x4x4 voxels, all inside the grid
  EXPECT_EQ(wrong, 0u);
  EXPECT_EQ(s->occupiedCount(), expected);
}

TEST(RoundTrip, MazeThroughPcdAndBtKeepsTheOccupiedSet) {
  TempDir d;
  auto maze = generateMaze(MazeConfig(), 1);
  ASSERT_TRUE(maze) << maze.message();
  ASSERT_TRUE(saveScenePcd(*maze, d.file("m.pcd")));
  ASSERT_TRUE(saveSceneBt(*maze, d.file("m.bt")));
  for (const char* f : {"m.pcd", "m.bt"}) {
    SceneFileSpec spec;
    spec.name = "maze";
    spec.file = d.file(f);
    spec.resolution = maze->resolution();
    spec.box = maze->box;
    spec.start = maze->start;
    spec.margin = 0.5;
    auto back = loadSceneFile(spec);
    ASSERT_TRUE(back) << back.message();
    EXPECT_EQ(back->geometry().dims(), maze->geometry().dims());
    EXPECT_EQ(occupiedSet(*back), occupiedSet(*maze)) << f;
  }
}

// A tall box (6 m, above the side view's 5 m) gets a side view under the top view, looking along +y with up
// at the top: 1 x 1 x 6 m at 0.1 m is 15 pixels a voxel, the top view 150 rows, a 6-row gap, then 60 rows of
// blocks, the top one the box's highest voxel layer. Two voxels, near the top and near the floor, show where
// they are and not mirrored.
TEST(SceneImage, TheSideViewHasUpAtTheTop) {
  Scene s = makeEmptyScene("tall", Aabb{Vec3(0, 0, 0), Vec3(1, 1, 6)}, 0.1, 0.0);
  ASSERT_TRUE(markOccupied(s, Vec3(0.55, 0.55, 5.05)));  // x index 5, z index 50
  ASSERT_TRUE(markOccupied(s, Vec3(0.25, 0.35, 0.55)));  // x index 2, z index 5
  const cv::Mat image = renderSceneImage(s, 900, 5.0);
  ASSERT_EQ(image.cols, 150);
  ASSERT_EQ(image.rows, 150 + 6 + 900);
  auto block = [&](int x, int z) { return image.at<cv::Vec3b>(156 + (59 - z) * 15 + 7, x * 15 + 7); };
  const cv::Vec3b white(255, 255, 255);
  EXPECT_NE(block(5, 50), white);
  EXPECT_NE(block(2, 5), white);
  EXPECT_EQ(block(5, 59 - 50), white);  // where a picture upside down would have them
  EXPECT_EQ(block(2, 59 - 5), white);
}

// The scene picture's top view against the grid: a pixel block is white exactly where no voxel of its
// column is occupied above the floor layer (away from the title and the start's disc). The scale comes from
// the box's longest side: a box 1 voxel wide and 20,000 long asked OpenCV for 18,000,000 rows (48.6 GB).
TEST(SceneImage, TopViewShowsEveryOccupiedColumnAndLongBoxesFit) {
  auto maze = generateMaze(MazeConfig(), 1);
  ASSERT_TRUE(maze) << maze.message();
  const auto& geo = maze->geometry();
  Index3 lo, hi;
  geo.centreRange(maze->box, lo, hi);
  const Index3 n = hi - lo;
  const int ppv = 900 / std::max({n.x(), n.y(), n.z()});
  ASSERT_GE(ppv, 2);
  const cv::Mat image = renderSceneImage(*maze, 900, 1e9);  // the top view only
  ASSERT_EQ(image.cols, n.x() * ppv);
  ASSERT_EQ(image.rows, n.y() * ppv);
  const cv::Point start(static_cast<int>((maze->start.position.x() - geo.origin().x() - lo.x() * geo.resolution()) /
                                         geo.resolution() * ppv),
                        static_cast<int>((hi.y() * geo.resolution() - (maze->start.position.y() - geo.origin().y())) /
                                         geo.resolution() * ppv));
  std::size_t shown = 0, checked = 0;
  for (int y = lo.y(); y < hi.y(); ++y)
    for (int x = lo.x(); x < hi.x(); ++x) {
      const cv::Point px((x - lo.x()) * ppv + ppv / 2, (hi.y() - 1 - y) * ppv + ppv / 2);
      if (px.y < 30 || cv::norm(px - start) < 40.0) continue;  // the title, the start's disc and heading
      bool occupied = false;
      for (int z = lo.z() + 1; z < hi.z(); ++z) occupied = occupied || maze->occupied.at(Index3(x, y, z));
      const cv::Vec3b c = image.at<cv::Vec3b>(px);
      EXPECT_EQ(c != cv::Vec3b(255, 255, 255), occupied) << "column " << x << ", " << y;
      shown += occupied;
      ++checked;
    }
  EXPECT_GT(shown, checked / 20) << "too few walls to compare";
  Aabb long_box;
  long_box.min = Vec3(0, 0, 0);
  long_box.max = Vec3(0.1, 2000.0, 0.1);
  Scene thin = makeEmptyScene("thin", long_box, 0.1, 0.0);
  ASSERT_TRUE(markOccupied(thin, Vec3(0.05, 1000.05, 0.05)));
  const cv::Mat long_image = renderSceneImage(thin, 900, 1e9);
  EXPECT_LE(std::max(long_image.rows, long_image.cols), 900);
  EXPECT_EQ(long_image.rows, 20000 / 23 + 1);  // 23 voxels a pixel: the fewest that fit 20,000 in 900
  Index3 thin_lo, thin_hi;
  thin.geometry().centreRange(thin.box, thin_lo, thin_hi);
  ASSERT_EQ(thin_hi.y() - thin_lo.y(), 20000);
  const int wall_y = thin.geometry().clampedIndex(Vec3(0.05, 1000.05, 0.05)).y();
  const int wall_row = (thin_hi.y() - 1 - wall_y) / 23;
  for (int row = 0; row < long_image.rows - 10; ++row)  // (the start's disc is drawn at the bottom)
    EXPECT_EQ(long_image.at<cv::Vec3b>(row, 0) != cv::Vec3b(255, 255, 255), row == wall_row) << "row " << row;
}

// A scene beyond OctoMap's keys (2^15 voxels from the origin: 3.3 km at 0.1 m) is refused by saveSceneBt,
// naming the voxel: every voxel was dropped in silence, and an empty tree written.
TEST(RoundTrip, BtOfASceneBeyondOctomapsReachIsRefused) {
  TempDir d;
  Aabb far_box;
  far_box.min = Vec3(5000.0, 0.0, 0.0);
  far_box.max = Vec3(5001.0, 1.0, 1.0);
  Scene far = makeEmptyScene("far", far_box, 0.1, 0.0);
  ASSERT_TRUE(markOccupied(far, Vec3(5000.55, 0.55, 0.55)));
  const go_feap::common::Status st = saveSceneBt(far, d.file("far.bt"));
  ASSERT_FALSE(st);
  expectErrorMentions(st.message(), {"far.bt", "scene 'far' has an occupied voxel at (5000.55", "beyond OctoMap's reach of 3276.8 m"});
  Scene near = makeEmptyScene("near", Aabb{Vec3(3000.0, 0.0, 0.0), Vec3(3001.0, 1.0, 1.0)}, 0.1, 0.0);
  ASSERT_TRUE(markOccupied(near, Vec3(3000.55, 0.55, 0.55)));
  ASSERT_TRUE(saveSceneBt(near, d.file("near.bt")));
  auto back = loadOctomap(d.file("near.bt"));
  ASSERT_TRUE(back) << back.message();
  ASSERT_EQ(back->size(), 1u);
  EXPECT_LT((back->front().centre - Vec3(3000.55, 0.55, 0.55)).norm(), 1e-3);
}

TEST(SceneYaml, GroundPlaneFillsTheBoxFloorLayer) {
  TempDir d;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(0.5f, 0.5f, 1.0f));
  pcl::io::savePCDFileBinary(d.file("p.pcd"), cloud);
  writeText(d.file("p.yaml"), sceneYaml("p.pcd", "ground_plane: true", "[0.05, 0.05, 0.05]"));
  auto s = loadSceneYaml(d.file("p.yaml"));
  ASSERT_TRUE(s) << s.message();
  EXPECT_TRUE(s->isOccupied(Vec3(1.95, -0.95, -0.95)));
  EXPECT_FALSE(s->isOccupied(Vec3(1.95, -0.95, -0.85)));
  EXPECT_TRUE(s->isOccupied(Vec3(0.55, 0.55, 1.05)));
}

// A relative file is found as the system finds it from the YAML's folder: through a symlinked folder, '..'
// is the link target's parent (a checkout linked into a catkin workspace, ../../shared/... from its config).
TEST(SceneYaml, ARelativeFileIsFoundThroughASymlinkedFolder) {
  TempDir d;
  fs::create_directories(d.file("real/data"));
  fs::create_directories(d.file("real/cfg"));
  fs::create_directories(d.file("ws"));
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(0.5f, 0.5f, 1.0f));
  pcl::io::savePCDFileBinary(d.file("real/data/p.pcd"), cloud);
  writeText(d.file("real/cfg/p.yaml"), sceneYaml("../data/p.pcd"));
  fs::create_directory_symlink(d.file("real/cfg"), d.file("ws/cfg"));
  auto s = loadSceneYaml(d.file("ws/cfg/p.yaml"));
  ASSERT_TRUE(s) << s.message();
  EXPECT_TRUE(s->isOccupied(Vec3(0.55, 0.55, 1.05)));
}

// ---- Real scenes from other projects ---------------------------------------------------

namespace {
// config/scenes/<name>.yaml as shipped, except that its file is the one under GO_FEAP_SHARED_DIR (the YAML
// names ../shared beside the repository, which a build pointed elsewhere may not have): a copy in `dir`.
std::string configScene(const TempDir& dir, const std::string& name) {
  const fs::path shipped = fs::path(__FILE__).parent_path().parent_path().parent_path() / "config/scenes" / (name + ".yaml");
  std::ifstream in(shipped);
  std::stringstream text;
  text << in.rdbuf();
  const std::regex file_line(R"(( file: )\S*/shared/scenes/(\S+))");
  const std::string shared = fs::absolute(GO_FEAP_SHARED_DIR).string();  // the copy lies elsewhere
  const std::string yaml = std::regex_replace(text.str(), file_line, "$1" + shared + "/scenes/$2");
  EXPECT_NE(yaml, text.str()) << shipped << ": no file line naming shared/scenes";
  const std::string copy = dir.file(name + ".yaml");
  writeText(copy, yaml);
  return copy;
}
bool sharedScene(const std::string& file) {
  const std::string p = std::string(GO_FEAP_SHARED_DIR) + "/scenes/" + file;
  if (fs::exists(p)) return true;
  std::cout << "[ SKIPPED  ] " << p << " is absent; the shared scenes live beside the repository\n";
  return false;
}
void occupiedExtent(const Scene& s, Vec3& lo, Vec3& hi, bool skip_floor_layer) {
  const auto& g = s.geometry();
  lo = Vec3::Constant(1e9);
  hi = Vec3::Constant(-1e9);
  const int floor_k = g.coordToIndex(s.box.min + Vec3::Constant(1e-6)).z();
  for (std::size_t l = 0; l < s.occupied.size(); ++l) {
    if (!s.occupied[l]) continue;
    const Index3 i = g.unlinear(l);
    if (skip_floor_layer && i.z() == floor_k) continue;
    const Vec3 c = g.indexToCoord(i);
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
}
}  // namespace

TEST(SharedScenes, PillarPcd) {
  if (!sharedScene("pillar.pcd")) GTEST_SKIP() << "pillar.pcd absent";
  auto pts = loadPointCloud(std::string(GO_FEAP_SHARED_DIR) + "/scenes/pillar.pcd");
  ASSERT_TRUE(pts) << pts.message();
  EXPECT_EQ(pts->size(), 144640u);
  const TempDir dir;
  auto s = loadSceneYaml(configScene(dir, "pillar"));
  ASSERT_TRUE(s) << s.message();
  // File frame = world: extents x -7.24..7.26, y -13.74..13.66, z -0.94..2.96 (README);
  // the grid spans the box + 1 m, so z is cut to [-1, 3]: it all fits.
  Vec3 lo, hi;
  occupiedExtent(*s, lo, hi, true);
  const double r = s->resolution();
  EXPECT_NEAR(lo.x(), -7.24, r);
  EXPECT_NEAR(hi.x(), 7.26, r);
  EXPECT_NEAR(lo.y(), -13.74, r);
  EXPECT_NEAR(hi.y(), 13.66, r);
  EXPECT_NEAR(lo.z(), -0.94, r);
  EXPECT_NEAR(hi.z(), 2.96, r);
  EXPECT_TRUE(s->isOccupied(Vec3(9.95, 14.95, 0.05))) << "ground plane";
  EXPECT_FALSE(s->isOccupied(s->start.position));
}

TEST(SharedScenes, ComplexOfficeBinaryStlStartingWithSolid) {
  if (!sharedScene("complex_office.stl")) GTEST_SKIP() << "complex_office.stl absent";
  std::ifstream in(std::string(GO_FEAP_SHARED_DIR) + "/scenes/complex_office.stl", std::ios::binary);
  char head[5];
  in.read(head, 5);
  ASSERT_EQ(std::string(head, 5), "solid");
  auto mesh = loadStl(std::string(GO_FEAP_SHARED_DIR) + "/scenes/complex_office.stl");
  ASSERT_TRUE(mesh) << mesh.message();
  EXPECT_EQ(mesh->triangleCount(), 572u);
  const TempDir dir;
  auto s = loadSceneYaml(configScene(dir, "complex_office"));
  ASSERT_TRUE(s) << s.message();
  // File x 0..31, y 0..3.5 (up), z 0..31 -> world x = 15.5 - z_f, y = 15.5 - x_f,
  // z = y_f - 0.5: x, y in -15.5..15.5, z in -0.5..3.0. Voxel centres lie within half a
  // voxel inside those faces.
  Vec3 lo, hi;
  occupiedExtent(*s, lo, hi, false);
  const double r = s->resolution();
  EXPECT_NEAR(lo.x(), -15.5, r);
  EXPECT_NEAR(hi.x(), 15.5, r);
  EXPECT_NEAR(lo.y(), -15.5, r);
  EXPECT_NEAR(hi.y(), 15.5, r);
  EXPECT_NEAR(lo.z(), -0.5, r);
  EXPECT_NEAR(hi.z(), 3.0, r);
  // The start is about 0.2 m from a wall at the origin, and free.
  EXPECT_FALSE(s->isOccupied(s->start.position));
  const auto obs = computeObservableSet(*s);
  EXPECT_GT(obs.free_count, 10000u);
}

// ---- Bad input -------------------------------------------------------------------------

TEST(BadInput, MissingFileAndUnknownExtension) {
  TempDir d;
  auto a = loadPointCloud(d.file("nope.pcd"));
  ASSERT_FALSE(a);
  expectErrorMentions(a.message(), {"nope.pcd", "not found"});
  writeText(d.file("x.obj"), "v 0 0 0\n");
  auto b = loadPointCloud(d.file("x.obj"));
  ASSERT_FALSE(b);
  expectErrorMentions(b.message(), {"x.obj", "extension"});
  writeText(d.file("x.yaml"), sceneYaml("x.obj"));
  auto c = loadSceneYaml(d.file("x.yaml"));
  ASSERT_FALSE(c);
  expectErrorMentions(c.message(), {"x.obj", "extension"});
  auto e = makeScene("city", 0);
  ASSERT_FALSE(e);
  expectErrorMentions(e.message(), {"city"});
  // A scene YAML that is not there is said to be missing (it was "cannot be read as YAML (bad file)").
  auto missing = makeScene(d.file("mistyped.yaml"), 0);
  ASSERT_FALSE(missing);
  expectErrorMentions(missing.message(), {"mistyped.yaml: file not found"});
}

TEST(BadInput, TruncatedAndCorruptStl) {
  TempDir d;
  writeBinaryStl(d.file("full.stl"), cubeTriangles(0, 1), "binary header");
  const std::string bytes = fileBytes(d.file("full.stl"));
  expectStlRefused(d.file("trunc.stl"), bytes.substr(0, bytes.size() - 30), {"binary STL", "12 triangles"});
  expectStlRefused(d.file("short.stl"), "abc", {"too short"});
  const std::string ascii = asciiStl(cubeTriangles(0, 1));
  expectStlRefused(d.file("atrunc.stl"), ascii.substr(0, ascii.size() / 2), {"truncated ASCII STL"});
  std::string bad = ascii;
  bad.replace(bad.find("vertex 0 0 0") + 7, 1, "x");
  expectStlRefused(d.file("abad.stl"), bad, {"non-numeric"});
  std::string junk = ascii;  // a number with junk after it: std::stod read "0abc" as 0
  junk.replace(junk.find("vertex 0 0 0") + 7, 1, "0abc");
  expectStlRefused(d.file("ajunk.stl"), junk, {"non-numeric"});
  // A binary STL whose header says 'solid ... facet', cut short: a binary file's problem, not ASCII's.
  writeBinaryStl(d.file("solidbin.stl"), cubeTriangles(0, 1), "solid cube facet");
  const std::string solid_bytes = fileBytes(d.file("solidbin.stl"));
  expectStlRefused(d.file("solidbin.stl"), solid_bytes.substr(0, solid_bytes.size() - 30),
                   {"truncated or corrupt binary STL", "12 triangles"});
  // An empty solid has no triangles (it was "too short for an STL file").
  expectStlRefused(d.file("empty.stl"), "solid x\nendsolid x\n", {"the mesh has no triangles"});
  // Keywords in upper case load as in lower case (they were read as a binary file of 1.3e9 triangles).
  std::string upper = ascii;
  for (char& ch : upper) ch = static_cast<char>(std::toupper(static_cast<unsigned char>(ch)));
  writeText(d.file("upper.stl"), upper);
  auto up = loadStl(d.file("upper.stl"));
  ASSERT_TRUE(up) << up.message();
  auto low = loadStl(d.file("full.stl"));
  ASSERT_TRUE(low) << low.message();
  EXPECT_EQ(up->vertices, low->vertices);
  // One record more than the header's count: corrupt (it lost a triangle without a word).
  expectStlRefused(d.file("extra.stl"), bytes + std::string(50, '\0'),
                   {"truncated or corrupt binary STL", "12 triangles"});
  // NUL padding after an ASCII file's text is no sign of a binary one: the same 12 triangles.
  writeText(d.file("padded.stl"), ascii + std::string(16, '\0'));
  auto padded = loadStl(d.file("padded.stl"));
  ASSERT_TRUE(padded) << padded.message();
  EXPECT_EQ(padded->vertices, low->vertices);
  auto tri = cubeTriangles(0, 1);
  tri[4].y() = std::numeric_limits<double>::quiet_NaN();
  writeBinaryStl(d.file("nan.stl"), tri);
  auto f = loadStl(d.file("nan.stl"));
  ASSERT_FALSE(f);
  expectErrorMentions(f.message(), {"nan.stl", "NaN"});
}

TEST(BadInput, TruncatedCorruptNanAndEmptyClouds) {
  TempDir d;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int i = 0; i < 100; ++i) cloud.push_back(pcl::PointXYZ(0.1f * i, 0.f, 1.f));
  pcl::io::savePCDFileBinary(d.file("ok.pcd"), cloud);
  std::string bytes = fileBytes(d.file("ok.pcd"));
  writeText(d.file("trunc.pcd"), bytes.substr(0, bytes.size() - 200));
  auto a = loadPointCloud(d.file("trunc.pcd"));
  ASSERT_FALSE(a);
  expectErrorMentions(a.message(), {"trunc.pcd"});
  writeText(d.file("garbage.pcd"), "this is not a point cloud\n\x01\x02\x03");
  auto b = loadPointCloud(d.file("garbage.pcd"));
  ASSERT_FALSE(b);
  expectErrorMentions(b.message(), {"garbage.pcd", "corrupt"});
  writeText(d.file("nan.pcd"),
            "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1 2 3\nnan 0 0\n");
  auto c = loadPointCloud(d.file("nan.pcd"));
  ASSERT_FALSE(c);
  expectErrorMentions(c.message(), {"nan.pcd", "NaN"});
  writeText(d.file("inf.ply"),
            "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
            "end_header\n1 2 3\ninf 0 0\n");
  auto c2 = loadPointCloud(d.file("inf.ply"));
  ASSERT_FALSE(c2);
  expectErrorMentions(c2.message(), {"inf.ply"});
  writeText(d.file("empty.pcd"),
            "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 0\nHEIGHT 1\n"
            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 0\nDATA ascii\n");
  auto e = loadPointCloud(d.file("empty.pcd"));
  ASSERT_FALSE(e);
  expectErrorMentions(e.message(), {"empty.pcd", "empty"});
  writeText(d.file("trunc.ply"),
            "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
            "end_header\n1 2 3\n");
  auto f = loadPointCloud(d.file("trunc.ply"));
  ASSERT_FALSE(f);
  expectErrorMentions(f.message(), {"trunc.ply"});
}

// Headers declaring far more points than their files hold: refused before PCL allocates for them (a
// 154-byte ASCII PCD declaring 3e8 points took 3.6 GB and 20 s; COUNT 1e9 asked for 12 GB).
TEST(BadInput, CloudHeadersDeclaringMorePointsThanTheFileHolds) {
  TempDir d;
  const std::string pcd_head = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\n";
  writeText(d.file("many.pcd"), pcd_head + "SIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 300000000\nHEIGHT 1\n"
                                           "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 300000000\nDATA ascii\n1 1 1\n");
  writeText(d.file("wide.pcd"), pcd_head + "SIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1000000000\nWIDTH 1\nHEIGHT 1\n"
                                           "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA binary\n" + std::string(12, '\0'));
  writeText(d.file("many.ply"), "ply\nformat ascii 1.0\nelement vertex 300000000\nproperty float x\n"
                                "property float y\nproperty float z\nend_header\n1 1 1\n");
  for (const char* f : {"many.pcd", "wide.pcd", "many.ply"}) {
    auto r = loadPointCloud(d.file(f));
    ASSERT_FALSE(r) << f;
    expectErrorMentions(r.message(), {f, "header declares", "bytes of data"});
  }
  // The same headers with what they declare load.
  writeText(d.file("one.pcd"), pcd_head + "SIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\nHEIGHT 1\n"
                                          "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1 1 1\n");
  writeText(d.file("one.ply"), "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"
                               "property float y\nproperty float z\nend_header\n1 1 1\n");
  for (const char* f : {"one.pcd", "one.ply"}) {
    auto r = loadPointCloud(d.file(f));
    ASSERT_TRUE(r) << f << ": " << r.message();
    EXPECT_EQ(r->size(), 1u);
  }
  // Rows with too few or too many values, or words that are no numbers: PCL loaded them without a word.
  writeText(d.file("rows.pcd"), pcd_head + "SIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 1\n"
                                           "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 4\nDATA ascii\n1 1 1\n2 2\n3 3 3 3\n4 4 4\n");
  auto rows = loadPointCloud(d.file("rows.pcd"));
  ASSERT_FALSE(rows) << (rows ? rows->size() : 0) << " points";
  expectErrorMentions(rows.message(), {"rows.pcd", "row 2 has 2 values, the header 3"});
  writeText(d.file("words.pcd"), pcd_head + "SIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                                            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n1 1 1\nfoo bar baz\n");
  auto words = loadPointCloud(d.file("words.pcd"));
  ASSERT_FALSE(words);
  expectErrorMentions(words.message(), {"words.pcd", "row 2 has 'foo', not a number"});
  // Integer fields take whole numbers within their type: PCL wrapped 300 in a U1 field to 44, cut 2.7 to 2.
  const std::string int_head = pcd_head + "SIZE 1 2 4\nTYPE U I I\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\n"
                                          "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n";
  for (const auto& [row, why] : std::vector<std::pair<std::string, std::string>>{
           {"300 1 1", "'300', not a whole number in the range of its field's type U1"},
           {"2.7 1 1", "'2.7', not a whole number in the range of its field's type U1"},
           {"-1 1 1", "'-1', not a whole number in the range of its field's type U1"},
           {"1 40000 1", "'40000', not a whole number in the range of its field's type I2"}}) {
    writeText(d.file("ints.pcd"), int_head + "1 -2 3\n" + row + "\n");
    auto ints = loadPointCloud(d.file("ints.pcd"));
    ASSERT_FALSE(ints) << row << ": " << ints->back().transpose();
    expectErrorMentions(ints.message(), {"ints.pcd", "row 2 has " + why});
  }
  writeText(d.file("ints.pcd"), int_head + "1 -2 3\n255 -32768 2147483647\n");
  auto good = loadPointCloud(d.file("ints.pcd"));
  ASSERT_TRUE(good) << good.message();
  EXPECT_EQ(*good, (std::vector<Vec3>{Vec3(1, -2, 3), Vec3(255, -32768, 2147483647)}));
  writeText(d.file("short.pcd"), pcd_head + "SIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\n"
                                            "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n1.00 1.00 1.00\n2.00 2.00 2.00\n");
  auto few = loadPointCloud(d.file("short.pcd"));
  ASSERT_FALSE(few);
  expectErrorMentions(few.message(), {"short.pcd", "declares 3 points, it has 2 rows"});
}

// PLY data against its header. PCL read the declared vertices and dropped what followed without a word.
TEST(BadInput, PlyDataThatDoesNotMatchItsHeader) {
  TempDir d;
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                           "property float z\n";
  auto refused = [&](const std::string& name, const std::string& text, const std::vector<std::string>& words) {
    writeText(d.file(name), text);
    auto r = loadPointCloud(d.file(name));
    ASSERT_FALSE(r) << name << ": " << r->size() << " points";
    std::vector<std::string> all{name};
    all.insert(all.end(), words.begin(), words.end());
    expectErrorMentions(r.message(), all);
  };
  refused("long.ply", head + "end_header\n1 1 1\n2 2 2\n3 3 3\n4 4 4\n5 5 5\n",
          {"declares 3 rows in all, 3 of them vertices; it has 5"});
  refused("narrow.ply", head + "end_header\n10 10 10\n2 2\n3 3 3\n", {"vertex 1 has 2 values, the header 3"});
  refused("word.ply", head + "end_header\n1 1 1\n2 2 2\n3 x 3\n", {"vertex 2 has 'x', not a number"});
  // A mesh: the faces follow the vertices, one row each, and are not vertices; one face too many is refused.
  const std::string mesh = head + "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
                                  "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  writeText(d.file("mesh.ply"), mesh);
  auto m = loadPointCloud(d.file("mesh.ply"));
  ASSERT_TRUE(m) << m.message();
  EXPECT_EQ(m->size(), 3u);
  refused("faces.ply", mesh + "3 0 2 1\n", {"declares 4 rows in all, 3 of them vertices; it has 5"});
  // PCL's own binary and ASCII PLYs load (with its camera element); binary with bytes to spare does not.
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int i = 0; i < 20; ++i) cloud.push_back(pcl::PointXYZ(0.1f * i, 0.2f, -0.3f * i));
  pcl::io::savePLYFileBinary(d.file("bin.ply"), cloud);
  pcl::io::savePLYFileASCII(d.file("ascii.ply"), cloud);
  for (const char* f : {"bin.ply", "ascii.ply"}) {
    auto r = loadPointCloud(d.file(f));
    ASSERT_TRUE(r) << f << ": " << r.message();
    ASSERT_EQ(r->size(), cloud.size()) << f;
    EXPECT_LT(((*r)[19] - Vec3(cloud[19].x, cloud[19].y, cloud[19].z)).norm(), 1e-5) << f;
  }
  std::ifstream in(d.file("bin.ply"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  refused("spare.ply", bytes + std::string(12, '\0'), {"12 bytes after the"});  // one more vertex
  writeText(d.file("newline.ply"), bytes + "\n");
  auto newline = loadPointCloud(d.file("newline.ply"));
  ASSERT_TRUE(newline) << newline.message();
  EXPECT_EQ(newline->size(), cloud.size());
}

// A finite T_world_file can still place a vertex or point at infinity (a scale of 1e300): named, not
// voxelised (a NaN cut point made a loop bound undefined).
TEST(BadInput, GeometryPlacedAtInfinity) {
  TempDir d;
  writeBinaryStl(d.file("far.stl"), cubeTriangles(0, 1e10));
  writeText(d.file("ok.pcd"), "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1\n"
                              "HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 1\nDATA ascii\n1e10 1 1\n");
  for (const char* f : {"far.stl", "ok.pcd"}) {
    std::string yaml = sceneYaml(f);
    const std::string identity = "T_world_file: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]";
    yaml.replace(yaml.find(identity), identity.size(), "T_world_file: [1e300,0,0,0, 0,1e300,0,0, 0,0,1e300,0, 0,0,0,1]");
    writeText(d.file("far.yaml"), yaml);
    auto s = loadSceneYaml(d.file("far.yaml"));
    ASSERT_FALSE(s) << f;
    expectErrorMentions(s.message(), {f, "not finite once placed by T_world_file"});
  }
}

TEST(BadInput, CorruptAndTruncatedOctomap) {
  TempDir d;
  octomap::OcTree tree(0.1);
  for (double x = 0.05; x < 2.0; x += 0.1) tree.updateNode(octomap::point3d(x, 0.37, 0.71), true);
  ASSERT_TRUE(tree.writeBinary(d.file("ok.bt")));
  std::string bytes = fileBytes(d.file("ok.bt"));
  writeText(d.file("trunc.bt"), bytes.substr(0, bytes.size() - 20));
  auto a = loadOctomap(d.file("trunc.bt"));
  ASSERT_FALSE(a);
  expectErrorMentions(a.message(), {"trunc.bt"});
  writeText(d.file("garbage.bt"), "# not an octomap\nabc");
  auto b = loadOctomap(d.file("garbage.bt"));
  ASSERT_FALSE(b);
  expectErrorMentions(b.message(), {"garbage.bt", "OctoMap"});
  // A valid header and then bytes that make every child a node with children: OctoMap's reader recursed
  // once per two bytes, and 200,000 of them overflowed the stack (a segfault). The good file still loads.
  const std::string header = bytes.substr(0, bytes.find("\ndata\n") + 6);
  writeText(d.file("deep.bt"), header + std::string(200000, '\xff'));
  auto c = loadOctomap(d.file("deep.bt"));
  ASSERT_FALSE(c);
  expectErrorMentions(c.message(), {"deep.bt", "deeper than 16 levels"});
  // The same bytes behind a header whose data OctoMap starts elsewhere than at the first 'data' line ('id'
  // alone takes the 'data' below as its value; a 'data junk' line): the depth check walked harmless bytes,
  // and OctoMap overflowed the stack. Each is refused by its header line, as is a resolution of 0.
  const std::string first = bytes.substr(0, bytes.find('\n') + 1);
  const std::string deep(200000, '\xff');
  const std::vector<std::pair<std::string, std::string>> headers = {
      {"id\ndata\n#AAA\nres 0.1\nsize 1\ndata\n", "header line 2 'id' is none of"},
      {"id OcTree\ndata junk\n#A\ndata\n", "header line 3 'data junk' is none of"},
      {"id OcTree\nsize 1\nres 0\ndata\n", "res '0' on header line 4 is no resolution > 0"},
      {"id OcTree\nsize 1\nres 0.1\n", "no 'data' line"}};
  for (const auto& [lines, why] : headers) {
    writeText(d.file("header.bt"), first + lines + deep);
    auto h = loadOctomap(d.file("header.bt"));
    ASSERT_FALSE(h) << lines;
    expectErrorMentions(h.message(), {"header.bt", why});
  }
  // Comments, empty lines and CR line ends are OctoMap's too.
  std::string crlf_header = "# comment\n\n" + header.substr(first.size());
  for (std::size_t at = 0; (at = crlf_header.find('\n', at)) != std::string::npos; at += 2) crlf_header.insert(at, "\r");
  writeText(d.file("crlf.bt"), first + crlf_header + bytes.substr(header.size()));
  auto crlf = loadOctomap(d.file("crlf.bt"));
  ASSERT_TRUE(crlf) << crlf.message();
  EXPECT_EQ(crlf->size(), 20u);
  auto ok = loadOctomap(d.file("ok.bt"));
  ASSERT_TRUE(ok) << ok.message();
  EXPECT_EQ(ok->size(), 20u);
}

TEST(BadInput, SceneYamlMissingOrWronglyTypedKeys) {
  TempDir d;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(0.5f, 0.5f, 1.0f));
  pcl::io::savePCDFileBinary(d.file("p.pcd"), cloud);
  const std::string good = sceneYaml("p.pcd");
  ASSERT_TRUE(loadSceneYaml((writeText(d.file("good.yaml"), good), d.file("good.yaml"))));
  {  // the start's yaw and the margin are read as given
    std::string turned = good;
    turned.replace(turned.find("yaw: 0"), 6, "yaw: 0.7");
    turned += "  margin: 0.3\n";
    writeText(d.file("turned.yaml"), turned);
    auto s = loadSceneYaml(d.file("turned.yaml"));
    ASSERT_TRUE(s) << s.message();
    EXPECT_DOUBLE_EQ(s->start.yaw, 0.7);
    EXPECT_NEAR(s->geometry().origin().x(), -1.3, 1e-9);  // the box's min less the margin
  }
  struct Case {
    std::string from, to, expect;
  };
  const std::vector<Case> cases = {
      {"  resolution: 0.1\n", "", "scene.resolution"},
      {"resolution: 0.1", "resolution: fine", "scene.resolution"},
      {"resolution: 0.1", "resolution: -0.1", "scene.resolution"},
      // a typo in the resolution: 3e9 voxels is refused, not allocated; at 2^-20 m the voxel count
      // wraps round 2^64 to 0, which once left an empty buffer that the loader wrote past
      {"resolution: 0.1", "resolution: 0.002", "scene.resolution"},
      {"resolution: 0.1", "resolution: 9.5367431640625e-07", "scene.resolution"},
      {"box: {min: [-1, -1, -1], max: [2, 2, 2]}", "box: {min: [-1, -1, -1], max: [1e12, 2, 2]}", "scene.box"},
      {"max: [2, 2, 2]", "max: [2, 2]", "scene.box.max"},
      {"min: [-1, -1, -1]", "min: [3, -1, -1]", "scene.box"},
      {"  T_world_file: [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]\n", "", "scene.T_world_file"},
      {"0,0,0,1]", "0,0,1,1]", "scene.T_world_file"},
      {"yaw: 0", "yaw: north", "scene.start.yaw"},
      {"yaw: 0", "yaw: .nan", "scene.start.yaw"},
      {"ground_plane: false", "ground_plane: false\n  margin: -0.5", "scene.margin"},
      {"ground_plane: false", "ground_plane: false\n  margin: .nan", "scene.margin"},
      {"  name: t\n", "", "scene.name"},
      {"ground_plane: false", "ground_plane: maybe", "scene.ground_plane"},
      // keys the loader does not read (a typo loaded with no floor) or given twice (the first value was taken)
      {"ground_plane: false", "ground_plnae: true",
       "unknown key 'scene.ground_plnae' ('scene' takes name, file, T_world_file, resolution, box, start, "
       "ground_plane, margin)"},
      {"  resolution: 0.1\n", "  resolution: 0.1\n  resolution: 10\n", "key 'scene.resolution' is given more than once"},
      {"box: {min", "box: {mni: [0, 0, 0], min", "unknown key 'scene.box.mni' ('scene.box' takes min, max)"},
      {"max: [2, 2, 2]", "max: [2, 2, 2], max: [3, 3, 3]", "key 'scene.box.max' is given more than once"},
      {"yaw: 0", "yaw: 0, pitch: 0", "unknown key 'scene.start.pitch' ('scene.start' takes position, yaw)"},
      {"scene:\n", "scenery: 1\nscene:\n", "unknown key 'scenery' (the file takes scene)"},
      {"  name: t\n", "  name: t\n  generator_seed: 4\n", "unknown key 'scene.generator_seed'"},
  };
  for (const Case& c : cases) {
    std::string y = good;
    const auto pos = y.find(c.from);
    ASSERT_NE(pos, std::string::npos) << c.from;
    y.replace(pos, c.from.size(), c.to);
    writeText(d.file("bad.yaml"), y);
    auto s = loadSceneYaml(d.file("bad.yaml"));
    ASSERT_FALSE(s) << "accepted: " << y;
    expectErrorMentions(s.message(), {"bad.yaml", c.expect});
  }
  writeText(d.file("broken.yaml"), "scene: [unclosed\n");
  auto s = loadSceneYaml(d.file("broken.yaml"));
  ASSERT_FALSE(s);
  expectErrorMentions(s.message(), {"broken.yaml", "YAML"});
}

TEST(BadInput, StartInsideObstacleOrOutsideBox) {
  TempDir d;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(0.55f, 0.55f, 0.55f));
  pcl::io::savePCDFileBinary(d.file("p.pcd"), cloud);
  writeText(d.file("in.yaml"), sceneYaml("p.pcd", "ground_plane: false", "[0.52, 0.58, 0.51]"));
  auto a = loadSceneYaml(d.file("in.yaml"));
  ASSERT_FALSE(a);
  expectErrorMentions(a.message(), {"in.yaml", "inside an obstacle"});
  writeText(d.file("out.yaml"), sceneYaml("p.pcd", "ground_plane: false", "[5, 0, 0]"));
  auto b = loadSceneYaml(d.file("out.yaml"));
  ASSERT_FALSE(b);
  expectErrorMentions(b.message(), {"out.yaml", "outside the exploration box"});
  // On the box's top face: in a voxel of the margin, with nothing observable.
  writeText(d.file("top.yaml"), sceneYaml("p.pcd", "ground_plane: false", "[0.05, 0.05, 2]"));
  auto c = loadSceneYaml(d.file("top.yaml"));
  ASSERT_FALSE(c);
  expectErrorMentions(c.message(), {"top.yaml", "voxel centred at", "outside the exploration box"});
}

namespace {

struct PcdField {
  std::string name;
  int size;
  char type;
  int count;
};

// A PCD header declaring `fields` and `points` points (one row), with the word `data` after DATA.
std::string pcdHeader(const std::vector<PcdField>& fields, int points, const std::string& data) {
  std::ostringstream os;
  os << "# .PCD v0.7\nVERSION 0.7\nFIELDS";
  for (const auto& f : fields) os << " " << f.name;
  os << "\nSIZE";
  for (const auto& f : fields) os << " " << f.size;
  os << "\nTYPE";
  for (const auto& f : fields) os << " " << f.type;
  os << "\nCOUNT";
  for (const auto& f : fields) os << " " << f.count;
  os << "\nWIDTH " << points << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << points << "\nDATA " << data << "\n";
  return os.str();
}

template <typename T>
void appendBytes(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof(v));
}

void expectPoints(const std::string& path, const std::vector<Vec3>& want) {
  auto r = loadPointCloud(path);
  ASSERT_TRUE(r) << r.message();
  ASSERT_EQ(r->size(), want.size()) << path;
  for (std::size_t i = 0; i < want.size(); ++i)
    EXPECT_LT(((*r)[i] - want[i]).norm(), 1e-12) << path << " point " << i << ": " << (*r)[i].transpose();
}

}  // namespace

// A field given twice is refused by name: which of the two x values is the point's would be a guess.
TEST(BadInput, PcdFieldGivenTwice) {
  TempDir d;
  writeText(d.file("twice.pcd"), pcdHeader({{"x", 4, 'F', 1}, {"y", 4, 'F', 1}, {"z", 4, 'F', 1}, {"x", 4, 'F', 1}}, 1,
                                           "ascii") + "1 2 3 9\n");
  auto r = loadPointCloud(d.file("twice.pcd"));
  ASSERT_FALSE(r) << (*r)[0].transpose();
  expectErrorMentions(r.message(), {"twice.pcd", "'x' twice"});
}

// x, y, z stored as float64 or an integer type are read at their offsets in their own type: PCL's
// conversion to PointXYZ, which only matched the names, made every such point (0, 0, 0) without a word.
TEST(PointCloud, XyzOfEveryNumericTypeKeepTheirValues) {
  TempDir d;
  // float64 behind another field (x is not at offset 0), with values a float32 cannot hold.
  const std::vector<Vec3> fine = {Vec3(1.000000123456789, -2.5, 0.1), Vec3(-7.123456789012, 3.0, 12.5)};
  const std::vector<PcdField> f64 = {{"intensity", 4, 'F', 1}, {"x", 8, 'F', 1}, {"y", 8, 'F', 1}, {"z", 8, 'F', 1}};
  std::ostringstream ascii;
  ascii.precision(17);
  for (const Vec3& p : fine) ascii << "0.5 " << p.x() << " " << p.y() << " " << p.z() << "\n";
  writeText(d.file("f64a.pcd"), pcdHeader(f64, 2, "ascii") + ascii.str());
  expectPoints(d.file("f64a.pcd"), fine);
  std::string bin = pcdHeader(f64, 2, "binary");
  for (const Vec3& p : fine) {
    appendBytes(bin, 0.5f);
    for (int a = 0; a < 3; ++a) appendBytes(bin, p[a]);
  }
  writeText(d.file("f64b.pcd"), bin);
  expectPoints(d.file("f64b.pcd"), fine);
  // Integer types, mixed: int32 x, int16 y, uint8 z; and int8, uint16, uint32.
  const std::vector<Vec3> whole = {Vec3(-7, -300, 200), Vec3(100000, 12, 0)};
  writeText(d.file("int.pcd"), pcdHeader({{"x", 4, 'I', 1}, {"y", 2, 'I', 1}, {"z", 1, 'U', 1}}, 2, "ascii") +
                                   "-7 -300 200\n100000 12 0\n");
  expectPoints(d.file("int.pcd"), whole);
  std::string ibin = pcdHeader({{"x", 1, 'I', 1}, {"y", 2, 'U', 1}, {"z", 4, 'U', 1}}, 2, "binary");
  appendBytes(ibin, std::int8_t(-7)), appendBytes(ibin, std::uint16_t(65000)), appendBytes(ibin, std::uint32_t(4000000000u));
  appendBytes(ibin, std::int8_t(5)), appendBytes(ibin, std::uint16_t(0)), appendBytes(ibin, std::uint32_t(1));
  writeText(d.file("int.bin.pcd"), ibin);
  expectPoints(d.file("int.bin.pcd"), {Vec3(-7, 65000, 4000000000.0), Vec3(5, 0, 1)});
  // PLY: double and uchar properties, ASCII and binary.
  const std::string ply_head = "ply\nformat ascii 1.0\nelement vertex 2\n";
  writeText(d.file("dbl.ply"), ply_head + "property double x\nproperty double y\nproperty double z\nend_header\n"
                                   "1.000000123456789 -2.5 0.1\n-7.123456789012 3 12.5\n");
  expectPoints(d.file("dbl.ply"), fine);
  writeText(d.file("uchar.ply"), ply_head + "property uchar x\nproperty uchar y\nproperty uchar z\nend_header\n"
                                            "1 2 3\n250 0 7\n");
  expectPoints(d.file("uchar.ply"), {Vec3(1, 2, 3), Vec3(250, 0, 7)});
  std::string pbin = "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty float intensity\n"
                     "property double x\nproperty double y\nproperty double z\nend_header\n";
  for (const Vec3& p : fine) {
    appendBytes(pbin, 0.5f);
    for (int a = 0; a < 3; ++a) appendBytes(pbin, p[a]);
  }
  writeText(d.file("dbl.bin.ply"), pbin);
  expectPoints(d.file("dbl.bin.ply"), fine);
  // A coordinate of several values is refused, naming the field.
  writeText(d.file("count2.pcd"), pcdHeader({{"x", 4, 'F', 2}, {"y", 4, 'F', 1}, {"z", 4, 'F', 1}}, 1, "ascii") +
                                      "1 1 1 1\n");
  auto c = loadPointCloud(d.file("count2.pcd"));
  ASSERT_FALSE(c) << c->size() << " points, the first " << c->front().transpose();
  expectErrorMentions(c.message(), {"count2.pcd", "field 'x'", "COUNT 2"});
  // NaN in a float64 field is still refused.
  writeText(d.file("nan64.pcd"), pcdHeader(f64, 1, "ascii") + "0 1 nan 2\n");
  auto n = loadPointCloud(d.file("nan64.pcd"));
  ASSERT_FALSE(n);
  expectErrorMentions(n.message(), {"nan64.pcd", "NaN"});
}

// DATA is read as PCL reads it: any word PCL does not know as binary or binary_compressed is ASCII to it, so
// "ASCII" gets the ASCII row checks (it skipped them), and a word that is none of the three is refused by
// name. Binary data with a whole point more than declared is refused (a newline after it is not a point).
TEST(BadInput, PcdDataWordAndSurplusBinaryData) {
  TempDir d;
  const std::vector<PcdField> xyz = {{"x", 4, 'F', 1}, {"y", 4, 'F', 1}, {"z", 4, 'F', 1}};
  writeText(d.file("upper.pcd"), pcdHeader(xyz, 3, "ASCII") + "1.05 1.05 1.05\n0.5 0.5\nfoo bar baz\n");
  auto a = loadPointCloud(d.file("upper.pcd"));
  ASSERT_FALSE(a) << a->size() << " points";
  expectErrorMentions(a.message(), {"upper.pcd", "row 2 has 2 values, the header 3"});
  writeText(d.file("long.pcd"), pcdHeader(xyz, 2, "Ascii") + "1 1 1\n-1 1 1\n-1 -1 1\n");
  auto l = loadPointCloud(d.file("long.pcd"));
  ASSERT_FALSE(l) << l->size() << " points";
  expectErrorMentions(l.message(), {"long.pcd", "declares 2 points, it has 3 rows"});
  writeText(d.file("fine.pcd"), pcdHeader(xyz, 2, "ASCII") + "1 1 1\n-1 1 1\n");
  expectPoints(d.file("fine.pcd"), {Vec3(1, 1, 1), Vec3(-1, 1, 1)});
  std::string point;
  for (float v : {1.0f, 1.0f, 1.0f}) appendBytes(point, v);
  for (const char* word : {"foo", "Binary", "binary_lzf"}) {
    writeText(d.file("word.pcd"), pcdHeader(xyz, 1, word) + point);
    auto w = loadPointCloud(d.file("word.pcd"));
    ASSERT_FALSE(w) << word << ": " << w->size() << " points";
    expectErrorMentions(w.message(), {"word.pcd", std::string("DATA '") + word + "'"});
  }
  writeText(d.file("bin.pcd"), pcdHeader(xyz, 1, "binary") + point);
  expectPoints(d.file("bin.pcd"), {Vec3(1, 1, 1)});
  writeText(d.file("nl.pcd"), pcdHeader(xyz, 1, "binary") + point + "\n");
  expectPoints(d.file("nl.pcd"), {Vec3(1, 1, 1)});
  writeText(d.file("extra.pcd"), pcdHeader(xyz, 1, "binary") + point + point);
  auto e = loadPointCloud(d.file("extra.pcd"));
  ASSERT_FALSE(e) << e->size() << " points";
  expectErrorMentions(e.message(), {"extra.pcd", "12 bytes after the 12"});
}

// A header line before DATA that is no PCD keyword: PCL's reader stops its header there and reads the points
// from the file's first byte (points at the origin, loaded without a word), or matches the key by its prefix
// ('POINTS_ 1e8' sized a 1.2 GB buffer). Empty lines and comments are PCL's too, and load.
TEST(BadInput, PcdHeaderLinesThatAreNoKeyword) {
  TempDir d;
  const std::vector<PcdField> xyz = {{"x", 4, 'F', 1}, {"y", 4, 'F', 1}, {"z", 4, 'F', 1}};
  const std::string header = pcdHeader(xyz, 2, "ascii");
  const std::size_t data_at = header.find("DATA");
  auto withLine = [&](const std::string& line) { return header.substr(0, data_at) + line + header.substr(data_at); };
  const std::string rows = "5 5 5\n6 6 6\n";
  for (const std::string& line : {std::string("FOO bar\n"), std::string("POINTS_ 100000000\n"), std::string(" \n"),
                                  std::string("COUNTS 1 1 1\n")}) {
    writeText(d.file("odd.pcd"), withLine(line) + rows);
    auto r = loadPointCloud(d.file("odd.pcd"));
    ASSERT_FALSE(r) << line << ": " << r->size() << " points, the first at " << r->front().transpose();
    expectErrorMentions(r.message(), {"odd.pcd", "line 11 '" + line.substr(0, line.size() - 1) + "' is no PCD header line"});
  }
  writeText(d.file("fine.pcd"), withLine("\n# a comment\n") + rows);
  expectPoints(d.file("fine.pcd"), {Vec3(5, 5, 5), Vec3(6, 6, 6)});
}

// Extensions are matched whatever their case, by the cloud loader as by the scene loader.
TEST(PointCloud, UpperCaseExtensions) {
  TempDir d;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(0.55f, 0.55f, 0.55f));
  pcl::io::savePCDFileBinary(d.file("UP.PCD"), cloud);
  pcl::io::savePLYFileBinary(d.file("Up.Ply"), cloud);
  writeBinaryStl(d.file("UP.STL"), cubeTriangles(0.5, 1.0));
  for (const char* f : {"UP.PCD", "Up.Ply"}) {
    auto pts = loadPointCloud(d.file(f));
    ASSERT_TRUE(pts) << pts.message();
    EXPECT_EQ(pts->size(), 1u) << f;
  }
  for (const char* f : {"UP.PCD", "Up.Ply", "UP.STL"}) {
    writeText(d.file("up.yaml"), sceneYaml(f));
    auto s = loadSceneYaml(d.file("up.yaml"));
    ASSERT_TRUE(s) << s.message();
    EXPECT_TRUE(s->isOccupied(Vec3(0.55, 0.55, 0.55))) << f;
  }
}

// A box holding no voxel centre has no voxel to explore (go_feap_scene then aborted writing an empty image),
// and a start in a voxel whose centre lies outside the box has nothing observable: both are refused.
TEST(BadInput, BoxWithoutVoxelCentresAndStartVoxelOutsideTheBox) {
  Scene flat = makeEmptyScene("flat", Aabb{Vec3(-2, -2, 0.51), Vec3(2, 2, 0.54)}, 0.1, 1.0);
  flat.start.position = Vec3(0.2, 0.2, 0.52);
  const auto a = validateScene(flat);
  ASSERT_FALSE(a.ok());
  expectErrorMentions(a.message(), {"scene 'flat'", "holds no voxel centre along z"});
  Scene edge = makeEmptyScene("edge", Aabb{Vec3(-2, -2, 0), Vec3(2, 2, 2)}, 0.1, 1.0);
  edge.start.position = Vec3(0.55, 0.55, 2.0);  // on the box's top face: in the voxel above it
  const auto b = validateScene(edge);
  ASSERT_FALSE(b.ok());
  expectErrorMentions(b.message(), {"scene 'edge'", "start (0.55, 0.55, 2)", "voxel centred at (0.55, 0.55, 2.05)",
                                    "outside the exploration box"});
  edge.start.position = Vec3(0.55, 0.55, 1.95);
  ASSERT_TRUE(validateScene(edge).ok()) << validateScene(edge).message();
  EXPECT_GT(computeObservableSet(edge).total(), 0u);
}

// ground_plane must not hide geometry misplaced outside the box: the file's own geometry is counted inside
// the box before the floor is added.
TEST(SceneYaml, GeometryOnlyOutsideTheBoxIsRefusedWithOrWithoutAGroundPlane) {
  TempDir d;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(2.55f, 0.55f, 0.55f));  // in the grid's margin, outside the box
  pcl::io::savePCDFileBinary(d.file("out.pcd"), cloud);
  cloud[0].x = 1.55f;
  pcl::io::savePCDFileBinary(d.file("in.pcd"), cloud);
  for (const char* floor : {"ground_plane: true", "ground_plane: false"}) {
    writeText(d.file("m.yaml"), sceneYaml("out.pcd", floor));
    auto s = loadSceneYaml(d.file("m.yaml"));
    ASSERT_FALSE(s) << floor;
    expectErrorMentions(s.message(), {"m.yaml", "out.pcd", "no geometry falls inside the exploration box"});
    writeText(d.file("i.yaml"), sceneYaml("in.pcd", floor));
    auto ok = loadSceneYaml(d.file("i.yaml"));
    ASSERT_TRUE(ok) << floor << ": " << ok.message();
    EXPECT_TRUE(ok->isOccupied(Vec3(1.55, 0.55, 0.55)));
  }
}

// A generated maze's YAML: a key the loader does not read (the maze's `hieght` was ignored in silence) or a key
// given twice is refused, naming it; a name that is no string is named too (it said "bad conversion").
TEST(BadInput, GeneratedMazeYamlUnknownRepeatedOrWronglyTypedKeys) {
  TempDir d;
  const std::string maze = "scene:\n  name: m\n  generator: maze\n  maze: {size_x: 10, size_y: 6, height: 3, cell_size: 2}\n";
  writeText(d.file("maze.yaml"), maze);
  auto m = makeScene(d.file("maze.yaml"), 0);
  ASSERT_TRUE(m) << m.message();
  EXPECT_EQ(m->name, "m");
  writeText(d.file("maze.YML"), maze);  // .yml, in any case, is YAML too
  auto yml = makeScene(d.file("maze.YML"), 0);
  ASSERT_TRUE(yml) << yml.message();
  EXPECT_EQ(yml->occupied.size(), m->occupied.size());
  const std::vector<std::array<std::string, 3>> cases = {  // replace what, by what, expected message
      {"height: 3", "hieght: 30", "unknown key 'scene.maze.hieght' ('scene.maze' takes size_x, size_y, height, cell_size)"},
      {"size_y: 6", "size_x: 12", "key 'scene.maze.size_x' is given more than once"},
      {"  name: m\n", "  name: m\n  file: p.pcd\n", "unknown key 'scene.file' ('scene' takes name, generator, maze)"},
      {"  name: m\n", "  name: m\n  name: n\n", "key 'scene.name' is given more than once"},
      {"name: m", "name: {a: 1}", "key 'scene.name' must be a non-empty string"},
      // Not UTF-8 (a Latin-1 byte aborted go_feap_scene at scene.json), a control character, an overlong form.
      {"name: m", "name: \"caf\xe9\"", "key 'scene.name' must be UTF-8 text without control characters"},
      {"name: m", "name: \"a\\tb\"", "key 'scene.name' must be UTF-8 text without control characters"},
      {"name: m", "name: \"\xc0\xaf\"", "key 'scene.name' must be UTF-8 text without control characters"},
      // A Latin-1 byte with more text after it (its next byte is no continuation), a surrogate, past U+10FFFF.
      {"name: m", "name: \"caf\xe9 bar\"", "key 'scene.name' must be UTF-8 text without control characters"},
      {"name: m", "name: \"\xed\xa0\x80\"", "key 'scene.name' must be UTF-8 text without control characters"},
      {"name: m", "name: \"\xf4\x90\x80\x80\"", "key 'scene.name' must be UTF-8 text without control characters"},
  };
  for (const auto& [from, to, expect] : cases) {
    std::string y = maze;
    y.replace(y.find(from), from.size(), to);
    writeText(d.file("badmaze.yaml"), y);
    auto s = makeScene(d.file("badmaze.yaml"), 0);
    ASSERT_FALSE(s) << "accepted: " << y;
    expectErrorMentions(s.message(), {"badmaze.yaml", expect});
  }
  std::string utf8 = maze;
  utf8.replace(utf8.find("name: m"), 7, "name: \"caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x99\x82\"");  // é, €, an emoji
  writeText(d.file("utf8.yaml"), utf8);
  auto u = makeScene(d.file("utf8.yaml"), 0);
  ASSERT_TRUE(u) << u.message();
  EXPECT_EQ(u->name, "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x99\x82");
  // Every maze key reaches the generator (the shipped files all give the defaults for height and cell_size).
  writeText(d.file("tall.yaml"),
            "scene:\n  name: tall\n  generator: maze\n  maze: {size_x: 10, size_y: 6, height: 4.5, cell_size: 2.5}\n");
  auto tall = makeScene(d.file("tall.yaml"), 0);
  ASSERT_TRUE(tall) << tall.message();
  MazeConfig config;
  config.size_x = 10.0;
  config.size_y = 6.0;
  config.height = 4.5;
  config.cell_size = 2.5;
  auto direct = generateMaze(config, 0);
  ASSERT_TRUE(direct) << direct.message();
  EXPECT_NEAR(tall->box.size().z(), 4.5, 1e-9);
  EXPECT_EQ(occupiedSet(*tall), occupiedSet(*direct));
}

// Singular means columns (nearly) dependent, whatever the scale: a millimetre mesh turned 45 degrees
// (|det| 1e-9) was refused by an absolute |det| < 1e-9, and a micrometre one by any turn.
TEST(SceneYaml, SmallScalesAreNotSingularDependentColumnsAre) {
  TempDir d;
  writeBinaryStl(d.file("mm.stl"), cubeTriangles(500, 1000));          // a 0.5 m cube in millimetres
  writeBinaryStl(d.file("um.stl"), cubeTriangles(500000, 1000000));    // and in micrometres
  const std::string c = "0.00070710678", n = "-0.00070710678";
  struct Case {
    std::string file, T;
    Vec3 on_face;  // a point on a face of the placed cube, off every voxel edge
  };
  const std::vector<Case> ok = {
      {"mm.stl", "[" + c + "," + n + ",0,0, " + c + "," + c + ",0,0, 0,0,0.001,0, 0,0,0,1]",
       Vec3(0.25 * 0.70710678, 1.75 * 0.70710678, 0.75)},
      {"um.stl", "[1e-6,0,0,0, 0,1e-6,0,0, 0,0,1e-6,0, 0,0,0,1]", Vec3(1.0, 0.75, 0.75)},
  };
  const std::string identity = "[1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]";
  for (const Case& k : ok) {
    std::string y = sceneYaml(k.file);
    y.replace(y.find(identity), identity.size(), k.T);
    writeText(d.file("t.yaml"), y);
    auto s = loadSceneYaml(d.file("t.yaml"));
    ASSERT_TRUE(s) << k.T << ": " << s.message();
    EXPECT_TRUE(s->isOccupied(k.on_face)) << k.T;
  }
  for (const std::string T : {"[1,0,1,0, 0,1,0,0, 0,0,0,0, 0,0,0,1]", "[1e6,0,1e6,0, 0,1e6,0,0, 0,0,1e-4,0, 0,0,0,1]",
                              "[1,0,0,0, 0,0,0,0, 0,0,1,0, 0,0,0,1]"}) {
    std::string y = sceneYaml("mm.stl");
    y.replace(y.find(identity), identity.size(), T);
    writeText(d.file("s.yaml"), y);
    auto s = loadSceneYaml(d.file("s.yaml"));
    ASSERT_FALSE(s) << T;
    expectErrorMentions(s.message(), {"s.yaml", "scene.T_world_file", "singular"});
  }
}

// A leaf marks every grid voxel its cube, placed by T_world_file, overlaps; a leaf face lying on a voxel face
// marks only the voxel on the leaf's side (so leaves filling whole voxels mark what they did). Marking only
// the voxels whose centres a leaf covered lost a 0.03 m wall on a 0.1 m grid and marked a 0.05 m one in part.
TEST(Octomap, LeavesFinerThanTheGridMarkEveryVoxelTheyOverlap) {
  TempDir d;
  const double kPi = 3.14159265358979323846;
  for (double leaf : {0.03, 0.05}) {
    SCOPED_TRACE(leaf);
    // A wall one leaf thick, x in [leaf, 2 leaf], y in [-0.5, 0.5], z in [0, 1] (to whole leaves).
    octomap::OcTree tree(leaf);
    std::vector<Vec3> centres;
    const int half = static_cast<int>(std::floor(0.5 / leaf + 1e-9)), high = static_cast<int>(std::floor(1.0 / leaf + 1e-9));
    for (int j = -half; j < half; ++j)
      for (int k = 0; k < high; ++k) {
        centres.emplace_back(1.5 * leaf, (j + 0.5) * leaf, (k + 0.5) * leaf);
        tree.updateNode(octomap::point3d(centres.back().x(), centres.back().y(), centres.back().z()), true);
      }
    ASSERT_TRUE(tree.writeBinary(d.file("w.bt")));
    writeText(d.file("w.yaml"), sceneYaml("w.bt", "ground_plane: false", "[1.55, 1.55, 1.55]"));
    auto s = loadSceneYaml(d.file("w.yaml"));
    ASSERT_TRUE(s) << s.message();
    // The voxels x in [0, 0.1), y in [-0.5, 0.5), z in [0, 1): one layer, and nothing else.
    std::size_t in_wall = 0;
    for (int j = -5; j < 5; ++j)
      for (int k = 0; k < 10; ++k) in_wall += s->isOccupied(Vec3(0.05, 0.1 * j + 0.05, 0.1 * k + 0.05));
    EXPECT_EQ(in_wall, 100u);
    EXPECT_EQ(s->occupiedCount(), 100u);

    // Turned 45 degrees about z and moved: every voxel holding a point of a leaf is marked (no holes), and
    // every marked voxel lies near a leaf (its centre within the two cubes' half diagonals of a leaf centre).
    Eigen::Affine3d T = Eigen::Translation3d(0.31, 0.2, 0.0) * Eigen::AngleAxisd(kPi / 4, Vec3::UnitZ());
    std::ostringstream yaml;
    yaml.precision(17);
    yaml << "scene:\n  name: t\n  file: w.bt\n  T_world_file: [";
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) yaml << T.matrix()(r, c) << (r == 3 && c == 3 ? "]\n" : ", ");
    yaml << "  resolution: 0.1\n  box: {min: [-1, -1, -1], max: [2, 2, 2]}\n  start: {position: [1.55, 1.55, 1.55], yaw: 0}\n";
    writeText(d.file("turned.yaml"), yaml.str());
    auto t = loadSceneYaml(d.file("turned.yaml"));
    ASSERT_TRUE(t) << t.message();
    std::size_t holes = 0, far = 0;
    for (const Vec3& c : centres)
      for (int a = 0; a < 64; ++a) {
        const Vec3 f = c + leaf * Vec3((a & 3) * 0.25 - 0.375, ((a >> 2) & 3) * 0.25 - 0.375, (a >> 4) * 0.25 - 0.375);
        holes += !t->isOccupied(T * f);
      }
    const double reach = 0.5 * std::sqrt(3.0) * (0.1 + leaf);
    const auto& g = t->geometry();
    for (std::size_t l : occupiedSet(*t)) {
      const Vec3 v = g.indexToCoord(g.unlinear(l));
      bool near = false;
      for (const Vec3& c : centres) near = near || (T * c - v).norm() <= reach;
      far += !near;
    }
    EXPECT_EQ(holes, 0u);
    EXPECT_EQ(far, 0u);
  }
}

// Every solid of an ASCII STL is read (a second `solid ... endsolid` was dropped); a word out of place (a
// fourth coordinate, stray words between facets) is refused with its line; a coordinate beyond double's range
// is called out of range (it was "non-numeric"). STL's words are separated by any white space, lines or not.
TEST(BadInput, AsciiStlSolidsAndMalformedLines) {
  TempDir d;
  const std::string a = " facet normal 0 0 1\n  outer loop\n   vertex 1 1 0.5\n   vertex 1.5 1 0.5\n"
                        "   vertex 1 1.5 0.5\n  endloop\n endfacet\n";
  const std::string b = " facet normal 0 0 1\n  outer loop\n   vertex -1 -1 0.5\n   vertex -1.5 -1 0.5\n"
                        "   vertex -1 -1.5 0.5\n  endloop\n endfacet\n";
  writeText(d.file("two.stl"), "solid a\n" + a + "endsolid a\nsolid b\n" + b + "endsolid b\n");
  auto two = loadStl(d.file("two.stl"));
  ASSERT_TRUE(two) << two.message();
  ASSERT_EQ(two->triangleCount(), 2u);
  EXPECT_EQ(two->vertices[1], Vec3(1.5, 1, 0.5));
  EXPECT_EQ(two->vertices[4], Vec3(-1.5, -1, 0.5));
  writeText(d.file("line.stl"), "solid x\nfacet normal 0 0 1 outer loop vertex 1 1 0.5 vertex 1.5 1 0.5 vertex 1 1.5 0.5 "
                                "endloop endfacet\nendsolid x\n");
  auto line = loadStl(d.file("line.stl"));
  ASSERT_TRUE(line) << line.message();
  EXPECT_EQ(line->triangleCount(), 1u);
  // The first facet on the solid's line, and a whole file of two solids on one line (a name there cannot
  // hold the word 'facet' or, after 'endsolid', 'solid').
  std::string flat = "solid a " + a + "endsolid a solid b " + b + "endsolid b";
  std::replace(flat.begin(), flat.end(), '\n', ' ');
  for (const auto& [name, text] : {std::pair<std::string, std::string>{"sameline.stl", "solid my part " + a + "endsolid my part\n"},
                                   {"flat.stl", flat}}) {
    writeText(d.file(name), text);
    auto r = loadStl(d.file(name));
    ASSERT_TRUE(r) << name << ": " << r.message();
    EXPECT_EQ(r->triangleCount(), name == "flat.stl" ? 2u : 1u) << name;
    EXPECT_EQ(r->vertices[1], Vec3(1.5, 1, 0.5)) << name;
  }
  // A name holding the word 'solid' after 'endsolid' (some CAD tools write "endsolid Solid Body 1"), at the
  // end of the file or before the next solid: a name, not a solid (it was called truncated or corrupt).
  for (const auto& [name, text, count] :
       {std::tuple<std::string, std::string, std::size_t>{"cad.stl", "solid Part\n" + a + "endsolid Solid Body 1\n", 1},
        {"cad2.stl", "solid A\n" + a + "endsolid Solid A\nsolid B\n" + b + "endsolid Solid B\n", 2}}) {
    writeText(d.file(name), text);
    auto r = loadStl(d.file(name));
    ASSERT_TRUE(r) << name << ": " << r.message();
    EXPECT_EQ(r->triangleCount(), count) << name;
  }
  auto refused = [&](const std::string& name, const std::string& text, const std::vector<std::string>& words) {
    expectStlRefused(d.file(name), text, words);
  };
  refused("cut.stl", "solid A\n" + a + "endsolid Solid A\nsolid B\n facet normal 0 0 1\n", {"truncated"});
  std::string four = "solid x\n" + a + "endsolid x\n";
  four.replace(four.find("1 1.5 0.5"), 9, "1 1.5 0.5 7");
  refused("four.stl", four, {"line 6", "'7'"});
  refused("junk.stl", "solid x\n" + a + " GARBAGE here 12 blah\n" + b + "endsolid x\n", {"line 9", "'GARBAGE'"});
  std::string huge = "solid x\n" + a + "endsolid x\n";
  huge.replace(huge.find("1.5 1 0.5"), 9, "1.5 1 1e999");
  refused("huge.stl", huge, {"line 5", "'1e999'", "out of range"});
  refused("after.stl", "solid x\n" + a + "endsolid x\nsome words\n", {"line 10", "'some'"});
  refused("open.stl", "solid x\n" + a + "solid y\n" + b + "endsolid y\n", {"line 9", "'solid'"});
}
