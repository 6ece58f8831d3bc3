#include "go_feap/planning/viewpoints.h"

#include <algorithm>
#include <cmath>
#include <string>

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
  if (!(positiveFinite(angular_step) && angular_step <= 2.0 * kPi))
    return err("angular_step", "must be in (0, 2 pi]");
  if (height_offsets.empty()) return err("height_offsets", "must not be empty");
  for (double h : height_offsets)
    if (!std::isfinite(h)) return err("height_offsets", "must all be finite");
  if (!(clearance >= 0.0 && std::isfinite(clearance))) return err("clearance", "must be finite and >= 0");
  if (!positiveFinite(sensor_range)) return err("sensor_range", "must be > 0");
  if (!(positiveFinite(hfov) && hfov < kPi)) return err("hfov", "must be in (0, pi)");
  if (!(positiveFinite(vfov) && vfov < kPi)) return err("vfov", "must be in (0, pi)");
  if (min_visible < 0) return err("min_visible", "must be >= 0");
  if (yaw_samples < 1) return err("yaw_samples", "must be >= 1");
  if (max_evaluated_cells < 0) return err("max_evaluated_cells", "must be >= 0 (0 = all cells)");
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

bool inView(const Vec3& position, double yaw, const Vec3& cell_centre, const ViewpointConfig& config) {
  const Vec3 d = cell_centre - position;
  if (d.squaredNorm() > config.sensor_range * config.sensor_range) return false;
  const double c = std::cos(yaw), s = std::sin(yaw);
  const double forward = c * d.x() + s * d.y();
  if (forward <= 0.0) return false;
  const double lateral = -s * d.x() + c * d.y();
  return std::abs(lateral) <= forward * std::tan(0.5 * config.hfov) &&
         std::abs(d.z()) <= forward * std::tan(0.5 * config.vfov);
}

bool lineOfSight(const Vec3& position, const Vec3& cell_centre, const map::OccupancyMap& map) {
  const Vec3 d = cell_centre - position;
  const double len = d.norm(), res = map.geometry().resolution();
  const Vec3 end = len > res ? Vec3(cell_centre - d * (res / len)) : position;
  return map.isLineFree(position, end, false);
}

int countVisible(const Vec3& position, double yaw, const std::vector<Index3>& cells,
                 const map::OccupancyMap& map, const ViewpointConfig& config) {
  int n = 0;
  for (const Index3& idx : cells) {
    const Vec3 c = map.geometry().indexToCoord(idx);
    // The view test is cheap, the ray is not: test it first.
    if (inView(position, yaw, c, config) && lineOfSight(position, c, map)) ++n;
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
  std::vector<Vec3> seen;  // centres within range and line of sight of the current position
  seen.reserve(centres.size());
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
        // Range and line of sight do not depend on the yaw: cast each ray once per position.
        seen.clear();
        for (const Vec3& c : centres)
          if ((c - p).squaredNorm() <= range2 && lineOfSight(p, c, map)) seen.push_back(c);
        if (std::lround(seen.size() * scale) < config.min_visible) continue;
        frontier::Viewpoint best;
        best.position = p;
        best.visible_cells = -1;
        for (double yaw : candidateYaws(p, frontier.average, config.yaw_samples)) {
          const int n = static_cast<int>(std::lround(
              scale * std::count_if(seen.begin(), seen.end(), [&](const Vec3& c) { return inView(p, yaw, c, config); })));
          if (n > best.visible_cells) {
            best.yaw = yaw;
            best.visible_cells = n;
          }
        }
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
