#include "go_feap/planning/astar.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace go_feap::planning {

using common::GridGeometry;
using common::Status;
using map::VoxelState;

namespace {

const double kSqrt2 = std::sqrt(2.0);
const double kSqrt3 = std::sqrt(3.0);

// Voxel distances within this fraction of a voxel of the clearance count as equal to it, so that a
// clearance given as a multiple of the resolution is not undone by rounding.
constexpr double kClearanceRounding = 1e-6;
// Crossing times (in units of the segment) closer than this are one crossing of an edge or corner.
constexpr double kCrossingTie = 1e-9;
constexpr std::size_t kInitialBrickTableBits = 8;
constexpr int kMaxExpansions = 50000000;
constexpr int kMaxStride = 8;

// The 26 neighbour offsets, the move type of each (number of axes changed minus one), and the
// neighbours a move to it sweeps past: those whose offset takes, on every axis, either 0 or the move's
// component (for a diagonal move the voxels sharing the edge or corner it passes through, and itself).
struct Neighbourhood {
  std::array<Index3, 26> offset;
  std::array<int, 26> type;
  std::array<std::uint32_t, 26> swept;
  Neighbourhood() {
    int i = 0;
    for (int z = -1; z <= 1; ++z)
      for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x) {
          if (x == 0 && y == 0 && z == 0) continue;
          offset[i] = Index3(x, y, z);
          type[i] = std::abs(x) + std::abs(y) + std::abs(z) - 1;
          ++i;
        }
    for (int k = 0; k < 26; ++k) {
      swept[k] = 0;
      for (int j = 0; j < 26; ++j) {
        bool inside = true;
        for (int a = 0; a < 3; ++a) inside &= offset[j][a] == 0 || offset[j][a] == offset[k][a];
        if (inside) swept[k] |= std::uint32_t{1} << j;
      }
    }
  }
};

const Neighbourhood& neighbourhood() {
  static const Neighbourhood kNeighbourhood;
  return kNeighbourhood;
}

// Cost in voxels of a path made of m[0] axis, m[1] face-diagonal and m[2] space-diagonal moves.
double movesCost(const std::int32_t m[3]) { return m[0] + m[1] * kSqrt2 + m[2] * kSqrt3; }

// The cheapest obstacle-free move counts from a to b: as many space diagonals as the smallest
// displacement, then face diagonals, then axis moves.
// On a lattice of step `stride` (a and b on it) the counts are of lattice moves.
void octileMoves(const Index3& a, const Index3& b, std::int32_t m[3], int stride = 1) {
  std::array<int, 3> d = {std::abs(b.x() - a.x()), std::abs(b.y() - a.y()), std::abs(b.z() - a.z())};
  if (stride > 1)
    for (int& v : d) v /= stride;
  std::sort(d.begin(), d.end());
  m[2] = d[0];
  m[1] = d[1] - d[0];
  m[0] = d[2] - d[1];
}

// Open list order: by f, then by h, so that among equal-cost candidates the one nearer the goal comes
// first.
template <typename Entry>
bool before(const Entry& a, const Entry& b) {
  return a.f < b.f || (a.f == b.f && a.h < b.h);
}

double pathLength(const std::vector<Vec3>& path) {
  double length = 0.0;
  for (std::size_t i = 1; i < path.size(); ++i) length += (path[i] - path[i - 1]).norm();
  return length;
}

bool sameGeometry(const GridGeometry& a, const GridGeometry& b) {
  const double res = a.resolution();
  return a.dims() == b.dims() && std::abs(a.resolution() - b.resolution()) <= 1e-9 * res &&
         (a.origin() - b.origin()).cwiseAbs().maxCoeff() <= 1e-6 * res;
}

}  // namespace

Status AstarConfig::validate() const {
  auto err = [this](const char* key, const char* why) { return Status::Error(name + ": " + key + " " + why); };
  if (!(clearance >= 0.0 && std::isfinite(clearance))) return err("clearance", "must be finite and >= 0");
  // Each expansion adds at most 26 nodes, indexed by int32.
  if (max_expansions < 1 || max_expansions > kMaxExpansions)
    return err("max_expansions", ("must be in [1, " + std::to_string(kMaxExpansions) + "]").c_str());
  if (probe_expansions < 0 || probe_expansions > kMaxExpansions)
    return err("probe_expansions", ("must be in [0, " + std::to_string(kMaxExpansions) + "]").c_str());
  if (!(known_radius >= 0.0 && known_radius <= clearance))
    return err("known_radius", "must be in [0, clearance]");
  if (!(tie_breaker >= 1.0 && std::isfinite(tie_breaker)))
    return err("tie_breaker", "must be finite and >= 1");
  if (stride < 1 || stride > kMaxStride)
    return err("stride", ("must be in [1, " + std::to_string(kMaxStride) + "]").c_str());
  return Status::Ok();
}

