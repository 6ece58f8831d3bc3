// Viewpoint sampling against oracles: the field of view by projecting into a pinhole camera, the line of
// sight by exact segment-voxel intersection with every occupied voxel, and the sampled set against an
// exhaustive enumeration of the ring positions, on random maps.
#include <gtest/gtest.h>

#include <map>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "go_feap/planning/local_planner.h"
#include "go_feap/planning/viewpoints.h"

using go_feap::common::Aabb;
using go_feap::common::GridGeometry;
using go_feap::common::Index3;
using go_feap::common::Vec3;
using go_feap::frontier::Frontier;
using go_feap::frontier::Viewpoint;
using go_feap::map::Esdf;
using go_feap::map::EsdfConfig;
using go_feap::map::OccupancyConfig;
using go_feap::map::OccupancyMap;
using go_feap::map::VoxelState;
using go_feap::planning::candidateYaws;
using go_feap::planning::countVisible;
using go_feap::planning::FrontierType;
using go_feap::planning::pathDistance;
using go_feap::planning::inView;
using go_feap::planning::sampleViewpoints;
using go_feap::planning::ViewpointConfig;
using go_feap::planning::wrapAngle;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRes = 0.1;

// An occupancy map with its corner at the origin, all free at first, and an ESDF kept in step with it.
class World {
 public:
  explicit World(const Index3& dims)
      : map_(config(), Aabb{Vec3::Zero(), dims.cast<double>() * kRes}),
        esdf_(map_.geometry(), esdfConfig()),
        synced_(map_.geometry().size(), 0) {
    set(Index3::Zero(), dims, VoxelState::kFree);
  }

  const GridGeometry& geo() const { return map_.geometry(); }
  const OccupancyMap& map() const { return map_; }
  const Esdf& esdf() const { return esdf_; }
  const std::vector<Index3>& occupied() const { return occupied_; }

  /// Sets the voxels of [lo, hi] (inclusive, clipped to the grid) and updates the ESDF.
  void set(const Index3& lo, const Index3& hi, VoxelState s) {
    const Index3 d = geo().dims();
    for (int z = std::max(0, lo.z()); z <= std::min(hi.z(), d.z() - 1); ++z)
      for (int y = std::max(0, lo.y()); y <= std::min(hi.y(), d.y() - 1); ++y)
        for (int x = std::max(0, lo.x()); x <= std::min(hi.x(), d.x() - 1); ++x)
          map_.setState(Index3(x, y, z), s);
    std::vector<std::size_t> inserted, removed;
    occupied_.clear();
    for (std::size_t l = 0; l < synced_.size(); ++l) {
      const std::uint8_t now = map_.stateAt(l) == VoxelState::kOccupied ? 1 : 0;
      if (now) occupied_.push_back(geo().unlinear(l));
      if (now == synced_[l]) continue;
      (now ? inserted : removed).push_back(l);
      synced_[l] = now;
    }
    esdf_.update(inserted, removed);
  }

 private:
  static OccupancyConfig config() {
    OccupancyConfig c;
    c.resolution = kRes;
    c.margin = 0.0;
    return c;
  }
  static EsdfConfig esdfConfig() {
    EsdfConfig c;
    c.max_distance = 1.0;
    return c;
  }

  OccupancyMap map_;
  Esdf esdf_;
  std::vector<std::uint8_t> synced_;
  std::vector<Index3> occupied_;
};

struct Rng {
  explicit Rng(unsigned seed) : engine(seed) {}
  int operator()(int lo, int hi) {
    return lo + static_cast<int>(engine() % static_cast<unsigned>(hi - lo + 1));
  }
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(engine); }
  std::mt19937 engine;
};

// --- Oracles -----------------------------------------------------------------------------------------

// A 640x480 pinhole camera at p looking along yaw (optical frame: z forward, x right, y down), with the
// focal lengths that give the configured fields of view.
bool projectsIntoImage(const Vec3& p, double yaw, const Vec3& c, const ViewpointConfig& cfg) {
  if ((c - p).norm() > cfg.sensor_range) return false;
  Eigen::Matrix3d R_W_C;
  R_W_C.col(2) = Vec3(std::cos(yaw), std::sin(yaw), 0.0);
  R_W_C.col(0) = Vec3(std::sin(yaw), -std::cos(yaw), 0.0);
  R_W_C.col(1) = Vec3(0.0, 0.0, -1.0);
  const Vec3 q = R_W_C.transpose() * (c - p);
  if (q.z() <= 0.0) return false;
  const double w = 640, h = 480;
  const double fx = 0.5 * w / std::tan(0.5 * cfg.hfov), fy = 0.5 * h / std::tan(0.5 * cfg.vfov);
  const double u = fx * q.x() / q.z() + 0.5 * w, v = fy * q.y() / q.z() + 0.5 * h;
  return u >= 0.0 && u <= w && v >= 0.0 && v <= h;
}

// True when the segment a-b crosses the open cube of voxel idx over a positive length (slab method).
bool segmentHitsVoxel(const GridGeometry& geo, const Vec3& a, const Vec3& b, const Index3& idx) {
  const Vec3 lo = geo.origin() + idx.cast<double>() * geo.resolution();
  const Vec3 hi = lo + Vec3::Constant(geo.resolution());
  double t0 = 0.0, t1 = 1.0;
  for (int i = 0; i < 3; ++i) {
    const double d = b[i] - a[i];
    if (d == 0.0) {
      if (a[i] <= lo[i] || a[i] >= hi[i]) return false;
      continue;
    }
    double ta = (lo[i] - a[i]) / d, tb = (hi[i] - a[i]) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
  }
  return t0 < t1;
}

bool oracleLineOfSight(const World& w, const Vec3& p, const Vec3& c) {
  const Vec3 d = c - p;
  const Vec3 end = d.norm() > kRes ? Vec3(c - d.normalized() * kRes) : p;
  const Vec3 lo = p.cwiseMin(end) - Vec3::Constant(kRes), hi = p.cwiseMax(end) + Vec3::Constant(kRes);
  for (const Index3& o : w.occupied()) {
    const Vec3 oc = w.geo().indexToCoord(o);
    if ((oc.array() < lo.array()).any() || (oc.array() > hi.array()).any()) continue;
    if (segmentHitsVoxel(w.geo(), p, end, o)) return false;
  }
  return true;
}

// N_view for every yaw of `yaws` at p, with the ray test done once per cell.
std::vector<int> oracleCounts(const World& w, const Vec3& p, const std::vector<double>& yaws,
                              const std::vector<Index3>& cells, const ViewpointConfig& cfg) {
  std::vector<int> counts(yaws.size(), 0);
  for (const Index3& idx : cells) {
    const Vec3 c = w.geo().indexToCoord(idx);
    if ((c - p).norm() > cfg.sensor_range || !oracleLineOfSight(w, p, c)) continue;
    for (std::size_t k = 0; k < yaws.size(); ++k)
      if (projectsIntoImage(p, yaws[k], c, cfg)) ++counts[k];
  }
  return counts;
}

// --- Fixtures ----------------------------------------------------------------------------------------

// 4 x 4 x 2 m, random occupied and unknown boxes.
void randomise(World& w, Rng& rng, int obstacles, int unknowns) {
  const Index3 d = w.geo().dims();
  auto box = [&](int lo_size, int hi_size, VoxelState s) {
    const Index3 lo(rng(0, d.x() - 1), rng(0, d.y() - 1), rng(0, d.z() - 1));
    const Index3 size(rng(lo_size, hi_size), rng(lo_size, hi_size), rng(lo_size, 2 * hi_size));
    w.set(lo, lo + size, s);
  };
  for (int i = 0; i < obstacles; ++i) box(1, 4, VoxelState::kOccupied);
  for (int i = 0; i < unknowns; ++i) box(3, 8, VoxelState::kUnknown);
}

Vec3 randomFreePoint(const World& w, Rng& rng) {
  const Index3 d = w.geo().dims();
  for (;;) {
    const Index3 idx(rng(0, d.x() - 1), rng(0, d.y() - 1), rng(0, d.z() - 1));
    if (w.map().state(idx) != VoxelState::kFree) continue;
    return w.geo().indexToCoord(idx) +
           Vec3(rng.uniform(-0.45, 0.45), rng.uniform(-0.45, 0.45), rng.uniform(-0.45, 0.45)) * kRes;
  }
}

// Free voxels with an unknown face neighbour inside the grid, in increasing linear order.
Frontier frontierOf(const World& w) {
  Frontier f;
  f.id = 7;
  for (std::size_t l = 0; l < w.geo().size(); ++l) {
    const Index3 idx = w.geo().unlinear(l);
    if (w.map().state(idx) != VoxelState::kFree) continue;
    for (const Index3& o : go_feap::common::faceNeighbours())
      if (const Index3 n = idx + o; w.geo().inside(n) && w.map().state(n) == VoxelState::kUnknown) {
        f.cells.push_back(idx);
        break;
      }
  }
  for (const Index3& c : f.cells) f.average += w.geo().indexToCoord(c);
  if (!f.cells.empty()) f.average /= static_cast<double>(f.cells.size());
  return f;
}

// Random clutter (30 boxes) round an unknown block in the middle: the frontier is the free cells bordering it.
Frontier clutterWithUnknownBlock(World& w, Rng& rng) {
  randomise(w, rng, 30, 0);
  const Index3 lo(rng(12, 22), rng(12, 22), 4);
  w.set(lo, lo + Index3(rng(3, 6), rng(3, 6), 8), VoxelState::kUnknown);
  return frontierOf(w);
}

ViewpointConfig testConfig() {
  ViewpointConfig c;
  c.ring_radii = {0.8, 1.2, 1.6};
  c.angular_step = kPi / 6;
  c.height_offsets = {-0.5, 0.0, 0.5};
  c.clearance = 0.3;
  c.sensor_range = 2.5;  // smaller than the map, so range matters
  c.min_visible = 5;
  c.yaw_samples = 12;
  return c;
}

