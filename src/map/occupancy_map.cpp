#include "go_feap/map/occupancy_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "go_feap/common/bits.h"
#include "go_feap/common/raycast.h"

namespace go_feap::map {

namespace {

double logit(double p) { return std::log(p / (1.0 - p)); }

using common::clearBit;
using common::setBit;
using common::testBit;

// Two mark bits per voxel in one word array: voxel l's marks are bits 2(l mod 32) and
// 2(l mod 32) + 1 of word l / 32.
constexpr std::uint64_t kHitMark = 1, kFreeMark = 2;
std::uint64_t& markWord(std::vector<std::uint64_t>& marks, std::size_t l) { return marks[l >> 5]; }
unsigned markShift(std::size_t l) { return 2 * static_cast<unsigned>(l & 31); }
std::uint64_t marksOf(const std::vector<std::uint64_t>& marks, std::size_t l) {
  return (marks[l >> 5] >> markShift(l)) & 3u;
}

// Clips the segment [a, b] to the box (slab method). False when it misses the box.
bool clipSegment(const Aabb& box, Vec3& a, Vec3& b) {
  double t0 = 0.0, t1 = 1.0;
  const Vec3 d = b - a;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(d[i]) < 1e-12) {
      if (a[i] < box.min[i] || a[i] > box.max[i]) return false;
      continue;
    }
    double ta = (box.min[i] - a[i]) / d[i], tb = (box.max[i] - a[i]) / d[i];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  const Vec3 a0 = a;
  a = a0 + t0 * d;
  b = a0 + t1 * d;
  return true;
}

}  // namespace

common::Status OccupancyConfig::validate() const {
  auto bad = [](const std::string& key, const std::string& why) {
    return common::Status::Error("occupancy: " + key + " " + why);
  };
  if (!(resolution > 0.0 && std::isfinite(resolution))) return bad("resolution", "must be finite and > 0");
  if (!(margin >= 0.0 && std::isfinite(margin))) return bad("margin", "must be finite and >= 0");
  if (!(p_min > 0.0 && p_min < 0.5)) return bad("p_min", "must be in (0, 0.5)");
  if (!(p_max > 0.5 && p_max < 1.0)) return bad("p_max", "must be in (0.5, 1)");
  if (!(p_hit > 0.5 && p_hit < 1.0)) return bad("p_hit", "must be in (0.5, 1)");
  if (!(p_miss > 0.0 && p_miss < 0.5)) return bad("p_miss", "must be in (0, 0.5)");
  if (!(p_occupied > 0.5 && p_occupied < p_max)) return bad("p_occupied", "must be in (0.5, p_max)");
  if (!(min_range >= 0.0)) return bad("min_range", "must be >= 0");
  if (!(max_range > min_range && std::isfinite(max_range))) return bad("max_range", "must be finite and > min_range");
  // At most the largest image side the cameras take: 2^31 - 1 overflowed the pixel loops' int steps.
  if (skip_pixel < 1 || skip_pixel > 8192) return bad("skip_pixel", "must be in [1, 8192] pixels");
  if (!(max_plausible_depth > max_range && std::isfinite(max_plausible_depth)))
    return bad("max_plausible_depth", "must be finite and > max_range");
  // One byte per voxel: log-odds * 50 must fit in [-127, 127].
  if (logit(p_max) * OccupancyMap::kScaleLimit() > 127.0 || logit(p_min) * OccupancyMap::kScaleLimit() < -127.0)
    return bad("p_min/p_max", "must lie within [0.08, 0.92] (one byte of log-odds per voxel)");
  // The byte values the map works with (as the constructor rounds them): a hit step that rounds to 0
  // (p_hit 0.502) would never mark a return occupied, and a clamp p_max that rounds to the threshold
  // p_occupied (0.8814 and 0.881) would never let a voxel pass it: both made maps without obstacles.
  const double scale = OccupancyMap::kScaleLimit();
  if (std::lround(logit(p_hit) * scale) < 1)
    return bad("p_hit", "must be at least 0.503: its log-odds step rounds to 0 at one byte per voxel");
  if (std::lround(logit(p_miss) * scale) > -1)
    return bad("p_miss", "must be at most 0.497: its log-odds step rounds to 0 at one byte per voxel");
  // A step past one byte wrapped round in the constructor's cast: p_hit 0.95 became a step of -109, and
  // every return made its voxel freer (a map without obstacles).
  if (std::lround(logit(p_hit) * scale) > 127)
    return bad("p_hit", "must be at most 0.927: its log-odds step must fit one byte per voxel");
  if (std::lround(logit(p_miss) * scale) < -127)
    return bad("p_miss", "must be at least 0.073: its log-odds step must fit one byte per voxel");
  if (std::lround(logit(p_max) * scale) <= std::floor(logit(p_occupied) * scale))
    return bad("p_occupied", "must lie below p_max by more than one byte step of log-odds (0.02): no voxel could pass it");
  return common::Status::Ok();
}

