#include "go_feap/planning/viewpoints.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <tuple>

namespace go_feap::planning {

using common::Index3;
using common::Status;
using common::Vec3;

namespace {

constexpr double kPi = 3.14159265358979323846;

bool positiveFinite(double v) { return v > 0.0 && std::isfinite(v); }

}  // namespace

Status ViewpointConfig::validate() const {
  auto err = [](const std::string& key, const char* why) {
    return Status::Error("viewpoints: " + key + " " + why);
  };
  if (ring_radii.empty()) return err("ring_radii", "must not be empty");
  for (double r : ring_radii)
    if (!positiveFinite(r)) return err("ring_radii", "must all be > 0");
  // A floor as well: at 1e-6 rad each ring held 6.3 million positions and the sampler never came back.
  if (!(angular_step >= kPi / 180.0 && angular_step <= 2.0 * kPi))
    return err("angular_step", "must be in [pi / 180, 2 pi] (1 to 360 degrees)");
  if (height_offsets.empty()) return err("height_offsets", "must not be empty");
  for (double h : height_offsets)
    if (!std::isfinite(h)) return err("height_offsets", "must all be finite");
  if (!(clearance >= 0.0 && std::isfinite(clearance))) return err("clearance", "must be finite and >= 0");
  if (!positiveFinite(sensor_range)) return err("sensor_range", "must be > 0");
  if (!(positiveFinite(hfov) && hfov < kPi)) return err("hfov", "must be in (0, pi)");
  if (!(positiveFinite(vfov) && vfov < kPi)) return err("vfov", "must be in (0, pi)");
  if (min_visible < 0) return err("min_visible", "must be >= 0");
  if (yaw_samples < 1 || yaw_samples > 360) return err("yaw_samples", "must be in [1, 360]");
  if (max_evaluated_cells < 0) return err("max_evaluated_cells", "must be >= 0 (0 = all cells)");
  return Status::Ok();
}

Status ViewpointConfig::validate(const map::EsdfConfig& esdf) const {
  if (Status s = validate(); !s) return s;
  if (clearance > esdf.max_distance)
    return Status::Error("viewpoints: clearance must be <= the ESDF's max_distance (" +
                         std::to_string(esdf.max_distance) + " m, where distances are truncated: no viewpoint " +
                         "would pass), got " + std::to_string(clearance));
  return Status::Ok();
}

Status ViewpointConfig::fitsMapper(const map::OccupancyConfig& occupancy) const {
  if (!(sensor_range <= occupancy.max_range))
    return Status::Error("viewpoints: sensor_range (" + std::to_string(sensor_range) +
                         " m) must not exceed occupancy: max_range (" + std::to_string(occupancy.max_range) +
                         " m): viewpoints would be scored on cells the map does not take from them");
  return Status::Ok();
}

Status ViewpointConfig::fitsCamera(const map::DepthIntrinsics& K) const {
  const double camera_hfov = 2.0 * std::atan(std::min(K.cx + 0.5, K.width - 0.5 - K.cx) / K.fx);
  const double camera_vfov = 2.0 * std::atan(std::min(K.cy + 0.5, K.height - 0.5 - K.cy) / K.fy);
  for (const auto& [key, model, camera] : {std::make_tuple("hfov", hfov, camera_hfov),
                                           std::make_tuple("vfov", vfov, camera_vfov)})
    if (!(model <= camera + 1e-3))
      return Status::Error(std::string("viewpoints: ") + key + " (" + std::to_string(model) +
                           " rad) must not exceed the depth camera's (" + std::to_string(camera) +
                           " rad): viewpoints would be scored on cells the camera does not see");
  return Status::Ok();
}

double wrapAngle(double a) {
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  return a <= -kPi ? a + 2.0 * kPi : a;
}

std::vector<double> candidateYaws(const Vec3& position, const Vec3& target, int yaw_samples) {
  const Vec3 d = target - position;
  const double first = (d.x() == 0.0 && d.y() == 0.0) ? 0.0 : std::atan2(d.y(), d.x());
  std::vector<double> yaws;
  yaws.reserve(static_cast<std::size_t>(std::max(0, yaw_samples)));
  for (int k = 0; k < yaw_samples; ++k) yaws.push_back(wrapAngle(first + 2.0 * kPi * k / yaw_samples));
  return yaws;
}

namespace {

// inView() for one camera pose, with its trigonometry done once instead of once per cell.
class Frustum {
 public:
  Frustum(const Vec3& position, double yaw, const ViewpointConfig& config)
      : position_(position),
        cos_(std::cos(yaw)),
        sin_(std::sin(yaw)),
        tan_h_(std::tan(0.5 * config.hfov)),
        tan_v_(std::tan(0.5 * config.vfov)),
        range2_(config.sensor_range * config.sensor_range) {}