// --- Tests -------------------------------------------------------------------------------------------

TEST(ViewpointConfig, ValidateNamesTheBadKey) {
  EXPECT_TRUE(ViewpointConfig().validate().ok());
  auto expectBad = [](const char* key, auto mutate) {
    ViewpointConfig c;
    mutate(c);
    const auto s = c.validate();
    EXPECT_FALSE(s.ok()) << key;
    EXPECT_NE(s.message().find(key), std::string::npos) << s.message();
  };
  expectBad("ring_radii", [](ViewpointConfig& c) { c.ring_radii.clear(); });
  expectBad("ring_radii", [](ViewpointConfig& c) { c.ring_radii = {1.0, -1.0}; });
  expectBad("angular_step", [](ViewpointConfig& c) { c.angular_step = 0.0; });
  expectBad("angular_step", [](ViewpointConfig& c) { c.angular_step = 1e-6; });  // 6.3 million per ring
  expectBad("height_offsets", [](ViewpointConfig& c) { c.height_offsets.clear(); });
  expectBad("height_offsets", [](ViewpointConfig& c) { c.height_offsets = {NAN}; });
  expectBad("clearance", [](ViewpointConfig& c) { c.clearance = -0.1; });
  expectBad("sensor_range", [](ViewpointConfig& c) { c.sensor_range = 0.0; });
  expectBad("hfov", [](ViewpointConfig& c) { c.hfov = kPi; });
  expectBad("hfov", [](ViewpointConfig& c) { c.hfov = 0.0; });  // nothing would ever be in view
  expectBad("hfov", [](ViewpointConfig& c) { c.hfov = -0.5; });
  expectBad("vfov", [](ViewpointConfig& c) { c.vfov = 0.0; });
  expectBad("min_visible", [](ViewpointConfig& c) { c.min_visible = -1; });
  expectBad("yaw_samples", [](ViewpointConfig& c) { c.yaw_samples = 0; });
  expectBad("yaw_samples", [](ViewpointConfig& c) { c.yaw_samples = 100000; });
  // Against the ESDF: a clearance past max_distance (where distances are truncated) passes no viewpoint.
  EsdfConfig esdf;
  esdf.max_distance = 2.0;
  ViewpointConfig c;
  c.clearance = 2.0;
  EXPECT_TRUE(c.validate(esdf)) << c.validate(esdf).message();
  c.clearance = 2.5;
  ASSERT_TRUE(c.validate());
  EXPECT_NE(c.validate(esdf).message().find("viewpoints: clearance"), std::string::npos) << c.validate(esdf).message();
}

TEST(Viewpoints, WrapAngleAndCandidateYaws) {
  EXPECT_NEAR(wrapAngle(3 * kPi / 2), -kPi / 2, 1e-12);
  EXPECT_NEAR(wrapAngle(-kPi), kPi, 1e-12);
  EXPECT_NEAR(wrapAngle(0.3 + 4 * kPi), 0.3, 1e-12);
  const std::vector<double> yaws = candidateYaws(Vec3(1, 1, 0), Vec3(1, 3, 5), 8);
  ASSERT_EQ(yaws.size(), 8u);
  EXPECT_NEAR(yaws[0], kPi / 2, 1e-12);  // faces the target
  for (std::size_t k = 0; k < yaws.size(); ++k) {
    EXPECT_GT(yaws[k], -kPi);
    EXPECT_LE(yaws[k], kPi);
    EXPECT_NEAR(std::abs(wrapAngle(yaws[k] - yaws[0] - 2 * kPi * k / 8)), 0.0, 1e-12);
  }
  EXPECT_NEAR(candidateYaws(Vec3(1, 1, 0), Vec3(1, 1, 2), 4)[0], 0.0, 1e-12);
}

TEST(Viewpoints, InViewMatchesCameraProjection) {
  const ViewpointConfig cfg;
  Rng rng(3);
  int inside = 0;
  for (int i = 0; i < 20000; ++i) {
    const Vec3 p(rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1));
    const Vec3 c = p + Vec3(rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-3, 3));
    const double yaw = rng.uniform(-kPi, kPi);
    const bool expected = projectsIntoImage(p, yaw, c, cfg);
    inside += expected;
    ASSERT_EQ(inView(p, yaw, c, cfg), expected) << i;
  }
  EXPECT_GT(inside, 500);  // both outcomes exercised
  EXPECT_LT(inside, 19500);
}

TEST(Viewpoints, CountVisibleMatchesBruteForce) {
  const ViewpointConfig cfg = testConfig();
  for (unsigned seed : {1u, 2u, 3u, 4u}) {
    World w(Index3(40, 40, 20));
    Rng rng(seed);
    randomise(w, rng, 25, 4);
    std::vector<Index3> cells;
    while (cells.size() < 100) {
      const Index3 idx(rng(0, 39), rng(0, 39), rng(0, 19));
      if (w.map().state(idx) == VoxelState::kFree) cells.push_back(idx);
    }
    const World empty(Index3(40, 40, 20));
    int total = 0, blocked_some = 0;
    for (int i = 0; i < 15; ++i) {
      const Vec3 p = randomFreePoint(w, rng);
      std::vector<double> yaws;
      for (int k = 0; k < 8; ++k) yaws.push_back(rng.uniform(-kPi, kPi));
      const std::vector<int> expected = oracleCounts(w, p, yaws, cells, cfg);
      const std::vector<int> in_fov_only = oracleCounts(empty, p, yaws, cells, cfg);
      for (std::size_t k = 0; k < yaws.size(); ++k) {
        ASSERT_EQ(countVisible(p, yaws[k], cells, w.map(), cfg), expected[k])
            << "seed " << seed << " i " << i;
        // Stopping at a threshold gives the count clipped there.
        for (int stop_at : {1, 5, 20})
          ASSERT_EQ(countVisible(p, yaws[k], cells, w.map(), cfg, stop_at), std::min(expected[k], stop_at))
              << "seed " << seed << " i " << i << " stop_at " << stop_at;
        total += expected[k];
        blocked_some += expected[k] < in_fov_only[k];
      }
    }
    EXPECT_GT(total, 0) << seed;
    EXPECT_GT(blocked_some, 0) << seed;  // occlusion really happens in the fixture
  }
}

// With known_clearance, a place whose voxels max(clearance, one voxel) away along the axes are not all known
// is left out too (a flight could not end there). Ties between yaws go to the earliest candidate (the one
// facing the frontier's average first).
TEST(Viewpoints, SampledViewpointsMatchExhaustiveEnumeration) {
  const double z_min = 0.4, z_max = 1.4;
  int left_out_for_unknown = 0;
  for (int run = 0; run < 6; ++run) {  // seeds 11-13 without known_clearance, then with it
    const unsigned seed = 11u + static_cast<unsigned>(run % 3);
    ViewpointConfig cfg = testConfig();
    cfg.known_clearance = run >= 3;
    World w(Index3(40, 40, 20));
    Rng rng(seed);
    const Frontier f = clutterWithUnknownBlock(w, rng);
    ASSERT_GE(f.cells.size(), 50u);
    if (cfg.known_clearance) {  // single unknown voxels scattered through free space (after the frontier)
      const Index3 d = w.geo().dims();
      for (int i = 0; i < 400; ++i) {
        const Index3 idx(rng(0, d.x() - 1), rng(0, d.y() - 1), rng(0, d.z() - 1));
        if (w.map().state(idx) == VoxelState::kFree) w.set(idx, idx, VoxelState::kUnknown);
      }
    }

    const std::vector<Viewpoint> vps = sampleViewpoints(f, w.map(), w.esdf(), z_min, z_max, cfg);
    ASSERT_FALSE(vps.empty()) << seed;
    for (std::size_t i = 0; i < vps.size(); ++i) {
      const Viewpoint& vp = vps[i];
      EXPECT_EQ(w.map().state(vp.position), VoxelState::kFree);
      EXPECT_GE(w.esdf().distance(vp.position), cfg.clearance);
      EXPECT_GE(vp.position.z(), z_min);
      EXPECT_LE(vp.position.z(), z_max);
      EXPECT_TRUE((vp.position.array() >= w.map().box().min.array() + cfg.clearance - 1e-9).all() &&
                  (vp.position.array() <= w.map().box().max.array() - cfg.clearance + 1e-9).all())
          << "viewpoint " << vp.position.transpose() << " closer than the clearance to the box's faces";
      EXPECT_GE(vp.visible_cells, cfg.min_visible);
      if (i > 0) {
        EXPECT_GE(vps[i - 1].visible_cells, vp.visible_cells);
      }
      // The count is right, and the chosen yaw sees at least as much as every other candidate yaw.
      const std::vector<double> yaws = candidateYaws(vp.position, f.average, cfg.yaw_samples);
      const std::vector<int> counts = oracleCounts(w, vp.position, yaws, f.cells, cfg);
      EXPECT_EQ(countVisible(vp.position, vp.yaw, f.cells, w.map(), cfg), vp.visible_cells);
      EXPECT_EQ(*std::max_element(counts.begin(), counts.end()), vp.visible_cells);
      const std::size_t first_best = std::max_element(counts.begin(), counts.end()) - counts.begin();
      EXPECT_DOUBLE_EQ(vp.yaw, yaws[first_best]) << "a tie not given to the earliest candidate yaw";
      EXPECT_TRUE(
          std::any_of(yaws.begin(), yaws.end(), [&](double y) { return std::abs(y - vp.yaw) < 1e-12; }));
    }

    // Every ring position that qualifies is returned, and nothing else.
    std::vector<Vec3> expected;
    const int n_angles = static_cast<int>(std::lround(2 * kPi / cfg.angular_step));
    for (double r : cfg.ring_radii)
      for (int a = 0; a < n_angles; ++a)
        for (double off : cfg.height_offsets) {
          const double theta = 2 * kPi * a / n_angles;
          const Vec3 p = f.average + Vec3(r * std::cos(theta), r * std::sin(theta), 0.0);
          // Heights are clamped to the band and to the box shrunk by the clearance.
          const double lo = std::max(z_min, w.map().box().min.z() + cfg.clearance);
          const double hi = std::min(z_max, w.map().box().max.z() - cfg.clearance);
          const Vec3 q(p.x(), p.y(), std::clamp(f.average.z() + off, lo, hi));
          if ((q.array() < w.map().box().min.array() + cfg.clearance).any() ||
              (q.array() > w.map().box().max.array() - cfg.clearance).any())
            continue;
          if (w.map().state(q) != VoxelState::kFree || w.esdf().distance(q) < cfg.clearance) continue;
          const std::vector<int> counts =
              oracleCounts(w, q, candidateYaws(q, f.average, cfg.yaw_samples), f.cells, cfg);
          if (*std::max_element(counts.begin(), counts.end()) < cfg.min_visible) continue;
          if (cfg.known_clearance) {
            const double step = std::max(cfg.clearance, w.map().geometry().resolution());
            bool all_known = true;
            for (int axis = 0; axis < 3; ++axis)
              for (double sgn : {-1.0, 1.0})
                all_known = all_known && w.map().state(Vec3(q + sgn * step * Vec3::Unit(axis))) != VoxelState::kUnknown;
            if (!all_known) {
              ++left_out_for_unknown;
              continue;
            }
          }
          if (std::none_of(expected.begin(), expected.end(),
                           [&](const Vec3& e) { return (e - q).norm() < 1e-9; }))
            expected.push_back(q);
        }
    ASSERT_EQ(vps.size(), expected.size()) << seed << (cfg.known_clearance ? " known_clearance" : "");
    for (const Vec3& e : expected)
      EXPECT_TRUE(std::any_of(vps.begin(), vps.end(),
                              [&](const Viewpoint& v) { return (v.position - e).norm() < 1e-9; }));
  }
  EXPECT_GT(left_out_for_unknown, 0) << "no place in the fixtures borders unknown space";
}