OccupancyMap::OccupancyMap(const OccupancyConfig& config, const Aabb& box)
    : config_(config),
      box_(box),
      geo_(common::GridGeometry::covering(box.expanded(config.margin), config.resolution)),
      logodds_(geo_.size(), kUnknown),
      hit_(static_cast<std::int8_t>(std::lround(logit(config.p_hit) * kScale))),
      miss_(static_cast<std::int8_t>(std::lround(logit(config.p_miss) * kScale))),
      min_(static_cast<std::int8_t>(std::lround(logit(config.p_min) * kScale))),
      max_(static_cast<std::int8_t>(std::lround(logit(config.p_max) * kScale))),
      occupied_(static_cast<std::int8_t>(std::floor(logit(config.p_occupied) * kScale))),
      marks_((geo_.size() + 31) / 32, 0),
      end_bits_((geo_.size() + 63) / 64, 0) {}

double OccupancyMap::probability(const Index3& idx) const {
  if (!geo_.inside(idx)) return 0.5;
  const std::int8_t v = logodds_[geo_.linear(idx)];
  if (v == kUnknown) return 0.5;
  return 1.0 / (1.0 + std::exp(-v / kScale));
}

common::Status DepthIntrinsics::validate() const {
  if (width <= 0 || height <= 0)
    return common::Status::Error("camera intrinsics are invalid: the image is " + std::to_string(width) + "x" +
                                 std::to_string(height) + " pixels");
  if (!(fx > 0.0 && fy > 0.0 && std::isfinite(fx) && std::isfinite(fy) && std::isfinite(cx) && std::isfinite(cy)))
    return common::Status::Error("camera intrinsics are invalid (fx, fy must be finite and > 0, cx, cy finite)");
  // Every pixel's ray within 85 degrees of the optical axis (a view under 170 degrees across): a focal length
  // of 1e-310 pixels made rays of NaN, cast for seconds over the whole grid, and tiny ones clear space the
  // camera never saw.
  const double reach = std::tan(85.0 * M_PI / 180.0);
  const double across_x = std::max(std::abs(cx), std::abs(width - cx)) / fx;
  const double across_y = std::max(std::abs(cy), std::abs(height - cy)) / fy;
  if (!(across_x <= reach && across_y <= reach)) {
    std::ostringstream why;
    why << "camera intrinsics are invalid: fx " << fx << ", fy " << fy << ", cx " << cx << ", cy " << cy << " for "
        << width << "x" << height << " pixels give rays more than 85 degrees off the optical axis";
    return common::Status::Error(why.str());
  }
  return common::Status::Ok();
}

common::Status OccupancyMap::checkFrame(const cv::Mat& depth, const DepthIntrinsics& K) const {
  if (depth.empty()) return common::Status::Error("depth image is empty");
  if (depth.type() != CV_32FC1 && depth.type() != CV_16UC1)
    return common::Status::Error("depth image must be 32FC1 (metres) or 16UC1 (millimetres)");
  if (depth.cols != K.width || depth.rows != K.height)
    return common::Status::Error("depth image is " + std::to_string(depth.cols) + "x" + std::to_string(depth.rows) +
                                 " but camera_info says " + std::to_string(K.width) + "x" + std::to_string(K.height));
  if (depth.type() == CV_32FC1) {
    std::size_t measured = 0, beyond = 0;
    for (int v = 0; v < depth.rows; v += 8)
      for (int u = 0; u < depth.cols; u += 8) {
        const float d = depth.at<float>(v, u);
        if (!(d > 0.0f) || !std::isfinite(d)) continue;
        ++measured;
        beyond += d > config_.max_plausible_depth;
      }
    if (2 * beyond > measured) {
      std::ostringstream why;
      why << "depth image: " << beyond << " of " << measured << " sampled depths are beyond "
          << config_.max_plausible_depth << " m (occupancy/max_plausible_depth): millimetres in a 32FC1 image, "
          << "which holds metres (REP 118)?";
      return common::Status::Error(why.str());
    }
  }
  return K.validate();
}

