// Depth camera renderer against analytic depth (planes and boxes whose faces lie on voxel
// boundaries, so the voxel world equals the analytic one) and against a brute-force
// per-pixel voxel traversal.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "go_feap/sim/depth_camera.h"
#include "go_feap/world/shapes.h"

using namespace go_feap;
using common::Aabb;
using common::Index3;
using common::Vec3;
using sim::CameraIntrinsics;
using sim::DepthCameraConfig;
using sim::DepthRenderer;
using sim::isReturn;

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kDepthTol = 0.01;  // m

double deg(double d) { return d * M_PI / 180.0; }

/// Camera at `p`, body yawed by `yaw` about +z and pitched by `pitch` (positive = nose down),
/// optical frame rolled by `roll` about its z axis.
Eigen::Isometry3d cameraPose(const Vec3& p, double yaw, double pitch = 0.0, double roll = 0.0) {
  Eigen::Matrix3d R_B_C;  // optical (z forward, x right, y down) in body (x forward, z up)
  R_B_C << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() =
      (Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY())).toRotationMatrix() *
      R_B_C * Eigen::AngleAxisd(roll, Vec3::UnitZ()).toRotationMatrix();
  T.translation() = p;
  return T;
}

/// World direction of the ray through pixel (u, v), scaled to optical z = 1 so that the ray
/// parameter is the depth.
Vec3 pixelRay(const CameraIntrinsics& K, const Eigen::Isometry3d& T, int u, int v) {
  return T.linear() * Vec3((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0);
}

/// Ray parameter where o + t d enters `box` (slab method); 0 when o is inside, inf on a miss.
double boxEntry(const Vec3& o, const Vec3& d, const Aabb& box) {
  double t0 = 0.0, t1 = kInf;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0) {
      if (o[a] < box.min[a] || o[a] > box.max[a]) return kInf;
      continue;
    }
    const double ta = (box.min[a] - o[a]) / d[a], tb = (box.max[a] - o[a]) / d[a];
    t0 = std::max(t0, std::min(ta, tb));
    t1 = std::min(t1, std::max(ta, tb));
  }
  return t0 <= t1 ? t0 : kInf;
}

int countReturns(const cv::Mat& depth) {
  int n = 0;
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) n += isReturn(depth.at<float>(v, u));
  return n;
}
int countEqual(const cv::Mat& depth, float value) {
  int n = 0;
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const float d = depth.at<float>(v, u);
      n += std::isnan(value) ? std::isnan(d) : d == value;
    }
  return n;
}
/// The same pixels bit for bit (NaN included).
bool sameBits(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && a.isContinuous() && b.isContinuous() &&
         std::memcmp(a.data, b.data, a.total() * a.elemSize()) == 0;
}

/// The renderer's range rules (REP 117) on the depth t of the first surface along a pixel's ray.
float inRange(double t, const DepthCameraConfig& config) {
  if (t < config.min_range) return -std::numeric_limits<float>::infinity();
  return t <= config.max_range ? static_cast<float>(t) : std::numeric_limits<float>::infinity();
}

/// Analytic depth image of a union of boxes, with the renderer's range rules.
cv::Mat analyticDepth(const std::vector<Aabb>& boxes, const DepthCameraConfig& config,
                      const Eigen::Isometry3d& T) {
  const CameraIntrinsics K = config.intrinsics();
  cv::Mat depth(K.height, K.width, CV_32FC1, cv::Scalar(0.0));
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u) {
      const Vec3 d = pixelRay(K, T, u, v);
      double t = kInf;
      for (const Aabb& b : boxes) t = std::min(t, boxEntry(T.translation(), d, b));
      depth.at<float>(v, u) = inRange(t, config);
    }
  return depth;
}

/// Brute-force reference: per-pixel 3D DDA through every voxel of the grid, depth where the
/// ray enters the first occupied one. The camera must lie inside the grid.
double traverseDepth(const world::Scene& scene, const Vec3& o, const Vec3& d, double t_max) {
  const auto& geo = scene.geometry();
  const Vec3 q = (o - geo.origin()) / geo.resolution();
  const Vec3 dir = d / geo.resolution();
  Index3 i = geo.coordToIndex(o);
  if (scene.isOccupied(i)) return 0.0;
  Vec3 t_next, t_delta;
  Index3 step;
  for (int a = 0; a < 3; ++a) {
    step[a] = dir[a] > 0 ? 1 : -1;
    t_delta[a] = dir[a] != 0.0 ? std::abs(1.0 / dir[a]) : kInf;
    t_next[a] = dir[a] > 0 ? (i[a] + 1 - q[a]) / dir[a] : dir[a] < 0 ? (i[a] - q[a]) / dir[a] : kInf;
  }
  for (;;) {
    int a = 0;
    if (t_next[1] < t_next[a]) a = 1;
    if (t_next[2] < t_next[a]) a = 2;
    const double t = t_next[a];
    if (t > t_max) return kInf;
    i[a] += step[a];
    t_next[a] += t_delta[a];
    if (i[a] < 0 || i[a] >= geo.dims()[a]) return kInf;  // left the grid for good
    if (scene.occupied.at(i)) return t;
  }
}

cv::Mat traversedDepth(const world::Scene& scene, const DepthCameraConfig& config,
                       const Eigen::Isometry3d& T) {
  const CameraIntrinsics K = config.intrinsics();
  cv::Mat depth(K.height, K.width, CV_32FC1, cv::Scalar(0.0));
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u) {
      const double t = traverseDepth(scene, T.translation(), pixelRay(K, T, u, v), config.max_range + 1.0);
      depth.at<float>(v, u) = inRange(t, config);
    }
  return depth;
}