  bool contains(const Vec3& cell_centre) const {
    const Vec3 d = cell_centre - position_;
    if (d.squaredNorm() > range2_) return false;
    const double forward = cos_ * d.x() + sin_ * d.y();
    if (forward <= 0.0) return false;
    const double lateral = -sin_ * d.x() + cos_ * d.y();
    return std::abs(lateral) <= forward * tan_h_ && std::abs(d.z()) <= forward * tan_v_;
  }

 private:
  Vec3 position_;
  double cos_, sin_, tan_h_, tan_v_, range2_;
};

}  // namespace

bool inView(const Vec3& position, double yaw, const Vec3& cell_centre, const ViewpointConfig& config) {
  return Frustum(position, yaw, config).contains(cell_centre);
}

bool lineOfSight(const Vec3& position, const Vec3& cell_centre, const map::OccupancyMap& map) {
  const Vec3 d = cell_centre - position;
  const double len = d.norm(), res = map.geometry().resolution();
  const Vec3 end = len > res ? Vec3(cell_centre - d * (res / len)) : position;
  return map.isLineFree(position, end, false);
}

int countVisible(const Vec3& position, double yaw, const std::vector<Index3>& cells,
                 const map::OccupancyMap& map, const ViewpointConfig& config, int stop_at) {
  const Frustum frustum(position, yaw, config);
  int n = 0;
  for (const Index3& idx : cells) {
    const Vec3 c = map.geometry().indexToCoord(idx);
    // The view test is cheap, the ray is not: test it first.
    if (frustum.contains(c) && lineOfSight(position, c, map) && ++n == stop_at) break;
  }
  return n;
}

namespace {

// The voxels `clearance` away from p along each axis are known (free or occupied).
bool surroundingsKnown(const Vec3& p, const map::OccupancyMap& map, double clearance) {
  const double step = std::max(clearance, map.geometry().resolution());
  for (int a = 0; a < 3; ++a)
    for (double s : {-step, step}) {
      Vec3 q = p;
      q[a] += s;
      if (map.state(q) == map::VoxelState::kUnknown) return false;
    }
  return true;
}

}  // namespace

std::vector<frontier::Viewpoint> sampleViewpoints(const frontier::Frontier& frontier,
                                                  const map::OccupancyMap& map, const map::Esdf& esdf,
                                                  double z_min, double z_max, const ViewpointConfig& config) {
  std::vector<frontier::Viewpoint> out;
  if (!config.validate() || !(z_min <= z_max) || frontier.cells.empty()) return out;

  // The vehicle stays inside the exploration box, clear of its faces (the floor and the top are often
  // unknown right under or over it, so the ESDF alone cannot keep it off them).
  const common::Aabb& box = map.box();
  const Vec3 lo = box.min + Vec3::Constant(config.clearance), hi = box.max - Vec3::Constant(config.clearance);
  z_min = std::max(z_min, lo.z());
  z_max = std::min(z_max, hi.z());
  if (!(z_min <= z_max)) return out;
  std::vector<double> heights;
  for (double off : config.height_offsets) {
    const double z = std::clamp(frontier.average.z() + off, z_min, z_max);
    if (std::none_of(heights.begin(), heights.end(), [&](double h) { return std::abs(h - z) < 1e-9; }))
      heights.push_back(z);
  }
  const int n_angles = std::max(1, static_cast<int>(std::lround(2.0 * kPi / config.angular_step)));

  std::vector<Vec3> centres;
  const std::size_t n_cells = frontier.cells.size();
  const std::size_t stride =
      config.max_evaluated_cells > 0
          ? (n_cells + config.max_evaluated_cells - 1) / static_cast<std::size_t>(config.max_evaluated_cells)
          : 1;
  for (std::size_t i = 0; i < n_cells; i += stride) centres.push_back(map.geometry().indexToCoord(frontier.cells[i]));
  const double scale = static_cast<double>(n_cells) / static_cast<double>(centres.size());
  std::vector<Vec3> near;             // centres within range of the current position
  std::vector<std::int8_t> sight;     // per near centre: -1 not cast yet, 0 blocked, 1 in line of sight
  std::vector<std::uint8_t> in_view;  // yaw-major: near centre i is in the frustum of yaw k
  std::vector<int> bound, order;      // per yaw: centres in its frustum (occlusion ignored), and yaws by it
  const double range2 = config.sensor_range * config.sensor_range;

  for (double r : config.ring_radii) {
    for (int a = 0; a < n_angles; ++a) {
      const double theta = 2.0 * kPi * a / n_angles;
      for (double z : heights) {
        const Vec3 p(frontier.average.x() + r * std::cos(theta), frontier.average.y() + r * std::sin(theta),
                     z);
        if ((p.array() < lo.array()).any() || (p.array() > hi.array()).any()) continue;
        if (map.state(p) != map::VoxelState::kFree || !(esdf.distance(p) >= config.clearance)) continue;
        if (config.known_clearance && !surroundingsKnown(p, map, config.clearance)) continue;
        near.clear();
        for (const Vec3& c : centres)
          if ((c - p).squaredNorm() <= range2) near.push_back(c);
        if (std::lround(near.size() * scale) < config.min_visible) continue;
        // The best yaw sees the most centres in line of sight. The count ignoring occlusion bounds each
        // yaw's count from above, so yaws are tried in decreasing bound and the rays cast lazily, once
        // per centre: a yaw whose bound cannot beat the best so far (or tie it from an earlier place in
        // the yaw order, which wins ties) is skipped without casting its rays.
        const std::vector<double> yaws = candidateYaws(p, frontier.average, config.yaw_samples);
        const std::size_t n = near.size();
        in_view.assign(yaws.size() * n, 0);
        bound.assign(yaws.size(), 0);
        for (std::size_t k = 0; k < yaws.size(); ++k) {
          const Frustum frustum(p, yaws[k], config);
          for (std::size_t i = 0; i < n; ++i)
            if (frustum.contains(near[i])) in_view[k * n + i] = 1, ++bound[k];
        }
        order.resize(yaws.size());
        for (std::size_t k = 0; k < yaws.size(); ++k) order[k] = static_cast<int>(k);
        std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return bound[x] > bound[y]; });
        sight.assign(n, -1);
        int best_count = -1, best_k = -1;
        for (int k : order) {
          if (bound[k] < best_count) break;                    // nor can any later yaw (sorted by bound)
          if (bound[k] == best_count && k > best_k) continue;  // could only tie, and would lose the tie
          int count = 0;
          for (std::size_t i = 0; i < n; ++i) {
            if (!in_view[k * n + i]) continue;
            if (sight[i] < 0) sight[i] = lineOfSight(p, near[i], map) ? 1 : 0;
            count += sight[i];
          }
          if (count > best_count || (count == best_count && k < best_k)) best_count = count, best_k = k;
        }
        frontier::Viewpoint best;
        best.position = p;
        best.yaw = yaws[static_cast<std::size_t>(best_k)];
        best.visible_cells = static_cast<int>(std::lround(scale * best_count));
        if (best.visible_cells >= config.min_visible) out.push_back(best);
      }
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const frontier::Viewpoint& a, const frontier::Viewpoint& b) {
    return a.visible_cells > b.visible_cells;
  });
  return out;
}

}  // namespace go_feap::planning
