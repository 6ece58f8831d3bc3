// Axis-aligned boxes and dense voxel grids in the world frame (metres).
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

namespace go_feap::common {

using Vec3 = Eigen::Vector3d;
using Index3 = Eigen::Vector3i;

/// Axis-aligned box [min, max] in metres.
struct Aabb {
  Vec3 min = Vec3::Zero();
  Vec3 max = Vec3::Zero();

  bool valid() const { return (max.array() > min.array()).all(); }
  Vec3 size() const { return max - min; }
  Vec3 center() const { return 0.5 * (min + max); }
  bool contains(const Vec3& p) const {
    return (p.array() >= min.array()).all() && (p.array() <= max.array()).all();
  }
  Aabb expanded(double margin) const {
    return {min - Vec3::Constant(margin), max + Vec3::Constant(margin)};
  }
  /// Smallest box holding this and `p`.
  void extend(const Vec3& p) {
    min = min.cwiseMin(p);
    max = max.cwiseMax(p);
  }
};

/// Geometry of a regular voxel grid: voxel (i, j, k) covers
/// [origin + (i, j, k) * resolution, origin + (i + 1, j + 1, k + 1) * resolution).
class GridGeometry {
 public:
  GridGeometry() = default;
  GridGeometry(const Vec3& origin, double resolution, const Index3& dims)
      : origin_(origin), resolution_(resolution), inv_resolution_(1.0 / resolution), dims_(dims) {}

  /// Smallest grid with voxels of `resolution` covering `box`; the origin is snapped to
  /// a multiple of the resolution so that grids built from different boxes align.
  static GridGeometry covering(const Aabb& box, double resolution) {
    const double eps = 1e-6 * resolution;
    Vec3 lo, hi;
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::floor(box.min[a] / resolution + eps) * resolution;
      hi[a] = std::ceil(box.max[a] / resolution - eps) * resolution;
    }
    Index3 dims;
    for (int a = 0; a < 3; ++a) dims[a] = std::max(1, static_cast<int>(std::lround((hi[a] - lo[a]) / resolution)));
    return GridGeometry(lo, resolution, dims);
  }

  /// At least covering(box, resolution).size(), at most one voxel per axis more, counted as a double (no
  /// int per axis nor their product can overflow before a size check).
  static double coveringCount(const Aabb& box, double resolution) {
    double n = 1.0;
    for (int a = 0; a < 3; ++a) n *= std::max(1.0, std::ceil((box.max[a] - box.min[a]) / resolution) + 1.0);
    return n;
  }

  const Vec3& origin() const { return origin_; }
  double resolution() const { return resolution_; }
  const Index3& dims() const { return dims_; }
  std::size_t size() const {
    return static_cast<std::size_t>(dims_.x()) * dims_.y() * dims_.z();
  }
  Aabb bounds() const { return {origin_, origin_ + dims_.cast<double>() * resolution_}; }

  /// Index of the voxel containing `p` (may be outside the grid).
  Index3 coordToIndex(const Vec3& p) const {
    return ((p - origin_) * inv_resolution_).array().floor().cast<int>();
  }
  /// coordToIndex() clamped to [-1, dims] on each axis before the cast to int: any point, however far
  /// outside the grid (1e30 is finite), gives an index, outside the grid when the point is (NaN gives -1).
  /// For loaders and clipping; hot paths use coordToIndex() on points known to be near the grid.
  Index3 clampedIndex(const Vec3& p) const {
    Index3 idx;
    for (int a = 0; a < 3; ++a) {
      const double f = std::floor((p[a] - origin_[a]) * inv_resolution_);
      idx[a] = f >= -1.0 ? static_cast<int>(std::min(f, static_cast<double>(dims_[a]))) : -1;
    }
    return idx;
  }
  /// Centre of voxel `idx`.
  Vec3 indexToCoord(const Index3& idx) const {
    return origin_ + (idx.cast<double>().array() + 0.5).matrix() * resolution_;
  }
  bool inside(const Index3& idx) const {
    return (idx.array() >= 0).all() && (idx.array() < dims_.array()).all();
  }
  /// Index range [lo, hi) of the grid voxels whose centres lie inside `box` (empty when
  /// hi <= lo on some axis).
  void centreRange(const Aabb& box, Index3& lo, Index3& hi) const {
    for (int a = 0; a < 3; ++a) {
      const double fl = (box.min[a] - origin_[a]) / resolution_ - 0.5;
      const double fh = (box.max[a] - origin_[a]) / resolution_ - 0.5;
      // Clamped as doubles: a box far outside the grid must not overflow the cast to int.
      lo[a] = static_cast<int>(std::clamp(std::ceil(fl - 1e-9), 0.0, static_cast<double>(dims_[a])));
      hi[a] = static_cast<int>(std::clamp(std::floor(fh + 1e-9) + 1.0, 0.0, static_cast<double>(dims_[a])));
    }
  }
  std::size_t linear(const Index3& idx) const {
    return (static_cast<std::size_t>(idx.z()) * dims_.y() + idx.y()) * dims_.x() + idx.x();
  }
  Index3 unlinear(std::size_t l) const {
    const std::size_t nx = dims_.x(), ny = dims_.y();
    return Index3(static_cast<int>(l % nx), static_cast<int>((l / nx) % ny),
                  static_cast<int>(l / (nx * ny)));
  }

 private:
  Vec3 origin_ = Vec3::Zero();
  double resolution_ = 0.1;
  double inv_resolution_ = 10.0;  // multiplying is cheaper than dividing on hot paths
  Index3 dims_ = Index3::Zero();
};

/// Dense grid of values of type T over a GridGeometry.
template <typename T>
class DenseGrid {
 public:
  DenseGrid() = default;
  explicit DenseGrid(const GridGeometry& geometry, T fill = T())
      : geometry_(geometry), data_(geometry.size(), fill) {}

  const GridGeometry& geometry() const { return geometry_; }
  T& at(const Index3& idx) { return data_[geometry_.linear(idx)]; }
  const T& at(const Index3& idx) const { return data_[geometry_.linear(idx)]; }
  T& operator[](std::size_t l) { return data_[l]; }
  const T& operator[](std::size_t l) const { return data_[l]; }
  std::size_t size() const { return data_.size(); }
  const std::vector<T>& data() const { return data_; }
  std::vector<T>& data() { return data_; }

 private:
  GridGeometry geometry_;
  std::vector<T> data_;
};

/// Offsets of the six face neighbours.
inline const std::array<Index3, 6>& faceNeighbours() {
  static const std::array<Index3, 6> kOffsets = {Index3(1, 0, 0),  Index3(-1, 0, 0),
                                                 Index3(0, 1, 0),  Index3(0, -1, 0),
                                                 Index3(0, 0, 1),  Index3(0, 0, -1)};
  return kOffsets;
}

}  // namespace go_feap::common