struct Comparison {
  int differing = 0;               ///< pixels whose depth differs from the reference by > kDepthTol
  int beyond_one_pixel = 0;        ///< ... and from every reference pixel within one pixel too
  double max_matched_error = 0.0;  ///< largest |error| over the pixels that agree
};

/// Pixel-wise comparison; a pixel that differs still lands within one pixel of the
/// reference when some 8-neighbour of the reference holds its value (a shifted edge).
Comparison compare(const cv::Mat& rendered, const cv::Mat& reference) {
  Comparison c;
  auto close = [](float a, float b) { return a == b || (isReturn(a) && isReturn(b) && std::abs(a - b) <= kDepthTol); };
  for (int v = 0; v < rendered.rows; ++v)
    for (int u = 0; u < rendered.cols; ++u) {
      const float r = rendered.at<float>(v, u);
      if (close(r, reference.at<float>(v, u))) {
        c.max_matched_error = std::max(c.max_matched_error, std::abs(double(r) - reference.at<float>(v, u)));
        continue;
      }
      ++c.differing;
      bool near = false;
      for (int dv = -1; dv <= 1 && !near; ++dv)
        for (int du = -1; du <= 1 && !near; ++du) {
          const int uu = u + du, vv = v + dv;
          near = uu >= 0 && vv >= 0 && uu < rendered.cols && vv < rendered.rows &&
                 close(r, reference.at<float>(vv, uu));
        }
      c.beyond_one_pixel += !near;
    }
  return c;
}

/// Box faces must lie on multiples of the resolution (all test boxes use multiples of 0.2 m)
/// so that the voxels fill exactly the analytic boxes.
world::Scene sceneWithBoxes(const std::vector<Aabb>& boxes, double resolution) {
  world::Scene s =
      world::makeEmptyScene("test", {Vec3(-1.0, -6.0, -3.0), Vec3(9.0, 6.0, 5.0)}, resolution, 0.5);
  for (const Aabb& b : boxes) world::fillBox(s, b);
  return s;
}

/// Renders the boxes' scene and checks it pixel-wise against their analytic depth.
void expectMatchesBoxes(const std::vector<Aabb>& boxes, double resolution, const DepthCameraConfig& config,
                        const Eigen::Isometry3d& T, int max_differing = 0) {
  const world::Scene scene = sceneWithBoxes(boxes, resolution);
  const DepthRenderer renderer(config, scene);
  cv::Mat depth;
  renderer.render(T, depth);
  EXPECT_GT(countReturns(depth), config.width * config.height / 20) << "too little in view to compare";
  const Comparison c = compare(depth, analyticDepth(boxes, config, T));
  EXPECT_EQ(c.beyond_one_pixel, 0);
  EXPECT_LE(c.differing, max_differing);
  EXPECT_LT(c.max_matched_error, 1e-3);
}

class DepthRendererTest : public ::testing::TestWithParam<double> {};

}  // namespace

TEST(CameraIntrinsics, FromFov) {
  const CameraIntrinsics k = CameraIntrinsics::fromFov(640, 480, deg(80.0), deg(60.0));
  EXPECT_EQ(k.width, 640);
  EXPECT_EQ(k.height, 480);
  EXPECT_NEAR(k.fx, 320.0 / std::tan(deg(40.0)), 1e-9);
  EXPECT_NEAR(k.fx, 381.3612, 1e-4);
  EXPECT_NEAR(k.fy, 240.0 / std::tan(deg(30.0)), 1e-9);
  EXPECT_NEAR(k.fy, 415.6922, 1e-4);
  EXPECT_DOUBLE_EQ(k.cx, 319.5);
  EXPECT_DOUBLE_EQ(k.cy, 239.5);
}

TEST(DepthCameraConfig, IntrinsicsFromFovOrGiven) {
  DepthCameraConfig c;
  const CameraIntrinsics derived = c.intrinsics();
  EXPECT_NEAR(derived.fx, 381.3612, 1e-4);
  EXPECT_DOUBLE_EQ(derived.cy, 239.5);
  c.fx = 500.0;
  c.fy = 510.0;
  c.cx = 300.0;
  c.cy = 200.0;
  const CameraIntrinsics given = c.intrinsics();
  EXPECT_EQ(given.width, 640);
  EXPECT_DOUBLE_EQ(given.fx, 500.0);
  EXPECT_DOUBLE_EQ(given.fy, 510.0);
  EXPECT_DOUBLE_EQ(given.cx, 300.0);
  EXPECT_DOUBLE_EQ(given.cy, 200.0);
}

TEST(DepthCameraConfig, ValidateNamesTheBadKey) {
  EXPECT_TRUE(DepthCameraConfig().validate().ok());
  struct Case {
    std::function<void(DepthCameraConfig&)> spoil;
    std::string key;
  };
  const std::vector<Case> cases = {
      {[](DepthCameraConfig& c) { c.width = 0; }, "width"},
      {[](DepthCameraConfig& c) { c.height = -1; }, "height"},
      {[](DepthCameraConfig& c) { c.width = 100000; }, "width"},  // 40 GB an image
      {[](DepthCameraConfig& c) { c.height = DepthCameraConfig::kMaxSide + 1; }, "height"},
      {[](DepthCameraConfig& c) { c.hfov_deg = 180.0; }, "hfov_deg"},
      {[](DepthCameraConfig& c) { c.vfov_deg = 0.0; }, "vfov_deg"},
      {[](DepthCameraConfig& c) { c.vfov_deg = 180.0; }, "vfov_deg"},  // no focal length
      {[](DepthCameraConfig& c) { c.vfov_deg = 250.0; }, "vfov_deg"},  // a negative one: the image upside down
      {[](DepthCameraConfig& c) { c.hfov_deg = 0.0; }, "hfov_deg"},
      {[](DepthCameraConfig& c) { c.cx = 320.0; }, "fx"},
      {[](DepthCameraConfig& c) { c.fx = 300.0; }, "fy"},
      {[](DepthCameraConfig& c) {
         c.fx = c.fy = 300.0;
         c.cx = NAN;
       },
       "cx"},
      {[](DepthCameraConfig& c) { c.min_range = -0.1; }, "min_range"},
      {[](DepthCameraConfig& c) { c.max_range = 0.1; }, "max_range"},
      {[](DepthCameraConfig& c) { c.noise_stddev_per_m = -0.01; }, "noise_stddev_per_m"},
      {[](DepthCameraConfig& c) { c.noise_stddev_per_m = 1e12; }, "noise_stddev_per_m"},  // half the returns past max_range
      {[](DepthCameraConfig& c) { c.dropout_probability = 1.5; }, "dropout_probability"},
      {[](DepthCameraConfig& c) { c.dropout_probability = 1.0; }, "dropout_probability"},  // no return to map
  };
  for (const Case& k : cases) {
    DepthCameraConfig c;
    k.spoil(c);
    const common::Status st = c.validate();
    ASSERT_FALSE(st.ok()) << k.key;
    EXPECT_NE(st.message().find("depth_camera: " + k.key + " "), std::string::npos) << st.message();
  }
  DepthCameraConfig bad;
  bad.max_range = 0.05;
  EXPECT_EQ(bad.validate().message(), "depth_camera: max_range must be > min_range");
}

