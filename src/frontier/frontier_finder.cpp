#include "go_feap/frontier/frontier_finder.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <unordered_set>

namespace go_feap::frontier {

common::Status FrontierConfig::validate() const {
  if (min_cluster_cells < 1) return common::Status::Error("frontier: min_cluster_cells must be >= 1");
  // Finite, and squared too (the finder compares squared distances): an infinite extent would split no
  // cluster, and an infinite s_near would make every frontier near every other, which zeroes every omission
  // likelihood (beta) once there are more than n_max frontiers.
  if (!(max_cluster_extent > 0.0) || !std::isfinite(max_cluster_extent * max_cluster_extent))
    return common::Status::Error("frontier: max_cluster_extent must be finite and > 0");
  if (!(s_near > 0.0) || !std::isfinite(s_near * s_near))
    return common::Status::Error("frontier: s_near must be finite and > 0");
  if (max_regrow_cells < 0) return common::Status::Error("frontier: max_regrow_cells must be >= 0");
  if (!(revive_factor >= 1.0) || !std::isfinite(revive_factor))
    return common::Status::Error("frontier: revive_factor must be >= 1 and finite");
  return common::Status::Ok();
}

FrontierFinder::FrontierFinder(const FrontierConfig& config, const common::GridGeometry& geometry, const Aabb& box)
    : config_(config),
      geo_(geometry),
      box_(box),
      is_frontier_((geometry.size() + 63) / 64, 0),
      scratch_((geometry.size() + 63) / 64, 0),
      retired_(config.revive_factor > 1.0 ? (geometry.size() + 63) / 64 : 0, 0),
      bricks_(((geometry.dims().array() + 3) / 4).matrix()),
      owner_(static_cast<std::size_t>(bricks_.x()) * bricks_.y() * bricks_.z() * 64, 0) {
  geo_.centreRange(box, box_lo_, box_hi_);
}

bool FrontierFinder::computeFrontierCell(const map::OccupancyMap& map, const Index3& idx) const {
  if (!inBox(idx) || map.state(idx) != map::VoxelState::kFree) return false;
  for (const Index3& o : common::faceNeighbours()) {
    const Index3 nb = idx + o;
    if (inBox(nb) && map.state(nb) == map::VoxelState::kUnknown) return true;
  }
  return false;
}

const Frontier* FrontierFinder::find(std::uint32_t id) const {
  auto it = std::lower_bound(frontiers_.begin(), frontiers_.end(), id,
                             [](const Frontier& f, std::uint32_t v) { return f.id < v; });
  return it != frontiers_.end() && it->id == id ? &*it : nullptr;
}

void FrontierFinder::setActiveBand(double z_min, double z_max) {
  band_min_ = z_min;
  band_max_ = z_max;
  for (Frontier& f : frontiers_) f.active = f.average.z() >= band_min_ && f.average.z() <= band_max_;
}

FrontierDelta FrontierFinder::update(const map::OccupancyMap& map, const Index3& changed_min,
                                     const Index3& changed_max, double now) {
  return rebuild(map, changed_min, changed_max, now);
}

FrontierDelta FrontierFinder::update(const map::OccupancyMap& map, const std::vector<std::size_t>& changed,
                                     double now) {
  if (changed.empty()) return {};
  // S: voxels whose frontier status may have changed (the changed ones and their face
  // neighbours, in the box), marked in a scratch bitset.
  std::vector<std::size_t> marked;
  Index3 s_lo = box_hi_, s_hi = box_lo_;
  auto mark = [&](const Index3& idx) {
    if (!inBox(idx)) return;
    const std::size_t l = geo_.linear(idx);
    if (common::testBit(scratch_, l)) return;
    common::setBit(scratch_, l);
    marked.push_back(l);
    s_lo = s_lo.cwiseMin(idx);
    s_hi = s_hi.cwiseMax(idx);
  };
  for (std::size_t l : changed) {
    const Index3 idx = geo_.unlinear(l);
    mark(idx);
    for (const Index3& o : common::faceNeighbours()) mark(idx + o);
  }
  auto inS = [&](const Index3& idx) {
    if (!geo_.inside(idx)) return false;
    const std::size_t l = geo_.linear(idx);
    return common::testBit(scratch_, l);
  };
  // Clusters with a cell in S or 26-adjacent to it (a box test first).
  std::unordered_set<std::uint32_t> affected;
  if (!marked.empty()) {
    const double r = geo_.resolution();
    const Aabb reach{geo_.indexToCoord(s_lo) - Vec3::Constant(1.5 * r), geo_.indexToCoord(s_hi) + Vec3::Constant(1.5 * r)};
    for (const Frontier& f : frontiers_) {
      if ((f.box.max.array() < reach.min.array()).any() || (f.box.min.array() > reach.max.array()).any()) continue;
      bool hit = false;
      for (const Index3& c : f.cells) {
        for (int dz = -1; dz <= 1 && !hit; ++dz)
          for (int dy = -1; dy <= 1 && !hit; ++dy)
            for (int dx = -1; dx <= 1 && !hit; ++dx) hit = inS(c + Index3(dx, dy, dz));
        if (hit) break;
      }
      if (hit) affected.insert(f.id);
    }
  }
  // New statuses in S; frontier cells of S seed the regrowth.
  std::vector<std::size_t> seeds;
  for (std::size_t l : marked) {
    const Index3 idx = geo_.unlinear(l);
    if (computeFrontierCell(map, idx)) {
      common::setBit(is_frontier_, l);
      seeds.push_back(l);
    } else {
      common::clearBit(is_frontier_, l);
    }
    common::clearBit(scratch_, l);
  }
  return regrow(std::move(affected), std::move(seeds), now);
}

FrontierDelta FrontierFinder::recomputeAll(const map::OccupancyMap& map, double now) {
  return rebuild(map, box_lo_, box_hi_ - Index3::Ones(), now);
}

// Frontier status of a voxel depends on it and its face neighbours, so statuses can change
// in the changed box grown by one voxel (R). A cluster is rebuilt when one of its cells lies
// within one more voxel of R (26-adjacency); everything farther away is untouched.
FrontierDelta FrontierFinder::rebuild(const map::OccupancyMap& map, const Index3& changed_min,
                                      const Index3& changed_max, double now) {
  const Index3 r_lo = (changed_min - Index3::Ones()).cwiseMax(box_lo_);
  const Index3 r_hi = (changed_max + Index3::Ones()).cwiseMin(box_hi_ - Index3::Ones());
  const Index3 n_lo = (changed_min - Index3::Constant(2)).cwiseMax(box_lo_);
  const Index3 n_hi = (changed_max + Index3::Constant(2)).cwiseMin(box_hi_ - Index3::Ones());
  if ((n_hi.array() < n_lo.array()).any()) return {};

  // 1. Clusters within reach of the change, before statuses change: those with a cell in
  // the reach box (a cheap box test first, then their cells).
  std::unordered_set<std::uint32_t> affected;
  const Aabb reach{geo_.indexToCoord(n_lo), geo_.indexToCoord(n_hi)};
  for (const Frontier& f : frontiers_) {
    if ((f.box.max.array() < reach.min.array()).any() || (f.box.min.array() > reach.max.array()).any()) continue;
    for (const Index3& c : f.cells)
      if ((c.array() >= n_lo.array()).all() && (c.array() <= n_hi.array()).all()) {
        affected.insert(f.id);
        break;
      }
  }
  // 2. New statuses in R.
  for (int z = r_lo.z(); z <= r_hi.z(); ++z)
    for (int y = r_lo.y(); y <= r_hi.y(); ++y)
      for (int x = r_lo.x(); x <= r_hi.x(); ++x) {
        const Index3 idx(x, y, z);
        const std::size_t l = geo_.linear(idx);
        if (computeFrontierCell(map, idx))
          common::setBit(is_frontier_, l);
        else
          common::clearBit(is_frontier_, l);
      }
  // 3. Seeds: frontier cells near the change (regrow adds the cells of the affected clusters).
  std::vector<std::size_t> seeds;
  for (int z = n_lo.z(); z <= n_hi.z(); ++z)
    for (int y = n_lo.y(); y <= n_hi.y(); ++y)
      for (int x = n_lo.x(); x <= n_hi.x(); ++x)
        if (isFrontierCell(Index3(x, y, z))) seeds.push_back(geo_.linear(Index3(x, y, z)));
  return regrow(std::move(affected), std::move(seeds), now);
}

// Rebuilds the removed (affected) clusters from the seeds and their own cells: flood fill over frontier
// cells not held by a kept cluster, then drop / split / age as a full recomputation does.
FrontierDelta FrontierFinder::regrow(std::unordered_set<std::uint32_t> affected, std::vector<std::size_t> seeds,
                                     double now) {
  FrontierDelta delta;
  std::unordered_map<std::uint32_t, double> first_seen;  // of removed clusters
  // A removed cluster: its age is kept for its successors, and every cell of it still a frontier seeds
  // the fill.
  auto remove = [&](std::uint32_t id) {
    const Frontier* f = find(id);
    if (!f) return;
    first_seen[id] = f->first_seen;
    for (const Index3& c : f->cells)
      if (isFrontierCell(c)) seeds.push_back(geo_.linear(c));
  };
  for (std::uint32_t id : affected) remove(id);

  // 4. Flood fill (26-connected) over frontier cells from the seeds: whole regions. Visited cells are
  // marked in scratch_ (all clear between updates) and cleared again afterwards.
  std::vector<std::size_t> visited;
  auto marked = [&](std::size_t l) { return common::testBit(scratch_, l); };
  auto visit = [&](std::size_t l) {
    common::setBit(scratch_, l);
    visited.push_back(l);
  };
  std::vector<std::vector<std::size_t>> regions;  // linear indices
  std::sort(seeds.begin(), seeds.end());
  // A cell of a cluster not marked affected: while the fill is small, that cluster's region is being
  // rebuilt, so it goes too; past max_regrow_cells the cluster is kept and the fill goes around it, so
  // an update costs about the size of the clusters it touches, not of the whole connected region.
  // A cluster that goes has all its cells seeded (remove): a piece of a split region can hold cells that
  // are connected to the rest only through a cluster kept later (a U-shaped region cut across its arms),
  // and those would otherwise be left out of every cluster, however many.
  auto kept = [&](const Index3& idx) {
    const std::uint32_t own = owner_[ownerSlot(idx)];
    if (own == 0 || affected.count(own) > 0) return false;
    if (visited.size() >= static_cast<std::size_t>(config_.max_regrow_cells)) return true;
    affected.insert(own);
    remove(own);
    return false;
  };
  std::vector<std::pair<std::size_t, Index3>> stack;
  for (std::size_t i = 0; i < seeds.size(); ++i) {  // seeds grows as clusters go (kept)
    const std::size_t s = seeds[i];
    if (marked(s)) continue;
    const Index3 seed = geo_.unlinear(s);
    if (kept(seed)) continue;
    visit(s);
    std::vector<std::size_t> region;
    stack.assign(1, {s, seed});
    while (!stack.empty()) {
      const auto [l, c] = stack.back();
      stack.pop_back();
      region.push_back(l);
      for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const Index3 nb = c + Index3(dx, dy, dz);
            if ((dx == 0 && dy == 0 && dz == 0) || !isFrontierCell(nb)) continue;
            const std::size_t ln = geo_.linear(nb);
            if (marked(ln) || kept(nb)) continue;
            visit(ln);
            stack.emplace_back(ln, nb);
          }
    }
    regions.push_back(std::move(region));
  }
  for (std::size_t l : visited) common::clearBit(scratch_, l);
  delta.filled_cells = visited.size();