common::Result<FrameChange> OccupancyMap::integrate(const cv::Mat& depth, const DepthIntrinsics& K,
                                                    const Eigen::Isometry3d& T_W_C) {
  if (auto st = checkFrame(depth, K); !st) return st;
  if (!T_W_C.matrix().allFinite()) return common::Result<FrameChange>::Error("camera pose is not finite");
  FrameChange change;
  const Aabb bounds = geo_.bounds();
  const Vec3 origin = T_W_C.translation();
  const Eigen::Matrix3d R = T_W_C.linear();
  const bool metric = depth.type() == CV_32FC1;
  const bool origin_inside = bounds.contains(origin);
  // Distinct end voxels with the first ray end point that reached each: casting towards
  // the measured point (not the voxel centre) keeps grazing rays out of the wall in front.
  std::vector<std::pair<std::size_t, Vec3>> ends;
  touched_.clear();
  // Marks voxel l; the first mark of a frame records it for step 3.
  auto mark = [&](std::size_t l, std::uint64_t bit) {
    std::uint64_t& word = markWord(marks_, l);
    const unsigned shift = markShift(l);
    if (((word >> shift) & 3u) == 0) touched_.push_back(l);
    word |= bit << shift;
  };

  // 1. Sampled pixels -> ray end voxels; returns mark their voxel as hit. The per-pixel
  // arithmetic is written out on scalars, in voxel units (the hot loop of a mapping update).
  const Vec3 du = R.col(0) / K.fx;
  const Vec3 g0 = geo_.origin();
  const double inv_res = 1.0 / geo_.resolution();
  const Index3 dims = geo_.dims();
  const Vec3 dims_v = dims.cast<double>();
  const Vec3 origin_v = (origin - g0) * inv_res, du_v = du * inv_res;
  // A return marks the voxel just behind the measured surface point, 2 % of a voxel further along the
  // ray: a point exactly on a voxel face (as a voxel world renders it) belongs to the surface's voxel. (A
  // push of 1 % of a voxel in depth missed 85 of the maze's 14,600 wall voxels at grazing angles, where the
  // rendered float depth is off by a millimetre or so.) In depth units it is 0.02 res / |ray|, with |ray| the
  // camera-frame length of the pixel's ray; computed once per intrinsics.
  const int step = config_.skip_pixel;
  const std::size_t per_row = static_cast<std::size_t>((depth.cols + step - 1) / step);
  if (behind_.empty() || behind_for_ != K || behind_.size() != per_row * static_cast<std::size_t>((depth.rows + step - 1) / step)) {
    behind_.clear();
    for (int v = 0; v < depth.rows; v += step)
      for (int u = 0; u < depth.cols; u += step)
        behind_.push_back(0.02 * geo_.resolution() / Vec3((u - K.cx) / K.fx, (v - K.cy) / K.fy, 1.0).norm());
    behind_for_ = K;
  }
  std::size_t last_end = std::numeric_limits<std::size_t>::max();
  bool last_hit = false;
  for (int v = 0; v < depth.rows; v += step) {
    const Vec3 row = R.col(1) * ((v - K.cy) / K.fy) + R.col(2);
    const Vec3 row_v = row * inv_res;
    const double* row_behind = behind_.data() + static_cast<std::size_t>(v / step) * per_row;  // once a row
    const float* row_m = metric ? depth.ptr<float>(v) : nullptr;
    const std::uint16_t* row_mm = metric ? nullptr : depth.ptr<std::uint16_t>(v);
    for (int u = 0, k = 0; u < depth.cols; u += step, ++k) {
      double d = metric ? static_cast<double>(row_m[u]) : 0.001 * row_mm[u];
      bool hit = true;
      // REP 117: +inf is no return within the range (free space to it), -inf a surface nearer than the
      // range begins, NaN no measurement. A surface too near is never cast free: the ray would pass
      // through it (a camera overshooting towards a wall cleared the wall in two frames).
      if (d > config_.max_range) {  // beyond the range, or +inf
        d = config_.max_range;
        hit = false;
      } else if (!(d >= config_.min_range && d > 0.0)) {
        ++change.pixels_invalid;
        const bool too_near = d == -std::numeric_limits<double>::infinity() || d > 0.0;
        if (too_near || !config_.invalid_as_free) continue;
        d = config_.max_range;  // 0 or NaN (or negative): no measurement
        hit = false;
      }
      ++change.pixels_used;
      // Ray direction with unit optical-axis component; the end point at depth t along it.
      const double t = hit ? d + row_behind[k] : d, s = u - K.cx;
      const double bx = origin_v.x() + (row_v.x() + du_v.x() * s) * t;
      const double by = origin_v.y() + (row_v.y() + du_v.y() * s) * t;
      const double bz = origin_v.z() + (row_v.z() + du_v.z() * s) * t;
      std::size_t l;
      Vec3 clipped;  // the end point in metres, where the map clipped the ray
      bool was_clipped = false;
      if (origin_inside && bx >= 0.0 && by >= 0.0 && bz >= 0.0 && bx < dims_v.x() && by < dims_v.y() &&
          bz < dims_v.z()) {
        // Inside the map the voxel coordinates are >= 0: truncation is the floor.
        l = (static_cast<std::size_t>(static_cast<int>(bz)) * dims.y() + static_cast<int>(by)) * dims.x() +
            static_cast<int>(bx);
      } else {
        Vec3 a = origin, b = origin + (row + du * s) * t;
        const Vec3 b_full = b;
        if (!clipSegment(bounds, a, b)) continue;
        if ((b - b_full).squaredNorm() > 1e-12) hit = false;  // the return lies outside the map
        l = geo_.linear(geo_.coordToIndex(b).cwiseMax(Index3::Zero()).cwiseMin(dims - Index3::Ones()));
        clipped = b;
        was_clipped = true;
      }
      // Neighbouring pixels mostly end in the same voxel: nothing new to record then.
      if (l == last_end && hit == last_hit) continue;
      last_end = l;
      last_hit = hit;
      if (hit) mark(l, kHitMark);
      if (!testBit(end_bits_, l)) {
        setBit(end_bits_, l);
        ends.emplace_back(l, was_clipped ? clipped : Vec3(origin + (row + du * s) * t));
      }
    }
  }

  // 2. One ray per distinct end voxel marks the voxels before it free.

  for (const auto& [e, point] : ends) {
    clearBit(end_bits_, e);
    const bool end_is_hit = marksOf(marks_, e) & kHitMark;
    Vec3 a = origin, b = point;
    if (!bounds.contains(a) && !clipSegment(bounds, a, b)) continue;  // camera outside the map
    ++change.rays;
    // Up to the end voxel, which is marked free unless a return marked it hit.
    const common::Walk walk = common::traverseInGrid(geo_, a, b, [&](std::size_t l) {
      if (l == e && end_is_hit) return false;
      mark(l, kFreeMark);
      return l != e;
    });
    if (walk != common::Walk::kLeavesGrid) continue;
    // A segment ending on the grid's far face: its last voxel lies outside.
    const Index3 end = geo_.unlinear(e);
    common::traverse(geo_, a, b, [&](const Index3& c) {
      if (c == end && end_is_hit) return false;
      if (!geo_.inside(c)) return true;
      mark(geo_.linear(c), kFreeMark);
      return c != end;
    });
  }

  // 3. Apply: a return wins over free space in the same frame.
  for (std::size_t l : touched_) {
    const std::int8_t old = logodds_[l];
    const VoxelState before = stateOf(old);
    int v = old == kUnknown ? occupied_ : old;
    v = marksOf(marks_, l) & kHitMark ? std::min<int>(max_, v + hit_) : std::max<int>(min_, v + miss_);
    logodds_[l] = static_cast<std::int8_t>(v);
    markWord(marks_, l) &= ~(std::uint64_t{3} << markShift(l));
    const VoxelState after = stateOf(logodds_[l]);
    if (after == before) continue;
    known_ += before == VoxelState::kUnknown;
    const Index3 idx = geo_.unlinear(l);
    if (!change.any_change) {
      change.changed_min = change.changed_max = idx;
      change.any_change = true;
    } else {
      change.changed_min = change.changed_min.cwiseMin(idx);
      change.changed_max = change.changed_max.cwiseMax(idx);
    }
    ++change.changed_voxels;
    change.changed.push_back(l);
    if (after == VoxelState::kOccupied) change.became_occupied.push_back(l);
    if (before == VoxelState::kOccupied) change.stopped_occupied.push_back(l);
  }
  return change;
}