TEST_P(DepthRendererTest, WallFacingTheCameraHasThePlaneDepthEverywhere) {
  // Wall face at x = 3.0 (a voxel boundary), wide and tall enough to fill the view.
  const world::Scene scene = sceneWithBoxes({{Vec3(3.0, -4.0, -2.0), Vec3(3.2, 4.0, 4.0)}}, GetParam());
  const DepthCameraConfig config;
  const DepthRenderer renderer(config, scene);
  for (const Vec3& p : {Vec3(0.03, 0.02, 1.01), Vec3(0.0, 0.0, 1.0), Vec3(-0.37, 0.41, 0.66)}) {
    cv::Mat depth;
    renderer.render(cameraPose(p, 0.0), depth);
    ASSERT_EQ(depth.type(), CV_32FC1);
    ASSERT_EQ(depth.rows, 480);
    ASSERT_EQ(depth.cols, 640);
    double max_err = 0.0;
    for (int v = 0; v < depth.rows; ++v)
      for (int u = 0; u < depth.cols; ++u)
        max_err = std::max(max_err, std::abs(depth.at<float>(v, u) - (3.0 - p.x())));
    EXPECT_LT(max_err, kDepthTol) << "camera at " << p.transpose();
    EXPECT_LT(max_err, 1e-5);
  }
}

TEST_P(DepthRendererTest, BoxSilhouetteLandsOnItsProjectedEdges) {
  // Front face x = 2.0, y in [-0.4, 0.4], z in [0.6, 1.4]; camera on the box's axis, so the
  // silhouette is the front face: u in cx -+ fx 0.4 / 2, v in cy -+ fy 0.4 / 2.
  const Aabb box{Vec3(2.0, -0.4, 0.6), Vec3(2.4, 0.4, 1.4)};
  const world::Scene scene = sceneWithBoxes({box}, GetParam());
  const DepthCameraConfig config;
  const CameraIntrinsics K = config.intrinsics();
  const DepthRenderer renderer(config, scene);
  cv::Mat depth;
  renderer.render(cameraPose(Vec3(0.0, 0.0, 1.0), 0.0), depth);
  const double u_left = K.cx - K.fx * 0.4 / 2.0, u_right = K.cx + K.fx * 0.4 / 2.0;
  const double v_top = K.cy - K.fy * 0.4 / 2.0, v_bottom = K.cy + K.fy * 0.4 / 2.0;
  int rows_seen = 0, first_row = -1, last_row = -1;
  for (int v = 0; v < depth.rows; ++v) {
    int first = -1, last = -1;
    for (int u = 0; u < depth.cols; ++u) {
      const float d = depth.at<float>(v, u);
      if (!isReturn(d)) continue;
      EXPECT_NEAR(d, 2.0, 1e-4);
      if (first < 0) first = u;
      last = u;
    }
    if (first < 0) continue;
    ++rows_seen;
    if (first_row < 0) first_row = v;
    last_row = v;
    EXPECT_NEAR(first, u_left, 1.0) << "row " << v;
    EXPECT_NEAR(last, u_right, 1.0) << "row " << v;
    EXPECT_EQ(last - first + 1, countReturns(depth.row(v))) << "row " << v << " has a hole";
  }
  EXPECT_NEAR(first_row, v_top, 1.0);
  EXPECT_NEAR(last_row, v_bottom, 1.0);
  EXPECT_EQ(rows_seen, last_row - first_row + 1);

  // Seen obliquely (side and top faces visible), pixel-wise against the analytic box.
  DepthCameraConfig cfg;
  expectMatchesBoxes({box}, GetParam(), cfg,
                     cameraPose(Vec3(0.13, -0.77, 1.61), deg(17.0), deg(12.0), deg(8.0)));
  expectMatchesBoxes({box}, GetParam(), cfg, cameraPose(Vec3(1.1, 1.37, 0.44), deg(-71.0), deg(-20.0)));
}

