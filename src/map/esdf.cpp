#include "go_feap/map/esdf.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace go_feap::map {

using common::GridGeometry;
using common::Index3;
using common::Status;
using common::Vec3;

namespace {

// Largest squared voxel distance whose offsets still fit in [-127, 127] on every axis.
constexpr int kMaxStorableKey = Esdf::kMaxRangeVoxels * Esdf::kMaxRangeVoxels;

// Largest squared voxel distance strictly below max_distance (a voxel at max_distance or beyond
// stores "none", which reads the same), capped at kMaxStorableKey + 1.
int maxKey(double max_distance, double resolution) {
  const double r = max_distance / resolution;
  return static_cast<int>(std::min(std::ceil(r * r - 1e-9) - 1.0, static_cast<double>(kMaxStorableKey + 1)));
}

// The waves read neighbours in three z-slices of a grid that can span ~100 MB: with 4 kB pages nearly
// every such read misses the TLB. Asks the kernel for transparent huge pages there (a hint; where
// unsupported nothing happens).
void adviseHugePages(void* data, std::size_t bytes) {
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  const std::uintptr_t page = 4096;
  const std::uintptr_t begin = (reinterpret_cast<std::uintptr_t>(data) + page - 1) & ~(page - 1);
  const std::uintptr_t end = (reinterpret_cast<std::uintptr_t>(data) + bytes) & ~(page - 1);
  if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
#else
  (void)data;
  (void)bytes;
#endif
}

}  // namespace

Status EsdfConfig::validate() const {
  auto err = [](const char* key, const char* why) {
    return Status::Error(std::string("esdf: ") + key + " " + why);
  };
  if (!(max_distance > 0.0 && std::isfinite(max_distance)))
    return err("max_distance", "must be finite and > 0");
  return Status::Ok();
}

Status EsdfConfig::validate(const GridGeometry& geometry) const {
  if (Status s = validate(); !s) return s;
  if (!(geometry.resolution() > 0.0) || (geometry.dims().array() <= 0).any())
    return Status::Error("esdf: the grid needs a resolution > 0 and at least one voxel");
  if (geometry.size() > std::numeric_limits<std::uint32_t>::max())
    return Status::Error("esdf: the grid has " + std::to_string(geometry.size()) +
                         " voxels, more than 2^32 - 1");
  // Below a voxel the field holds the obstacles alone (and below 3e-5 voxels no distance at all: the
  // buckets were sized 0 and the first obstacle was written past them).
  if (!(max_distance >= geometry.resolution()))
    return Status::Error("esdf: max_distance must be >= the map's resolution (one voxel), got " +
                         std::to_string(max_distance) + " m at " + std::to_string(geometry.resolution()) + " m");
  if (maxKey(max_distance, geometry.resolution()) > kMaxStorableKey)
    return Status::Error("esdf: max_distance must be <= 127 voxels (max_distance / resolution), got " +
                         std::to_string(max_distance / geometry.resolution()));
  return Status::Ok();
}

Esdf::Esdf(const GridGeometry& geometry, const EsdfConfig& config) : geometry_(geometry), config_(config) {
  if (Status s = config.validate(geometry); !s) throw std::invalid_argument(s.message());
  stride_y_ = geometry.dims().x();
  stride_z_ = stride_y_ * geometry.dims().y();
  max_key_ = maxKey(config.max_distance, geometry.resolution());
  offsets_.reserve(geometry.size());
  adviseHugePages(offsets_.data(), offsets_.capacity() * sizeof(Offset));
  offsets_.assign(geometry.size(), Offset{kNone, 0, 0});
  touched_.assign((geometry.size() + 63) / 64, 0);
  buckets_.resize(static_cast<std::size_t>(max_key_) + 1);
  metres_of_key_.resize(static_cast<std::size_t>(max_key_) + 1);
  for (int k = 0; k <= max_key_; ++k) metres_of_key_[k] = geometry_.resolution() * std::sqrt(static_cast<double>(k));
  int i = 0;
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x) {
        if (x == 0 && y == 0 && z == 0) continue;
        nb_[i][0] = static_cast<std::int8_t>(x);
        nb_[i][1] = static_cast<std::int8_t>(y);
        nb_[i][2] = static_cast<std::int8_t>(z);
        nb_linear_[i] = x + y * stride_y_ + z * stride_z_;
        ++i;
      }
}

