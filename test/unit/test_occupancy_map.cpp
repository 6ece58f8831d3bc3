// Occupancy from depth against ground truth: depth rendered by the simulator's camera in
// known scenes, integrated, and compared voxel by voxel.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <functional>
#include <limits>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <octomap/OcTree.h>

#include "go_feap/map/voxel_map.h"
#include "go_feap/sim/depth_camera.h"
#include "go_feap/world/shapes.h"
#include "go_feap/world/generators.h"

using namespace go_feap;
using common::Aabb;
using common::Index3;
using common::Vec3;
using map::VoxelState;

namespace {

map::DepthIntrinsics intrinsicsOf(const sim::CameraIntrinsics& c) {
  return {c.width, c.height, c.fx, c.fy, c.cx, c.cy};
}

// Optical frame (z forward, x right, y down) of a camera at p looking along yaw, level.
Eigen::Isometry3d cameraPose(const Vec3& p, double yaw) {
  Eigen::Matrix3d R_B_C;
  R_B_C << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw, Vec3::UnitZ()).toRotationMatrix() * R_B_C;
  T.translation() = p;
  return T;
}

struct Fixture {
  world::Scene scene;
  sim::DepthCameraConfig camera;
  std::vector<Eigen::Isometry3d> poses;
};

// The maze, seen while turning in place at the start and at two cells further on.
Fixture mazeFixture() {
  Fixture f;
  auto s = world::generateMaze(world::MazeConfig(), 0);
  EXPECT_TRUE(s) << s.message();
  f.scene = std::move(s).value();
  for (const Vec3& p : {Vec3(-9, -4, 1.0), Vec3(-9, -2, 1.3), Vec3(-7, -4, 0.8)})
    for (int k = 0; k < 16; ++k) f.poses.push_back(cameraPose(p, k * 2 * M_PI / 16));
  return f;
}

map::MapConfig mapConfig() {
  map::MapConfig c;
  c.occupancy.skip_pixel = 2;
  return c;
}