// REP 117: +inf where no surface lies within max_range, -inf where the first one is nearer than min_range.
TEST_P(DepthRendererTest, PixelsOutsideTheRangeAreInfinite) {
  const DepthCameraConfig config;  // 0.1 .. 4.5 m
  const Vec3 p(0.0, 0.0, 1.0);
  constexpr float kFar = std::numeric_limits<float>::infinity();
  cv::Mat depth;
  {  // Wall beyond max_range.
    const world::Scene scene = sceneWithBoxes({{Vec3(4.6, -4.0, -2.0), Vec3(5.0, 4.0, 4.0)}}, GetParam());
    DepthRenderer(config, scene).render(cameraPose(p, 0.0), depth);
    EXPECT_EQ(countEqual(depth, kFar), 640 * 480);
  }
  {  // The same wall just within range.
    const world::Scene scene = sceneWithBoxes({{Vec3(4.4, -4.0, -2.0), Vec3(5.0, 4.0, 4.0)}}, GetParam());
    DepthRenderer(config, scene).render(cameraPose(p, 0.0), depth);
    EXPECT_EQ(countReturns(depth), 640 * 480);
  }
  {  // Nothing in view.
    const world::Scene scene = sceneWithBoxes({{Vec3(-1.0, -4.0, -2.0), Vec3(-0.6, 4.0, 4.0)}}, GetParam());
    DepthRenderer(config, scene).render(cameraPose(p, 0.0), depth);
    EXPECT_EQ(countEqual(depth, kFar), 640 * 480);
  }
  {  // Wall closer than min_range occludes everything behind it.
    const world::Scene scene = sceneWithBoxes(
        {{Vec3(0.0, -4.0, -2.0), Vec3(0.2, 4.0, 4.0)}, {Vec3(2.0, -4.0, -2.0), Vec3(2.2, 4.0, 4.0)}},
        GetParam());
    DepthRenderer(config, scene).render(cameraPose(Vec3(-0.05, 0.0, 1.0), 0.0), depth);
    EXPECT_EQ(countEqual(depth, -kFar), 640 * 480);
  }
  // A floor seen from 0.5 m looking down: near rows fall below min_range after pitching,
  // far ones beyond max_range; compared pixel-wise with the analytic floor.
  const std::vector<Aabb> floor = {{Vec3(-1.0, -6.0, -0.6), Vec3(9.0, 6.0, 0.0)}};
  expectMatchesBoxes(floor, GetParam(), config, cameraPose(Vec3(0.02, 0.01, 0.5), 0.0));
  DepthCameraConfig near_config;
  near_config.min_range = 0.6;
  expectMatchesBoxes(floor, GetParam(), near_config, cameraPose(Vec3(0.02, 0.01, 0.5), deg(30.0), deg(40.0)));
}

TEST_P(DepthRendererTest, YawingTheCameraTurnsTheView) {
  // Wall face at y = 2.0 facing -y, spanning x in [-1, 8].
  const std::vector<Aabb> wall = {{Vec3(-1.0, 2.0, -2.0), Vec3(8.0, 2.2, 4.0)}};
  const world::Scene scene = sceneWithBoxes(wall, GetParam());
  const DepthCameraConfig config;
  const CameraIntrinsics K = config.intrinsics();
  const DepthRenderer renderer(config, scene);
  const Vec3 p(1.03, 0.07, 1.02);
  cv::Mat ahead, left;
  // Looking along +x the wall lies to the left: pixel u sees it at depth (2 - y) / ((cx - u) / fx).
  renderer.render(cameraPose(p, 0.0), ahead);
  // Yawed 90 deg to the left the wall fills the view at 2 - y.
  renderer.render(cameraPose(p, deg(90.0)), left);
  EXPECT_EQ(countReturns(left), 640 * 480);
  for (int v = 0; v < K.height; ++v)
    for (int u = 0; u < K.width; ++u) {
      EXPECT_NEAR(left.at<float>(v, u), 2.0 - p.y(), 1e-4);
      const double slope = (K.cx - u) / K.fx;
      const double expected = slope > 0.0 ? (2.0 - p.y()) / slope : kInf;
      if (std::abs(expected - config.max_range) < 1e-3) continue;  // on the range edge
      if (expected > config.max_range)
        EXPECT_EQ(ahead.at<float>(v, u), std::numeric_limits<float>::infinity()) << "u " << u << " v " << v;
      else
        EXPECT_NEAR(ahead.at<float>(v, u), expected, 1e-3) << "u " << u << " v " << v;
    }
  EXPECT_GT(countReturns(ahead), 0);
  EXPECT_LT(countReturns(ahead), 640 * 480 / 2);
  for (double yaw : {30.0, 45.0, 120.0, 160.0})
    expectMatchesBoxes(wall, GetParam(), config, cameraPose(p, deg(yaw)));
}

TEST_P(DepthRendererTest, RollingAboutTheOpticalAxisRotatesTheImage) {
  // Square image, fx = fy, centred principal point: a 90 deg roll maps pixel centres onto
  // pixel centres, (u, v) -> (u' = v, v' = W - 1 - u).
  DepthCameraConfig config;
  config.width = config.height = 201;
  config.fx = config.fy = 150.0;
  config.cx = config.cy = 100.0;
  const std::vector<Aabb> boxes = {{Vec3(-1.0, -6.0, -0.6), Vec3(9.0, 6.0, 0.0)},
                                   {Vec3(2.0, 0.4, 0.0), Vec3(2.6, 1.2, 1.8)},
                                   {Vec3(3.2, -1.4, 0.6), Vec3(3.4, -0.2, 1.0)}};
  const world::Scene scene = sceneWithBoxes(boxes, GetParam());
  const DepthRenderer renderer(config, scene);
  const Vec3 p(0.11, 0.03, 0.95);
  cv::Mat upright, rolled;
  renderer.render(cameraPose(p, deg(5.0)), upright);
  renderer.render(cameraPose(p, deg(5.0), 0.0, deg(90.0)), rolled);
  int differing = 0;
  for (int v = 0; v < 201; ++v)
    for (int u = 0; u < 201; ++u)
      differing += std::abs(rolled.at<float>(200 - u, v) - upright.at<float>(v, u)) > 1e-4f;
  EXPECT_EQ(differing, 0);
  EXPECT_GT(countReturns(upright), 201 * 100);
  expectMatchesBoxes(boxes, GetParam(), config, cameraPose(p, deg(5.0)));
  expectMatchesBoxes(boxes, GetParam(), config, cameraPose(p, deg(5.0), 0.0, deg(90.0)));
  expectMatchesBoxes(boxes, GetParam(), config, cameraPose(p, deg(-40.0), deg(10.0), deg(33.0)));
}