// With max_evaluated_cells (shipped 60) a viewpoint's N_view is counted on every ceil(n / max)-th cell and
// scaled by n over that subset's size: exactly lround(scale * the best yaw's subset count), the yaw the first
// best one on the subset, and a ring position kept exactly when that scaled count reaches min_visible (the
// exhaustive enumeration of SampledViewpointsMatchExhaustiveEnumeration on the subset).
TEST(Viewpoints, SubsetCountsAreTheScaledCountsOfEveryStrideThCell) {
  const double z_min = 0.4, z_max = 1.4;
  for (const unsigned seed : {11u, 12u, 13u}) {
    ViewpointConfig cfg = testConfig();
    cfg.max_evaluated_cells = 7;
    cfg.sensor_range = 1.3;  // part of the frontier out of range from most ring places: few subset cells near
    World w(Index3(40, 40, 20));
    Rng rng(seed);
    const Frontier f = clutterWithUnknownBlock(w, rng);
    ASSERT_GE(f.cells.size(), 50u);
    const std::size_t stride = (f.cells.size() + 6) / 7;
    std::vector<Index3> sub;
    for (std::size_t i = 0; i < f.cells.size(); i += stride) sub.push_back(f.cells[i]);
    ASSERT_LE(sub.size(), 7u);
    const double scale = static_cast<double>(f.cells.size()) / static_cast<double>(sub.size());
    auto scaledBest = [&](const Vec3& q, double* yaw) {
      const std::vector<double> yaws = candidateYaws(q, f.average, cfg.yaw_samples);
      const std::vector<int> counts = oracleCounts(w, q, yaws, sub, cfg);
      const std::size_t k = std::max_element(counts.begin(), counts.end()) - counts.begin();
      if (yaw) *yaw = yaws[k];
      return static_cast<int>(std::lround(scale * counts[k]));
    };
    const std::vector<Viewpoint> vps = sampleViewpoints(f, w.map(), w.esdf(), z_min, z_max, cfg);
    ASSERT_FALSE(vps.empty()) << seed;
    for (const Viewpoint& vp : vps) {
      double yaw = 0.0;
      EXPECT_EQ(vp.visible_cells, scaledBest(vp.position, &yaw)) << seed << " at " << vp.position.transpose();
      EXPECT_DOUBLE_EQ(vp.yaw, yaw);
    }
    std::size_t expected = 0;
    const int n_angles = static_cast<int>(std::lround(2 * kPi / cfg.angular_step));
    std::vector<Vec3> seen;
    for (double r : cfg.ring_radii)
      for (int a = 0; a < n_angles; ++a)
        for (double off : cfg.height_offsets) {
          const double theta = 2 * kPi * a / n_angles;
          const double zlo = std::max(z_min, w.map().box().min.z() + cfg.clearance);
          const double zhi = std::min(z_max, w.map().box().max.z() - cfg.clearance);
          const Vec3 q(f.average.x() + r * std::cos(theta), f.average.y() + r * std::sin(theta),
                       std::clamp(f.average.z() + off, zlo, zhi));
          if ((q.array() < w.map().box().min.array() + cfg.clearance).any() ||
              (q.array() > w.map().box().max.array() - cfg.clearance).any())
            continue;
          if (w.map().state(q) != VoxelState::kFree || w.esdf().distance(q) < cfg.clearance) continue;
          if (std::any_of(seen.begin(), seen.end(), [&](const Vec3& e) { return (e - q).norm() < 1e-9; })) continue;
          seen.push_back(q);
          expected += scaledBest(q, nullptr) >= cfg.min_visible;
        }
    EXPECT_EQ(vps.size(), expected) << seed;
  }
}

// min_visible is the fewest cells a viewpoint may see: in open space a 2 x 2 x 1 frontier is seen whole from
// every viewpoint on a 1 m ring round it, so min_visible 4 (its size) keeps them and 5 keeps none.
TEST(Viewpoints, AViewpointSeeingExactlyMinVisibleCellsIsKept) {
  World w(Index3(40, 40, 20));
  Frontier f;
  f.id = 3;
  for (int dx = 0; dx < 2; ++dx)
    for (int dy = 0; dy < 2; ++dy) f.cells.push_back(Index3(20 + dx, 20 + dy, 10));
  for (const Index3& c : f.cells) f.average += w.geo().indexToCoord(c) / 4.0;
  ViewpointConfig cfg = testConfig();
  cfg.ring_radii = {1.0};
  cfg.angular_step = kPi / 2;
  cfg.height_offsets = {0.0};
  cfg.min_visible = 4;
  const std::vector<Viewpoint> kept = sampleViewpoints(f, w.map(), w.esdf(), 0.4, 1.4, cfg);
  EXPECT_EQ(kept.size(), 4u);
  for (const Viewpoint& vp : kept) EXPECT_EQ(vp.visible_cells, 4) << vp.position.transpose();
  cfg.min_visible = 5;
  EXPECT_TRUE(sampleViewpoints(f, w.map(), w.esdf(), 0.4, 1.4, cfg).empty());
}

TEST(Viewpoints, HeightsAreClampedToTheBand) {
  World w(Index3(40, 40, 20));
  w.set(Index3(15, 15, 0), Index3(25, 25, 19), VoxelState::kUnknown);
  const Frontier f = frontierOf(w);
  ViewpointConfig cfg = testConfig();
  cfg.height_offsets = {-2.0, 0.0, 2.0};
  const std::vector<Viewpoint> vps = sampleViewpoints(f, w.map(), w.esdf(), 0.9, 1.1, cfg);
  ASSERT_FALSE(vps.empty());
  for (const Viewpoint& vp : vps) {
    EXPECT_GE(vp.position.z(), 0.9);
    EXPECT_LE(vp.position.z(), 1.1);
  }
  EXPECT_TRUE(sampleViewpoints(f, w.map(), w.esdf(), 1.1, 0.9, cfg).empty());  // empty band
  // Offsets that clamp to one height are sampled there once: -2 and -1 m give what -2 alone gives.
  ViewpointConfig twice = cfg, once = cfg;
  twice.height_offsets = {-2.0, -1.0, 0.0};
  once.height_offsets = {-2.0, 0.0};
  const std::vector<Viewpoint> a = sampleViewpoints(f, w.map(), w.esdf(), 0.9, 1.1, twice);
  const std::vector<Viewpoint> b = sampleViewpoints(f, w.map(), w.esdf(), 0.9, 1.1, once);
  ASSERT_FALSE(b.empty());
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].position, b[i].position) << i;
    for (std::size_t j = 0; j < i; ++j) EXPECT_GT((a[i].position - a[j].position).norm(), 1e-9) << i << " " << j;
  }
  cfg.yaw_samples = 0;
  EXPECT_TRUE(sampleViewpoints(f, w.map(), w.esdf(), 0.9, 1.1, cfg).empty());  // invalid config
}

TEST(Viewpoints, OccludedFrontierIsNotSeen) {
  // A wall between the viewpoint and the frontier hides it; without the wall every cell in view counts.
  World w(Index3(40, 20, 20));
  w.set(Index3(30, 0, 0), Index3(39, 19, 19), VoxelState::kUnknown);
  const Frontier f = frontierOf(w);  // the plane x = 29
  ViewpointConfig cfg;
  const Vec3 p(0.55, 1.0, 1.0);
  const int open = countVisible(p, 0.0, f.cells, w.map(), cfg);
  EXPECT_GT(open, 100);
  w.set(Index3(15, 0, 0), Index3(15, 19, 19), VoxelState::kOccupied);
  EXPECT_EQ(countVisible(p, 0.0, f.cells, w.map(), cfg), 0);
  EXPECT_EQ(countVisible(p, kPi, f.cells, w.map(), cfg), 0);
}

}  // namespace

