#include "go_feap/sim/depth_camera.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

namespace go_feap::sim {

using common::Index3;
using common::Status;

CameraIntrinsics CameraIntrinsics::fromFov(int width, int height, double hfov_rad, double vfov_rad) {
  CameraIntrinsics k;
  k.width = width;
  k.height = height;
  k.fx = 0.5 * width / std::tan(0.5 * hfov_rad);
  k.fy = 0.5 * height / std::tan(0.5 * vfov_rad);
  k.cx = 0.5 * (width - 1);
  k.cy = 0.5 * (height - 1);
  return k;
}

Status DepthCameraConfig::validate() const {
  auto err = [](const char* key, const char* why) {
    return Status::Error(std::string("depth_camera: ") + key + " " + why);
  };
  // Up to 8192 a side (a D435i's depth is 1280 x 720): 1e5 x 1e5 asked for 40 GB at the first frame.
  if (width <= 0 || width > kMaxSide) return err("width", "must be in [1, 8192] pixels");
  if (height <= 0 || height > kMaxSide) return err("height", "must be in [1, 8192] pixels");
  if (!(hfov_deg > 0.0 && hfov_deg < 180.0)) return err("hfov_deg", "must be in (0, 180)");
  if (!(vfov_deg > 0.0 && vfov_deg < 180.0)) return err("vfov_deg", "must be in (0, 180)");
  if (fx != 0.0 || fy != 0.0 || cx != 0.0 || cy != 0.0) {
    const char* why =
        "must be finite and > 0 when the intrinsics are given (all of fx, fy, cx, cy 0 derives them "
        "from the FOV)";
    if (!(fx > 0.0 && std::isfinite(fx))) return err("fx", why);
    if (!(fy > 0.0 && std::isfinite(fy))) return err("fy", why);
    if (!std::isfinite(cx)) return err("cx", "must be finite");
    if (!std::isfinite(cy)) return err("cy", "must be finite");
  }
  if (!(min_range >= 0.0 && std::isfinite(min_range))) return err("min_range", "must be >= 0");
  if (!(max_range > min_range && std::isfinite(max_range))) return err("max_range", "must be > min_range");
  // At most 1 (100 % of the depth per metre): 1e12 would send half the returns past max_range, which the
  // mapper takes for free space through the walls. A dropout of 1 leaves no return to map.
  if (!(noise_stddev_per_m >= 0.0 && noise_stddev_per_m <= 1.0))
    return err("noise_stddev_per_m", "must be in [0, 1]");
  if (!(dropout_probability >= 0.0 && dropout_probability < 1.0))
    return err("dropout_probability", "must be in [0, 1)");
  return Status::Ok();
}

CameraIntrinsics DepthCameraConfig::intrinsics() const {
  if (fx == 0.0 && fy == 0.0 && cx == 0.0 && cy == 0.0) {
    return CameraIntrinsics::fromFov(width, height, hfov_deg * M_PI / 180.0, vfov_deg * M_PI / 180.0);
  }
  CameraIntrinsics k;
  k.width = width;
  k.height = height;
  k.fx = fx;
  k.fy = fy;
  k.cx = cx;
  k.cy = cy;
  return k;
}

DepthRenderer::DepthRenderer(const DepthCameraConfig& config, const world::Scene& scene)
    : config_(config), intrinsics_(config.intrinsics()), scene_(scene) {
  buildSurface();
}

void DepthRenderer::buildSurface() {
  const Index3 n = scene_.geometry().dims();
  const std::vector<std::uint8_t>& occ = scene_.occupied.data();
  for (int a = 0; a < 3; ++a) blocks_[a] = (n[a] + kBlock - 1) / kBlock;
  const std::size_t block_count = static_cast<std::size_t>(blocks_.x()) * blocks_.y() * blocks_.z();

  std::vector<std::uint8_t> block_has_voxels(block_count, 0);
  for (int z = 0, l = 0; z < n.z(); ++z)
    for (int y = 0; y < n.y(); ++y)
      for (int x = 0; x < n.x(); ++x, ++l)
        if (occ[l]) block_has_voxels[blockIndex(x / kBlock, y / kBlock, z / kBlock)] = 1;

  const auto nx = static_cast<unsigned>(n.x()), ny = static_cast<unsigned>(n.y()),
             nz = static_cast<unsigned>(n.z());
  auto occupied = [&](const Index3& i) {  // outside the grid is free
    const auto x = static_cast<unsigned>(i.x()), y = static_cast<unsigned>(i.y()),
               z = static_cast<unsigned>(i.z());
    return x < nx && y < ny && z < nz && occ[(static_cast<std::size_t>(z) * ny + y) * nx + x] != 0;
  };

  group_begin_.assign(6 * block_count + 1, 0);
  for (int bz = 0; bz < blocks_.z(); ++bz)
    for (int by = 0; by < blocks_.y(); ++by)
      for (int bx = 0; bx < blocks_.x(); ++bx) {
        const std::size_t b = blockIndex(bx, by, bz);
        const Index3 lo = Index3(bx, by, bz) * kBlock;
        const Index3 hi = (lo + Index3::Constant(kBlock)).cwiseMin(n);
        for (int d = 0; d < 6; ++d) {
          group_begin_[6 * b + d] = static_cast<std::uint32_t>(rects_.size());
          if (!block_has_voxels[b]) continue;
          const int a = d / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
          const bool positive = d % 2 == 0;
          for (int s = lo[a]; s < hi[a]; ++s) {
            // Exposed faces of this slice: bit ru of row rv is voxel (lo[ua] + ru, lo[va] + rv).
            std::array<std::uint8_t, kBlock> mask{};
            Index3 idx;
            idx[a] = s;
            for (int rv = 0; rv < hi[va] - lo[va]; ++rv) {
              idx[va] = lo[va] + rv;
              for (int ru = 0; ru < hi[ua] - lo[ua]; ++ru) {
                idx[ua] = lo[ua] + ru;
                Index3 beyond = idx;
                beyond[a] += positive ? 1 : -1;
                if (occupied(idx) && !occupied(beyond)) mask[rv] |= static_cast<std::uint8_t>(1u << ru);
              }
            }
            // Greedy merge: take a run of a row, grow it over the following rows.
            for (int rv = 0; rv < kBlock; ++rv) {
              while (mask[rv]) {
                int u0 = 0;
                while (!((mask[rv] >> u0) & 1u)) ++u0;
                int w = 0;
                while (u0 + w < kBlock && ((mask[rv] >> (u0 + w)) & 1u)) ++w;
                const auto run = static_cast<std::uint8_t>(((1u << w) - 1u) << u0);
                int h = 1;
                while (rv + h < kBlock && (mask[rv + h] & run) == run) {
                  mask[rv + h] = static_cast<std::uint8_t>(mask[rv + h] & ~run);
                  ++h;
                }
                mask[rv] = static_cast<std::uint8_t>(mask[rv] & ~run);
                rects_.push_back(
                    Rect{positive ? s + 1 : s, lo[ua] + u0, lo[ua] + u0 + w, lo[va] + rv, lo[va] + rv + h});
              }
            }
          }
        }
      }
  group_begin_.back() = static_cast<std::uint32_t>(rects_.size());
}

void DepthRenderer::render(const Eigen::Isometry3d& T_W_C, cv::Mat& depth) const {
  const CameraIntrinsics& K = intrinsics_;
  depth.create(K.height, K.width, CV_32FC1);
  // A pose that is not finite (a diverged state) measures nothing; its index arithmetic below was undefined.
  if (!T_W_C.matrix().allFinite()) {
    depth.setTo(cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
    return;
  }
  // A camera inside a cube, or touching one: every ray starts in it, too close everywhere. Touching
  // counts: the faces through the camera are skipped as edge-on below, and the wall looked transparent.
  const Eigen::Vector3d t = T_W_C.translation();
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d touch(corner & 1 ? kTouch : -kTouch, corner & 2 ? kTouch : -kTouch,
                                corner & 4 ? kTouch : -kTouch);
    if (scene_.isOccupied(Eigen::Vector3d(t + touch))) {
      depth.setTo(cv::Scalar(-std::numeric_limits<float>::infinity()));
      return;
    }
  }
  depth.setTo(cv::Scalar(0.0));

  // Work in grid-index units: grid vertex p lies at camera-frame point sum_a E[a] (p_a - q_a).
  const common::GridGeometry& geo = scene_.geometry();
  const double res = geo.resolution();
  const Eigen::Matrix3d R_C_W = T_W_C.linear().transpose();
  const Eigen::Vector3d q = (T_W_C.translation() - geo.origin()) / res;
  std::array<Eigen::Vector3d, 3> E;
  for (int a = 0; a < 3; ++a) E[a] = res * R_C_W.col(a);

  // Everything a pixel ray can reach lies in the frustum spanned by the outermost pixel
  // centres, cut at depth max_range.
  const double x_lo = -K.cx / K.fx, x_hi = (K.width - 1 - K.cx) / K.fx;
  const double y_lo = -K.cy / K.fy, y_hi = (K.height - 1 - K.cy) / K.fy;
  const double max_depth = config_.max_range;
  const std::array<Eigen::Vector3d, 4> side_normals = {
      Eigen::Vector3d(1, 0, -x_lo).normalized(), Eigen::Vector3d(-1, 0, x_hi).normalized(),
      Eigen::Vector3d(0, 1, -y_lo).normalized(), Eigen::Vector3d(0, -1, y_hi).normalized()};
  Eigen::Vector3d fmin = q, fmax = q;
  for (double x : {x_lo, x_hi})
    for (double y : {y_lo, y_hi}) {
      const Eigen::Vector3d corner =
          q + T_W_C.linear() * Eigen::Vector3d(x * max_depth, y * max_depth, max_depth) / res;
      fmin = fmin.cwiseMin(corner);
      fmax = fmax.cwiseMax(corner);
    }
  Index3 b_lo, b_hi;
  const Index3 n = geo.dims();
  for (int a = 0; a < 3; ++a) {
    const double lo = std::clamp(std::floor(fmin[a]) - 1.0, 0.0, n[a] - 1.0);
    const double hi = std::clamp(std::floor(fmax[a]) + 1.0, 0.0, n[a] - 1.0);
    b_lo[a] = static_cast<int>(lo) / kBlock;
    b_hi[a] = static_cast<int>(hi) / kBlock;
    if (fmax[a] < -1.0 || fmin[a] > n[a] + 1.0) {  // the frustum misses the grid: nothing in range
      depth.setTo(cv::Scalar(std::numeric_limits<float>::infinity()));
      return;
    }
  }

  // A face whose plane passes within this distance (index units) of the camera is seen
  // edge-on: it covers no pixel, and its plane depth would be ill-conditioned. (A camera that near
  // a face's rectangle touches its cube, rendered too near above.)
  const double kEdgeOn = kTouch / 2.0 / res;
  // Inclusive tolerance of the edge tests (normalised edge-plane units, ~radians): closes
  // rounding gaps between faces that share an edge, far below a pixel.
  const double kEdgeTol = 1e-9;
  const int W = K.width, H = K.height;

  for (int bz = b_lo.z(); bz <= b_hi.z(); ++bz)
    for (int by = b_lo.y(); by <= b_hi.y(); ++by)
      for (int bx = b_lo.x(); bx <= b_hi.x(); ++bx) {
        const std::size_t b = blockIndex(bx, by, bz);
        if (group_begin_[6 * b] == group_begin_[6 * b + 6]) continue;
        const Index3 lo = Index3(bx, by, bz) * kBlock;
        const Index3 hi = (lo + Index3::Constant(kBlock)).cwiseMin(n);
        // Bounding-sphere test of the block against the frustum.
        const Eigen::Vector3d centre_idx = 0.5 * (lo + hi).cast<double>() - q;
        const Eigen::Vector3d centre = E[0] * centre_idx.x() + E[1] * centre_idx.y() + E[2] * centre_idx.z();
        const double radius = 0.5 * res * (hi - lo).cast<double>().norm();
        if (centre.z() < -radius || centre.z() - radius > max_depth) continue;
        bool outside = false;
        for (const auto& nrm : side_normals) outside = outside || nrm.dot(centre) < -radius;
        if (outside) continue;

        for (int d = 0; d < 6; ++d) {
          const std::uint32_t r_begin = group_begin_[6 * b + d], r_end = group_begin_[6 * b + d + 1];
          if (r_begin == r_end) continue;
          const int a = d / 2, ua = (a + 1) % 3, va = (a + 2) % 3;
          const bool positive = d % 2 == 0;
          // Faces are seen from their free side only.
          if (positive ? q[a] - (lo[a] + 1) <= kEdgeOn : (hi[a] - 1) - q[a] <= kEdgeOn) continue;
          // Rectangle vertices run (u0, v0), (u1, v0), (u1, v1), (u0, v1), counter-clockwise
          // seen from +a; `orient` turns the edge planes so that the rectangle's cone (the rays
          // through it) lies on their positive side whichever side the camera sees.
          const double orient = positive ? -1.0 : 1.0;
          const Eigen::Vector3d& N = R_C_W.col(a);

          for (std::uint32_t ri = r_begin; ri < r_end; ++ri) {
            const Rect& r = rects_[ri];
            const double plane_offset = r.plane - q[a];  // index units, along +e_a
            if (positive ? -plane_offset <= kEdgeOn : plane_offset <= kEdgeOn) continue;
            const Eigen::Vector3d P_plane = E[a] * plane_offset;
            const Eigen::Vector3d U0 = E[ua] * (r.u0 - q[ua]), U1 = E[ua] * (r.u1 - q[ua]);
            const Eigen::Vector3d V0 = E[va] * (r.v0 - q[va]), V1 = E[va] * (r.v1 - q[va]);
            const std::array<Eigen::Vector3d, 4> P = {P_plane + U0 + V0, P_plane + U1 + V0, P_plane + U1 + V1,
                                                      P_plane + U0 + V1};
            double z_min = P[0].z(), z_max = P[0].z();
            for (int i = 1; i < 4; ++i) {
              z_min = std::min(z_min, P[i].z());
              z_max = std::max(z_max, P[i].z());
            }
            if (z_max <= 0.0 || z_min > max_depth) continue;

            // Pixel rows and columns that can hit the rectangle.
            double row0 = 0, row1 = H - 1, col0 = 0, col1 = W - 1;
            if (z_min > 1e-9) {
              double u_min = 1e300, u_max = -1e300, v_min = 1e300, v_max = -1e300;
              for (const auto& p : P) {
                const double u = K.fx * p.x() / p.z() + K.cx, v = K.fy * p.y() / p.z() + K.cy;
                u_min = std::min(u_min, u);
                u_max = std::max(u_max, u);
                v_min = std::min(v_min, v);
                v_max = std::max(v_max, v);
              }
              col0 = std::max(col0, std::ceil(u_min - 1e-3));
              col1 = std::min(col1, std::floor(u_max + 1e-3));
              row0 = std::max(row0, std::ceil(v_min - 1e-3));
              row1 = std::min(row1, std::floor(v_max + 1e-3));
              if (col0 > col1 || row0 > row1) continue;
            }

            // Edge functions: pixel ray (u, v) passes inside edge i when A u + B v + C >= 0, with
            // (A, B, C) the normalised plane through the camera and the edge, written in pixels.
            std::array<double, 4> A, B, C;
            for (int i = 0; i < 4; ++i) {
              const Eigen::Vector3d m = (orient * P[i].cross(P[(i + 1) % 4])).normalized();
              A[i] = m.x() / K.fx;
              B[i] = m.y() / K.fy;
              C[i] = m.z() - A[i] * K.cx - B[i] * K.cy + kEdgeTol;
            }
            // Inverse depth of the face plane, affine in (u, v): n . ray / (n . point on plane).
            const double c = res * plane_offset;
            const double pa = N.x() / (K.fx * c), pb = N.y() / (K.fy * c);
            const double pd = N.z() / c - pa * K.cx - pb * K.cy;
            const auto fa = static_cast<float>(pa);

            for (int v = static_cast<int>(row0); v <= static_cast<int>(row1); ++v) {
              double lo_u = col0, hi_u = col1;
              for (int i = 0; i < 4; ++i) {
                const double k = B[i] * v + C[i];
                if (A[i] > 0.0)
                  lo_u = std::max(lo_u, -k / A[i]);
                else if (A[i] < 0.0)
                  hi_u = std::min(hi_u, -k / A[i]);
                else if (k < 0.0)
                  hi_u = -1.0;
              }
              if (!(lo_u <= hi_u)) continue;
              const int u_begin = static_cast<int>(std::ceil(lo_u)),
                        u_end = static_cast<int>(std::floor(hi_u));
              float* row = depth.ptr<float>(v);
              const auto base = static_cast<float>(pb * v + pd);
              for (int u = u_begin; u <= u_end; ++u) {
                const float w = base + fa * static_cast<float>(u);
                row[u] = w > row[u] ? w : row[u];
              }
            }
          }
        }
      }

  // The buffer holds the largest inverse depth per pixel (0: nothing hit); convert and apply the range
  // as REP 117 says: +inf no return within max_range, -inf a surface nearer than min_range.
  const float w_far = static_cast<float>(1.0 / config_.max_range);
  const float w_near = config_.min_range > 0.0 ? static_cast<float>(1.0 / config_.min_range)
                                               : std::numeric_limits<float>::infinity();
  constexpr float kInf = std::numeric_limits<float>::infinity();
  for (int v = 0; v < H; ++v) {
    float* row = depth.ptr<float>(v);
    for (int u = 0; u < W; ++u) {
      const float w = row[u];
      row[u] = w < w_far ? kInf : (w > w_near ? -kInf : 1.0f / w);
    }
  }
}

void toMillimetres(cv::Mat& metres, cv::Mat& mm) {
  for (int v = 0; v < metres.rows; ++v) {  // REP 117's +-inf and NaN have no millimetres
    float* row = metres.ptr<float>(v);
    for (int u = 0; u < metres.cols; ++u)
      if (!isReturn(row[u])) row[u] = 0.0f;
  }
  metres.convertTo(mm, CV_16UC1, 1000.0);
}

void DepthRenderer::addNoise(cv::Mat& depth, std::mt19937_64& rng) const {
  const double sigma_per_m = config_.noise_stddev_per_m, dropout = config_.dropout_probability;
  if (depth.type() != CV_32FC1 || (sigma_per_m == 0.0 && dropout == 0.0)) return;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> gaussian(0.0, 1.0);
  constexpr float kInf = std::numeric_limits<float>::infinity();
  for (int v = 0; v < depth.rows; ++v) {
    float* row = depth.ptr<float>(v);
    for (int u = 0; u < depth.cols; ++u) {
      if (!isReturn(row[u])) continue;
      if (dropout > 0.0 && uniform(rng) < dropout) {
        row[u] = std::numeric_limits<float>::quiet_NaN();
        continue;
      }
      if (sigma_per_m > 0.0) {
        const double d = row[u] * (1.0 + sigma_per_m * gaussian(rng));
        row[u] = d < config_.min_range ? -kInf : (d > config_.max_range ? kInf : static_cast<float>(d));
      }
    }
  }
}

}  // namespace go_feap::sim