// Every ground-truth voxel a full-resolution camera ray ends in (the visible surface).
std::set<std::size_t> visibleSurface(const Fixture& f, const sim::DepthRenderer& renderer, const common::GridGeometry& geo) {
  std::set<std::size_t> seen;
  const auto K = f.camera.intrinsics();
  cv::Mat depth;
  for (const auto& T : f.poses) {
    renderer.render(T, depth);
    for (int v = 0; v < depth.rows; ++v)
      for (int u = 0; u < depth.cols; ++u) {
        const double d = depth.at<float>(v, u);
        if (!sim::isReturn(static_cast<float>(d))) continue;
        const Vec3 ray = T.linear() * Vec3((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
        const Vec3 p = T.translation() + ray * d + ray.normalized() * 1e-4;
        const Index3 idx = geo.coordToIndex(p);
        if (geo.inside(idx) && f.scene.isOccupied(p)) seen.insert(geo.linear(idx));
      }
  }
  return seen;
}

// A tiny camera 1.5 m up looking along +x at a wall 2.05 m ahead (`wall`), or through it at nothing within
// 9 m (`through`); the return on the optical axis is marked at `surface`, just behind the wall's face.
struct WallAhead {
  const map::DepthIntrinsics K{8, 6, 8.0, 8.0, 4.0, 3.0};
  const world::Scene empty = world::makeEmptyScene("empty", {Vec3(-1, -3, 0), Vec3(5, 3, 3)}, 0.1, 0.0);
  const Eigen::Isometry3d T = cameraPose(Vec3(0, 0, 1.5), 0.0);
  const cv::Mat wall{K.height, K.width, CV_32FC1, cv::Scalar(2.05f)};
  const cv::Mat through{K.height, K.width, CV_32FC1, cv::Scalar(9.0f)};
  const Vec3 surface{2.052, 0.0, 1.5};

  /// How many frames of `depth` integrated into `m` until the surface is `wanted` (0: not within `limit`).
  int framesUntil(map::VoxelMap& m, const cv::Mat& depth, VoxelState wanted, int limit) const {
    for (int i = 1; i <= limit; ++i) {
      EXPECT_TRUE(m.integrate(depth, K, T));
      if (m.occupancy().state(surface) == wanted) return i;
    }
    return 0;
  }
};

}  // namespace

TEST(OccupancyMap, RenderedMazeMatchesGroundTruthSurfaceAndFreeSpace) {
  const Fixture f = mazeFixture();
  const sim::DepthRenderer renderer(f.camera, f.scene);
  map::VoxelMap m(mapConfig(), f.scene.box);
  cv::Mat depth;
  for (const auto& T : f.poses) {
    renderer.render(T, depth);
    auto info = m.integrate(depth, intrinsicsOf(f.camera.intrinsics()), T);
    ASSERT_TRUE(info) << info.message();
  }
  const auto& geo = m.geometry();
  const std::set<std::size_t> seen = visibleSurface(f, renderer, geo);
  ASSERT_GT(seen.size(), 2000u);
  std::size_t occ = 0, occ_true = 0, recalled = 0, free = 0, free_true = 0;
  for (std::size_t l = 0; l < geo.size(); ++l) {
    const VoxelState s = m.occupancy().stateAt(l);
    const bool gt = f.scene.isOccupied(geo.indexToCoord(geo.unlinear(l)));
    if (s == VoxelState::kOccupied) {
      ++occ;
      occ_true += gt;
      recalled += seen.count(l);
    } else if (s == VoxelState::kFree) {
      ++free;
      free_true += !gt;
    }
  }
  const double precision = double(occ_true) / occ, recall = double(recalled) / seen.size();
  const double free_precision = double(free_true) / free;
  std::cout << "occupied precision " << precision << ", recall " << recall << " (" << seen.size()
            << " visible surface voxels), free precision " << free_precision << " over " << free << " voxels\n";
  EXPECT_GE(precision, 0.95);
  EXPECT_GE(recall, 0.95);
  EXPECT_GE(free_precision, 0.99);
  EXPECT_GT(free, 50000u);
  // The ESDF follows the occupancy exactly.
  for (std::size_t l = 0; l < geo.size(); ++l)
    ASSERT_EQ(m.esdf().isObstacle(geo.unlinear(l)), m.occupancy().stateAt(l) == VoxelState::kOccupied);
  // The kept count of known voxels is the count of free and occupied ones, and setState() keeps it.
  EXPECT_EQ(m.occupancy().knownCount(), occ + free);
  map::OccupancyMap copy = m.occupancy();
  const Index3 known_voxel = geo.unlinear(*seen.begin()), corner = geo.dims() - Index3::Ones();
  const std::size_t base = occ + free - 1 + (copy.state(corner) == VoxelState::kUnknown ? 1 : 0);
  copy.setState(known_voxel, VoxelState::kUnknown);
  copy.setState(corner, VoxelState::kFree);
  EXPECT_EQ(copy.knownCount(), base);
  copy.setState(corner, VoxelState::kOccupied);
  copy.setState(known_voxel, VoxelState::kUnknown);
  EXPECT_EQ(copy.knownCount(), base);
}

TEST(OccupancyMap, MillimetreAndMetreEncodingsGiveTheSameMap) {
  const Fixture f = mazeFixture();
  const sim::DepthRenderer renderer(f.camera, f.scene);
  map::VoxelMap a(mapConfig(), f.scene.box), b(mapConfig(), f.scene.box);
  cv::Mat depth, mm, metres;
  for (std::size_t i = 0; i < f.poses.size(); i += 3) {
    renderer.render(f.poses[i], depth);
    sim::toMillimetres(depth, mm);  // rounds to the millimetre, 0 without a return, as a D435i does
    mm.convertTo(metres, CV_32FC1, 0.001);
    ASSERT_TRUE(a.integrate(mm, intrinsicsOf(f.camera.intrinsics()), f.poses[i]));
    ASSERT_TRUE(b.integrate(metres, intrinsicsOf(f.camera.intrinsics()), f.poses[i]));
  }
  std::size_t known = 0;
  for (std::size_t l = 0; l < a.geometry().size(); ++l) {
    ASSERT_EQ(a.occupancy().stateAt(l), b.occupancy().stateAt(l)) << "voxel " << l;
    known += a.occupancy().stateAt(l) != VoxelState::kUnknown;
  }
  EXPECT_GT(known, 10000u);
}

TEST(OccupancyMap, InvalidPixelsAreFreeOrSkippedByParameter) {
  // Empty world: every pixel of the rendered image is 0 (nothing in range); add NaNs.
  world::Scene empty = world::makeEmptyScene("empty", {Vec3(-6, -6, -2), Vec3(6, 6, 4)}, 0.1, 0.0);
  sim::DepthCameraConfig cam;
  cv::Mat depth(cam.height, cam.width, CV_32FC1, cv::Scalar(0.0f));
  for (int v = 0; v < depth.rows; v += 7) depth.at<float>(v, v % depth.cols) = std::numeric_limits<float>::quiet_NaN();
  const auto T = cameraPose(Vec3(0, 0, 1), 0.0);
  for (bool as_free : {true, false}) {
    map::MapConfig c = mapConfig();
    c.occupancy.invalid_as_free = as_free;
    map::VoxelMap m(c, empty.box);
    auto info = m.integrate(depth, intrinsicsOf(cam.intrinsics()), T);
    ASSERT_TRUE(info) << info.message();
    EXPECT_EQ(info->frame.pixels_invalid, (cam.width / 2) * (cam.height / 2));
    // A point 3 m ahead on the optical axis; and one beyond the range.
    EXPECT_EQ(m.occupancy().state(Vec3(3.0, 0.0, 1.0)), as_free ? VoxelState::kFree : VoxelState::kUnknown);
    EXPECT_EQ(m.occupancy().state(Vec3(5.0, 0.0, 1.0)), VoxelState::kUnknown);
  }
  // Beyond-range returns carve free space to the range, never a hit.
  cv::Mat far(cam.height, cam.width, CV_32FC1, cv::Scalar(9.0f));
  map::VoxelMap m(mapConfig(), empty.box);
  auto info = m.integrate(far, intrinsicsOf(cam.intrinsics()), T);
  ASSERT_TRUE(info);
  EXPECT_TRUE(info->frame.became_occupied.empty());
  EXPECT_EQ(m.occupancy().state(Vec3(4.3, 0.0, 1.0)), VoxelState::kFree);
  EXPECT_EQ(m.occupancy().state(Vec3(4.8, 0.0, 1.0)), VoxelState::kUnknown);
}

// The probabilities become byte steps of log-odds (1/50 each). A configuration whose hit or miss step
// rounds to 0 or past one byte (p_hit 0.95 wrapped round to a step of -109: every return made its voxel
// freer), or whose clamp p_max rounds to no more than the threshold p_occupied, is refused with the key
// named; every configuration that is accepted must map a surface seen again and again as occupied and the
// same voxel, then seen through again and again, as free (which those refused ones never did).
TEST(OccupancyMap, ConfigsWhoseByteStepsVanishAreRefusedAndAcceptedOnesMapObstacles) {
  const WallAhead view;
  int accepted = 0, refused = 0;
  for (double p_hit : {0.5005, 0.502, 0.503, 0.51, 0.65, 0.927, 0.95})
    for (double p_miss : {0.4995, 0.498, 0.497, 0.35, 0.073, 0.05})
      for (auto [p_occupied, p_max] : {std::pair{0.8, 0.9}, std::pair{0.881, 0.8814}, std::pair{0.87, 0.8814}}) {
        map::MapConfig c = mapConfig();
        c.occupancy.skip_pixel = 1;
        c.occupancy.p_hit = p_hit, c.occupancy.p_miss = p_miss;
        c.occupancy.p_occupied = p_occupied, c.occupancy.p_max = p_max;
        const std::string what = "p_hit " + std::to_string(p_hit) + ", p_miss " + std::to_string(p_miss) +
                                 ", p_occupied " + std::to_string(p_occupied) + ", p_max " + std::to_string(p_max);
        const common::Status st = c.occupancy.validate();
        if (!st.ok()) {
          ++refused;
          const bool named = ((p_hit < 0.503 || p_hit > 0.927) && st.message().find("p_hit") != std::string::npos) ||
                             ((p_miss > 0.497 || p_miss < 0.073) && st.message().find("p_miss") != std::string::npos) ||
                             (p_occupied == 0.881 && st.message().find("p_occupied") != std::string::npos);
          EXPECT_TRUE(named) << what << ": " << st.message();
          continue;
        }
        ++accepted;
        SCOPED_TRACE(what);
        map::VoxelMap m(c, view.empty.box);
        EXPECT_GT(view.framesUntil(m, view.wall, VoxelState::kOccupied, 300), 0) << "a surface seen 300 times is not occupied";
        EXPECT_GT(view.framesUntil(m, view.through, VoxelState::kFree, 300), 0) << "seen through 300 times, still not free";
        EXPECT_GT(view.framesUntil(m, view.wall, VoxelState::kOccupied, 300), 0) << "seen again 300 times, not occupied";
      }
  EXPECT_EQ(accepted, 4 * 3 * 2);  // p_hit 0.503 to 0.927, p_miss 0.497 down to 0.073, the two real margins
  EXPECT_EQ(refused, 7 * 6 * 3 - accepted);
}

// The clamps p_min and p_max hold a voxel's log-odds (to the byte step, 1/50), so that evidence on either side
// is undone by a bounded number of frames: a surface seen through many times is at p_min and becomes occupied
// after as many returns as it takes from there to pass p_occupied, and a surface seen many times is at p_max
// and becomes free after as many misses as it takes from there to fall to it. For two configurations: the
// shipped one, and one whose clamps lie nearer the threshold.
TEST(OccupancyMap, TheClampsBoundTheEvidenceEachWay) {
  const WallAhead view;
  auto logit = [](double p) { return std::log(p / (1.0 - p)); };
  for (auto [p_min, p_max] : {std::pair{0.12, 0.90}, std::pair{0.3, 0.86}}) {
    map::MapConfig c = mapConfig();
    c.occupancy.skip_pixel = 1;
    c.occupancy.p_min = p_min, c.occupancy.p_max = p_max;
    SCOPED_TRACE("p_min " + std::to_string(p_min) + ", p_max " + std::to_string(p_max));
    ASSERT_TRUE(c.occupancy.validate().ok());
    const double hit = logit(c.occupancy.p_hit), miss = logit(c.occupancy.p_miss), occupied = logit(c.occupancy.p_occupied);
    map::VoxelMap m(c, view.empty.box);
    const common::Index3 idx = m.occupancy().geometry().coordToIndex(view.surface);
    auto integrate = [&](const cv::Mat& depth, int times) {
      for (int i = 0; i < times; ++i) ASSERT_TRUE(m.integrate(depth, view.K, view.T));
    };
    integrate(view.wall, 40);
    ASSERT_EQ(m.occupancy().state(view.surface), VoxelState::kOccupied);
    EXPECT_NEAR(logit(m.occupancy().probability(idx)), logit(p_max), 0.011) << "a surface seen 40 times";
    // From p_max: the misses it takes to fall to p_occupied or below.
    EXPECT_EQ(view.framesUntil(m, view.through, VoxelState::kFree, 50),
              static_cast<int>(std::floor((logit(p_max) - occupied) / -miss)) + 1);
    integrate(view.through, 40);
    EXPECT_NEAR(logit(m.occupancy().probability(idx)), logit(p_min), 0.011) << "a surface seen through 40 times";
    // From p_min: the returns it takes to pass p_occupied.
    EXPECT_EQ(view.framesUntil(m, view.wall, VoxelState::kOccupied, 50),
              static_cast<int>(std::floor((occupied - logit(p_min)) / hit)) + 1);
  }
}

// REP 117's values: +inf (no return within the range) is free space to max_range whatever
// invalid_as_free says; -inf and a depth below min_range (a surface too near to measure) are never cast
// free, with invalid_as_free or without: the ray would pass through that surface. The rendered frames of a
// wall: mapped from 2 m, then with the camera against it (its frame all -inf), the wall stays occupied; it
// used to be cleared in two frames (0 too near, taken as free to max_range).
TEST(OccupancyMap, ASurfaceTooNearIsNeverCastFreeAndNoReturnIsFree) {
  world::Scene empty = world::makeEmptyScene("empty", {Vec3(-6, -6, -2), Vec3(6, 6, 4)}, 0.1, 0.0);
  sim::DepthCameraConfig cam;
  const auto K = intrinsicsOf(cam.intrinsics());
  const auto T = cameraPose(Vec3(0, 0, 1), 0.0);
  const float inf = std::numeric_limits<float>::infinity();
  for (bool as_free : {true, false}) {
    map::MapConfig c = mapConfig();
    c.occupancy.invalid_as_free = as_free;
    for (float near : {-inf, 0.05f}) {
      map::VoxelMap m(c, empty.box);
      auto info = m.integrate(cv::Mat(cam.height, cam.width, CV_32FC1, cv::Scalar(near)), K, T);
      ASSERT_TRUE(info) << info.message();
      EXPECT_EQ(m.occupancy().knownCount(), 0u) << "a frame too near changed the map (invalid_as_free " << as_free << ")";
      EXPECT_EQ(info->frame.pixels_invalid, (cam.width / 2) * (cam.height / 2));
    }
    map::VoxelMap m(c, empty.box);
    auto info = m.integrate(cv::Mat(cam.height, cam.width, CV_32FC1, cv::Scalar(inf)), K, T);
    ASSERT_TRUE(info) << info.message();
    EXPECT_EQ(info->frame.pixels_invalid, 0u);
    EXPECT_EQ(m.occupancy().state(Vec3(4.3, 0.0, 1.0)), VoxelState::kFree) << "invalid_as_free " << as_free;
    EXPECT_EQ(m.occupancy().state(Vec3(4.8, 0.0, 1.0)), VoxelState::kUnknown);
    EXPECT_TRUE(info->frame.became_occupied.empty());
  }

  // A wall face at x = 2.0, seen by the simulated camera from 2 m, then from 0.05 m in front of it.
  world::Scene scene = world::makeEmptyScene("wall", {Vec3(-1, -3, 0), Vec3(3, 3, 2.5)}, 0.1, 0.0);
  world::fillBox(scene, {Vec3(2.0, -3.0, 0.0), Vec3(2.4, 3.0, 2.5)});
  const sim::DepthRenderer renderer(cam, scene);
  map::VoxelMap m(mapConfig(), scene.box);
  cv::Mat depth;
  renderer.render(cameraPose(Vec3(0.0, 0.0, 1.2), 0.0), depth);
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(m.integrate(depth, K, cameraPose(Vec3(0.0, 0.0, 1.2), 0.0)));
  std::vector<Vec3> face;
  for (double y = -0.55; y <= 0.55; y += 0.1)
    for (double z = 0.75; z <= 1.65; z += 0.1) face.emplace_back(2.05, y, z);
  for (const Vec3& p : face) ASSERT_EQ(m.occupancy().state(p), VoxelState::kOccupied) << p.transpose();
  const auto against = cameraPose(Vec3(1.95, 0.0, 1.2), 0.0);
  renderer.render(against, depth);
  ASSERT_EQ(cv::countNonZero(depth == -inf), cam.width * cam.height) << "the frame is not all too near";
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(m.integrate(depth, K, against));
  for (const Vec3& p : face) EXPECT_EQ(m.occupancy().state(p), VoxelState::kOccupied) << p.transpose();
  EXPECT_EQ(m.occupancy().state(Vec3(2.55, 0.0, 1.2)), VoxelState::kUnknown) << "space behind the wall was cast free";
}

TEST(OccupancyMap, BadFramesAreRefusedAndChangeNothing) {
  world::Scene empty = world::makeEmptyScene("empty", {Vec3(-3, -3, 0), Vec3(3, 3, 3)}, 0.1, 0.0);
  sim::DepthCameraConfig cam;
  map::VoxelMap m(mapConfig(), empty.box);
  const auto K = intrinsicsOf(cam.intrinsics());
  const auto T = cameraPose(Vec3(0, 0, 1), 0.0);
  cv::Mat wrong_type(cam.height, cam.width, CV_8UC1, cv::Scalar(1));
  auto a = m.integrate(wrong_type, K, T);
  ASSERT_FALSE(a);
  EXPECT_NE(a.message().find("32FC1"), std::string::npos) << a.message();
  cv::Mat small(100, 100, CV_32FC1, cv::Scalar(1.0f));
  auto b = m.integrate(small, K, T);
  ASSERT_FALSE(b);
  EXPECT_NE(b.message().find("camera_info"), std::string::npos) << b.message();
  // One side right, the other not (a D435i's 640x360 depth beside the 640x480 camera_info of another mode).
  for (const cv::Size& size : {cv::Size(cam.width, cam.height / 2), cv::Size(cam.width / 2, cam.height)}) {
    auto one_side = m.integrate(cv::Mat(size, CV_32FC1, cv::Scalar(1.0f)), K, T);
    ASSERT_FALSE(one_side) << size;
    EXPECT_NE(one_side.message().find("but camera_info says"), std::string::npos) << one_side.message();
  }
  Eigen::Isometry3d bad = T;
  bad.translation().x() = std::nan("");
  cv::Mat ok(cam.height, cam.width, CV_32FC1, cv::Scalar(2.0f));
  auto c = m.integrate(ok, K, bad);
  ASSERT_FALSE(c);
  // Millimetres in a 32FC1 image (REP 118 says metres): every pixel past max_range was cast free through
  // the walls. Refused when most finite depths are beyond occupancy/max_plausible_depth, even with holes;
  // +inf (no return) is no depth and does not count.
  cv::Mat millimetres(cam.height, cam.width, CV_32FC1, cv::Scalar(2000.0f));
  millimetres(cv::Rect(0, 0, cam.width / 3, cam.height)) = 0.0f;
  auto mm = m.integrate(millimetres, K, T);
  ASSERT_FALSE(mm);
  EXPECT_NE(mm.message().find("beyond 100 m (occupancy/max_plausible_depth): millimetres in a 32FC1 image"),
            std::string::npos)
      << mm.message();
  cv::Mat open_view(cam.height, cam.width, CV_32FC1, cv::Scalar(std::numeric_limits<float>::infinity()));
  open_view(cv::Rect(0, 0, 8, 8)) = 2.0f;
  map::VoxelMap open_map(mapConfig(), empty.box);
  EXPECT_TRUE(open_map.integrate(open_view, K, T));
  // Intrinsics that cannot describe the image: named, and the frame changes nothing.
  for (auto [field, broken] : std::vector<std::pair<std::string, std::function<void(map::DepthIntrinsics&)>>>{
           {"0x0", [](map::DepthIntrinsics& k) { k.width = 0, k.height = 0; }},
           {"fx", [](map::DepthIntrinsics& k) { k.fx = 0.0; }},
           {"fx", [](map::DepthIntrinsics& k) { k.fy = std::nan(""); }},
           {"cx", [](map::DepthIntrinsics& k) { k.cy = INFINITY; }},
           // Finite and > 0, but rays of NaN (1e-310: inf / inf), or a view of nearly 180 degrees.
           {"85 degrees", [](map::DepthIntrinsics& k) { k.fy = 1e-310; }},
           {"85 degrees", [](map::DepthIntrinsics& k) { k.fx = 1e-3; }},
           {"85 degrees", [](map::DepthIntrinsics& k) { k.cx = -1e6; }}}) {
    map::DepthIntrinsics k = K;
    broken(k);
    const common::Status st = k.validate();
    ASSERT_FALSE(st.ok()) << field;
    EXPECT_NE(st.message().find(field), std::string::npos) << st.message();
    if (k.width == K.width) {
      EXPECT_FALSE(m.integrate(ok, k, T)) << field;
    }
  }
  EXPECT_TRUE(K.validate().ok()) << K.validate().message();
  EXPECT_EQ(m.occupancy().knownCount(), 0u);
}

// A map beyond OctoMap's keys (2^15 voxels from the origin: 3.3 km at 0.1 m) is not saved: its voxels were
// dropped and the file written as if whole. A file already at the path is left as it was.
TEST(OccupancyMap, OctomapSaveOfAMapBeyondItsReachIsRefused) {
  world::Scene far = world::makeEmptyScene("far", {Vec3(4997, -3, 0), Vec3(5003, 3, 3)}, 0.1, 0.0);
  sim::DepthCameraConfig cam;
  map::VoxelMap m(mapConfig(), far.box);
  const cv::Mat wall(cam.height, cam.width, CV_32FC1, cv::Scalar(2.0f));
  ASSERT_TRUE(m.integrate(wall, intrinsicsOf(cam.intrinsics()), cameraPose(Vec3(4999, 0, 1.5), 0.0)));
  ASSERT_GT(m.occupancy().knownCount(), 0u);
  const std::string path =
      (std::filesystem::temp_directory_path() / ("go_feap_far_" + std::to_string(::getpid()) + ".bt")).string();
  std::ofstream(path) << "an earlier map";
  const common::Status st = m.saveBt(path);
  ASSERT_FALSE(st);
  EXPECT_NE(st.message().find("beyond OctoMap's reach of 3276.8 m"), std::string::npos) << st.message();
  std::ifstream in(path);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "an earlier map");
  EXPECT_FALSE(std::filesystem::exists(path + ".part"));
  std::filesystem::remove(path);
}