// Counting N_view on a subset of a large frontier's cells approximates the full count.
TEST(SampleViewpointsSubset, ScaledCountsFollowTheFullCounts) {
  OccupancyMap m(OccupancyConfig(), {Vec3(0, 0, 0), Vec3(8, 8, 3)});
  const auto& g = m.geometry();
  Frontier f;
  // Known free below x < 4, unknown beyond: a large planar frontier at x = 3.95.
  for (std::size_t l = 0; l < g.size(); ++l) {
    const Index3 i = g.unlinear(l);
    m.setState(i, g.indexToCoord(i).x() < 4.0 ? VoxelState::kFree : VoxelState::kUnknown);
    const Vec3 c = g.indexToCoord(i);
    if (std::abs(c.x() - 3.95) < 1e-6 && c.y() > 2.0 && c.y() < 6.0 && c.z() > 0.0 && c.z() < 3.0) f.cells.push_back(i);
  }
  for (const Index3& c : f.cells) f.average += g.indexToCoord(c);
  f.average /= static_cast<double>(f.cells.size());
  Esdf esdf(g, EsdfConfig());
  ViewpointConfig all;
  ViewpointConfig subset = all;
  subset.max_evaluated_cells = 100;
  const auto a = sampleViewpoints(f, m, esdf, 0.0, 3.0, all);
  const auto b = sampleViewpoints(f, m, esdf, 0.0, 3.0, subset);
  ASSERT_GT(f.cells.size(), 1000u);
  ASSERT_FALSE(a.empty());
  ASSERT_EQ(a.size(), b.size());
  std::map<std::pair<long, long>, int> full;
  for (const auto& v : a) full[{std::lround(v.position.x() * 100), std::lround(v.position.y() * 100 + v.position.z() * 1e4)}] = v.visible_cells;
  for (const auto& v : b) {
    const int n = full[{std::lround(v.position.x() * 100), std::lround(v.position.y() * 100 + v.position.z() * 1e4)}];
    // 100 of ~1200 cells: the sampling error of a proportion is ~10 % (1 sigma) here.
    EXPECT_NEAR(v.visible_cells, n, 0.25 * n + 15) << v.position.transpose();
  }
  ViewpointConfig bad;
  bad.max_evaluated_cells = -1;
  EXPECT_NE(bad.validate().message().find("max_evaluated_cells"), std::string::npos);
}

TEST(Viewpoints, CacheGivesTheSampledViewpointsAndDropsThoseTheMapHasFilled) {
  const ViewpointConfig cfg = testConfig();
  const double z_min = 0.4, z_max = 1.4;
  World w(Index3(40, 40, 20));
  Rng rng(21);
  randomise(w, rng, 30, 0);
  const Index3 lo(rng(12, 22), rng(12, 22), 4);
  w.set(lo, lo + Index3(5, 5, 8), VoxelState::kUnknown);
  Frontier f = frontierOf(w);
  f.id = 7;
  const std::vector<Viewpoint> sampled = sampleViewpoints(f, w.map(), w.esdf(), z_min, z_max, cfg);
  ASSERT_GE(sampled.size(), 2u);
  go_feap::planning::ViewpointCache cache;
  auto same = [](const std::vector<Viewpoint>& a, const std::vector<Viewpoint>& b) {
    if (a.size() != b.size()) return false;
    for (std::size_t i = 0; i < a.size(); ++i)
      if (a[i].position != b[i].position || a[i].yaw != b[i].yaw || a[i].visible_cells != b[i].visible_cells)
        return false;
    return true;
  };
  EXPECT_TRUE(same(cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg), sampled));
  EXPECT_TRUE(same(cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg), sampled));
  EXPECT_EQ(cache.misses(), 1u);
  EXPECT_EQ(cache.hits(), 1u);
  // An obstacle appears at the best viewpoint: the cached list loses it (and every viewpoint now
  // too close to it), the others stay.
  const Index3 at = w.geo().coordToIndex(sampled.front().position);
  w.set(at, at, VoxelState::kOccupied);
  const std::vector<Viewpoint> after = cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg);
  EXPECT_LT(after.size(), sampled.size());
  for (const Viewpoint& vp : after) {
    EXPECT_EQ(w.map().state(vp.position), VoxelState::kFree);
    EXPECT_GE(w.esdf().distance(vp.position), cfg.clearance);
    EXPECT_TRUE(std::any_of(sampled.begin(), sampled.end(), [&](const Viewpoint& s) { return s.position == vp.position; }));
  }
  // Another band, or a forgotten frontier, is sampled afresh: a band with another floor only (the layer
  // manager's switch from the top band to the whole box moves z_min alone), another ceiling.
  ASSERT_TRUE(
      std::any_of(after.begin(), after.end(), [&](const Viewpoint& vp) { return vp.position.z() < z_min + 0.5; }));
  const std::vector<Viewpoint> raised = cache.get(f, w.map(), w.esdf(), z_min + 0.5, z_max, cfg);
  EXPECT_EQ(cache.misses(), 2u);
  EXPECT_TRUE(same(raised, sampleViewpoints(f, w.map(), w.esdf(), z_min + 0.5, z_max, cfg)));
  for (const Viewpoint& vp : raised) EXPECT_GE(vp.position.z(), z_min + 0.5 - 1e-9);
  cache.get(f, w.map(), w.esdf(), z_min + 0.5, z_max + 0.5, cfg);
  EXPECT_EQ(cache.misses(), 3u);
  cache.retain({});
  EXPECT_EQ(cache.size(), 0u);
  cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg);
  EXPECT_EQ(cache.misses(), 4u);
  // The same id at another place (ids from a bag or a tool, not the finder's): sampled there, not the
  // viewpoints of the first place.
  Frontier moved = f;
  moved.average += Vec3(0.3, 0.0, 0.0);
  for (Index3& c : moved.cells) c += Index3(3, 0, 0);
  const std::vector<Viewpoint> there = cache.get(moved, w.map(), w.esdf(), z_min, z_max, cfg);
  EXPECT_EQ(cache.misses(), 5u);
  EXPECT_TRUE(same(there, sampleViewpoints(moved, w.map(), w.esdf(), z_min, z_max, cfg)));
}

// A frontier keeps its id while its cells stay the same, however the map round it changes: its cached
// viewpoints go when a change reaches where they were sampled from, and stay for a change elsewhere. The
// cache was emptied only with the id, so that a frontier whose ring was unknown when it was first sampled
// kept no viewpoint (and was skipped at every plan until blacklisted) after its ring had been seen.
TEST(Viewpoints, CacheForgetsAFrontierWhenTheMapChangesWithinItsReach) {
  const ViewpointConfig cfg = testConfig();
  const double z_min = 0.4, z_max = 1.4;
  World w(Index3(80, 40, 20));
  w.set(Index3::Zero(), Index3(79, 39, 19), VoxelState::kUnknown);
  w.set(Index3(16, 16, 4), Index3(23, 23, 15), VoxelState::kFree);   // a free shell two voxels thick
  w.set(Index3(18, 18, 6), Index3(21, 21, 13), VoxelState::kUnknown);  // round an unknown block
  const Frontier f = [&] {
    Frontier g = frontierOf(w);
    // Only the block's faces (the shell's outer faces border unknown space too).
    g.cells.erase(std::remove_if(g.cells.begin(), g.cells.end(),
                                 [](const Index3& c) {
                                   return (c.array() < Eigen::Array3i(17, 17, 5)).any() ||
                                          (c.array() > Eigen::Array3i(22, 22, 14)).any();
                                 }),
                  g.cells.end());
    // No box, as a frontier built from a FrontierArray message by the LocalPlanner nodelet: the reach
    // comes from the cells (from the unset box it sat at the origin, and this change was never seen).
    g.box = go_feap::common::Aabb{};
    g.average = Vec3::Zero();
    for (const Index3& c : g.cells) g.average += w.geo().indexToCoord(c) / static_cast<double>(g.cells.size());
    return g;
  }();
  ASSERT_GE(f.cells.size(), 50u);
  go_feap::planning::ViewpointCache cache;
  EXPECT_TRUE(cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg).empty()) << "the ring lies in unknown space";
  // A change 4 m away, beyond the ring's reach: the (empty) entry stays.
  auto changed = [&](const Index3& lo, const Index3& hi) {
    std::vector<std::size_t> out;
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) out.push_back(w.geo().linear(Index3(x, y, z)));
    return out;
  };
  w.set(Index3(70, 0, 0), Index3(79, 39, 19), VoxelState::kFree);
  cache.forgetChanged(w.geo(), changed(Index3(70, 0, 0), Index3(79, 39, 19)));
  EXPECT_TRUE(cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg).empty());
  EXPECT_EQ(cache.misses(), 1u);
  // The space round the block is seen free; the frontier's cells are the block's faces still.
  w.set(Index3::Zero(), Index3(69, 39, 19), VoxelState::kFree);
  w.set(Index3(18, 18, 6), Index3(21, 21, 13), VoxelState::kUnknown);
  cache.forgetChanged(w.geo(), changed(Index3::Zero(), Index3(69, 39, 19)));
  const std::vector<Viewpoint> fresh = sampleViewpoints(f, w.map(), w.esdf(), z_min, z_max, cfg);
  ASSERT_FALSE(fresh.empty());
  const std::vector<Viewpoint> got = cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg);
  ASSERT_EQ(got.size(), fresh.size());
  for (std::size_t i = 0; i < got.size(); ++i) EXPECT_EQ(got[i].position, fresh[i].position);
  EXPECT_EQ(cache.misses(), 2u);
  // By box: one far off keeps the entry, one within reach forgets it.
  cache.forgetChanged(go_feap::common::Aabb{Vec3(7.0, 0.0, 0.0), Vec3(7.9, 3.9, 1.9)});
  cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg);
  EXPECT_EQ(cache.misses(), 2u);
  cache.forgetChanged(go_feap::common::Aabb{Vec3(3.5, 2.0, 1.0), Vec3(3.6, 2.1, 1.1)});
  cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg);
  EXPECT_EQ(cache.misses(), 3u);

}

