// Omission-aware global planner (DESIGN §3.5, paper §III-A.2): picks the frontiers near the
// UAV (NearCur_IDs), builds the travel-time matrix and omission likelihoods, and orders them
// with the tour solver. Path lengths come from injected callables, so the map and A* live
// elsewhere and this stays a pure function of its inputs.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"
#include "go_feap/planning/omission.h"

namespace go_feap::planning {

struct GlobalPlannerConfig {
  double s_near = 5.0;  ///< m, path distance from the UAV under which a frontier is near
  int n_min_tsp = 3;    ///< fewer near frontiers are topped up with the nearest others
  int n_max_tsp = 12;   ///< at most this many frontiers are ordered, nearest first
  double lambda = 0.1;  ///< 1/s, weight of sum xi_k t_k against travel time (0: shortest path)
  double v_max = 2.0;   ///< m/s, turns path lengths into travel times
  int max_exact = 12;   ///< candidate sets up to this size are solved exactly (<= 16)
  /// m: a path length searched between two points is reused for other points in the same two cells of
  /// this size (cubes from the world origin; 0 = never), for reuse_time s. Clusters are regrown with new
  /// ids and the UAV moves a little between calls: this spares most of their searches.
  double reuse_cell = 0.4;
  double reuse_time = 1.0;  ///< s
  /// Weight of the rest leg (0 = the paper's open path, eq. 3). When active frontiers remain beyond the
  /// candidates, the tour ends with a leg from its last frontier to the nearest of the rest_frontiers
  /// frontiers nearest the UAV outside the candidate set, weighted by this: the order then leaves
  /// towards what is left to explore, and the candidates on the far side of it are visited first
  /// instead of being left behind (a return flight later).
  double rest_weight = 0.0;
  int rest_frontiers = 3;  ///< frontiers outside the candidates the rest leg may end at (>= 1)
  OmissionConfig omission;

  /// Checks every key; the message names the bad one as its section does, e.g. "global: lambda must be
  /// >= 0" or "omission: t_max must be > 0".
  common::Status validate() const;
};

/// What the planner needs to know of a frontier (paper Table I).
struct FrontierSummary {
  unsigned id = 0;
  common::Vec3 average = common::Vec3::Zero();  ///< P_avg, world frame, m
  int cell_count = 0;                           ///< |C|
  double duration = 0.0;                        ///< T, s
  int n_near = 0;                               ///< N_near
  bool active = true;                           ///< inside the current altitude band
};

/// Path lengths (m) between average positions, indices into the frontier list given to
/// planTour(). A value that is not finite means "unreachable".
struct PathDistances {
  std::function<double(std::size_t j)> from_uav;                ///< UAV -> frontier j
  std::function<double(std::size_t i, std::size_t j)> between;  ///< frontier i -> frontier j
  /// Optional: a lower bound of from_uav(j) (the straight-line distance). When given, frontiers are
  /// asked about in increasing bound, and from_uav is not called for one whose bound is no smaller
  /// than the n_max_tsp-th smallest distance found so far (n_max_tsp + rest_frontiers-th with a rest
  /// leg, rest_weight > 0): it could not be a candidate, nor an end of the rest leg.
  std::function<double(std::size_t j)> from_uav_lower_bound;
  /// Optional: the path length UAV -> frontier j where from_uav(j) is only an estimate (a frontier at
  /// or beyond s_near, whose straight-line distance orders the top-up). When given, it prices the leg
  /// from the UAV of every candidate that from_uav put at s_near or beyond: a frontier 3 m away behind a
  /// wall (12 m by path) was otherwise priced at 3 m and visited first.
  std::function<double(std::size_t j)> from_uav_path;
};

/// NearCur_IDs: indices of the active frontiers whose distance from the UAV is below s_near,
/// topped up with the nearest other active frontiers to n_min_tsp when fewer are near, and
/// capped at the n_max_tsp nearest; sorted by distance (ties by index). Frontiers at a
/// non-finite or negative distance are never chosen. `distances_from_uav[j]` (m) belongs to
/// `frontiers[j]`; both vectors must have the same size (an empty result otherwise).
std::vector<std::size_t> selectCandidates(const std::vector<FrontierSummary>& frontiers,
                                          const std::vector<double>& distances_from_uav,
                                          const GlobalPlannerConfig& config);

/// The ordered tour handed to the local planner and rviz.
struct GlobalTour {
  std::vector<unsigned> frontier_ids;   ///< visiting order
  std::vector<std::size_t> indices;     ///< the same frontiers as indices into the input list
  std::vector<common::Vec3> waypoints;  ///< their P_avg, same order, m
  std::vector<double> xi;               ///< their omission likelihood, same order, s
  double cost = 0.0;                    ///< J = travel time + lambda * sum xi_k t_k (+ the rest leg), s
  double rest_leg = 0.0;                ///< s, the weighted rest leg J includes (0 without one)
  double lambda = 0.0;                  ///< omission weight used, 1/s
  bool exact = false;                   ///< true when solved by Held-Karp
};

/// Orders the NearCur_IDs candidates among `frontiers` (only active ones are considered):
/// cost matrix M[0][j] = from_uav(j) / v_max, M[i][j] = between(i, j) / v_max, column 0 = 0,
/// xi from config.omission, solved exactly up to max_exact candidates, heuristically above.
/// With rest_weight > 0 and active reachable frontiers outside the candidates (the rest), the tour
/// ends with a leg to the rest: rest_weight * min over the rest_frontiers rest frontiers nearest the
/// UAV of between(last, r) / v_max (one more node, always last, which the solver's exact limit
/// counts on top of max_exact). between is then also called for each candidate and those frontiers.
/// from_uav is called once per active frontier (fewer with from_uav_lower_bound; the candidates are the
/// same, distance ties aside), from_uav_path (when given) once per candidate at s_near or beyond, between
/// once per ordered pair of candidates.
/// `hint` (frontier ids, typically the last tour's order) warm-starts the heuristic solver when
/// the candidates are too many to solve exactly (solveHeuristic()); ids that are not candidates now
/// are skipped. Exact solutions ignore it.
/// No active reachable frontier gives an empty tour. Errors: an invalid config, or a
/// non-finite or negative distance between two candidates (named by frontier id).
common::Result<GlobalTour> planTour(const std::vector<FrontierSummary>& frontiers,
                                    const PathDistances& distances, const GlobalPlannerConfig& config,
                                    const std::vector<unsigned>& hint = {});

}  // namespace go_feap::planning