TEST(OccupancyMap, OctomapRoundTripKeepsStates) {
  const Fixture f = mazeFixture();
  const sim::DepthRenderer renderer(f.camera, f.scene);
  map::VoxelMap m(mapConfig(), f.scene.box);
  cv::Mat depth;
  for (std::size_t i = 0; i < 16; ++i) {
    renderer.render(f.poses[i], depth);
    ASSERT_TRUE(m.integrate(depth, intrinsicsOf(f.camera.intrinsics()), f.poses[i]));
  }
  const std::string path = (std::filesystem::temp_directory_path() / ("go_feap_map_" + std::to_string(::getpid()) + ".bt")).string();
  ASSERT_TRUE(m.saveBt(path));
  map::VoxelMap back(mapConfig(), f.scene.box);
  // The file's header and then bytes that make every child a node with children: refused as the scene
  // loader refuses them (OctoMap's own reader, which loadBt called, recursed until the stack overflowed).
  std::string bytes;
  {
    std::ifstream in(path, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const std::string deep = path + ".deep.bt";
  std::ofstream(deep, std::ios::binary) << bytes.substr(0, bytes.find("\ndata\n") + 6) << std::string(200000, '\xff');
  const common::Status refused = back.loadBt(deep);
  std::filesystem::remove(deep);
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.message().find("deeper than 16 levels"), std::string::npos) << refused.message();
  EXPECT_EQ(back.occupancy().knownCount(), 0u);
  ASSERT_TRUE(back.loadBt(path));
  std::filesystem::remove(path);
  std::size_t known = 0;
  for (std::size_t l = 0; l < m.geometry().size(); ++l) {
    ASSERT_EQ(m.occupancy().stateAt(l), back.occupancy().stateAt(l)) << "voxel " << l;
    known += m.occupancy().stateAt(l) != VoxelState::kUnknown;
    ASSERT_EQ(back.esdf().isObstacle(m.geometry().unlinear(l)), back.occupancy().stateAt(l) == VoxelState::kOccupied);
  }
  EXPECT_GT(known, 10000u);
  EXPECT_FALSE(back.loadBt(path));
}

// A .bt at half the grid's resolution puts every grid centre on the corner of eight leaves, all of
// which cover it. A checkerboard of occupied and free leaves makes each voxel both: occupied wins, and
// the ESDF must agree with the occupancy (a voxel set occupied and then free by a later leaf went to
// the ESDF both inserted and removed, and stayed an obstacle there).
TEST(OccupancyMap, OctomapLeavesSharingAVoxelCentre) {
  map::MapConfig c = mapConfig();
  c.occupancy.resolution = 0.5;
  c.occupancy.margin = 0.0;
  ASSERT_TRUE(c.validate()) << c.validate().message();
  map::VoxelMap m(c, {Vec3(0, 0, 0), Vec3(2, 2, 1)});
  const auto& geo = m.geometry();
  ASSERT_TRUE(geo.origin().isZero()) << geo.origin().transpose();
  octomap::OcTree tree(0.25);
  const float occ = tree.getClampingThresMaxLog(), fre = tree.getClampingThresMinLog();
  for (int z = 0; z < 4; ++z)
    for (int y = 0; y < 8; ++y)
      for (int x = 0; x < 8; ++x)
        tree.setNodeValue(octomap::point3d(0.125f + 0.25f * x, 0.125f + 0.25f * y, 0.125f + 0.25f * z),
                          (x + y + z) % 2 == 0 ? occ : fre, /*lazy_eval=*/true);
  tree.updateInnerOccupancy();
  const std::string path =
      (std::filesystem::temp_directory_path() / ("go_feap_half_" + std::to_string(::getpid()) + ".bt")).string();
  {
    std::ofstream out(path, std::ios::binary);
    ASSERT_TRUE(tree.writeBinary(out));
  }
  ASSERT_TRUE(m.loadBt(path));
  std::filesystem::remove(path);
  std::size_t occupied = 0;
  for (std::size_t l = 0; l < geo.size(); ++l) {
    const Index3 i = geo.unlinear(l);
    const VoxelState s = m.occupancy().stateAt(l);
    occupied += s == VoxelState::kOccupied;
    EXPECT_NE(s, VoxelState::kUnknown) << i.transpose();
    EXPECT_EQ(m.esdf().isObstacle(i), s == VoxelState::kOccupied) << i.transpose();
  }
  EXPECT_EQ(occupied, geo.size());
}

// A return beyond the map's edge is clipped there as free space, not marked as an obstacle at the border: a
// camera 1 m from the far face sees a wall 1.5 m away, outside the map, and every ray leaves through that face.
TEST(OccupancyMap, AReturnBeyondTheMapEdgeMarksNoObstacleAtTheBorder) {
  const map::DepthIntrinsics K{8, 6, 8.0, 8.0, 4.0, 3.0};
  map::OccupancyConfig c;
  c.margin = 0.0;
  c.skip_pixel = 1;
  ASSERT_TRUE(c.validate()) << c.validate().message();
  map::OccupancyMap m(c, {Vec3(-1, -1, 0), Vec3(1, 1, 2)});
  const cv::Mat beyond(K.height, K.width, CV_32FC1, cv::Scalar(1.5f));
  const auto change = m.integrate(beyond, K, cameraPose(Vec3(0, 0, 1), 0.0));
  ASSERT_TRUE(change) << change.message();
  EXPECT_TRUE(change->became_occupied.empty());
  for (std::size_t l = 0; l < m.geometry().size(); ++l)
    ASSERT_NE(m.stateAt(l), VoxelState::kOccupied) << m.geometry().unlinear(l).transpose();
  EXPECT_EQ(m.state(Vec3(0.95, 0.0, 1.0)), VoxelState::kFree);  // the border voxel the axis leaves through
  // Points outside the map, however far or not numbers at all, are unknown (their index was cast to int
  // from the raw floor: undefined past INT_MAX voxels, and for NaN).
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Vec3& p : {Vec3(1.05, 0.0, 1.0), Vec3(1e30, 0.0, 1.0), Vec3(0.0, -1e30, 1.0), Vec3(nan, 0.0, 1.0),
                        Vec3(0.95, 0.0, nan), Vec3(std::numeric_limits<double>::infinity(), 0.0, 1.0)})
    EXPECT_EQ(m.state(p), VoxelState::kUnknown) << p.transpose();
}