// Differential: single voxels seen occupied and then free again, half of them within the clearance (and a
// voxel) of a candidate position on the outer ring, the rest anywhere up to a few voxels past the ring's reach:
// after forgetChanged, what the cache gives is what sampling anew gives, every time. The frontier is the six
// faces of one unknown voxel and the rings lie at its height (so neither the cells' box nor the heights give
// the reach slack of their own): a reach box without the clearance keeps a stale entry for a change that
// moves a viewpoint.
TEST(Viewpoints, CacheGivesWhatSamplingAnewGivesAfterAnyNearbyChange) {
  ViewpointConfig cfg = testConfig();
  cfg.min_visible = 1;
  cfg.height_offsets = {0.0};
  const double z_min = 0.4, z_max = 1.4;
  World w(Index3(40, 40, 20));
  const Index3 hole(20, 20, 9);
  w.set(hole, hole, VoxelState::kUnknown);
  const Frontier f = frontierOf(w);
  ASSERT_EQ(f.cells.size(), 6u);
  go_feap::planning::ViewpointCache cache;
  ASSERT_FALSE(cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg).empty());
  Rng rng(11);
  const double reach = 1.6 + cfg.clearance + 3 * kRes;  // the outer ring 1.6 m
  int moved = 0;
  const int n_angles = static_cast<int>(std::lround(2.0 * kPi / cfg.angular_step));
  for (int k = 0; k < 2000; ++k) {
    Vec3 p = f.average + Vec3(rng.uniform(-reach, reach), rng.uniform(-reach, reach), rng.uniform(-reach, reach));
    if (k % 2 == 0) {  // near a candidate position on the outer ring
      const double r = *std::max_element(cfg.ring_radii.begin(), cfg.ring_radii.end());
      const double theta = 2.0 * kPi * rng(0, n_angles - 1) / n_angles;
      const double z = std::clamp(f.average.z() + cfg.height_offsets[rng(0, static_cast<int>(cfg.height_offsets.size()) - 1)],
                                  z_min, z_max);
      const double d = cfg.clearance + kRes;
      p = Vec3(f.average.x() + r * std::cos(theta), f.average.y() + r * std::sin(theta), z) +
          Vec3(rng.uniform(-d, d), rng.uniform(-d, d), rng.uniform(-d, d));
    }
    const Index3 idx = w.geo().coordToIndex(p);
    if (!w.geo().inside(idx) || (idx - hole).cwiseAbs().maxCoeff() <= 1) continue;  // the hole and its faces stay
    const std::vector<Viewpoint> before = sampleViewpoints(f, w.map(), w.esdf(), z_min, z_max, cfg);
    // Seen occupied, then free again (the free world each time, so that every near change counts).
    for (const VoxelState now : {VoxelState::kOccupied, VoxelState::kFree}) {
      w.set(idx, idx, now);
      cache.forgetChanged(w.geo(), {w.geo().linear(idx)});
      const std::vector<Viewpoint> want = sampleViewpoints(f, w.map(), w.esdf(), z_min, z_max, cfg);
      const std::vector<Viewpoint> have = cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg);
      ASSERT_EQ(have.size(), want.size()) << "after setting " << idx.transpose() << " to " << static_cast<int>(now);
      for (std::size_t i = 0; i < want.size(); ++i) {
        ASSERT_EQ(have[i].position, want[i].position) << "after setting " << idx.transpose();
        ASSERT_EQ(have[i].yaw, want[i].yaw);
        ASSERT_EQ(have[i].visible_cells, want[i].visible_cells);
      }
      if (now == VoxelState::kOccupied) {
        bool same = before.size() == want.size();
        for (std::size_t i = 0; same && i < want.size(); ++i) same = before[i].position == want[i].position;
        moved += !same;
      }
    }
  }
  EXPECT_GE(moved, 20) << "too few toggles changed the viewpoints for the test to tell";
}

// The local planner node's way with the mapper's updates (ViewpointCache::forgetFor): one voxel toggled a
// frame, each frame's update delivered at once, late (after the next frame is in the map: by its box, the
// map's list being the later frame's), or never (the next one then shows a gap and everything is
// forgotten). The frames delivered late or never toggle a voxel near the viewpoints, the others one far
// beyond their reach, which forgets nothing. After each delivery the cache gives what sampling anew gives.
TEST(Viewpoints, CacheFollowsUpdatesDeliveredLateOrAfterAMissedOne) {
  ViewpointConfig cfg = testConfig();
  cfg.min_visible = 1;
  cfg.height_offsets = {0.0};
  const double z_min = 0.4, z_max = 1.4;
  World w(Index3(100, 40, 20));  // 10 m long: the far end lies beyond the viewpoints' reach
  const Index3 hole(20, 20, 9);
  w.set(hole, hole, VoxelState::kUnknown);
  const Frontier f = frontierOf(w);
  go_feap::planning::ViewpointCache cache;
  ASSERT_FALSE(cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg).empty());
  Rng rng(23);
  const double r = *std::max_element(cfg.ring_radii.begin(), cfg.ring_radii.end());
  const int n_angles = static_cast<int>(std::lround(2.0 * kPi / cfg.angular_step));
  std::uint64_t last = 0;
  std::optional<go_feap::frontier::MapUpdateNote> held;
  Index3 late_voxel = Index3::Zero();
  int compared = 0, moved = 0;
  for (std::uint64_t frame = 1; frame <= 400; ++frame) {
    // A voxel within the clearance (and a voxel) of a candidate position on the outer ring, toggled.
    const double theta = 2.0 * kPi * rng(0, n_angles - 1) / n_angles, d = cfg.clearance + kRes;
    const bool near = frame % 2 == 0;  // the frames delivered late or never
    const Vec3 p = near ? Vec3(Vec3(f.average.x() + r * std::cos(theta), f.average.y() + r * std::sin(theta), f.average.z()) +
                               Vec3(rng.uniform(-d, d), rng.uniform(-d, d), rng.uniform(-d, d)))
                        : Vec3(rng.uniform(7.0, 9.9), rng.uniform(0.0, 3.9), rng.uniform(0.0, 1.9));
    // The frame never delivered toggles back what the late one toggled: unheard, it leaves the cache short
    // of a viewpoint that sampling anew finds again.
    const Index3 idx = frame % 4 == 0 ? late_voxel : w.geo().coordToIndex(p);
    if (frame % 4 == 2) late_voxel = idx;
    std::vector<std::size_t> changed;
    go_feap::frontier::MapUpdateNote note;
    note.sequence = frame;
    if (w.geo().inside(idx) && (idx - hole).cwiseAbs().maxCoeff() > 1) {
      const std::vector<Viewpoint> before = sampleViewpoints(f, w.map(), w.esdf(), z_min, z_max, cfg);
      w.set(idx, idx, w.map().state(idx) == VoxelState::kOccupied ? VoxelState::kFree : VoxelState::kOccupied);
      const std::vector<Viewpoint> after = sampleViewpoints(f, w.map(), w.esdf(), z_min, z_max, cfg);
      moved += before.size() != after.size() ||
               !std::equal(before.begin(), before.end(), after.begin(),
                           [](const Viewpoint& a, const Viewpoint& b) { return a.position == b.position; });
      changed.push_back(w.geo().linear(idx));
      note.changed_voxels = 1;
      note.changed_min = w.geo().origin() + idx.cast<double>() * kRes;
      note.changed_max = note.changed_min + Vec3::Constant(kRes);
    }
    auto deliver = [&](const go_feap::frontier::MapUpdateNote& n) {
      cache.forgetFor(n, last, frame, w.geo(), changed);
      last = n.sequence;
    };
    switch (frame % 4) {
      case 1: deliver(note); break;
      case 2: held = note; break;
      case 3: deliver(*held), deliver(note); break;
      default: break;  // missed
    }
    if (frame % 4 == 2 || frame % 4 == 0) continue;  // the map has a change the cache has not heard of (yet)
    const std::vector<Viewpoint> want = sampleViewpoints(f, w.map(), w.esdf(), z_min, z_max, cfg);
    const std::vector<Viewpoint> have = cache.get(f, w.map(), w.esdf(), z_min, z_max, cfg);
    ++compared;
    ASSERT_EQ(have.size(), want.size()) << "frame " << frame;
    for (std::size_t i = 0; i < want.size(); ++i) {
      ASSERT_EQ(have[i].position, want[i].position) << "frame " << frame;
      ASSERT_EQ(have[i].yaw, want[i].yaw) << "frame " << frame;
      ASSERT_EQ(have[i].visible_cells, want[i].visible_cells) << "frame " << frame;
    }
  }
  EXPECT_EQ(compared, 200);
  EXPECT_GE(moved, 20) << "too few toggles changed the viewpoints for the test to tell";
}