Status AstarConfig::validate(const map::EsdfConfig& esdf) const {
  if (Status s = validate(); !s) return s;
  if (clearance > esdf.max_distance)
    return Status::Error(name + ": clearance must be <= the ESDF's max_distance (" +
                         std::to_string(esdf.max_distance) + " m, where distances are truncated), got " +
                         std::to_string(clearance));
  return Status::Ok();
}

const char* toString(PathStatus s) {
  switch (s) {
    case PathStatus::kFound:
      return "found";
    case PathStatus::kStartBlocked:
      return "start_blocked";
    case PathStatus::kGoalBlocked:
      return "goal_blocked";
    case PathStatus::kNoPath:
      return "no_path";
    case PathStatus::kBudgetExceeded:
      return "budget_exceeded";
  }
  return "unknown";
}

Astar::Astar(const map::OccupancyMap& occupancy, const map::Esdf& esdf, const AstarConfig& config)
    : occupancy_(occupancy), esdf_(esdf), config_(config), geo_(occupancy.geometry()) {
  if (Status s = config.validate(esdf.config()); !s) throw std::invalid_argument(s.message());
  if (!sameGeometry(occupancy.geometry(), esdf.geometry()))
    throw std::invalid_argument("astar: the occupancy map and the ESDF must share one grid geometry");
  if (geo_.size() > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("astar: grids of 2^32 voxels or more are not supported");
  blocked_below_ = config.clearance - kClearanceRounding * geo_.resolution();
  brick_dims_ = (geo_.dims().array() + (kBrickEdge - 1)) / kBrickEdge;
  // known_clearance: the six voxels ceil(clearance) away along the axes and every voxel whose centre lies
  // within known_radius (the ball traversableWith() checks: a path the search vouches for passes that test
  // with any min_distance up to known_radius); the farthest first, where unseen space mostly begins.
  if (config.known_clearance) {
    const int n = std::max(1, static_cast<int>(std::ceil(config.clearance / geo_.resolution() - 1e-9)));
    const double r = config.known_radius / geo_.resolution();
    for (int dz = -n; dz <= n; ++dz)
      for (int dy = -n; dy <= n; ++dy)
        for (int dx = -n; dx <= n; ++dx) {
          const int d2 = dx * dx + dy * dy + dz * dz;
          const bool axis = d2 == n * n && (dx == 0) + (dy == 0) + (dz == 0) == 2;
          if (d2 > 0 && (d2 <= r * r || axis)) known_offsets_.emplace_back(dx, dy, dz);
        }
    std::stable_sort(known_offsets_.begin(), known_offsets_.end(),
                     [](const Index3& a, const Index3& b) { return a.squaredNorm() > b.squaredNorm(); });
  }
  const common::Aabb& box = occupancy.box();
  for (int a = 0; a < 3; ++a) {
    const double lo = box.min[a] + config.clearance, hi = box.max[a] - config.clearance;
    box_lo_[a] = static_cast<int>(std::ceil((lo - geo_.origin()[a]) / geo_.resolution() - 0.5 - 1e-9));
    box_hi_[a] = static_cast<int>(std::floor((hi - geo_.origin()[a]) / geo_.resolution() - 0.5 + 1e-9));
  }
}

bool Astar::traversable(const Index3& idx) const {
  return geo_.inside(idx) && traversable(idx, geo_.linear(idx));
}

bool Astar::traversableWith(const Index3& idx, double min_distance, bool* unseen) const {
  if (unseen) *unseen = false;
  if (!geo_.inside(idx)) return false;
  const Vec3 c = geo_.indexToCoord(idx);
  const common::Aabb& box = occupancy_.box();
  if ((c.array() < box.min.array() + min_distance).any() || (c.array() > box.max.array() - min_distance).any())
    return false;
  const VoxelState state = occupancy_.stateAt(geo_.linear(idx));
  if (state == VoxelState::kOccupied || !(esdf_.distance(idx) >= min_distance)) return false;
  // Clear of every mapped obstacle: what remains is whether the space is seen.
  bool seen = state != VoxelState::kUnknown || config_.unknown_is_free;
  if (seen && config_.known_clearance && !config_.unknown_is_free) {
    // Nothing unseen within min_distance either: an obstacle there would be that close to the vehicle.
    const double r = min_distance / geo_.resolution();
    const int n = static_cast<int>(std::floor(r));
    for (int dz = -n; dz <= n && seen; ++dz)
      for (int dy = -n; dy <= n && seen; ++dy)
        for (int dx = -n; dx <= n && seen; ++dx)
          seen = dx * dx + dy * dy + dz * dz > r * r ||
                 occupancy_.state(Index3(idx + Index3(dx, dy, dz))) != VoxelState::kUnknown;
  }
  if (unseen) *unseen = !seen;
  return seen;
}

bool Astar::traversable(const Index3& idx, std::size_t linear) const {
  if ((idx.array() < box_lo_.array()).any() || (idx.array() > box_hi_.array()).any()) return false;
  return freeAndKnown(idx, linear, true) && esdf_.distance(idx) >= blocked_below_;
}

bool Astar::traversableFrom(const Index3& idx, std::size_t linear, const Index3& start, int exempt2) const {
  return (idx - start).squaredNorm() <= exempt2 ? traversableNearStart(idx, linear) : traversable(idx, linear);
}

bool Astar::traversableNearStart(const Index3& idx, std::size_t linear) const {
  if ((idx.array() < box_lo_.array()).any() || (idx.array() > box_hi_.array()).any()) return false;
  return freeAndKnown(idx, linear, false) && esdf_.distance(idx) >= blocked_below_;
}

bool Astar::freeAndKnown(const Index3& idx, std::size_t linear, bool surroundings) const {
  const VoxelState state = occupancy_.stateAt(linear);
  if (state == VoxelState::kOccupied) return false;
  if (state == VoxelState::kUnknown && !config_.unknown_is_free) return false;
  if (surroundings)
    for (const Index3& offset : known_offsets_)
      if (occupancy_.state(Index3(idx + offset)) == VoxelState::kUnknown) return false;
  return true;
}

bool Astar::snap(const Vec3& p, double radius, Index3& out, bool near_start, const Index3* lattice) const {
  if (!p.allFinite() || !(radius >= 0.0)) return false;
  const int step = lattice ? config_.stride : 1;
  auto onLattice = [&](const Index3& idx) {
    if (step == 1) return true;
    for (int a = 0; a < 3; ++a)
      if ((idx[a] - (*lattice)[a]) % step != 0) return false;
    return true;
  };
  auto pass = [&](const Index3& idx) {
    return near_start ? geo_.inside(idx) && traversableNearStart(idx, geo_.linear(idx)) : traversable(idx);
  };
  if (geo_.bounds().contains(p)) {
    const Index3 own = geo_.coordToIndex(p);
    if (onLattice(own) && pass(own)) {
      out = own;
      return true;
    }
  }
  // Index range of the voxels whose centres can lie within the radius, clamped to the grid in doubles
  // before converting (p may be far outside).
  Index3 lo, hi;
  for (int a = 0; a < 3; ++a) {
    const double n = geo_.dims()[a];
    const double l = std::floor((p[a] - radius - geo_.origin()[a]) / geo_.resolution() - 0.5);
    const double h = std::ceil((p[a] + radius - geo_.origin()[a]) / geo_.resolution() - 0.5);
    lo[a] = static_cast<int>(std::clamp(l, 0.0, n));
    hi[a] = static_cast<int>(std::clamp(h, -1.0, n - 1.0));
    if (step > 1) lo[a] += (((*lattice)[a] - lo[a]) % step + step) % step;  // first lattice voxel
    if (lo[a] > hi[a]) return false;
  }
  const double r2 = radius * radius;
  double best = std::numeric_limits<double>::infinity();
  Index3 idx;
  for (idx.z() = lo.z(); idx.z() <= hi.z(); idx.z() += step)
    for (idx.y() = lo.y(); idx.y() <= hi.y(); idx.y() += step)
      for (idx.x() = lo.x(); idx.x() <= hi.x(); idx.x() += step) {
        const double d2 = (geo_.indexToCoord(idx) - p).squaredNorm();
        if (d2 <= r2 && d2 < best && pass(idx)) {
          best = d2;
          out = idx;
        }
      }
  return best <= r2;
}

bool Astar::segmentTraversable(const Vec3& a, const Vec3& b) const {
  return segmentPasses(a, b, [this](const Index3& v) { return traversable(v); });
}

template <typename Pass>
bool Astar::segmentPasses(const Vec3& a, const Vec3& b, const Pass& pass) const {
  if (!a.allFinite() || !b.allFinite()) return false;
  const GridGeometry& g = geo_;
  if (!g.bounds().contains(a) || !g.bounds().contains(b)) return false;
  const Vec3 pa = (a - g.origin()) / g.resolution(), pb = (b - g.origin()) / g.resolution();
  Index3 cur = pa.array().floor().cast<int>();
  const Index3 last = pb.array().floor().cast<int>();
  if (!pass(cur) || !pass(last)) return false;
  const Vec3 d = pb - pa;
  Index3 step, remaining;
  Vec3 t_max, t_delta;
  for (int i = 0; i < 3; ++i) {
    step[i] = d[i] > 0.0 ? 1 : -1;
    remaining[i] = std::abs(last[i] - cur[i]);
    if (remaining[i] == 0) {
      t_max[i] = t_delta[i] = std::numeric_limits<double>::infinity();
    } else {
      t_delta[i] = 1.0 / std::abs(d[i]);
      t_max[i] = (d[i] > 0.0 ? std::floor(pa[i]) + 1.0 - pa[i] : pa[i] - std::floor(pa[i])) * t_delta[i];
    }
  }
  // Walks the voxels in order of the boundary crossings; where the segment crosses an edge or a corner
  // (two or three crossings at once) every voxel around it is checked, not only the one a rounding
  // would pick.
  while ((remaining.array() > 0).any()) {
    double t = std::numeric_limits<double>::infinity();
    for (int i = 0; i < 3; ++i)
      if (remaining[i] > 0) t = std::min(t, t_max[i]);
    int axes[3], n = 0;
    for (int i = 0; i < 3; ++i)
      if (remaining[i] > 0 && t_max[i] <= t + kCrossingTie) axes[n++] = i;
    for (int mask = 1; mask < (1 << n); ++mask) {
      Index3 v = cur;
      for (int k = 0; k < n; ++k)
        if (mask & (1 << k)) v[axes[k]] += step[axes[k]];
      if (!pass(v)) return false;
    }
    for (int k = 0; k < n; ++k) {
      cur[axes[k]] += step[axes[k]];
      --remaining[axes[k]];
      t_max[axes[k]] += t_delta[axes[k]];
    }
  }
  return true;
}

bool Astar::moveClear(const Index3& a, const Index3& b, double esdf_a, const Index3& start, int exempt2) const {
  if (config_.unknown_is_free && !config_.known_clearance) {
    // Every voxel the segment touches has its centre within half a voxel diagonal of a point of it, and a
    // point at distance t from a lies at length - t from b: with distances 1-Lipschitz, every touched
    // voxel is at least (d_a + d_b - length) / 2 - sqrt(3) / 2 voxel from every obstacle. Truncated
    // distances are lower bounds too; one more voxel per end covers the ESDF's rare overestimates (a
    // slightly farther obstacle, see Esdf). Whatever this cannot prove goes to the exact walk.
    const double length = (b - a).cast<double>().norm() * geo_.resolution();
    const double slack = (kSqrt3 + 2.0) * geo_.resolution();
    if (esdf_a + esdf_.distance(b) > 2.0 * config_.clearance + length + slack) return true;
  }
  // The voxels near the start need not have known surroundings here either, or a vehicle that has only
  // looked ahead could not leave on a coarse lattice.
  return segmentPasses(geo_.indexToCoord(a), geo_.indexToCoord(b), [&](const Index3& v) {
    return geo_.inside(v) && traversableFrom(v, geo_.linear(v), start, exempt2);
  });
}

std::vector<Vec3> Astar::shorten(const std::vector<Vec3>& path) const {
  if (path.size() <= 2) return path;
  const std::size_t last = path.size() - 1;
  std::vector<Vec3> out{path.front()};
  std::size_t anchor = 0;
  while (anchor < last) {
    // Gallop ahead (1, 2, 4, ... points) while the straight segment stays traversable, then bisect
    // between the last point that passed and the first that failed: O(log n) segment tests per kept
    // point instead of one per path point.
    std::size_t good = anchor + 1, bad = path.size();
    for (std::size_t stride = 1; good < last; stride *= 2) {
      const std::size_t probe = std::min(good + stride, last);
      if (!segmentTraversable(path[anchor], path[probe])) {
        bad = probe;
        break;
      }
      good = probe;
    }
    while (bad < path.size() && bad - good > 1) {
      const std::size_t mid = good + (bad - good) / 2;
      (segmentTraversable(path[anchor], path[mid]) ? good : bad) = mid;
    }
    out.push_back(path[good]);
    anchor = good;
  }
  return out;
}

void Astar::resetScratch() const {
  if (brick_slots_.empty()) brick_slots_.assign(std::size_t{1} << kInitialBrickTableBits, BrickSlot{0, 0, 0});
  if (++search_stamp_ == 0) {  // wrapped: forget every old stamp
    for (BrickSlot& s : brick_slots_) s.stamp = 0;
    search_stamp_ = 1;
  }
  bricks_used_ = 0;
  nodes_.clear();
  open_.clear();
}

// The open list is a 4-ary min-heap (shallow, and a node's children share a cache line) with each node's
// position kept in the node, so that a cheaper route to an open node moves its entry up instead of adding
// a second one: the heap holds only the open nodes.
void Astar::heapUp(std::size_t i, const OpenEntry& e) const {
  while (i > 0) {
    const std::size_t parent = (i - 1) / 4;
    if (!before(e, open_[parent])) break;
    open_[i] = open_[parent];
    nodes_[open_[i].node].heap_pos = static_cast<std::int32_t>(i);
    i = parent;
  }
  open_[i] = e;
  nodes_[e.node].heap_pos = static_cast<std::int32_t>(i);
}

void Astar::heapPush(const OpenEntry& e) const {
  const std::int32_t pos = nodes_[e.node].heap_pos;
  if (pos >= 0) {
    heapUp(static_cast<std::size_t>(pos), e);  // the entry only ever gets cheaper
  } else {
    open_.push_back(e);
    heapUp(open_.size() - 1, e);
  }
}

std::int32_t Astar::heapPop() const {
  const std::int32_t top = open_.front().node;
  nodes_[top].heap_pos = -1;
  const OpenEntry last = open_.back();
  open_.pop_back();
  const std::size_t n = open_.size();
  if (n == 0) return top;
  std::size_t i = 0;
  for (;;) {
    const std::size_t first = 4 * i + 1;
    if (first >= n) break;
    std::size_t best = first;
    for (std::size_t c = first + 1; c < std::min(first + 4, n); ++c)
      if (before(open_[c], open_[best])) best = c;
    if (!before(open_[best], last)) break;
    open_[i] = open_[best];
    nodes_[open_[i].node].heap_pos = static_cast<std::int32_t>(i);
    i = best;
  }
  open_[i] = last;
  nodes_[last.node].heap_pos = static_cast<std::int32_t>(i);
  return top;
}

std::size_t Astar::brickSlot(std::uint32_t key) const {
  // Fibonacci hashing: the top bits of the product, as many as the table is long.
  const std::size_t mask = brick_slots_.size() - 1;
  const int shift = 64 - __builtin_ctzll(brick_slots_.size());
  std::size_t i = static_cast<std::size_t>((std::uint64_t{key} * 0x9E3779B97F4A7C15ull) >> shift);
  while (brick_slots_[i].stamp == search_stamp_ && brick_slots_[i].key != key) i = (i + 1) & mask;
  return i;
}

std::size_t Astar::brick(std::uint32_t key) const {
  std::size_t i = brickSlot(key);
  if (brick_slots_[i].stamp == search_stamp_) return std::size_t{brick_slots_[i].brick} * kBrickCells;
  const std::uint32_t b = bricks_used_++;
  const std::size_t first = std::size_t{b} * kBrickCells;
  if (cells_.size() < first + kBrickCells) cells_.resize(first + kBrickCells);
  std::fill_n(cells_.begin() + first, kBrickCells, kCellUnseen);
  brick_slots_[i] = BrickSlot{search_stamp_, key, b};
  if (2 * std::size_t{bricks_used_} > brick_slots_.size()) {
    std::vector<BrickSlot> old;
    for (const BrickSlot& s : brick_slots_)
      if (s.stamp == search_stamp_) old.push_back(s);
    brick_slots_.assign(brick_slots_.size() * 2, BrickSlot{0, 0, 0});
    search_stamp_ = 1;
    for (BrickSlot s : old) {
      s.stamp = search_stamp_;
      brick_slots_[brickSlot(s.key)] = s;
    }
  }
  return first;
}

std::int32_t Astar::run(const Index3& s, const Index3& g, const Index3& start, double snap_radius, int budget,
                       PathResult& result, std::int32_t& nearest) const {
  const Neighbourhood& nb = neighbourhood();
  // Voxels (in squared voxel units) within snap_radius of the start: no known-surroundings rule there.
  const double exempt_voxels = snap_radius / geo_.resolution();
  const int exempt2 = static_cast<int>(std::floor(exempt_voxels * exempt_voxels));
  const double w_extra = config_.tie_breaker - 1.0;

  // f = cost + heuristic is computed from summed move counts so that equal costs give bit-identical f
  // (h only breaks those ties, so single precision is enough for it).
  const int stride = config_.stride;
  // Lattice coordinates of a voxel on the run's lattice (the one through s): the scratch is indexed by
  // them, so a coarse lattice fills its bricks densely.
  Index3 residue = Index3::Zero();
  for (int a = 0; a < 3; ++a) residue[a] = s[a] % stride;
  auto lattice = [&](const Index3& q) { return stride == 1 ? q : Index3((q - residue) / stride); };
  auto open = [&](std::int32_t n) {
    std::int32_t h[3], f[3];
    octileMoves(nodes_[n].idx, g, h, stride);
    for (int i = 0; i < 3; ++i) f[i] = nodes_[n].moves[i] + h[i];
    const double hc = movesCost(h);
    heapPush(OpenEntry{movesCost(f) + w_extra * hc, static_cast<float>(hc), n});
  };
  // Cell of a voxel inside the grid; neighbouring voxels mostly share a brick, so the last one is kept.
  std::uint32_t cached_key = std::numeric_limits<std::uint32_t>::max();
  std::size_t cached_first = 0;
  auto cellOf = [&](const Index3& voxel) {
    const Index3 q = lattice(voxel);
    const auto key = static_cast<std::uint32_t>(
        (q.x() >> kBrickBits) + (static_cast<std::size_t>(q.y() >> kBrickBits) +
                                 static_cast<std::size_t>(q.z() >> kBrickBits) * brick_dims_.y()) *
                                    brick_dims_.x());
    if (key != cached_key) {
      cached_first = brick(key);
      cached_key = key;
    }
    constexpr int kMask = (1 << kBrickBits) - 1;
    return cached_first + static_cast<std::size_t>((q.x() & kMask) | (q.y() & kMask) << kBrickBits |
                                                   (q.z() & kMask) << (2 * kBrickBits));
  };

  resetScratch();
  nodes_.push_back(Node{s, -1, {0, 0, 0}, -1});
  cells_[cellOf(s)] = 0;
  open(0);
  std::int32_t reached = -1;
  nearest = 0;
  float nearest_h = std::numeric_limits<float>::infinity();
  result.status = PathStatus::kNoPath;
  result.expansions = 0;
  while (!open_.empty()) {
    const float h = open_.front().h;  // the heuristic its entry was opened with
    const std::int32_t n = heapPop();
    if (h < nearest_h) nearest_h = h, nearest = n;
    if (nodes_[n].idx == g) {
      ++result.expansions;
      reached = n;
      result.status = PathStatus::kFound;
      break;
    }
    if (result.expansions >= budget) {
      result.status = PathStatus::kBudgetExceeded;
      break;
    }
    ++result.expansions;
    const Index3 idx = nodes_[n].idx;
    cells_[cellOf(idx)] = kCellClosed;  // later visits skip it without reading the node
    std::array<std::size_t, 26> cell;
    std::uint32_t free = 0;
    const double esdf_here = stride > 1 ? esdf_.distance(idx) : 0.0;
    for (int k = 0; k < 26; ++k) {
      const Index3 q = idx + stride * nb.offset[k];
      if (!geo_.inside(q)) continue;
      cell[k] = cellOf(q);
      std::int32_t& c = cells_[cell[k]];
      if (c == kCellUnseen) {
        const std::size_t linear = geo_.linear(q);
        c = traversableFrom(q, linear, start, exempt2) ? kCellFree : kCellBlocked;
      }
      if (c != kCellBlocked) free |= std::uint32_t{1} << k;
    }
    for (int k = 0; k < 26; ++k) {
      // Blocked, or (every voxel) cutting a blocked edge / corner; on a coarse lattice the move's segment is
      // checked below, only when the move would open or improve a node (the check is the costly part there).
      const std::uint32_t needed = stride == 1 ? nb.swept[k] : std::uint32_t{1} << k;
      if ((free & needed) != needed) continue;
      std::int32_t m = cells_[cell[k]];
      if (m == kCellClosed) continue;
      std::int32_t moves[3] = {nodes_[n].moves[0], nodes_[n].moves[1], nodes_[n].moves[2]};
      ++moves[nb.type[k]];
      if (m >= 0 && movesCost(moves) >= movesCost(nodes_[m].moves)) continue;
      if (stride > 1 && !moveClear(idx, idx + stride * nb.offset[k], esdf_here, start, exempt2)) continue;
      if (m < 0) {
        m = static_cast<std::int32_t>(nodes_.size());
        nodes_.push_back(Node{idx + stride * nb.offset[k], n, {0, 0, 0}, -1});
        cells_[cell[k]] = m;
      }
      nodes_[m].parent = n;
      std::copy(moves, moves + 3, nodes_[m].moves);
      open(m);
    }
  }
  return reached;
}

std::vector<Vec3> Astar::chain(std::int32_t n) const {
  std::vector<Vec3> out;
  for (; n >= 0; n = nodes_[n].parent) out.push_back(geo_.indexToCoord(nodes_[n].idx));
  return out;
}

PathResult Astar::search(const Vec3& start, const Vec3& goal, double snap_radius) const {
  PathResult result;
  Index3 s, g;
  if (!snap(start, snap_radius, s, true)) {
    result.status = PathStatus::kStartBlocked;
    return result;
  }
  if (!snap(goal, snap_radius, g, false, config_.stride > 1 ? &s : nullptr)) {
    result.status = PathStatus::kGoalBlocked;
    return result;
  }
  // Voxel centres from the run's first node to node n.
  auto fromStart = [&](std::int32_t n) {
    std::vector<Vec3> raw = chain(n);
    std::reverse(raw.begin(), raw.end());
    return raw;
  };
  auto found = [&](std::vector<Vec3> raw) {
    result.status = PathStatus::kFound;
    result.raw_path = std::move(raw);
    result.raw_length = pathLength(result.raw_path);
    result.path = shorten(result.raw_path);
    result.length = pathLength(result.path);
    return result;
  };
  std::int32_t nearest = 0;
  int spent = 0;
  const int probe = config_.probe_expansions;
  if (probe > 0 && probe < config_.max_expansions) {
    const std::int32_t reached = run(s, g, s, snap_radius, probe, result, nearest);
    if (reached >= 0) return found(fromStart(reached));
    // Taken before the search from the goal's side reuses the scratch; shortened only if it is returned.
    const std::vector<Vec3> toward = nearest > 0 ? fromStart(nearest) : std::vector<Vec3>();
    if (result.status == PathStatus::kBudgetExceeded) {
      PathResult back;
      std::int32_t unused = 0;
      const std::int32_t met = run(g, s, s, snap_radius, probe, back, unused);
      result.expansions += back.expansions;
      if (met >= 0) return found(chain(met));  // from the start voxel back to the goal: start first
      if (back.status == PathStatus::kNoPath) result.status = PathStatus::kNoPath;  // the goal's side ran out
    }
    if (result.status == PathStatus::kNoPath) {
      if (!toward.empty()) result.toward = shorten(toward);
      return result;
    }
    spent = result.expansions;
  }
  const std::int32_t reached = run(s, g, s, snap_radius, config_.max_expansions, result, nearest);
  result.expansions += spent;
  if (reached >= 0) return found(fromStart(reached));
  if (nearest > 0) result.toward = shorten(fromStart(nearest));
  return result;
}

PathDistance pathDistance(const Astar& astar, const Vec3& a, const Vec3& b) {
  // On a coarse lattice, a pair in plain sight is answered by the walk along it (no path is shorter):
  // cheaper than a search whose every move is checked along its segment. On the every-voxel lattice the
  // search there only expands the voxels of the straight path, and returns it.
  if (astar.config().stride > 1 && astar.segmentTraversable(a, b)) return {(b - a).norm(), false};
  const PathResult r = astar.search(a, b);
  if (r.status != PathStatus::kFound) return {(b - a).norm(), true};
  return {(r.path.front() - a).norm() + r.length + (b - r.path.back()).norm(), false};
}

}  // namespace go_feap::planning