TEST_P(DepthRendererTest, SlantedWallsSeenAtGrazingAnglesHaveNoHoles) {
  const double res = GetParam();
  world::Scene scene =
      world::makeEmptyScene("slanted", {Vec3(-1.0, -3.0, -1.0), Vec3(8.0, 3.0, 4.0)}, res, 0.5);
  // A wall y = 1 + 0.15 x (0.3 m thick along y: a staircase whose steps are face-adjacent)
  // and a ramp z = -0.2 + 0.08 x + 0.05 y, 0.25 m thick.
  const auto& geo = scene.geometry();
  for (std::size_t l = 0; l < geo.size(); ++l) {
    const Vec3 c = geo.indexToCoord(geo.unlinear(l));
    const double wall = c.y() - (1.0 + 0.15 * c.x());
    const double ramp = c.z() - (-0.2 + 0.08 * c.x() + 0.05 * c.y());
    const bool in_wall =
        wall >= 0.0 && wall <= 0.3 && c.x() >= -0.5 && c.x() <= 7.5 && c.z() >= -0.8 && c.z() <= 3.5;
    const bool in_ramp = ramp <= 0.0 && ramp >= -0.25;
    scene.occupied[l] = in_wall || in_ramp;
  }
  const DepthCameraConfig config;
  const CameraIntrinsics K = config.intrinsics();
  const DepthRenderer renderer(config, scene);
  const Vec3 p(0.01, -0.23, 0.45);
  for (double yaw : {0.0, 3.0, 8.0, 15.0, -10.0}) {
    const Eigen::Isometry3d T = cameraPose(p, deg(yaw), deg(4.0));
    cv::Mat depth;
    renderer.render(T, depth);
    // Where the ray meets the wall's or the ramp's surface plane well inside the range (and the
    // wall's extent), the staircase of voxels lies within a voxel of it: a depth must show.
    int covered = 0, holes = 0;
    for (int v = 0; v < K.height; ++v)
      for (int u = 0; u < K.width; ++u) {
        const Vec3 d = pixelRay(K, T, u, v);
        const double dw = d.y() - 0.15 * d.x(), dr = d.z() - 0.08 * d.x() - 0.05 * d.y();
        const double tw = dw > 0.0 ? (1.0 + 0.15 * p.x() - p.y()) / dw : kInf;
        const double tr = dr < 0.0 ? (-0.2 + 0.08 * p.x() + 0.05 * p.y() - p.z()) / dr : kInf;
        const double t = std::min(tw, tr);
        if (!(t > 0.5 && t < 3.0)) continue;
        const Vec3 hit = p + t * d;
        if (std::abs(hit.y()) > 3.2 || hit.x() < -1.0 || hit.x() > 8.0) continue;
        if (t == tw && !(hit.x() > 0.0 && hit.x() < 7.0 && hit.z() > -0.3 && hit.z() < 3.0)) continue;
        ++covered;
        holes += !isReturn(depth.at<float>(v, u));
      }
    EXPECT_GT(covered, 640 * 480 / 3) << "yaw " << yaw;
    EXPECT_EQ(holes, 0) << "yaw " << yaw;
    // And pixel-wise the same image as the brute-force voxel traversal.
    const Comparison c = compare(depth, traversedDepth(scene, config, T));
    EXPECT_EQ(c.beyond_one_pixel, 0) << "yaw " << yaw;
    EXPECT_EQ(c.differing, 0) << "yaw " << yaw;
  }
}

INSTANTIATE_TEST_SUITE_P(Resolutions, DepthRendererTest, ::testing::Values(0.1, 0.05, 0.2));

TEST(DepthRenderer, MatchesBruteForceTraversalInClutter) {
  // Random voxels and small boxes: many edges, corners and thin gaps.
  world::Scene scene =
      world::makeEmptyScene("clutter", {Vec3(-3.0, -3.0, 0.0), Vec3(3.0, 3.0, 3.0)}, 0.1, 0.3);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ux(-3.0, 3.0), uz(0.0, 3.0), size(0.05, 0.6);
  for (int i = 0; i < 300; ++i) {
    const Vec3 c(ux(rng), ux(rng), uz(rng));
    world::fillBox(scene, {c, c + Vec3(size(rng), size(rng), size(rng))});
  }
  for (int i = 0; i < 3000; ++i) world::markOccupied(scene, Vec3(ux(rng), ux(rng), uz(rng)));
  // The FOV-derived intrinsics (centred), and given ones with fx != fy and the principal point off centre (as
  // a real D435i's), where a renderer taking the image centre for (cx, cy) anywhere would differ.
  DepthCameraConfig centred;
  centred.max_range = 6.0;
  DepthCameraConfig off_centre = centred;
  off_centre.width = 480, off_centre.height = 400;
  off_centre.fx = 300.0, off_centre.fy = 260.0, off_centre.cx = 190.0, off_centre.cy = 240.0;
  for (const DepthCameraConfig& config : {centred, off_centre}) {
    SCOPED_TRACE("cx " + std::to_string(config.intrinsics().cx));
    ASSERT_TRUE(config.validate().ok());
    const DepthRenderer renderer(config, scene);
    std::uniform_real_distribution<double> angle(-M_PI, M_PI);
    int poses = 0;
    while (poses < 6) {
      const Vec3 p(0.8 * ux(rng), 0.8 * ux(rng), 0.3 + 0.8 * uz(rng));
      if (scene.isOccupied(p)) continue;
      const Eigen::Isometry3d T = cameraPose(p, angle(rng), 0.4 * angle(rng), 0.2 * angle(rng));
      cv::Mat depth;
      renderer.render(T, depth);
      const Comparison c = compare(depth, traversedDepth(scene, config, T));
      EXPECT_EQ(c.beyond_one_pixel, 0) << "pose " << poses;
      EXPECT_EQ(c.differing, 0) << "pose " << poses;
      EXPECT_LT(c.max_matched_error, 1e-3);
      ++poses;
    }
  }
}