// A target whose frontier was seen on the way is dropped however long it has been kept: assessTarget
// counts the cells still visible from it after commit_time too, and decideTarget switches on that even
// when the proposal is costlier than the rest of the way to the target.
TEST(Viewpoints, TargetSeenOutIsDroppedAfterTheCommitment) {
  const ViewpointConfig cfg = testConfig();
  World w(Index3(40, 40, 20));
  w.set(Index3(25, 15, 5), Index3(30, 25, 15), VoxelState::kUnknown);
  const Frontier f = frontierOf(w);
  ASSERT_GE(f.cells.size(), 50u);
  const std::vector<Viewpoint> vps = sampleViewpoints(f, w.map(), w.esdf(), 0.5, 1.5, cfg);
  ASSERT_FALSE(vps.empty());
  const Viewpoint& target = vps.front();
  go_feap::planning::LocalPlannerConfig local;
  local.commit_time = 1.5;
  const Vec3 vehicle = target.position + Vec3(0.6, 0.0, 0.0);  // on the way, moving
  const double extent = 2.0;
  // Long after the commitment, with the frontier still there: its cells are counted (up to min_visible).
  auto current = go_feap::planning::assessTarget(target, 0.0, vehicle, target.yaw, 1.0, 0.0, {f}, w.map(),
                                                 cfg, extent, local);
  EXPECT_FALSE(current.reached);
  EXPECT_EQ(current.remaining_visible, cfg.min_visible);
  Viewpoint other;
  other.position = target.position + Vec3(0.0, 1.0, 0.0);
  other.yaw = target.yaw + 1.0;
  // The proposal is costlier to reach than the rest of the way to the target.
  auto costlier = [&](const Viewpoint& v) { return (v.position - target.position).norm() < 1e-9 ? 1.0 : 2.0; };
  using go_feap::planning::TargetDecision;
  EXPECT_EQ(go_feap::planning::decideTarget(&current, other, costlier, 100.0, cfg.min_visible, local),
            TargetDecision::kKeep);
  // The frontier is gone (seen on the way): nothing is left to see there, so the target goes.
  current = go_feap::planning::assessTarget(target, 0.0, vehicle, target.yaw, 1.0, 0.0, {}, w.map(), cfg,
                                            extent, local);
  EXPECT_EQ(current.remaining_visible, 0);
  EXPECT_EQ(go_feap::planning::decideTarget(&current, other, costlier, 100.0, cfg.min_visible, local),
            TargetDecision::kSwitch);
  // Reached (close, facing it, slow): the count decides nothing and is not made.
  current = go_feap::planning::assessTarget(target, 0.0, target.position, target.yaw, 0.0, 0.0, {}, w.map(),
                                            cfg, extent, local);
  EXPECT_TRUE(current.reached);
  EXPECT_TRUE(current.settled);
  EXPECT_EQ(current.remaining_visible, cfg.min_visible);
}

// The camera is settled when it is level or the vehicle at rest: tilted while braking into the
// viewpoint it is not (decideTarget() then keeps the target instead of booking a failed attempt), and
// tilted while hovering (in wind) it is, or no verdict would ever come.
TEST(Viewpoints, ReachedTargetIsJudgedOnlyWithTheCameraSettled) {
  using go_feap::planning::tiltOf;
  EXPECT_NEAR(tiltOf(Eigen::Quaterniond::Identity()), 0.0, 1e-12);
  EXPECT_NEAR(tiltOf(Eigen::Quaterniond(Eigen::AngleAxisd(1.2, Vec3::UnitZ()))), 0.0, 1e-12);  // heading only
  const Eigen::Quaterniond pitched(Eigen::AngleAxisd(0.19, Vec3::UnitY()));
  EXPECT_NEAR(tiltOf(pitched), 0.19, 1e-12);
  // Roll and pitch combine: the body's z axis is (sin p cos r, -sin r, cos p cos r).
  const double roll = 0.1, pitch = -0.15;
  const Eigen::Quaterniond tilted = Eigen::AngleAxisd(0.7, Vec3::UnitZ()) *
                                    Eigen::AngleAxisd(pitch, Vec3::UnitY()) *
                                    Eigen::AngleAxisd(roll, Vec3::UnitX());
  EXPECT_NEAR(tiltOf(tilted), std::acos(std::cos(pitch) * std::cos(roll)), 1e-12);
  EXPECT_NEAR(tiltOf(Eigen::Quaterniond(2.0 * pitched.coeffs())), 0.19, 1e-12);  // not unit: normalised
  EXPECT_TRUE(std::isnan(tiltOf(Eigen::Quaterniond(0.0, 0.0, 0.0, 0.0))));

  const ViewpointConfig cfg = testConfig();
  World w(Index3(20, 20, 10));
  go_feap::planning::LocalPlannerConfig local;
  local.settled_tilt = 0.05;
  local.settled_speed = 0.1;
  Viewpoint target;
  target.position = Vec3(1.0, 1.0, 0.5);
  target.yaw = 0.3;
  auto assess = [&](double speed, double tilt) {
    return go_feap::planning::assessTarget(target, 0.0, target.position, target.yaw, speed, tilt, {}, w.map(),
                                           cfg, 2.0, local);
  };
  // The commitment's start is the one given (the callers' time of choosing the target), not 0: a target
  // chosen at 7 s is kept at 7.5 s against a quicker proposal.
  local.commit_time = 1.5;
  const auto chosen = go_feap::planning::assessTarget(target, 7.0, target.position + Vec3(1.0, 0.0, 0.0), target.yaw,
                                                      1.0, 0.0, {}, w.map(), cfg, 2.0, local);
  EXPECT_EQ(chosen.committed_at, 7.0);
  go_feap::planning::CurrentTarget seeing = chosen;
  seeing.remaining_visible = cfg.min_visible;
  Viewpoint other = target;
  other.position.y() += 1.0;
  other.yaw += 1.0;
  const auto quicker_other = [&](const Viewpoint& v) { return v.position == other.position ? 0.5 : 1.0; };
  EXPECT_EQ(go_feap::planning::decideTarget(&seeing, other, quicker_other, 7.5, cfg.min_visible, local),
            go_feap::planning::TargetDecision::kKeep);
  EXPECT_EQ(go_feap::planning::decideTarget(&seeing, other, quicker_other, 8.5, cfg.min_visible, local),
            go_feap::planning::TargetDecision::kSwitchQuicker);
  const auto braking = assess(0.5, 0.19);
  EXPECT_TRUE(braking.reached);
  EXPECT_FALSE(braking.settled);
  EXPECT_TRUE(assess(0.5, 0.04).settled);   // level enough, still moving
  EXPECT_TRUE(assess(0.05, 0.19).settled);  // at rest, tilted (holding against wind)
  EXPECT_FALSE(assess(0.1, 0.05).settled);  // both limits are strict
  using go_feap::planning::TargetDecision;
  auto cost = [](const Viewpoint&) { return 1.0; };
  EXPECT_EQ(go_feap::planning::decideTarget(&braking, target, cost, 10.0, cfg.min_visible, local),
            TargetDecision::kKeep);
  const auto at_rest = assess(0.05, 0.19);
  EXPECT_EQ(go_feap::planning::decideTarget(&at_rest, target, cost, 10.0, cfg.min_visible, local),
            TargetDecision::kReachedInVain);
}

// Targets are compared by the time to reach them along a path: behind a wall, a target as near as
// another in a straight line costs the way round (pathCost() is edgeCost() over pathDistance()), so the
// hysteresis keeps the target in front.
TEST(Viewpoints, TargetsAreComparedByPathNotStraightLine) {
  World w(Index3(40, 40, 20));
  // A wall across x = 2.0 m from y = 0 to 3.0 m, full height: the way round goes past y = 3.0 m.
  w.set(Index3(20, 0, 0), Index3(21, 29, 19), VoxelState::kOccupied);
  go_feap::planning::AstarConfig ac;
  ac.clearance = 0.2;
  ac.unknown_is_free = true;
  ac.max_expansions = 100000;
  const go_feap::planning::Astar astar(w.map(), w.esdf(), ac);
  go_feap::planning::LocalPlannerConfig local;
  const Vec3 vehicle(1.5, 1.0, 1.0);
  Viewpoint behind, ahead;
  behind.position = Vec3(2.6, 1.0, 1.0);  // 1.1 m away through the wall
  ahead.position = Vec3(1.5, 2.5, 1.0);   // 1.5 m away, in the open
  behind.yaw = ahead.yaw = 0.0;
  const double straight_behind = go_feap::planning::edgeCost(1.1, 0.0, 0.0, local);
  const double cost_behind = go_feap::planning::pathCost(astar, vehicle, Vec3::Zero(), 0.0, behind, local);
  const double cost_ahead = go_feap::planning::pathCost(astar, vehicle, Vec3::Zero(), 0.0, ahead, local);
  const auto d = go_feap::planning::pathDistance(astar, vehicle, behind.position);
  ASSERT_FALSE(d.euclidean_fallback);
  EXPECT_DOUBLE_EQ(cost_behind, go_feap::planning::edgeCost(d.metres, 0.0, 0.0, local));
  // Round the wall's end at y = 3.0 m (plus clearance) and back: more than 2 x 2 m.
  EXPECT_GT(d.metres, 4.0);
  EXPECT_GT(cost_behind, 3.0 * straight_behind);
  EXPECT_NEAR(cost_ahead, 1.5 / local.v_max, 0.1);
  // A vehicle moving at 1 m/s along +x (away from `ahead`'s direction, +y, at a right angle) pays for
  // braking that speed at a_max on top of the path: 1 / 2 s more; moving towards it, nothing more.
  local.a_max = 2.0;
  EXPECT_NEAR(go_feap::planning::pathCost(astar, vehicle, Vec3(1, 0, 0), 0.0, ahead, local), cost_ahead + 0.5, 1e-9);
  EXPECT_NEAR(go_feap::planning::pathCost(astar, vehicle, Vec3(0, 1, 0), 0.0, ahead, local), cost_ahead, 1e-9);
  local.a_max = 0.0;
  // Kept past the commitment: the target in front is not dropped for the one behind the wall.
  go_feap::planning::CurrentTarget current;
  current.viewpoint = ahead;
  current.remaining_visible = 50;
  auto cost = [&](const Viewpoint& v) { return go_feap::planning::pathCost(astar, vehicle, Vec3::Zero(), 0.0, v, local); };
  EXPECT_EQ(go_feap::planning::decideTarget(&current, behind, cost, 100.0, 10, local),
            go_feap::planning::TargetDecision::kKeep);
}

