#include "go_feap/metrics/metrics.h"

#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "go_feap/common/bits.h"

namespace go_feap::metrics {

double obstacleDistance(const world::Scene& scene, const common::Vec3& p, double radius) {
  const common::GridGeometry& geo = scene.geometry();
  const double res = geo.resolution();
  // Clamped to the grid's rim: a position 2e8 m away (finite odometry, however wrong) overflowed the int
  // loop bound and crashed the metrics recorder.
  const common::Index3 lo = geo.clampedIndex(p - common::Vec3::Constant(radius));
  const common::Index3 hi = geo.clampedIndex(p + common::Vec3::Constant(radius));
  double best = radius;
  for (int z = lo.z(); z <= hi.z(); ++z)
    for (int y = lo.y(); y <= hi.y(); ++y)
      for (int x = lo.x(); x <= hi.x(); ++x) {
        const common::Index3 idx(x, y, z);
        if (!scene.isOccupied(idx)) continue;
        // Distance from p to the voxel's cube.
        const common::Vec3 cmin = geo.origin() + idx.cast<double>() * res;
        const common::Vec3 d = (cmin - p).cwiseMax(p - (cmin + common::Vec3::Constant(res))).cwiseMax(0.0);
        best = std::min(best, d.norm());
      }
  return best;
}

common::Status checkStartClearance(const world::Scene& scene, double collision_distance) {
  const common::Vec3& p = scene.start.position;
  const double clearance = obstacleDistance(scene, p, collision_distance);
  if (clearance >= collision_distance) return common::Status::Ok();
  std::ostringstream why;
  why << "scene '" << scene.name << "': the start (" << p.x() << ", " << p.y() << ", " << p.z() << ") lies "
      << clearance << " m from an obstacle, under metrics/collision_distance (" << collision_distance
      << " m): every run would begin with a collision (move the start into the open)";
  return common::Status::Error(why.str());
}

bool CollisionMonitor::update(const common::Vec3& p) {
  last_ = obstacleDistance(scene_, p, kHorizon);
  closest_ = std::min(closest_, last_);
  const bool entered = !inside_ && last_ < collision_distance_;
  collisions_ += entered;
  inside_ = inside_ ? last_ < release_distance_ : entered;
  return entered;
}

CoverageTracker::CoverageTracker(const world::Scene& scene, const common::GridGeometry& map_geometry)
    : observable_((map_geometry.size() + 63) / 64, 0) {
  const world::ObservableSet observable = world::computeObservableSet(scene);
  observable_total_ = observable.total();
  const auto& geo = observable.mask.geometry();
  for (std::size_t l = 0; l < observable.mask.size(); ++l) {
    if (!observable.mask[l]) continue;
    const common::Index3 idx = map_geometry.coordToIndex(geo.indexToCoord(geo.unlinear(l)));
    if (!map_geometry.inside(idx)) continue;
    const std::size_t m = map_geometry.linear(idx);
    if (common::testBit(observable_, m))
      ++extra_weight_[m];
    else
      common::setBit(observable_, m);
  }
  pending_ = observable_;
}

std::size_t CoverageTracker::weight(std::size_t l) const {
  if (extra_weight_.empty()) return 1;
  const auto it = extra_weight_.find(l);
  return it == extra_weight_.end() ? 1 : 1 + it->second;
}

template <typename Visit>
void CoverageTracker::forEachKnownObservable(const map::OccupancyMap& map, Visit&& visit) const {
  for (std::size_t w = 0; w < observable_.size(); ++w)
    for (std::uint64_t bits = observable_[w]; bits; bits &= bits - 1) {
      const std::size_t l = (w << 6) + static_cast<std::size_t>(__builtin_ctzll(bits));
      if (map.stateAt(l) != map::VoxelState::kUnknown) visit(l);
    }
}

double CoverageTracker::coverage(const map::OccupancyMap& map) const {
  if (observable_total_ == 0) return 0.0;
  std::size_t known = 0;
  forEachKnownObservable(map, [&](std::size_t l) { known += weight(l); });
  return static_cast<double>(known) / static_cast<double>(observable_total_);
}

void CoverageTracker::reset(const map::OccupancyMap& map) {
  pending_ = observable_;
  known_ = 0;
  forEachKnownObservable(map, [&](std::size_t l) {
    common::clearBit(pending_, l);
    known_ += weight(l);
  });
}

void CoverageTracker::update(const map::OccupancyMap& map, const std::vector<std::size_t>& changed) {
  for (std::size_t l : changed) {
    if ((l >> 6) >= pending_.size() || !common::testBit(pending_, l) || map.stateAt(l) == map::VoxelState::kUnknown) continue;
    common::clearBit(pending_, l);
    known_ += weight(l);
  }
}

double CoverageTracker::current() const {
  return observable_total_ == 0 ? 0.0 : static_cast<double>(known_) / static_cast<double>(observable_total_);
}

namespace {

nlohmann::json toJson(const Summary& s) {
  nlohmann::json j;
  j["scene"] = s.scene;
  j["seed"] = s.seed;
  j["planner"] = s.planner;
  j["finish_reason"] = s.finish_reason;
  j["exploration_time_s"] = s.exploration_time_s;
  j["flight_distance_m"] = s.flight_distance_m;
  // Figures that need a scene to compare with are null without one (onboard, replay): 0 m from an
  // obstacle, no collision and a coverage of -1 read as measured. So is a coverage never measured with
  // one (-1: a recorder that heard no map before the run ended).
  j["coverage"] = s.ground_truth && s.coverage >= 0.0 ? nlohmann::json(s.coverage) : nlohmann::json(nullptr);
  j["collisions"] = s.ground_truth ? nlohmann::json(s.collisions) : nlohmann::json(nullptr);
  j["blacklisted_frontiers"] = s.blacklisted_frontiers;
  j["min_obstacle_distance_m"] = s.ground_truth ? nlohmann::json(s.min_obstacle_distance_m) : nlohmann::json(nullptr);
  j["wall_time_s"] = s.wall_time_s;
  nlohmann::json compute = nlohmann::json::object();
  double total = 0.0;
  for (const auto& [name, b] : s.compute) {
    compute[name] = {{"mean", b.mean()}, {"max", b.max_ms}, {"count", b.count}};
    if (isPlanningBlock(name)) total += b.mean();
  }
  compute["total"] = {{"mean", total}};
  j["compute_ms"] = compute;
  for (const auto& [k, v] : s.extra) j[k] = v;
  return j;
}

}  // namespace

// Strings that are not UTF-8 (a finish reason from outside the chain) are written with U+FFFD in place of
// their bad bytes: nlohmann would throw, and the run would end without its summary.
bool isPlanningBlock(const std::string& block) {
  return block == "frontier" || block == "global" || block == "local" || block == "trajectory";
}
bool isComputeBlock(const std::string& block) { return block == "mapping" || isPlanningBlock(block); }

std::string summaryJson(const Summary& summary) {
  return toJson(summary).dump(2, ' ', false, nlohmann::json::error_handler_t::replace);
}

common::Status Recorder::writeSummary(const std::string& path) const {
  std::ofstream out(path);
  if (!out) return common::Status::Error(path + ": cannot be written");
  out << summaryJson(summary_) << "\n";
  out.close();  // flushed here: a full disk fails now, not silently in the destructor
  return out ? common::Status::Ok() : common::Status::Error(path + ": write failed");
}

common::Status Recorder::writeCsv(const std::string& path) const {
  std::ofstream out(path);
  if (!out) return common::Status::Error(path + ": cannot be written");
  out << "t,coverage,explored_m3,distance,layer,frontiers,x,y,z\n" << std::fixed;
  for (const Sample& s : samples_)
    // Time to the millisecond: metrics/sample_rate may reach 1000 Hz, and rows to 0.01 s repeated their t.
    out << std::setprecision(3) << s.t << "," << std::setprecision(5) << s.coverage << "," << std::setprecision(3)
        << s.explored_m3 << "," << s.distance << "," << s.layer << "," << s.frontiers << "," << s.position.x() << ","
        << s.position.y() << "," << s.position.z() << "\n";
  out.close();
  return out ? common::Status::Ok() : common::Status::Error(path + ": write failed");
}

common::Status Recorder::writePlot(const std::string& path, const std::string& title) const {
  return plotCoverage({{summary_.planner, samples_}}, title, path);
}

common::Status writeWhole(const std::string& path, const std::function<common::Status(const std::string&)>& write) {
  const std::filesystem::path final_path(path);
  const std::filesystem::path partial = final_path.parent_path() / (".partial-" + final_path.filename().string());
  std::error_code ec;
  if (const common::Status st = write(partial.string()); !st.ok()) {
    std::filesystem::remove(partial, ec);
    return st;
  }
  std::filesystem::rename(partial, final_path, ec);
  if (ec) {
    std::filesystem::remove(partial, ec);
    return common::Status::Error(path + ": cannot be written (" + ec.message() + ")");
  }
  return common::Status::Ok();
}

common::Status writeTextWhole(const std::string& path, const std::string& text) {
  return writeWhole(path, [&](const std::string& partial) {
    std::ofstream out(partial);
    if (!out) return common::Status::Error(path + ": cannot be written");
    out << text;
    out.close();
    return out ? common::Status::Ok() : common::Status::Error(path + ": write failed");
  });
}

common::Status Recorder::writeAll(const std::string& dir) const {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return common::Status::Error(dir + ": cannot be created (" + ec.message() + ")");
  // Each file whole (writeWhole), summary.json last: its presence means all three are there.
  const std::string title = summary_.scene + " (seed " + std::to_string(summary_.seed) + ")";
  const std::vector<std::pair<std::string, std::function<common::Status(const std::string&)>>> files = {
      {"metrics.csv", [&](const std::string& path) { return writeCsv(path); }},
      {"coverage.png", [&](const std::string& path) { return writePlot(path, title); }},
      {"summary.json", [&](const std::string& path) { return writeSummary(path); }},
  };
  for (const auto& [name, write] : files)
    if (const common::Status st = writeWhole((std::filesystem::path(dir) / name).string(), write); !st.ok()) return st;
  return common::Status::Ok();
}

namespace {

// A "nice" axis step: 1, 2 or 5 times a power of ten, giving about `ticks` intervals over `range`.
double niceStep(double range, int ticks) {
  const double raw = range / std::max(1, ticks);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10.0 * p;
}

std::string fmt(double v) {
  std::ostringstream s;
  s << std::setprecision(4) << v;
  return s.str();
}

}  // namespace

common::Status plotCoverage(const std::vector<std::pair<std::string, std::vector<Sample>>>& series,
                            const std::string& title, const std::string& path) {
  const int W = 800, H = 500, left = 70, right = 20, top = 40, bottom = 55;
  cv::Mat img(H, W, CV_8UC3, cv::Scalar(255, 255, 255));
  double t_max = 1.0;
  for (const auto& [name, samples] : series)
    for (const Sample& s : samples) t_max = std::max(t_max, s.t);
  const double t_step = niceStep(t_max, 8);
  t_max = std::ceil(t_max / t_step) * t_step;
  const int pw = W - left - right, ph = H - top - bottom;
  auto px = [&](double t, double c) {
    return cv::Point(left + static_cast<int>(std::lround(t / t_max * pw)),
                     top + ph - static_cast<int>(std::lround(std::clamp(c, 0.0, 100.0) / 100.0 * ph)));
  };
  const cv::Scalar grid(225, 225, 225), axis(60, 60, 60), text(30, 30, 30);
  const int font = cv::FONT_HERSHEY_SIMPLEX;
  for (double c = 0; c <= 100.0 + 1e-9; c += 20.0) {
    cv::line(img, px(0, c), px(t_max, c), grid, 1);
    cv::putText(img, fmt(c), px(0, c) + cv::Point(-40, 5), font, 0.45, text, 1, cv::LINE_AA);
  }
  for (double t = 0; t <= t_max + 1e-9; t += t_step) {
    cv::line(img, px(t, 0), px(t, 100), grid, 1);
    cv::putText(img, fmt(t), px(t, 0) + cv::Point(-10, 20), font, 0.45, text, 1, cv::LINE_AA);
  }
  cv::rectangle(img, px(0, 100), px(t_max, 0), axis, 1);
  cv::putText(img, "time (s)", cv::Point(left + pw / 2 - 30, H - 12), font, 0.5, text, 1, cv::LINE_AA);
  cv::putText(img, "coverage (%)", cv::Point(8, top - 12), font, 0.5, text, 1, cv::LINE_AA);
  cv::putText(img, title, cv::Point(left + 120, top - 12), font, 0.55, text, 1, cv::LINE_AA);
  const cv::Scalar colours[] = {{200, 90, 20}, {40, 40, 220}, {40, 160, 40}, {160, 40, 160}, {20, 160, 200}};
  for (std::size_t k = 0; k < series.size(); ++k) {
    const cv::Scalar colour = colours[k % 5];
    const auto& samples = series[k].second;
    for (std::size_t i = 1; i < samples.size(); ++i)
      if (samples[i - 1].coverage >= 0 && samples[i].coverage >= 0)
        cv::line(img, px(samples[i - 1].t, 100.0 * samples[i - 1].coverage), px(samples[i].t, 100.0 * samples[i].coverage),
                 colour, 2, cv::LINE_AA);
    const cv::Point legend(left + pw - 150, top + ph - 20 - 20 * static_cast<int>(series.size() - 1 - k));
    cv::line(img, legend, legend + cv::Point(25, 0), colour, 2, cv::LINE_AA);
    cv::putText(img, series[k].first, legend + cv::Point(32, 5), font, 0.45, text, 1, cv::LINE_AA);
  }
  try {
    if (!cv::imwrite(path, img)) return common::Status::Error(path + ": cannot be written");
  } catch (const cv::Exception& e) {
    return common::Status::Error(path + ": " + e.what());
  }
  return common::Status::Ok();
}

}  // namespace go_feap::metrics