  // 5. Regions -> clusters: drop small ones, split wide ones, inherit the oldest age (of the removed
  // clusters that held their cells: owner_ still names them here).
  const double h = 0.5 * geo_.resolution();
  std::vector<Frontier> added;
  std::vector<Cell> cells, buffer;
  std::vector<std::pair<std::size_t, std::size_t>> pieces;
  // A piece made of exactly the cells of a removed cluster is that cluster, unchanged: it keeps its id and
  // is neither removed nor added. (Every piece of a regrown region took a new id, though the change lay
  // metres away: a blacklisted frontier came back under a new id and was tried again, and the planners'
  // caches and tours keyed by id were dropped for the whole region at every frame.)
  std::unordered_set<std::uint32_t> unchanged;
  auto sameCluster = [&](std::size_t b, std::size_t e) -> std::uint32_t {
    const std::uint32_t own = owner_[ownerSlot(cells[b].index)];
    if (own == 0 || affected.count(own) == 0) return 0;
    const Frontier* old = find(own);
    if (!old || old->cells.size() != e - b) return 0;
    for (std::size_t i = b; i < e; ++i)
      if (owner_[ownerSlot(cells[i].index)] != own) return 0;
    return own;  // as many cells, all its own: the same set
  };
  for (auto& region : regions) {
    if (!keepRegion(region)) continue;
    // Sorted cells make the split independent of the order the flood fill found them in; the split
    // keeps the order, so every piece is sorted too.
    std::sort(region.begin(), region.end());
    cells.clear();
    cells.reserve(region.size());
    for (std::size_t l : region) {
      const Index3 c = geo_.unlinear(l);
      cells.push_back({c, geo_.indexToCoord(c)});
    }
    pieces.clear();
    splitRange(cells, 0, cells.size(), buffer, pieces);
    for (const auto& [b, e] : pieces) {
      Frontier f;
      const std::uint32_t same = sameCluster(b, e);
      f.id = same != 0 ? same : next_id_++;
      f.first_seen = now;
      f.box = {Vec3::Constant(1e18), Vec3::Constant(-1e18)};
      f.cells.reserve(e - b);
      for (std::size_t i = b; i < e; ++i) {
        const Cell& c = cells[i];
        const std::size_t l = ownerSlot(c.index);
        f.average += c.centre;
        f.box.min = f.box.min.cwiseMin(c.centre - Vec3::Constant(h));
        f.box.max = f.box.max.cwiseMax(c.centre + Vec3::Constant(h));
        if (const std::uint32_t own = owner_[l]) {
          auto it = first_seen.find(own);
          if (it != first_seen.end()) f.first_seen = std::min(f.first_seen, it->second);
        }
        owner_[l] = f.id;
        f.cells.push_back(c.index);
      }
      f.average /= static_cast<double>(e - b);
      f.active = f.average.z() >= band_min_ && f.average.z() <= band_max_;
      if (same != 0) {
        unchanged.insert(same);
      } else {
        delta.added.push_back(f.id);
      }
      added.push_back(std::move(f));
    }
  }
  // Cells of removed clusters that no new cluster took lose their owner.
  for (std::uint32_t id : affected) {
    const Frontier* f = find(id);
    if (!f || unchanged.count(id) > 0) continue;
    for (const Index3& c : f->cells) {
      std::uint32_t& own = owner_[ownerSlot(c)];
      if (own == id) own = 0;
    }
    delta.removed.push_back(id);
  }
  std::sort(delta.removed.begin(), delta.removed.end());
  frontiers_.erase(std::remove_if(frontiers_.begin(), frontiers_.end(),
                                  [&](const Frontier& f) { return affected.count(f.id) > 0; }),
                   frontiers_.end());
  for (Frontier& f : added) frontiers_.push_back(std::move(f));
  refreshNeighbourCounts();
  return delta;
}