// A camera outside the map (a take-off short of a tight box) maps what it sees inside: the part of each ray
// within the map is cast free and the returns there are marked, every voxel as a larger map holding the
// camera has it (the oracle: the same rays, unclipped). Before, none of its rays cast free space: no free
// voxel, so no frontier, and no exploration could start.
TEST(OccupancyMap, ACameraOutsideTheMapMapsTheRaysWithinIt) {
  // Nothing in round numbers: a ray through a voxel's edge or corner may take either side, depending on
  // where its walk started.
  const map::DepthIntrinsics K{16, 12, 12.3, 12.1, 7.9, 6.2};
  map::OccupancyConfig c;
  c.margin = 0.0;
  c.skip_pixel = 1;
  map::OccupancyMap inside_map(c, {Vec3(-1, -1, 0), Vec3(3, 1, 2)}), holding(c, {Vec3(-2, -1, 0), Vec3(3, 1, 2)});
  const Eigen::Isometry3d T = cameraPose(Vec3(-1.537, 0.013, 1.021), 0.07);  // short of the map's x = -1 face
  ASSERT_FALSE(inside_map.geometry().bounds().contains(T.translation()));
  cv::Mat depth(K.height, K.width, CV_32FC1, cv::Scalar(2.973f));  // a wall 1.4 m into the map ...
  depth(cv::Rect(0, 0, 4, K.height)) = std::numeric_limits<float>::infinity();  // ... and no return to the left
  ASSERT_TRUE(inside_map.integrate(depth, K, T));
  ASSERT_TRUE(holding.integrate(depth, K, T));
  std::size_t free = 0, occupied = 0;
  for (std::size_t l = 0; l < inside_map.geometry().size(); ++l) {
    const Vec3 p = inside_map.geometry().indexToCoord(inside_map.geometry().unlinear(l));
    ASSERT_EQ(inside_map.stateAt(l), holding.state(p)) << "at " << p.transpose();
    free += inside_map.stateAt(l) == VoxelState::kFree;
    occupied += inside_map.stateAt(l) == VoxelState::kOccupied;
  }
  EXPECT_GT(free, 500u);
  EXPECT_GT(occupied, 10u);
  EXPECT_EQ(inside_map.state(Vec3(-0.95, 0.05, 1.05)), VoxelState::kFree);  // where the optical axis enters
}