// With the principal point off centre the image reaches farther to one side than the other: boxes 5.4 m away
// seen in the right columns and the top rows, wholly or mostly beyond where a frustum taken about the image
// centre ends (50 and 40 pixels short of the edges), are drawn with their analytic depth.
TEST(DepthRenderer, AnOffCentrePrincipalPointSeesToTheImageEdges) {
  DepthCameraConfig config;
  config.max_range = 6.0;
  config.width = 480, config.height = 400;
  config.fx = 300.0, config.fy = 260.0, config.cx = 190.0, config.cy = 240.0;
  ASSERT_TRUE(config.validate().ok());
  // From (0, 0, 0.5) looking along +x: image right is -y, image up is +z. At depth x, u = 190 + 300 * (-y) / x
  // and v = 240 - 260 * (z - 0.5) / x (no box edge on a pixel centre).
  const std::vector<Aabb> boxes{{Vec3(5.4, -5.0, 0.2), Vec3(5.6, -4.6, 0.8)},   // u 436 .. 468 (the right one)
                                {Vec3(5.4, -0.4, 4.8), Vec3(5.8, 0.4, 5.4)}};  // v 4 .. 47 (the top one)
  const Eigen::Isometry3d T = cameraPose(Vec3(0.0, 0.0, 0.5), 0.0);
  const world::Scene scene = sceneWithBoxes(boxes, 0.1);
  const DepthRenderer renderer(config, scene);
  cv::Mat depth;
  renderer.render(T, depth);
  const cv::Mat right = depth(cv::Rect(380, 0, 100, 400)), top = depth(cv::Rect(0, 0, 480, 60));
  EXPECT_GT(countReturns(right), 600);
  EXPECT_GT(countReturns(top), 1000);
  const Comparison c = compare(depth, analyticDepth(boxes, config, T));
  EXPECT_EQ(c.beyond_one_pixel, 0);
  EXPECT_EQ(c.differing, 0);
  EXPECT_LT(c.max_matched_error, 1e-3);
}

TEST(DepthRenderer, CameraOutsideTheGridSeesTheScene) {
  // The grid spans x >= -1.6, z <= 5.6: faces on the grid's border are drawn too.
  const std::vector<Aabb> boxes = {{Vec3(-1.0, -6.0, -0.6), Vec3(9.0, 6.0, 0.0)},
                                   {Vec3(2.0, -0.4, 0.6), Vec3(2.4, 0.4, 1.4)}};
  DepthCameraConfig config;
  config.max_range = 8.0;
  expectMatchesBoxes(boxes, 0.1, config, cameraPose(Vec3(-2.1, 0.13, 1.07), deg(3.0)));
  expectMatchesBoxes(boxes, 0.1, config, cameraPose(Vec3(1.3, 0.21, 5.9), deg(-10.0), deg(75.0)));
}

TEST(DepthRenderer, CameraInsideAnOccupiedVoxelSeesEverythingTooNear) {
  const world::Scene scene = sceneWithBoxes({{Vec3(0.0, -1.0, 0.0), Vec3(3.0, 1.0, 2.0)}}, 0.1);
  const DepthRenderer renderer(DepthCameraConfig(), scene);
  cv::Mat depth;
  renderer.render(cameraPose(Vec3(1.0, 0.0, 1.0), 0.0), depth);
  EXPECT_EQ(countEqual(depth, -std::numeric_limits<float>::infinity()), 640 * 480);
}

// A camera on a voxel's face, outside it (touching a wall: a collision) sees -inf everywhere, as one
// inside it. The faces through the camera are skipped as edge-on, and the wall used to look transparent:
// +inf over the whole image, which the mapper casts free to its range, through the wall.
TEST(DepthRenderer, CameraTouchingAWallSeesEverythingTooNear) {
  const world::Scene scene = sceneWithBoxes({{Vec3(2.0, -4.0, -2.0), Vec3(2.2, 4.0, 4.0)}}, 0.1);
  const DepthRenderer renderer(DepthCameraConfig(), scene);
  cv::Mat depth;
  const float inf = std::numeric_limits<float>::infinity();
  // On the wall's near face (x = 2.0), looking away from it and along it.
  for (const double yaw : {M_PI, 0.5 * M_PI}) {
    renderer.render(cameraPose(Vec3(2.0, 0.33, 1.07), yaw), depth);
    EXPECT_EQ(countEqual(depth, -inf), 640 * 480) << "yaw " << yaw;
  }
  // Touching a ceiling from below (its lower face at z = 2.0), looking along it: the same.
  const world::Scene ceiling = sceneWithBoxes({{Vec3(-1.0, -6.0, 2.0), Vec3(9.0, 6.0, 2.2)}}, 0.1);
  const DepthRenderer under(DepthCameraConfig(), ceiling);
  for (const double yaw : {0.0, 0.5 * M_PI}) {
    under.render(cameraPose(Vec3(1.0, 0.33, 2.0), yaw), depth);
    EXPECT_EQ(countEqual(depth, -inf), 640 * 480) << "under a ceiling, yaw " << yaw;
  }
  // A hair off the face (5 microns): the wall ahead at that depth, nothing else in view.
  renderer.render(cameraPose(Vec3(2.0 - 5e-6, 0.33, 1.07), 0.0), depth);
  EXPECT_EQ(countEqual(depth, -inf), 640 * 480);  // nearer than min_range
  renderer.render(cameraPose(Vec3(2.0 - 5e-6, 0.33, 1.07), M_PI), depth);
  EXPECT_EQ(countEqual(depth, -inf), 0) << "a camera 5 microns from a wall, looking away from it";
  // With min_range 0 nothing is too near: 3 cm from the wall every pixel has the analytic depth, none -inf.
  DepthCameraConfig no_min;
  no_min.min_range = 0.0;
  ASSERT_TRUE(no_min.validate().ok());
  const DepthRenderer close_renderer(no_min, scene);
  const Eigen::Isometry3d T = cameraPose(Vec3(1.97, 0.33, 1.07), 0.0);
  close_renderer.render(T, depth);
  EXPECT_EQ(countEqual(depth, -inf), 0);
  const Comparison c = compare(depth, analyticDepth({{Vec3(2.0, -4.0, -2.0), Vec3(2.2, 4.0, 4.0)}}, no_min, T));
  EXPECT_EQ(c.differing, 0);
  EXPECT_LT(c.max_matched_error, 1e-5);
  EXPECT_NEAR(depth.at<float>(240, 320), 0.03, 1e-5);
}