bool FrontierFinder::keepRegion(const std::vector<std::size_t>& region) {
  const auto n = static_cast<double>(region.size());
  const double min_cells = config_.min_cluster_cells;
  if (retired_.empty()) return n >= min_cells;
  auto retired = [&](std::size_t l) { return common::testBit(retired_, l); };
  auto retire = [&] {
    for (std::size_t l : region) common::setBit(retired_, l);
    return false;
  };
  // A region kept is a cluster like any other from now on: it is held down to min_cluster_cells, not to the
  // revive size (its cells' old retirement would drop it again at the first cell it lost).
  auto keep = [&] {
    for (std::size_t l : region) common::clearBit(retired_, l);
    return true;
  };
  if (n < min_cells) {
    // Retired only when it comes from a cluster: a region growing up from nothing is not held back.
    if (std::any_of(region.begin(), region.end(), [&](std::size_t l) { return owner_[ownerSlot(geo_.unlinear(l))] != 0; }))
      retire();
    return false;
  }
  if (n >= config_.revive_factor * min_cells) return keep();
  const auto r = static_cast<double>(std::count_if(region.begin(), region.end(), retired));
  return 2.0 * r < n ? keep() : retire();
}

void FrontierFinder::splitRange(std::vector<Cell>& cells, std::size_t begin, std::size_t end,
                                std::vector<Cell>& buffer, std::vector<std::pair<std::size_t, std::size_t>>& out) const {
  const std::size_t n = end - begin;
  Vec3 mean = Vec3::Zero();
  for (std::size_t i = begin; i < end; ++i) mean += cells[i].centre;
  mean /= static_cast<double>(n);
  // Wide when a cell lies farther than max_cluster_extent from the mean: the first such cell decides
  // (the square root only near the limit, so the test is exactly that of the farthest cell's distance).
  const double extent = config_.max_cluster_extent, below = extent * extent * (1.0 - 1e-9);
  bool wide = false;
  for (std::size_t i = begin; i < end && !wide; ++i) {
    const double d2 = (cells[i].centre - mean).squaredNorm();
    wide = d2 >= below && std::sqrt(d2) > extent;
  }
  if (!wide || n < 2) {
    out.emplace_back(begin, end);
    return;
  }
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t i = begin; i < end; ++i) {
    const Vec3 d = cells[i].centre - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Vec3 axis = eig.eigenvectors().col(2);  // largest eigenvalue
  // Stable partition: the half along the axis first, each half in its original order.
  buffer.clear();
  std::size_t mid = begin;
  for (std::size_t i = begin; i < end; ++i) {
    if ((cells[i].centre - mean).dot(axis) >= 0.0)
      cells[mid++] = cells[i];
    else
      buffer.push_back(cells[i]);
  }
  if (mid == begin || mid == end) {
    std::copy(buffer.begin(), buffer.end(), cells.begin() + static_cast<std::ptrdiff_t>(mid));
    out.emplace_back(begin, end);
    return;
  }
  std::copy(buffer.begin(), buffer.end(), cells.begin() + static_cast<std::ptrdiff_t>(mid));
  splitRange(cells, begin, mid, buffer, out);
  splitRange(cells, mid, end, buffer, out);
}