// A pose reached max_visits times is exhausted and left out of the local plan: two viewpoints whose
// frontiers are never cleared (and get new ids every frame) cannot take turns for ever.
// One unknown block's frontier in an open room, and the local plan for it from a fixed pose.
struct OneFrontierPlan {
  OneFrontierPlan() : w(Index3(40, 40, 20)), f(unknownBlock(w)), astar(w.map(), w.esdf(), searchConfig()) {}
  static Frontier unknownBlock(World& world) {
    world.set(Index3(25, 15, 5), Index3(30, 25, 15), VoxelState::kUnknown);
    return frontierOf(world);
  }
  static go_feap::planning::AstarConfig searchConfig() {
    go_feap::planning::AstarConfig ac;
    ac.clearance = 0.2;
    ac.unknown_is_free = true;
    return ac;
  }
  /// From (0.8, 2.0, 1.0), heading 0, at `velocity`; the obstacle window empty unless one is given.
  go_feap::common::Result<go_feap::planning::LocalPlan> operator()(
      const go_feap::planning::LocalPlannerConfig& local, const go_feap::planning::VisitedViewpoints* visited,
      const go_feap::planning::ObstacleWindow* window = nullptr, const Vec3& velocity = Vec3::Zero()) const {
    const go_feap::planning::ObstacleWindow empty(local.window_size, local.clutter_threshold);
    return go_feap::planning::chooseLocalTarget(Vec3(0.8, 2.0, 1.0), velocity, 0.0, {f}, 0.5, 1.5, w.map(), w.esdf(),
                                                astar, window ? *window : empty, testConfig(), local, nullptr, visited);
  }
  World w;
  Frontier f;
  go_feap::planning::Astar astar;
};

// A frontier within d_near in a straight line is typed by its path length: with a wall between, the way round
// is longer than d_near and its viewpoints are ranked as an open frontier's (by visible cells); without the
// wall, as a near one's (by steering rate). Typed by the straight line it was near either way.
TEST(Viewpoints, AFrontierNearInALineButFarByPathIsTypedOpen) {
  OneFrontierPlan one;
  const Vec3 uav(0.8, 2.0, 1.0);
  const double straight = (one.f.average - uav).norm();
  one.w.set(Index3(15, 0, 0), Index3(16, 24, 19), VoxelState::kOccupied);  // x 1.5 .. 1.7 m, y up to 2.5 m
  const double round = pathDistance(one.astar, uav, one.f.average).metres;
  ASSERT_FALSE(pathDistance(one.astar, uav, one.f.average).euclidean_fallback);
  ASSERT_GT(round, straight + 0.3);
  go_feap::planning::LocalPlannerConfig local;
  local.d_near = 0.5 * (straight + round);
  local.top_k = 3;
  local.k_frontiers = 1;
  const go_feap::planning::ObstacleWindow calm(local.window_size, local.clutter_threshold);
  ASSERT_FALSE(calm.cluttered());
  auto expectLayer = [&](FrontierType type, const char* what,
                         const go_feap::planning::ObstacleWindow* window = nullptr) {
    SCOPED_TRACE(what);
    const auto plan = one(local, nullptr, window);
    ASSERT_TRUE(plan) << plan.message();
    const auto sampled = sampleViewpoints(one.f, one.w.map(), one.w.esdf(), 0.5, 1.5, testConfig());
    const auto expected = go_feap::planning::filterViewpoints(sampled, type, uav, 0.0, local);
    const auto other = go_feap::planning::filterViewpoints(
        sampled, type == FrontierType::kOpen ? FrontierType::kNearOrCluttered : FrontierType::kOpen, uav, 0.0, local);
    ASSERT_EQ(plan->layers.size(), 1u);
    ASSERT_EQ(plan->layers[0].size(), expected.size());
    bool differs = other.size() != expected.size();
    for (std::size_t i = 0; i < expected.size(); ++i) {
      EXPECT_EQ(plan->layers[0][i].position, expected[i].position) << i;
      EXPECT_EQ(plan->layers[0][i].yaw, expected[i].yaw) << i;
      differs = differs || (i < other.size() && other[i].position != expected[i].position);
    }
    EXPECT_TRUE(differs) << "the two rankings agree here: the test cannot tell the types apart";
  };
  expectLayer(FrontierType::kOpen, "with the wall");
  // Far by path, but in clutter (the obstacle window's mean above its threshold): near-or-cluttered.
  go_feap::planning::ObstacleWindow clutter(local.window_size, local.clutter_threshold);
  for (int k = 0; k < local.window_size; ++k) clutter.push(0.9);
  ASSERT_TRUE(clutter.cluttered());
  expectLayer(FrontierType::kNearOrCluttered, "with the wall, in clutter", &clutter);
  one.w.set(Index3(15, 0, 0), Index3(16, 24, 19), VoxelState::kFree);
  ASSERT_LT(pathDistance(one.astar, uav, one.f.average).metres, local.d_near);
  expectLayer(FrontierType::kNearOrCluttered, "without it");
}

// The vehicle's velocity reaches the plan's first leg: moving away from the frontier at 2 m/s with a_max 2,
// the plan costs what startCost() gives for the best of its viewpoints (the Euclidean legs of the DAG), at
// least a second more than from rest.
TEST(Viewpoints, TheLocalPlanPricesTheFirstLegFromTheVehiclesVelocity) {
  OneFrontierPlan one;
  go_feap::planning::LocalPlannerConfig local;
  local.k_frontiers = 1;
  local.a_max = 2.0;
  const Vec3 uav(0.8, 2.0, 1.0), away(-2.0, 0.0, 0.0);
  ASSERT_GT(one.f.average.x(), uav.x() + 1.0);  // the frontier lies ahead in +x
  const auto moving = one(local, nullptr, nullptr, away);
  const auto resting = one(local, nullptr);
  ASSERT_TRUE(moving) << moving.message();
  ASSERT_TRUE(resting) << resting.message();
  ASSERT_EQ(moving->layers.size(), 1u);
  double best = INFINITY;
  for (const Viewpoint& v : moving->layers[0])
    best = std::min(best, go_feap::planning::startCost(uav, away, 0.0, v, (v.position - uav).norm(), local));
  EXPECT_NEAR(moving->cost, best, 1e-9);
  EXPECT_GT(moving->cost, resting->cost + 1.0);
}

// Frontiers without a viewpoint (too small to be seen from anywhere) take no layer of the DAG: with
// k_frontiers 1, a tour that begins with one is planned to the next frontier.
TEST(Viewpoints, FrontiersWithoutViewpointsTakeNoLayer) {
  OneFrontierPlan one;
  Frontier tiny;
  tiny.id = 99;
  tiny.cells = {Index3(5, 5, 10), Index3(6, 5, 10)};  // 2 cells, min_visible 5
  for (const Index3& c : tiny.cells) tiny.average += one.w.geo().indexToCoord(c) / 2.0;
  ASSERT_TRUE(sampleViewpoints(tiny, one.w.map(), one.w.esdf(), 0.5, 1.5, testConfig()).empty());
  go_feap::planning::LocalPlannerConfig local;
  local.k_frontiers = 1;
  const go_feap::planning::ObstacleWindow window(local.window_size, local.clutter_threshold);
  const auto plan = go_feap::planning::chooseLocalTarget(Vec3(0.8, 2.0, 1.0), Vec3::Zero(), 0.0, {tiny, one.f}, 0.5,
                                                         1.5, one.w.map(), one.w.esdf(), one.astar, window,
                                                         testConfig(), local);
  ASSERT_TRUE(plan) << plan.message();
  EXPECT_EQ(plan->frontier_ids, std::vector<unsigned>{one.f.id});
  EXPECT_EQ(plan->layers.size(), 1u);
}

// What is left to see from a target counts the cells of every frontier whose average lies within the sensor
// range plus the cluster extent: a long frontier whose average is beyond the range still has cells in it. A
// line of frontier cells 1.55 .. 4.05 m ahead (average 2.8 m, range 2.5 m): its cells within range count
// (up to min_visible); with no extent allowed for, none.
TEST(Viewpoints, RemainingVisibleCountsFrontiersWhoseAverageLiesBeyondTheRange) {
  World w(Index3(60, 40, 20));
  Frontier f;
  for (int x = 20; x <= 45; ++x) f.cells.push_back(Index3(x, 20, 10));
  for (const Index3& c : f.cells) f.average += w.geo().indexToCoord(c);
  f.average /= static_cast<double>(f.cells.size());
  const ViewpointConfig cfg = testConfig();
  const Viewpoint target{Vec3(0.5, 2.05, 1.05), 0.0, 0};
  ASSERT_GT((f.average - target.position).norm(), cfg.sensor_range);
  const int in_view = countVisible(target.position, target.yaw, f.cells, w.map(), cfg);
  ASSERT_GE(in_view, cfg.min_visible);  // the cells within range
  EXPECT_EQ(go_feap::planning::remainingVisible(target, {f}, w.map(), cfg, 2.0), cfg.min_visible);
  EXPECT_EQ(go_feap::planning::remainingVisible(target, {f}, w.map(), cfg, 0.0), 0);
  // Fewer cells in view than min_visible: their own count.
  Frontier few = f;
  few.cells.erase(few.cells.begin() + 2, few.cells.begin() + 12);  // 1.75 .. 2.65 m ahead gone: two left in range
  const int few_in_view = countVisible(target.position, target.yaw, few.cells, w.map(), cfg);
  ASSERT_LT(few_in_view, cfg.min_visible);
  ASSERT_GT(few_in_view, 0);
  few.average = Vec3::Zero();
  for (const Index3& c : few.cells) few.average += w.geo().indexToCoord(c);
  few.average /= static_cast<double>(few.cells.size());
  ASSERT_GT((few.average - target.position).norm(), cfg.sensor_range);
  EXPECT_EQ(go_feap::planning::remainingVisible(target, {few}, w.map(), cfg, 2.0), few_in_view);
}

