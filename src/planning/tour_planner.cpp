#include "go_feap/planning/tour_planner.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>

namespace go_feap::planning {

FrontierSummary summarize(const frontier::Frontier& frontier, double now) {
  FrontierSummary s;
  s.id = frontier.id;
  s.average = frontier.average;
  s.cell_count = static_cast<int>(frontier.cells.size());
  s.duration = frontier.duration(now);
  s.n_near = frontier.n_near;
  s.active = frontier.active;
  return s;
}

TourPlanner::Recent TourPlanner::search(const Vec3& a, const Vec3& b, double now) {
  const double cell = config_.reuse_cell;
  // Cells keyed in 64-bit integers: a point 1e12 cells or more away (or not finite) has no key (its cast
  // would be undefined), and is searched.
  const bool keyed =
      cell > 0.0 && ((a / cell).array().abs() < 1e12).all() && ((b / cell).array().abs() < 1e12).all();
  if (!keyed) {
    ++searches_;
    return {pathDistance(astar_, a, b), now};
  }
  CellPair key;
  for (int i = 0; i < 3; ++i) {
    key[i] = static_cast<std::int64_t>(std::floor(a[i] / cell));
    key[i + 3] = static_cast<std::int64_t>(std::floor(b[i] / cell));
  }
  if (std::lexicographical_compare(key.begin() + 3, key.end(), key.begin(), key.begin() + 3))
    std::rotate(key.begin(), key.begin() + 3, key.end());  // the same key either way round
  auto it = recent_.find(key);
  if (it != recent_.end()) return it->second;
  ++searches_;
  return recent_.emplace(key, Recent{pathDistance(astar_, a, b), now}).first->second;
}

common::Result<GlobalTour> TourPlanner::plan(const std::vector<FrontierSummary>& frontiers, const Vec3& uav,
                                             double now, std::size_t* fallbacks) {
  // Reused lengths expire (the map has grown since), and so does anything from a clock that went back.
  for (auto it = recent_.begin(); it != recent_.end();)
    it = now - it->second.time > config_.reuse_time || now < it->second.time ? recent_.erase(it) : std::next(it);
  // A pair's length is kept while both frontiers are listed; one that fell back to a straight line (the
  // search failed: no way through the known map, or over budget) is searched again after reuse_time,
  // since the map may have opened a way since and the straight line understates any way round.
  std::set<unsigned> ids;
  for (const FrontierSummary& f : frontiers) ids.insert(f.id);
  for (auto it = cache_.begin(); it != cache_.end();) {
    const bool listed = ids.count(it->first.first) && ids.count(it->first.second);
    const Recent& length = it->second.length;
    const bool stale = length.distance.euclidean_fallback &&
                       (now - length.time > config_.reuse_time || now < length.time);
    it = listed && !stale ? std::next(it) : cache_.erase(it);
  }
  std::size_t local_fallbacks = 0;
  std::set<std::pair<unsigned, unsigned>> fallback_pairs;  // each pair counted once per call
  PathDistances d;
  std::vector<double> path_from_uav(frontiers.size(), -1.0);  // searched in this call (-1: not yet)
  d.from_uav_path = [&](std::size_t j) {
    if (path_from_uav[j] >= 0.0) return path_from_uav[j];
    const PathDistance pd = search(uav, frontiers[j].average, now).distance;
    local_fallbacks += pd.euclidean_fallback;
    return path_from_uav[j] = pd.metres;
  };
  d.from_uav = [&](std::size_t j) {
    const double e = (frontiers[j].average - uav).norm();
    return e >= config_.s_near ? e : d.from_uav_path(j);
  };
  d.from_uav_lower_bound = [&](std::size_t j) { return (frontiers[j].average - uav).norm(); };
  // A path is as long one way as the other: one search per unordered pair, from the frontier with
  // the lower id (so that the same pair always gets the same search).
  d.between = [&](std::size_t i, std::size_t j) {
    if (frontiers[j].id < frontiers[i].id) std::swap(i, j);
    const auto key = std::make_pair(frontiers[i].id, frontiers[j].id);
    auto it = cache_.find(key);
    const Vec3 &from = frontiers[i].average, &to = frontiers[j].average;
    if (it != cache_.end() && (it->second.from != from || it->second.to != to)) {  // the same ids elsewhere
      cache_.erase(it);
      it = cache_.end();
    }
    if (it == cache_.end()) it = cache_.emplace(key, Pair{search(from, to, now), from, to}).first;
    const PathDistance& length = it->second.length.distance;
    if (length.euclidean_fallback) fallback_pairs.insert(key);  // asked both ways round, and for rests
    return length.metres;
  };
  auto tour = planTour(frontiers, d, config_, last_tour_);
  if (tour) last_tour_ = tour->frontier_ids;
  if (fallbacks) *fallbacks = local_fallbacks + fallback_pairs.size();
  return tour;
}

}  // namespace go_feap::planning