// A view that misses the grid has no return anywhere: +inf (REP 117: nothing in range), not 0 (no
// measurement). A pose that is not finite (a diverged simulation) measures nothing: NaN everywhere; its
// index arithmetic was undefined, and the bench crashed in it.
TEST(DepthRenderer, AViewMissingTheGridIsInfiniteAndAPoseNotFiniteMeasuresNothing) {
  const world::Scene scene = sceneWithBoxes({{Vec3(2.0, -4.0, -2.0), Vec3(2.2, 4.0, 4.0)}}, 0.1);
  const DepthRenderer renderer(DepthCameraConfig(), scene);
  cv::Mat depth;
  const float inf = std::numeric_limits<float>::infinity();
  renderer.render(cameraPose(Vec3(-30.0, 0.0, 1.0), M_PI), depth);  // 29 m outside, looking away
  EXPECT_EQ(countEqual(depth, inf), 640 * 480);
  renderer.render(cameraPose(Vec3(1.0, 0.0, 1e12), 0.0), depth);  // far above, finite
  EXPECT_EQ(countEqual(depth, inf), 640 * 480);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const Eigen::Isometry3d& pose : {cameraPose(Vec3(nan, 1.0, 1.0), 0.0), cameraPose(Vec3(1.0, 0.0, 1.0), nan)}) {
    renderer.render(pose, depth);
    EXPECT_EQ(countEqual(depth, std::numeric_limits<float>::quiet_NaN()), 640 * 480);
  }
}

// As a RealSense sends depth: millimetres, 0 where there is no return (REP 117's +-inf and NaN, 0 and
// negative values alike; converted as they are, +inf saturated to 65535 mm, a wall 65 m away).
TEST(DepthRenderer, MillimetresAreZeroWithoutAReturn) {
  const float inf = std::numeric_limits<float>::infinity();
  cv::Mat metres = (cv::Mat_<float>(1, 7) << inf, -inf, std::numeric_limits<float>::quiet_NaN(), 0.0f, -1.0f, 1.25f, 4.5f);
  cv::Mat mm;
  sim::toMillimetres(metres, mm);
  ASSERT_EQ(mm.type(), CV_16UC1);
  const std::vector<std::uint16_t> expected{0, 0, 0, 0, 0, 1250, 4500};
  for (int u = 0; u < 7; ++u) EXPECT_EQ(mm.at<std::uint16_t>(0, u), expected[u]) << "pixel " << u;
}

TEST(DepthRendererNoise, ZeroConfigChangesNothing) {
  const world::Scene scene = sceneWithBoxes({{Vec3(2.0, -4.0, -2.0), Vec3(2.2, 4.0, 4.0)}}, 0.1);
  const DepthRenderer renderer(DepthCameraConfig(), scene);
  cv::Mat clean, noisy;
  renderer.render(cameraPose(Vec3(0.0, 0.0, 1.0), deg(30.0)), clean);
  noisy = clean.clone();
  std::mt19937_64 rng(1), untouched(1);
  renderer.addNoise(noisy, rng);
  EXPECT_TRUE(sameBits(noisy, clean));
  EXPECT_GT(countEqual(clean, std::numeric_limits<float>::infinity()), 0);  // beyond the wall's edge: kept
  EXPECT_EQ(rng(), untouched());
}

// Noise and dropout touch returns only: a pixel with nothing in range stays +inf (free space to the range for
// the mapper), never becoming NaN (no measurement) or a finite depth; returns do change.
TEST(DepthRendererNoise, PixelsWithNothingInRangeStayInfinite) {
  const world::Scene scene = sceneWithBoxes({{Vec3(2.0, -4.0, -2.0), Vec3(2.2, 4.0, 4.0)}}, 0.1);
  DepthCameraConfig config;
  config.dropout_probability = 0.5;
  config.noise_stddev_per_m = 0.01;
  const DepthRenderer renderer(config, scene);
  cv::Mat clean;
  renderer.render(cameraPose(Vec3(0.0, 0.0, 1.0), deg(30.0)), clean);
  cv::Mat noisy = clean.clone();
  std::mt19937_64 rng(5);
  renderer.addNoise(noisy, rng);
  int empty = 0, changed = 0;
  for (int v = 0; v < clean.rows; ++v)
    for (int u = 0; u < clean.cols; ++u) {
      const float before = clean.at<float>(v, u), after = noisy.at<float>(v, u);
      if (isReturn(before)) {
        changed += !(after == before);
        continue;
      }
      ++empty;
      ASSERT_EQ(std::memcmp(&before, &after, sizeof(float)), 0) << "pixel " << u << ", " << v << ": " << after;
    }
  EXPECT_GT(empty, 0);
  EXPECT_GT(changed, 0);
}