TEST(Viewpoints, PosesReachedMaxVisitsTimesAreNoLongerProposed) {
  go_feap::planning::LocalPlannerConfig local;
  local.max_visits = 2;
  const OneFrontierPlan one;
  auto plan = [&](const go_feap::planning::VisitedViewpoints* visited) { return one(local, visited); };
  const auto first = plan(nullptr);
  ASSERT_TRUE(first) << first.message();
  const Viewpoint chosen = first->path.front();
  go_feap::planning::VisitedViewpoints visited;
  // Once: not yet exhausted, the same viewpoint comes back.
  visited.add(chosen, local);
  EXPECT_FALSE(visited.exhausted(chosen, local));
  auto again = plan(&visited);
  ASSERT_TRUE(again) << again.message();
  EXPECT_LT((again->path.front().position - chosen.position).norm(), 1e-9);
  // A nearby pose (same target) counts for it; then the pose is exhausted and another is chosen.
  Viewpoint nearby = chosen;
  nearby.position.x() += 0.5 * local.same_target_distance;
  visited.add(nearby, local);
  EXPECT_EQ(visited.size(), 1u);
  EXPECT_TRUE(visited.exhausted(chosen, local));
  Viewpoint turned = chosen;
  turned.yaw += 2.0 * local.same_target_yaw;
  EXPECT_FALSE(visited.exhausted(turned, local));
  const auto other = plan(&visited);
  ASSERT_TRUE(other) << other.message();
  EXPECT_FALSE(visited.exhausted(other->path.front(), local));
  EXPECT_GT((other->path.front().position - chosen.position).norm() +
                std::abs(go_feap::planning::wrapAngle(other->path.front().yaw - chosen.yaw)),
            0.1);
}

// stepTarget, the rule the LocalPlanner nodelet and go_feap_bench share: a kept target counts nothing; one
// replaced after it was reached counts a visit, and its replacement a choice of its place; a target reached
// in vain counts the visit but no choice; the first target (none to replace) no choice. max_choices choices
// of one place exhaust it, and the step that does says so.
TEST(Viewpoints, StepTargetCountsVisitsAndChoicesAsTheNodeletAndBenchDo) {
  go_feap::planning::LocalPlannerConfig local;
  local.max_choices = 3;
  local.max_visits = 2;
  local.commit_time = 1.5;
  const int min_visible = 5;
  Viewpoint a, b;
  a.position = Vec3(1.0, 1.0, 1.0), a.yaw = 0.0;
  b.position = Vec3(5.0, 1.0, 1.0), b.yaw = 0.0;
  auto cost = [](const Viewpoint&) { return 1.0; };
  go_feap::planning::VisitedViewpoints visited;
  using go_feap::planning::TargetDecision;
  // The first target: nothing to replace, no choice counted.
  auto step = go_feap::planning::stepTarget(nullptr, a, cost, 0.0, min_visible, local, visited);
  EXPECT_EQ(step.decision, TargetDecision::kSwitch);
  EXPECT_FALSE(step.exhausted);
  // Kept (committed 0.5 s ago, much left to see): nothing counted.
  go_feap::planning::CurrentTarget current;
  current.viewpoint = a, current.committed_at = 0.0, current.remaining_visible = min_visible;
  step = go_feap::planning::stepTarget(&current, b, cost, 0.5, min_visible, local, visited);
  EXPECT_EQ(step.decision, TargetDecision::kKeep);
  EXPECT_EQ(visited.size(), 0u);
  // a reached, b proposed: a's visit counts, and b's choice.
  current.reached = true;
  step = go_feap::planning::stepTarget(&current, b, cost, 2.0, min_visible, local, visited);
  EXPECT_EQ(step.decision, TargetDecision::kSwitch);
  EXPECT_EQ(visited.size(), 1u);
  // b reached in vain (proposed again once there, the camera settled): the visit counts, no choice.
  current.viewpoint = b, current.committed_at = 2.0, current.reached = true;
  step = go_feap::planning::stepTarget(&current, b, cost, 4.0, min_visible, local, visited);
  EXPECT_EQ(step.decision, TargetDecision::kReachedInVain);
  EXPECT_EQ(visited.size(), 2u);
  EXPECT_FALSE(step.exhausted);
  // b chosen twice more to replace a target not reached (seen out): the third choice in the window exhausts it.
  current.viewpoint = a, current.reached = false, current.remaining_visible = 0;
  step = go_feap::planning::stepTarget(&current, b, cost, 6.0, min_visible, local, visited);
  EXPECT_EQ(step.decision, TargetDecision::kSwitch);
  EXPECT_FALSE(step.exhausted);
  EXPECT_FALSE(visited.exhausted(b, local));
  step = go_feap::planning::stepTarget(&current, b, cost, 8.0, min_visible, local, visited);
  EXPECT_TRUE(step.exhausted);
  EXPECT_TRUE(visited.exhausted(b, local));
  EXPECT_EQ(visited.size(), 2u);  // no visit counted for targets not reached
  // a chosen twice to replace b: two choices of a within the window, its first (no target replaced) not one.
  current.viewpoint = b;
  for (const double t : {10.0, 12.0}) {
    step = go_feap::planning::stepTarget(&current, a, cost, t, min_visible, local, visited);
    EXPECT_EQ(step.decision, TargetDecision::kSwitch);
  }
  EXPECT_FALSE(step.exhausted);
  EXPECT_FALSE(visited.exhausted(a, local));
}

// A place chosen max_choices times within choice_window is exhausted, reached or not, at any height within
// choice_radius and heading within same_target_yaw, and left out of the local plan: two viewpoints whose
// frontier regrows with a new id on every pass (so that neither is reached nor its frontier failed) cannot
// take turns for ever. Choices further apart in time than the window, or of other places, do not add up.
TEST(Viewpoints, PlacesChosenMaxChoicesTimesWithinTheWindowAreNoLongerProposed) {
  go_feap::planning::LocalPlannerConfig local;
  local.max_choices = 3;
  local.choice_window = 60.0;
  local.choice_radius = 1.0;
  const OneFrontierPlan one;
  auto plan = [&](const go_feap::planning::VisitedViewpoints* visited) { return one(local, visited); };
  const auto first = plan(nullptr);
  ASSERT_TRUE(first) << first.message();
  const Viewpoint a = first->path.front();
  Viewpoint higher = a, elsewhere = a, turned = a;
  higher.position.z() += 0.8;                      // the same place, offered at another height
  elsewhere.position.x() += 2.0 * local.choice_radius;  // the other end of a ping-pong
  turned.yaw += 2.0 * local.same_target_yaw;
  go_feap::planning::VisitedViewpoints visited;
  EXPECT_FALSE(visited.choose(a, 0.0, local));
  EXPECT_FALSE(visited.choose(elsewhere, 3.0, local));
  EXPECT_FALSE(visited.choose(higher, 6.0, local));
  EXPECT_FALSE(visited.choose(elsewhere, 9.0, local));
  EXPECT_FALSE(visited.exhausted(a, local));
  auto again = plan(&visited);
  ASSERT_TRUE(again) << again.message();
  EXPECT_LT((again->path.front().position - a.position).norm(), 1e-9);
  EXPECT_TRUE(visited.choose(a, 12.0, local));  // the third choice of this place in 12 s
  EXPECT_TRUE(visited.exhausted(a, local));
  EXPECT_TRUE(visited.exhausted(higher, local));
  EXPECT_FALSE(visited.exhausted(turned, local));
  EXPECT_FALSE(visited.exhausted(elsewhere, local));
  EXPECT_EQ(visited.size(), 0u);  // nothing was reached
  const auto other = plan(&visited);
  ASSERT_TRUE(other) << other.message();
  EXPECT_FALSE(visited.exhausted(other->path.front(), local));
  EXPECT_GT((other->path.front().position - a.position).norm() +
                std::abs(go_feap::planning::wrapAngle(other->path.front().yaw - a.yaw)),
            0.1);
  EXPECT_TRUE(visited.exhausted(a, local));  // for good: long after the window
  EXPECT_FALSE(visited.choose(turned, 1000.0, local));

  // Choices from before the clock went back (a bag played again) do not add up with those after it.
  go_feap::planning::VisitedViewpoints replayed;
  EXPECT_FALSE(replayed.choose(a, 100.0, local));
  EXPECT_FALSE(replayed.choose(a, 101.0, local));
  EXPECT_FALSE(replayed.choose(a, 5.0, local));
  EXPECT_FALSE(replayed.choose(a, 6.0, local));
  EXPECT_FALSE(replayed.exhausted(a, local));
  EXPECT_TRUE(replayed.choose(a, 7.0, local));  // the third since the clock went back

  // Choices a window apart never add up; with max_choices 0 nothing is ever exhausted.
  go_feap::planning::VisitedViewpoints spread;
  for (int k = 0; k < 5; ++k) EXPECT_FALSE(spread.choose(a, k * (local.choice_window + 1.0), local)) << k;
  EXPECT_FALSE(spread.exhausted(a, local));
  local.max_choices = 0;
  go_feap::planning::VisitedViewpoints off;
  for (int k = 0; k < 5; ++k) EXPECT_FALSE(off.choose(a, k, local)) << k;
  EXPECT_FALSE(off.exhausted(a, local));
}