// A return is marked a fiftieth of a voxel behind the measured surface, so that a depth that reads a hair
// short of a voxel face (1.9985 m for a face at 2 m) marks the wall's voxel, not the free one before it.
TEST(OccupancyMap, AReturnJustShortOfAVoxelFaceMarksTheVoxelBehindIt) {
  const map::DepthIntrinsics K{8, 6, 8.0, 8.0, 4.0, 3.0};
  map::OccupancyConfig c;
  c.margin = 0.0;
  c.skip_pixel = 1;
  map::OccupancyMap m(c, {Vec3(-1, -1, 0), Vec3(3, 1, 2)});
  ASSERT_NEAR(m.geometry().indexToCoord(m.geometry().coordToIndex(Vec3(2.01, 0, 1))).x(), 2.05, 1e-12);
  const cv::Mat wall(K.height, K.width, CV_32FC1, cv::Scalar(1.9985f));
  ASSERT_TRUE(m.integrate(wall, K, cameraPose(Vec3(0, 0, 1), 0.0)));
  EXPECT_EQ(m.state(Vec3(2.05, 0.0, 1.0)), VoxelState::kOccupied);
  EXPECT_EQ(m.state(Vec3(1.95, 0.0, 1.0)), VoxelState::kFree);
}

// A return at exactly max_range is a surface (only depths beyond it, and +inf, mean "no return"): the voxel
// it ends in is occupied.
TEST(OccupancyMap, AReturnAtExactlyMaxRangeIsASurface) {
  const map::DepthIntrinsics K{8, 6, 8.0, 8.0, 4.0, 3.0};
  map::OccupancyConfig c;
  c.margin = 0.0;
  c.skip_pixel = 1;
  ASSERT_EQ(c.max_range, 4.5);
  map::OccupancyMap m(c, {Vec3(-1, -3, 0), Vec3(6, 3, 3)});
  const cv::Mat wall(K.height, K.width, CV_32FC1, cv::Scalar(4.5f));
  ASSERT_TRUE(m.integrate(wall, K, cameraPose(Vec3(0, 0, 1.5), 0.0)));
  EXPECT_EQ(m.state(Vec3(4.502, 0.0, 1.5)), VoxelState::kOccupied);
  EXPECT_EQ(m.state(Vec3(4.4, 0.0, 1.5)), VoxelState::kFree);
}