std::size_t Esdf::update(const std::vector<std::size_t>& inserted, const std::vector<std::size_t>& removed) {
  changes_.clear();
  changed_any_ = false;
  raise_stack_.clear();
  const std::size_t n = offsets_.size();
  for (const std::size_t r : removed) {
    if (r >= n || !isZero(offsets_[r])) continue;
    touch(r);
    offsets_[r].x = kNone;
    raise_stack_.push_back(static_cast<std::uint32_t>(r));
  }
  const bool any_removed = !raise_stack_.empty();
  for (const std::size_t i : inserted) {
    if (i >= n || isZero(offsets_[i])) continue;
    touch(i);
    offsets_[i] = Offset{0, 0, 0};
    push(i, 0);
  }

  // First the raise wave forgets the removed obstacles, then the lower wave, in order of squared
  // distance, offers the remaining and new ones to the voxels around; stale queue entries (whose
  // voxel has since got a nearer obstacle) are skipped.
  raise(true);
  std::size_t v;
  int k;
  while (pop(v, k)) {
    const Offset o = offsets_[v];
    if (hasSite(o) && squaredNorm(o) == k && (!any_removed || siteValid(v, o))) lower(v, o, any_removed);
  }

  std::size_t changed = 0;
  for (const Change& c : changes_) {
    common::clearBit(touched_, c.voxel);
    if (key(c.voxel) == c.old_key) continue;
    ++changed;
    const Index3 idx = geometry_.unlinear(c.voxel);
    if (!changed_any_) {
      changed_lo_ = idx;
      changed_hi_ = idx;
      changed_any_ = true;
    } else {
      changed_lo_ = changed_lo_.cwiseMin(idx);
      changed_hi_ = changed_hi_.cwiseMax(idx);
    }
  }
  if (changed_any_) changed_hi_ += Index3::Ones();
  releaseLargeScratch();
  return changed;
}

// Scratch is kept between updates (no reallocation per frame) unless one structure grew beyond a
// quarter byte per voxel of the grid, as an update touching much of a small grid makes it.
void Esdf::releaseLargeScratch() {
  const std::size_t budget = offsets_.size() / 4;
  changes_.clear();
  if (changes_.capacity() * sizeof(Change) > budget) std::vector<Change>().swap(changes_);
  if (raise_stack_.capacity() * sizeof(std::uint32_t) > budget)
    std::vector<std::uint32_t>().swap(raise_stack_);
  std::size_t bucket_bytes = 0;
  for (const auto& b : buckets_) bucket_bytes += b.capacity() * sizeof(std::uint32_t);
  if (bucket_bytes > budget)
    for (auto& b : buckets_) std::vector<std::uint32_t>().swap(b);
}

bool Esdf::lastChangedRange(Index3& lo, Index3& hi) const {
  if (!changed_any_) return false;
  lo = changed_lo_;
  hi = changed_hi_;
  return true;
}

inline void Esdf::touch(std::size_t v) {
  std::uint64_t& word = touched_[v >> 6];
  const std::uint64_t bit = std::uint64_t{1} << (v & 63);
  if (word & bit) return;
  word |= bit;
  changes_.push_back({static_cast<std::uint32_t>(v), key(v)});
}

inline void Esdf::push(std::size_t v, int key) {
  buckets_[key].push_back(static_cast<std::uint32_t>(v));
  lowest_bucket_ = std::min(lowest_bucket_, key);
  ++queued_;
}

bool Esdf::pop(std::size_t& v, int& key) {
  if (queued_ == 0) return false;
  while (buckets_[lowest_bucket_].empty()) ++lowest_bucket_;
  std::vector<std::uint32_t>& bucket = buckets_[lowest_bucket_];
  v = bucket.back();
  bucket.pop_back();
  key = lowest_bucket_;
  --queued_;
  return true;
}

template <typename F>
void Esdf::forNeighbours(std::size_t v, F&& f) const {
  const Index3 c = geometry_.unlinear(v);
  const Index3& d = geometry_.dims();
  const bool interior = (c.array() > 0).all() && (c.array() < d.array() - 1).all();
  for (int i = 0; i < 26; ++i) {
    if (!interior) {
      const Index3 nc = c + Index3(nb_[i][0], nb_[i][1], nb_[i][2]);
      if (!geometry_.inside(nc)) continue;
    }
    f(static_cast<std::size_t>(static_cast<std::int64_t>(v) + nb_linear_[i]), i);
  }
}

// Clears every voxel reachable from raise_stack_ (voxels already cleared) through voxels that point to
// removed obstacles, and queues the voxels with valid obstacles that border them, to lower into the
// cleared region. In the first, main raise every such voxel is queued once (the touched bit tells
// which are); later raises (from leftovers found by lower()) queue them again.
void Esdf::raise(bool first) {
  while (!raise_stack_.empty()) {
    const std::size_t v = raise_stack_.back();
    raise_stack_.pop_back();
    if (hasSite(offsets_[v])) continue;  // a removed obstacle inserted again in this update
    forNeighbours(v, [&](std::size_t n, int) {
      const Offset on = offsets_[n];
      if (!hasSite(on)) return;
      if (!siteValid(n, on)) {
        touch(n);
        offsets_[n].x = kNone;
        raise_stack_.push_back(static_cast<std::uint32_t>(n));
        return;
      }
      if (first) {
        if (touched(n)) return;  // queued already (frontier or inserted obstacle)
        touch(n);
      }
      push(n, squaredNorm(on));
    });
  }
}

