// Simulated depth camera (DESIGN §3.2): renders the ground-truth voxel scene as a depth
// image on the CPU, one thread.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "go_feap/common/result.h"
#include "go_feap/world/scene.h"

namespace go_feap::sim {

/// Pinhole intrinsics; pixel (u, v) has its centre at integer coordinates (OpenCV convention).
/// A camera-frame point (x, y, z) projects to u = fx x / z + cx, v = fy y / z + cy.
struct CameraIntrinsics {
  int width = 640, height = 480;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  /// fx = (width / 2) / tan(hfov / 2), fy = (height / 2) / tan(vfov / 2), cx = (width - 1) / 2,
  /// cy = (height - 1) / 2.
  static CameraIntrinsics fromFov(int width, int height, double hfov_rad, double vfov_rad);
};

struct DepthCameraConfig {
  static constexpr int kMaxSide = 8192;  ///< pixels, the most validate() accepts for width and height
  int width = 640;         ///< image width (pixels), in [1, kMaxSide]
  int height = 480;        ///< image height (pixels), in [1, kMaxSide]
  double hfov_deg = 80.0;  ///< horizontal field of view (deg), used when fx..cy are all 0
  double vfov_deg = 60.0;  ///< vertical field of view (deg), used when fx..cy are all 0
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  ///< pixels; all 0 -> derived from the FOV
  double min_range = 0.1;                         ///< m, on the depth (optical z) value
  double max_range = 4.5;                         ///< m, on the depth (optical z) value
  double noise_stddev_per_m = 0.0;                ///< Gaussian depth noise sigma = this * depth
  double dropout_probability = 0.0;               ///< probability that a return becomes NaN (no measurement)

  /// Checks every key; the message names the bad one, e.g.
  /// "depth_camera: max_range must be > min_range".
  common::Status validate() const;
  /// The given fx, fy, cx, cy, or the FOV-derived ones when all four are 0.
  CameraIntrinsics intrinsics() const;
};

/// Renders depth images of a world::Scene by rasterising the exposed faces of its occupied
/// voxels with a per-pixel depth test. Per pixel the result equals casting the ray through
/// the pixel centre and taking the first voxel cube it enters (the geometry is the cubes
/// themselves); face edges are tested with a tiny inclusive tolerance, so rays along a
/// shared edge never slip between adjacent faces (no holes in walls).
///
/// Construction builds a surface mesh of the scene (per 8^3 block, coplanar exposed faces
/// merged into rectangles); the scene must outlive the renderer and must not change
/// after construction. The config must pass validate().
class DepthRenderer {
 public:
  using Config = DepthCameraConfig;

  DepthRenderer(const DepthCameraConfig& config, const world::Scene& scene);

  /// Renders a CV_32FC1 depth image in metres (optical-frame z of the first occupied voxel
  /// surface hit by the ray through each pixel centre), with REP 117's values where there is no
  /// measurement: -inf where that surface is nearer than min_range (it occludes the view), +inf where
  /// it is farther than max_range or absent. A camera inside an occupied voxel, or within kTouch of
  /// one, sees -inf everywhere; a pose that is not finite gives NaN everywhere (no measurement).
  /// `depth` is (re)allocated to height x width.
  /// T_W_C maps camera optical-frame coordinates (z forward, x right, y down) to world.
  void render(const Eigen::Isometry3d& T_W_C, cv::Mat& depth) const;

  /// Applies the configured noise and dropout in place to a CV_32FC1 image from render():
  /// a return is dropped (set to NaN, REP 117's "no measurement") with probability
  /// dropout_probability, otherwise gets Gaussian noise of sigma noise_stddev_per_m * depth; a noisy
  /// value below min_range becomes -inf, above max_range +inf. Pixels without a return stay as they
  /// are. Deterministic for a given rng state; draws nothing when both settings are 0.
  void addNoise(cv::Mat& depth, std::mt19937_64& rng) const;

  const DepthCameraConfig& config() const { return config_; }
  const CameraIntrinsics& intrinsics() const { return intrinsics_; }
  /// Number of merged surface rectangles (benchmark statistics).
  std::size_t rectangleCount() const { return rects_.size(); }

 private:
  /// Axis-aligned rectangle of exposed voxel faces in grid-index coordinates: it lies in
  /// the plane index[axis] = plane, spans [u0, u1] along axis (axis + 1) % 3 and [v0, v1]
  /// along (axis + 2) % 3. Axis and facing side come from the group it is stored in.
  struct Rect {
    std::int32_t plane, u0, u1, v0, v1;
  };
  static constexpr int kBlock = 8;  ///< block edge (voxels) of the culling grid
  /// m: a camera this near an occupied voxel touches it (see render()).
  static constexpr double kTouch = 2e-6;

  void buildSurface();
  std::size_t blockIndex(int bx, int by, int bz) const {
    return (static_cast<std::size_t>(bz) * blocks_.y() + by) * blocks_.x() + bx;
  }

  DepthCameraConfig config_;
  CameraIntrinsics intrinsics_;
  const world::Scene& scene_;
  common::Index3 blocks_ = common::Index3::Zero();  ///< block counts per axis
  /// Rectangles of block b facing direction d (0..5 = +x, -x, +y, -y, +z, -z) are
  /// rects_[group_begin_[6 b + d] .. group_begin_[6 b + d + 1]).
  std::vector<std::uint32_t> group_begin_;
  std::vector<Rect> rects_;
};

/// A measured depth (m): REP 117's values for none (+inf nothing in range, -inf too near, NaN), 0 and
/// negative values are no return.
inline bool isReturn(float depth) { return depth > 0.0f && depth < std::numeric_limits<float>::infinity(); }

/// A CV_32FC1 image in metres as a RealSense sends it, CV_16UC1 millimetres with 0 where there is no
/// return (near or far alike): `metres` has its pixels without a return set to 0 on the way.
void toMillimetres(cv::Mat& metres, cv::Mat& mm);

}  // namespace go_feap::sim