// Settings that would break the map are refused by name: no pixel step (a division by zero), a plausible
// depth inside the range (valid frames refused as millimetres), and clamps whose log-odds leave a voxel's
// byte (they wrapped round: every hit made a voxel free, or every miss an obstacle).
TEST(OccupancyMap, ConfigsThatWouldBreakTheMapAreRefusedByName) {
  ASSERT_TRUE(map::OccupancyConfig().validate());
  const Aabb box{Vec3(-5, -3, 0), Vec3(5, 3, 3)};
  for (const auto& [key, broken] : std::vector<std::pair<std::string, std::function<void(map::OccupancyConfig&)>>>{
           {"skip_pixel", [](map::OccupancyConfig& o) { o.skip_pixel = 0; }},
           {"skip_pixel", [](map::OccupancyConfig& o) { o.skip_pixel = -3; }},
           {"skip_pixel", [](map::OccupancyConfig& o) { o.skip_pixel = std::numeric_limits<int>::max(); }},
           {"skip_pixel", [](map::OccupancyConfig& o) { o.skip_pixel = 8193; }},
           {"max_plausible_depth", [](map::OccupancyConfig& o) { o.max_plausible_depth = 3.0; }},
           {"max_plausible_depth", [](map::OccupancyConfig& o) { o.max_plausible_depth = 4.5; }},
           {"p_min/p_max", [](map::OccupancyConfig& o) { o.p_max = 0.95; }},
           {"p_min/p_max", [](map::OccupancyConfig& o) { o.p_min = 0.05; }}}) {
    map::OccupancyConfig bad;
    broken(bad);
    const common::Status st = bad.validate();
    ASSERT_FALSE(st) << key;
    EXPECT_NE(st.message().find(key), std::string::npos) << st.message();
    map::MapConfig whole = mapConfig();
    whole.occupancy = bad;
    EXPECT_FALSE(whole.validate(box)) << key;
  }
  map::OccupancyConfig wider;
  wider.max_plausible_depth = 5.0;  // above max_range: valid
  EXPECT_TRUE(wider.validate()) << wider.validate().message();
  wider.skip_pixel = 8192;  // the largest image side: only the corner pixel of each frame is cast
  EXPECT_TRUE(wider.validate()) << wider.validate().message();
}

