// The global planning step with its path-length cache (DESIGN §3.4, §3.5): frontier summaries
// and the UAV position in, ordered tour out. Path lengths come from A* on the inflated map;
// frontier-to-frontier lengths are cached per id pair until either frontier changes (a changed
// frontier gets a new id; one whose cells stay the same keeps its id, and its lengths, however the map
// between the two changes, as FUEL keeps them). A length that fell back to a straight line is searched
// again after reuse_time. Shared by the GlobalPlanner nodelet and the lock-step bench.
#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "go_feap/frontier/frontier_finder.h"
#include "go_feap/planning/astar.h"
#include "go_feap/planning/global_planner.h"

namespace go_feap::planning {

/// Table I fields the global planner uses, taken from a frontier at time `now` (s).
FrontierSummary summarize(const frontier::Frontier& frontier, double now);

class TourPlanner {
 public:
  /// Keeps a reference to `astar` (and so to its map): the caller holds the map still during plan().
  TourPlanner(const GlobalPlannerConfig& config, const Astar& astar) : config_(config), astar_(astar) {}

  /// planTour() over `frontiers` from `uav` at time `now` (s). Beyond s_near (Euclidean, a lower bound of
  /// the path) a frontier cannot be near: its Euclidean distance orders the top-up, so no search is spent
  /// on it until it is chosen; a chosen one's leg from the UAV is searched (PathDistances::from_uav_path).
  /// Lengths between frontiers are searched once per unordered pair (from the lower id) and
  /// cached by id pair; cached lengths of frontiers no longer listed are dropped first, and so are
  /// Euclidean fallbacks (failed searches) older than reuse_time s, which are searched again. A length to
  /// search is first looked up among those searched in the last reuse_time s between the same two
  /// reuse_cell cells (either way round; a point 1e12 cells or more from the origin is searched, not looked
  /// up). A cached pair whose frontiers' averages are not those it was searched between (ids from outside
  /// the chain: a bag, a tool) is searched again. `fallbacks` (when not null) counts the distances that fell
  /// back to Euclidean. The last tour warm-starts the next (planTour()'s hint): a large tour is
  /// improved from where it was, not rebuilt from scratch at every call.
  common::Result<GlobalTour> plan(const std::vector<FrontierSummary>& frontiers, const Vec3& uav, double now,
                                  std::size_t* fallbacks = nullptr);

  const GlobalPlannerConfig& config() const { return config_; }
  std::size_t cacheSize() const { return cache_.size(); }
  std::size_t searches() const { return searches_; }  ///< path searches run so far

 private:
  using CellPair = std::array<std::int64_t, 6>;
  struct Recent {
    PathDistance distance;
    double time;  ///< when it was searched
  };
  struct Pair {
    Recent length;
    Vec3 from, to;  ///< the averages it was searched between (lower id first)
  };
  /// The length between a and b, searched now or reused from recent_.
  Recent search(const Vec3& a, const Vec3& b, double now);

  GlobalPlannerConfig config_;
  const Astar& astar_;
  std::map<std::pair<unsigned, unsigned>, Pair> cache_;  ///< by id pair, with when it was searched
  std::map<CellPair, Recent> recent_;
  std::vector<unsigned> last_tour_;  ///< frontier ids of the last tour, in order
  std::size_t searches_ = 0;
};

}  // namespace go_feap::planning