void OccupancyMap::setState(const Index3& idx, VoxelState s) {
  if (!geo_.inside(idx)) return;
  std::int8_t& v = logodds_[geo_.linear(idx)];
  known_ -= v != kUnknown;
  v = s == VoxelState::kUnknown ? kUnknown : (s == VoxelState::kOccupied ? max_ : min_);
  known_ += v != kUnknown;
}

bool OccupancyMap::isLineFree(const Vec3& a, const Vec3& b, bool unknown_blocks) const {
  // A segment with an end voxel outside the grid is blocked there.
  return common::traverseInGrid(geo_, a, b, [&](std::size_t l) {
           const VoxelState s = stateAt(l);
           return !(s == VoxelState::kOccupied || (unknown_blocks && s == VoxelState::kUnknown));
         }) == common::Walk::kCompleted;
}

OccupancySnapshot OccupancyMap::snapshot() const {
  OccupancySnapshot s{geo_, std::vector<VoxelState>(logodds_.size())};
  for (std::size_t l = 0; l < logodds_.size(); ++l) s.states[l] = stateOf(logodds_[l]);
  return s;
}

std::size_t OccupancyMap::memoryBytes() const {
  return logodds_.capacity() + 8 * (marks_.capacity() + end_bits_.capacity()) +
         sizeof(std::size_t) * touched_.capacity() + sizeof(double) * behind_.capacity();
}

}  // namespace go_feap::map