// Offers v's obstacle (at offset o) to its neighbours. With `check_sites` (obstacles were removed in
// this update) it also catches a voxel that still points to a removed obstacle because the raise wave
// could not reach it (its neighbours that had the same obstacle got nearer ones since): the voxel takes
// v's obstacle, or is raised when that is out of range.
void Esdf::lower(std::size_t v, const Offset& o, bool check_sites) {
  forNeighbours(v, [&](std::size_t n, int i) {
    const Offset no{static_cast<std::int8_t>(o.x - nb_[i][0]), static_cast<std::int8_t>(o.y - nb_[i][1]),
                    static_cast<std::int8_t>(o.z - nb_[i][2])};
    const int nk = squaredNorm(no);
    if (nk > max_key_ && !check_sites) return;
    const Offset on = offsets_[n];
    if (hasSite(on) && squaredNorm(on) <= nk) {
      if (!check_sites || siteValid(n, on)) return;
      touch(n);
      if (nk > max_key_) {
        offsets_[n].x = kNone;
        raise_stack_.push_back(static_cast<std::uint32_t>(n));
        raise(false);
        return;
      }
    } else {
      if (nk > max_key_) return;
      touch(n);
    }
    offsets_[n] = no;
    push(n, nk);
  });
}

bool Esdf::isObstacle(const Index3& idx) const {
  if (!geometry_.inside(idx)) return false;
  const Offset& o = offsets_[geometry_.linear(idx)];
  return o.x == 0 && o.y == 0 && o.z == 0;
}

double Esdf::distanceOfKey(int key) const {
  // Stored keys never exceed max_key_: lower() does not store a farther site.
  return key < 0 ? config_.max_distance : metres_of_key_[static_cast<std::size_t>(key)];
}

double Esdf::distance(const Index3& idx) const {
  if (!geometry_.inside(idx)) return config_.max_distance;
  return distanceOfKey(key(geometry_.linear(idx)));
}

bool Esdf::nearestObstacle(const Index3& idx, Index3& obstacle) const {
  if (!geometry_.inside(idx)) return false;
  const Offset& o = offsets_[geometry_.linear(idx)];
  if (!hasSite(o)) return false;
  obstacle = idx + Index3(o.x, o.y, o.z);
  return true;
}

void Esdf::corners(const Vec3& p, double c[8], Vec3& t) const {
  // Clamped so that far-away (or non-finite) points land two voxels outside the grid, where every
  // corner reads max_distance, before the conversion to int.
  Vec3 q = (p - geometry_.origin()) / geometry_.resolution() - Vec3::Constant(0.5);
  Index3 base;
  for (int a = 0; a < 3; ++a) {
    if (!(q[a] >= -2.0)) q[a] = -2.0;  // NaN included
    q[a] = std::min(q[a], static_cast<double>(geometry_.dims()[a] + 1));
    base[a] = static_cast<int>(std::floor(q[a]));
    t[a] = q[a] - base[a];
  }
  for (int i = 0; i < 8; ++i)
    c[i] = distance(Index3(base.x() + (i & 1), base.y() + ((i >> 1) & 1), base.z() + (i >> 2)));
}

double Esdf::distance(const Vec3& p) const {
  double c[8];
  Vec3 t;
  corners(p, c, t);
  const double x00 = c[0] + t.x() * (c[1] - c[0]), x10 = c[2] + t.x() * (c[3] - c[2]);
  const double x01 = c[4] + t.x() * (c[5] - c[4]), x11 = c[6] + t.x() * (c[7] - c[6]);
  const double y0 = x00 + t.y() * (x10 - x00), y1 = x01 + t.y() * (x11 - x01);
  return y0 + t.z() * (y1 - y0);
}

double Esdf::distanceAndGradient(const Vec3& p, Vec3& gradient) const {
  double c[8];
  Vec3 t;
  corners(p, c, t);
  const double tx = t.x(), ty = t.y(), tz = t.z(), ux = 1.0 - tx, uy = 1.0 - ty, uz = 1.0 - tz;
  const double inv = 1.0 / geometry_.resolution();
  gradient.x() = inv * (uy * uz * (c[1] - c[0]) + ty * uz * (c[3] - c[2]) + uy * tz * (c[5] - c[4]) +
                        ty * tz * (c[7] - c[6]));
  gradient.y() = inv * (ux * uz * (c[2] - c[0]) + tx * uz * (c[3] - c[1]) + ux * tz * (c[6] - c[4]) +
                        tx * tz * (c[7] - c[5]));
  gradient.z() = inv * (ux * uy * (c[4] - c[0]) + tx * uy * (c[5] - c[1]) + ux * ty * (c[6] - c[2]) +
                        tx * ty * (c[7] - c[3]));
  return uz * (uy * (ux * c[0] + tx * c[1]) + ty * (ux * c[2] + tx * c[3])) +
         tz * (uy * (ux * c[4] + tx * c[5]) + ty * (ux * c[6] + tx * c[7]));
}


std::size_t Esdf::memoryBytes() const {
  std::size_t bytes = sizeof(*this) + offsets_.capacity() * sizeof(Offset) +
                      touched_.capacity() * sizeof(std::uint64_t) + changes_.capacity() * sizeof(Change) +
                      raise_stack_.capacity() * sizeof(std::uint32_t) +
                      buckets_.capacity() * sizeof(buckets_[0]) + metres_of_key_.capacity() * sizeof(double);
  for (const auto& b : buckets_) bytes += b.capacity() * sizeof(std::uint32_t);
  return bytes;
}

}  // namespace go_feap::map