// A dropped return is NaN (REP 117: no measurement); the rest keep their depth (no noise here). At a dropout of
// 0.99 of 307200 returns, the count dropped lies within 6 standard deviations (55) of 304128.
TEST(DepthRendererNoise, DroppedReturnsAreNoMeasurement) {
  const world::Scene scene = sceneWithBoxes({{Vec3(2.0, -4.0, -2.0), Vec3(2.2, 4.0, 4.0)}}, 0.1);
  DepthCameraConfig config;
  config.dropout_probability = 0.99;
  ASSERT_TRUE(config.validate().ok());
  const DepthRenderer renderer(config, scene);
  cv::Mat depth;
  renderer.render(cameraPose(Vec3(0.0, 0.0, 1.0), 0.0), depth);
  ASSERT_EQ(countReturns(depth), 640 * 480);
  const cv::Mat clean = depth.clone();
  std::mt19937_64 rng(3);
  renderer.addNoise(depth, rng);
  const int dropped = countEqual(depth, std::numeric_limits<float>::quiet_NaN());
  EXPECT_NEAR(dropped, 0.99 * 640 * 480, 6 * 55);
  int kept_as_they_were = 0;
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) kept_as_they_were += depth.at<float>(v, u) == clean.at<float>(v, u);
  EXPECT_EQ(kept_as_they_were + dropped, 640 * 480);
}

// A wall 0.2 m thick whose face lies `wall_x` ahead of a camera at (0, 0, 1) looking along x: its clean
// rendering, and the same with `config`'s noise drawn from `seed`.
void renderNoisyWall(double wall_x, const DepthCameraConfig& config, unsigned seed, cv::Mat& clean, cv::Mat& noisy) {
  const DepthRenderer renderer(config, sceneWithBoxes({{Vec3(wall_x, -6.0, -4.0), Vec3(wall_x + 0.2, 6.0, 6.0)}}, 0.1));
  renderer.render(cameraPose(Vec3(0.0, 0.0, 1.0), 0.0), clean);
  noisy = clean.clone();
  std::mt19937_64 rng(seed);
  renderer.addNoise(noisy, rng);
}

// A noisy depth beyond max_range is no return (+inf), one nearer than min_range a surface too near (-inf),
// as REP 117 says: a wall 4.4 m off with sigma 2 %/m (8.8 cm) puts P(z > 0.1 / 0.088) of its pixels past
// 4.5 m, and one 0.2 m off with sigma 50 %/m (10 cm) P(z < -1) of them under 0.1 m. No finite value lies
// outside the range, and every other pixel keeps its noisy return.
TEST(DepthRendererNoise, ValuesPushedOutOfRangeAreNoReturns) {
  struct Case {
    double wall_x, sigma_per_m;
    bool beyond;  // past max_range (else under min_range)
  };
  for (const Case c : {Case{4.4, 0.02, true}, Case{0.2, 0.5, false}}) {
    DepthCameraConfig config;
    config.noise_stddev_per_m = c.sigma_per_m;
    cv::Mat clean, noisy;
    renderNoisyWall(c.wall_x, config, 7, clean, noisy);
    int returns = 0, out = 0, other = 0;
    for (int v = 0; v < noisy.rows; ++v)
      for (int u = 0; u < noisy.cols; ++u) {
        const float before = clean.at<float>(v, u), after = noisy.at<float>(v, u);
        if (!isReturn(before)) continue;
        ASSERT_NEAR(before, c.wall_x, 1e-4);
        ++returns;
        if (std::isfinite(after)) {
          ASSERT_GE(after, config.min_range);
          ASSERT_LE(after, config.max_range);
        } else if (after == (c.beyond ? 1.0f : -1.0f) * std::numeric_limits<float>::infinity()) {
          ++out;
        } else {
          ++other;  // NaN, or the other infinity
        }
      }
    ASSERT_GT(returns, 100000);
    const double sigma = c.sigma_per_m * c.wall_x;
    const double a = c.beyond ? (config.max_range - c.wall_x) / sigma : (c.wall_x - config.min_range) / sigma;
    const double expected = 0.5 * std::erfc(a / std::sqrt(2.0));
    EXPECT_NEAR(static_cast<double>(out) / returns, expected, 0.01) << "wall at " << c.wall_x;
    EXPECT_GT(expected, 0.1);
    EXPECT_EQ(other, 0);
  }
}

TEST(DepthRendererNoise, StatisticsMatchTheModelOnAFlatWall) {
  DepthCameraConfig config;
  config.noise_stddev_per_m = 0.01;  // sigma = 2 cm at 2 m
  config.dropout_probability = 0.2;
  cv::Mat clean, noisy;
  renderNoisyWall(2.0, config, 42, clean, noisy);
  double sum = 0.0, sum_sq = 0.0;
  int valid = 0;
  for (int v = 0; v < noisy.rows; ++v)
    for (int u = 0; u < noisy.cols; ++u) {
      if (!isReturn(noisy.at<float>(v, u))) continue;
      const double e = noisy.at<float>(v, u) - clean.at<float>(v, u);
      sum += e;
      sum_sq += e * e;
      ++valid;
    }
  const double n = static_cast<double>(noisy.total());
  EXPECT_NEAR(valid / n, 0.8, 0.01);
  const double mean = sum / valid, sigma = std::sqrt(sum_sq / valid - mean * mean);
  EXPECT_NEAR(mean, 0.0, 0.001);
  EXPECT_NEAR(sigma, 0.02, 0.001);

  // The same rng state gives the same image.
  cv::Mat clean_again, again;
  renderNoisyWall(2.0, config, 42, clean_again, again);
  EXPECT_TRUE(sameBits(again, noisy));
}