void FrontierFinder::refreshNeighbourCounts() {
  std::sort(frontiers_.begin(), frontiers_.end(), [](const Frontier& a, const Frontier& b) { return a.id < b.id; });
  const double r2 = config_.s_near * config_.s_near;
  for (Frontier& f : frontiers_) {
    f.n_near = 0;
    for (const Frontier& g : frontiers_)
      if (g.id != f.id && (g.average - f.average).squaredNorm() < r2) ++f.n_near;
  }
}

UpdatePath updatePath(const MapUpdateNote& note, std::uint64_t last_sequence, std::uint64_t map_sequence) {
  if (last_sequence != 0 && note.sequence != last_sequence + 1) return UpdatePath::kRecomputed;
  if (note.changed_voxels == 0) return UpdatePath::kUnchanged;
  return map_sequence == note.sequence ? UpdatePath::kListed : UpdatePath::kBoxed;
}

UpdatePath applyMapUpdate(FrontierFinder& finder, const map::OccupancyMap& map, std::uint64_t map_sequence,
                          const std::vector<std::size_t>& map_changed, std::uint64_t last_sequence,
                          const MapUpdateNote& note, double now) {
  const UpdatePath path = updatePath(note, last_sequence, map_sequence);
  if (path == UpdatePath::kRecomputed) finder.recomputeAll(map, now);
  if (path == UpdatePath::kListed) finder.update(map, map_changed, now);
  if (path != UpdatePath::kBoxed) return path;
  // The box's cubes to their centres, clamped to the map first: a box reaching far outside it would not fit
  // a voxel index.
  const auto& geo = map.geometry();
  const Vec3 h = Vec3::Constant(0.5 * geo.resolution());
  const Aabb bounds = geo.bounds();
  const Vec3 lo = (note.changed_min + h).cwiseMax(bounds.min).cwiseMin(bounds.max);
  const Vec3 hi = (note.changed_max - h).cwiseMax(bounds.min).cwiseMin(bounds.max);
  finder.update(map, geo.coordToIndex(lo), geo.coordToIndex(hi), now);
  return path;
}

}  // namespace go_feap::frontier