// The world box of what a frame changed is the union of the changed voxels' cubes (the frontier finder and
// the local planner redo what lies in it).
TEST(VoxelMap, TheChangedBoxIsTheChangedVoxelsCubes) {
  const map::DepthIntrinsics K{8, 6, 8.0, 8.0, 4.0, 3.0};
  map::MapConfig c = mapConfig();
  c.occupancy.skip_pixel = 1;
  map::VoxelMap m(c, {Vec3(-1, -3, 0), Vec3(5, 3, 3)});
  const cv::Mat wall(K.height, K.width, CV_32FC1, cv::Scalar(2.05f));
  const auto info = m.integrate(wall, K, cameraPose(Vec3(0, 0, 1.5), 0.3));
  ASSERT_TRUE(info) << info.message();
  ASSERT_TRUE(info->frame.any_change);
  ASSERT_FALSE(info->frame.changed.empty());
  const auto& geo = m.geometry();
  Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
  for (std::size_t l : info->frame.changed) {
    const Vec3 corner = geo.origin() + geo.unlinear(l).cast<double>() * geo.resolution();
    lo = lo.cwiseMin(corner);
    hi = hi.cwiseMax(Vec3(corner + Vec3::Constant(geo.resolution())));
  }
  EXPECT_LT((info->changed_box.min - lo).cwiseAbs().maxCoeff(), 1e-9)
      << info->changed_box.min.transpose() << " / " << lo.transpose();
  EXPECT_LT((info->changed_box.max - hi).cwiseAbs().maxCoeff(), 1e-9)
      << info->changed_box.max.transpose() << " / " << hi.transpose();
}

// A frame that only clears obstacles reaches the ESDF too: a wall seen once, then seen through once (its
// voxel back at the threshold, free), leaves no obstacle in the ESDF where the map has none.
TEST(OccupancyMap, AFrameThatOnlyClearsObstaclesUpdatesTheEsdf) {
  const map::DepthIntrinsics K{8, 6, 8.0, 8.0, 4.0, 3.0};
  map::MapConfig c = mapConfig();
  c.occupancy.skip_pixel = 1;
  map::VoxelMap m(c, {Vec3(-1, -3, 0), Vec3(5, 3, 3)});
  const auto T = cameraPose(Vec3(0, 0, 1.5), 0.0);
  const cv::Mat wall(K.height, K.width, CV_32FC1, cv::Scalar(2.05f)), through(K.height, K.width, CV_32FC1, cv::Scalar(9.0f));
  const Vec3 surface(2.052, 0.0, 1.5);
  const Index3 at = m.geometry().coordToIndex(surface);
  ASSERT_TRUE(m.integrate(wall, K, T));
  ASSERT_EQ(m.occupancy().state(surface), VoxelState::kOccupied);
  ASSERT_TRUE(m.esdf().isObstacle(at));
  const auto info = m.integrate(through, K, T);
  ASSERT_TRUE(info) << info.message();
  ASSERT_TRUE(info->frame.became_occupied.empty());
  ASSERT_FALSE(info->frame.stopped_occupied.empty());
  EXPECT_EQ(m.occupancy().state(surface), VoxelState::kFree);
  EXPECT_GT(info->esdf_changed, 0u);
  for (std::size_t l = 0; l < m.geometry().size(); ++l) {
    const Index3 i = m.geometry().unlinear(l);
    ASSERT_EQ(m.esdf().isObstacle(i), m.occupancy().stateAt(l) == VoxelState::kOccupied) << i.transpose();
  }
}

// Loading a .bt over a map that has obstacles: voxels the file gives as free stop being ESDF obstacles. A
// file of occupied leaves, then one of free leaves over the same 4 x 4 x 2 voxels: the map and its ESDF are
// what loading the second file into a fresh map gives.
TEST(OccupancyMap, OctomapLoadedOverObstaclesClearsThemFromTheEsdf) {
  map::MapConfig c = mapConfig();
  c.occupancy.resolution = 0.5;
  c.occupancy.margin = 0.0;
  const Aabb box{Vec3(0, 0, 0), Vec3(2, 2, 1)};
  auto written = [&](bool occupied) {
    octomap::OcTree tree(0.5);
    const float value = occupied ? tree.getClampingThresMaxLog() : tree.getClampingThresMinLog();
    for (int z = 0; z < 2; ++z)
      for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x)
          tree.setNodeValue(octomap::point3d(0.25f + 0.5f * x, 0.25f + 0.5f * y, 0.25f + 0.5f * z), value, true);
    tree.updateInnerOccupancy();
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("go_feap_reload_" + std::to_string(::getpid()) + (occupied ? "_occ" : "_free") + ".bt"))
                                 .string();
    std::ofstream out(path, std::ios::binary);
    EXPECT_TRUE(tree.writeBinary(out));
    return path;
  };
  const std::string occupied = written(true), free = written(false);
  map::VoxelMap m(c, box), fresh(c, box);
  ASSERT_TRUE(m.loadBt(occupied));
  const auto& geo = m.geometry();
  ASSERT_EQ(geo.size(), 32u);
  ASSERT_TRUE(m.esdf().isObstacle(Index3(1, 1, 0)));
  ASSERT_TRUE(m.loadBt(free));
  ASSERT_TRUE(fresh.loadBt(free));
  std::filesystem::remove(occupied);
  std::filesystem::remove(free);
  for (std::size_t l = 0; l < geo.size(); ++l) {
    const Index3 i = geo.unlinear(l);
    EXPECT_EQ(m.occupancy().stateAt(l), VoxelState::kFree) << i.transpose();
    EXPECT_FALSE(m.esdf().isObstacle(i)) << i.transpose();
    EXPECT_EQ(m.esdf().distance(i), fresh.esdf().distance(i)) << i.transpose();
  }
}

// The map's size is checked before anything is allocated: finite values, and at most 2^32 - 1 voxels
// (an infinite margin or resolution made a 1x1x1 map at a NaN origin; a huge box threw from an allocation
// or from the ESDF, naming no parameter).
TEST(OccupancyMap, MapSizeAndInfiniteValuesAreRefusedBeforeAllocating) {
  const Aabb box{Vec3(-5, -3, 0), Vec3(5, 3, 3)};
  map::MapConfig c = mapConfig();
  ASSERT_TRUE(c.validate(box)) << c.validate(box).message();
  for (const auto& [field, broken] : std::vector<std::pair<std::string, std::function<void(map::MapConfig&)>>>{
           {"margin", [](map::MapConfig& m) { m.occupancy.margin = INFINITY; }},
           {"resolution", [](map::MapConfig& m) { m.occupancy.resolution = INFINITY; }},
           {"max_range", [](map::MapConfig& m) { m.occupancy.max_range = INFINITY; }}}) {
    map::MapConfig bad = c;
    broken(bad);
    const common::Status st = bad.validate(box);
    ASSERT_FALSE(st) << field;
    EXPECT_NE(st.message().find(field), std::string::npos) << st.message();
  }
  for (const Aabb& bad : {Aabb{Vec3(-5, -3, 0), Vec3(INFINITY, 3, 3)}, Aabb{Vec3(-5, -3, 0), Vec3(-6, 3, 3)},
                          Aabb{Vec3(-5, -3, 0), Vec3(1e6, 3, 3)}, Aabb{Vec3(-1e6, -1e6, 0), Vec3(1e6, 1e6, 3)}}) {
    const common::Status st = c.validate(bad);
    ASSERT_FALSE(st) << bad.max.transpose();
    EXPECT_NE(st.message().find("exploration_box"), std::string::npos) << st.message();
  }
  // 2^32 - 1 voxels is the ESDF's own limit: a large box below it (3010 x 3010 x 310 voxels with the
  // margin, 2.8e9) passes both.
  const Aabb large{Vec3(0, 0, 0), Vec3(300, 300, 30)};
  ASSERT_TRUE(c.validate(large)) << c.validate(large).message();
  EXPECT_TRUE(c.esdf.validate(common::GridGeometry::covering(large.expanded(c.occupancy.margin), c.occupancy.resolution)));
  // Its size, known before it is allocated, is what a map takes (here one of the maze's box), and a machine
  // with less memory refuses it by its keys (an 8 GB onboard computer and that box's 11.8 GiB).
  const Aabb maze{Vec3(-20, -10, 0), Vec3(20, 10, 3)};
  const map::VoxelMap built(c, maze);
  // (Within 4 %, and not below: the ESDF's bit a voxel comes with its first update.)
  EXPECT_GE(c.estimatedBytes(maze), static_cast<double>(built.memoryBytes()));
  EXPECT_NEAR(c.estimatedBytes(maze), static_cast<double>(built.memoryBytes()), 0.04 * built.memoryBytes());
  constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
  EXPECT_TRUE(c.checkFits(large, 16 * kGiB));
  const common::Status too_large = c.checkFits(large, 8 * kGiB);
  ASSERT_FALSE(too_large);
  EXPECT_NE(too_large.message().find("exploration_box with occupancy/resolution 0.1 m and margin 0.5 m needs a map "
                                     "of about 11.8 GiB, more than this machine's 8 GiB"),
            std::string::npos)
      << too_large.message();
}

TEST(OccupancyMap, LineVisibility) {
  map::OccupancyMap m(map::OccupancyConfig(), {Vec3(-3, -3, 0), Vec3(3, 3, 3)});
  const auto& geo = m.geometry();
  // Free everywhere except a wall at x in [1.0, 1.1) and an unknown slab at x in [-1.1, -1.0).
  for (std::size_t l = 0; l < geo.size(); ++l) {
    const Index3 i = geo.unlinear(l);
    const double x = geo.indexToCoord(i).x();
    m.setState(i, x > 1.0 && x < 1.1 ? VoxelState::kOccupied
                                     : (x > -1.1 && x < -1.0 ? VoxelState::kUnknown : VoxelState::kFree));
  }
  EXPECT_FALSE(m.isLineFree(Vec3(0, 0, 1), Vec3(2, 0, 1), false));
  EXPECT_TRUE(m.isLineFree(Vec3(0, 0, 1), Vec3(0.9, 0.5, 1.5), false));
  EXPECT_TRUE(m.isLineFree(Vec3(0, 0, 1), Vec3(-2, 0, 1), false));
  EXPECT_FALSE(m.isLineFree(Vec3(0, 0, 1), Vec3(-2, 0, 1), true));
  EXPECT_FALSE(m.isLineFree(Vec3(0, 0, 1), Vec3(0, 0, 5), false)) << "leaves the map";
}
