#include "go_feap/planning/global_planner.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <queue>
#include <string>

#include "go_feap/planning/tour_solver.h"

namespace go_feap::planning {

using common::Result;
using common::Status;

Status GlobalPlannerConfig::validate() const {
  auto err = [](const char* key, const char* why) {
    return Status::Error(std::string("global: ") + key + " " + why);  // the keys are global/*
  };
  if (!(s_near > 0.0 && std::isfinite(s_near))) return err("s_near", "must be > 0");
  if (n_min_tsp < 1) return err("n_min_tsp", "must be >= 1");
  if (n_max_tsp < n_min_tsp) return err("n_max_tsp", "must be >= n_min_tsp");
  if (!(lambda >= 0.0 && std::isfinite(lambda))) return err("lambda", "must be >= 0");
  if (!(v_max > 0.0 && std::isfinite(v_max))) return err("v_max", "must be > 0");
  // 0 (off) or at least a millimetre: a cell of 1e-310 m made cell indices of inf, cast to integers.
  if (!(reuse_cell == 0.0 || (reuse_cell >= 1e-3 && std::isfinite(reuse_cell))))
    return err("reuse_cell", "must be 0 or finite and >= 0.001");
  if (!(reuse_time >= 0.0 && std::isfinite(reuse_time))) return err("reuse_time", "must be finite and >= 0");
  if (!(rest_weight >= 0.0 && std::isfinite(rest_weight))) return err("rest_weight", "must be finite and >= 0");
  if (rest_frontiers < 1) return err("rest_frontiers", "must be >= 1");
  if (max_exact < 0 || max_exact > kMaxExactFrontiers)
    return err("max_exact", ("must be in [0, " + std::to_string(kMaxExactFrontiers) + "]").c_str());
  // The rest leg's node is solved with the candidates: 16 of them and it were 17, past the exact solver,
  // and every tour went to the heuristic without a word.
  if (rest_weight > 0.0 && max_exact > kMaxExactFrontiers - 1)
    return err("max_exact", ("must be <= " + std::to_string(kMaxExactFrontiers - 1) +
                             " with a rest leg (rest_weight > 0): its node is solved with the candidates")
                                .c_str());
  if (Status s = omission.validate(); !s) return s;  // "omission: ...", as its keys omission/*
  // One frontier's lambda xi is at most lambda alpha_max w_t n_t, each key finite alone: 1e200 twice made
  // tour costs of inf, and no tour was ever chosen, without a key named. Past 1e6 travel time no longer counts.
  if (!(lambda * omission.alpha_max * omission.w_t * omission.n_t <= 1e6))
    return err("lambda", "times omission: alpha_max * w_t * n_t (the largest lambda xi of a frontier) must be <= 1e6");
  return Status::Ok();
}

std::vector<std::size_t> selectCandidates(const std::vector<FrontierSummary>& frontiers,
                                          const std::vector<double>& distances_from_uav,
                                          const GlobalPlannerConfig& config) {
  if (frontiers.size() != distances_from_uav.size()) return {};
  std::vector<std::size_t> reachable;
  for (std::size_t j = 0; j < frontiers.size(); ++j) {
    const double d = distances_from_uav[j];
    if (frontiers[j].active && d >= 0.0 && std::isfinite(d)) reachable.push_back(j);
  }
  std::stable_sort(reachable.begin(), reachable.end(), [&](std::size_t a, std::size_t b) {
    return distances_from_uav[a] < distances_from_uav[b];
  });
  // Sorted by distance, the near ones come first: keep them all, then the nearest others
  // up to n_min_tsp, and never more than n_max_tsp.
  const auto near =
      static_cast<std::size_t>(std::count_if(reachable.begin(), reachable.end(), [&](std::size_t j) {
        return distances_from_uav[j] < config.s_near;
      }));
  const std::size_t keep =
      std::min({reachable.size(), std::max(near, static_cast<std::size_t>(config.n_min_tsp)),
                static_cast<std::size_t>(std::max(config.n_max_tsp, 0))});
  reachable.resize(keep);
  return reachable;
}

Result<GlobalTour> planTour(const std::vector<FrontierSummary>& frontiers, const PathDistances& distances,
                            const GlobalPlannerConfig& config, const std::vector<unsigned>& hint) {
  if (Status s = config.validate(); !s) return s;
  constexpr double kUnreachable = std::numeric_limits<double>::infinity();
  std::vector<double> from_uav(frontiers.size(), kUnreachable);
  if (!distances.from_uav_lower_bound) {
    for (std::size_t j = 0; j < frontiers.size(); ++j)
      if (frontiers[j].active) from_uav[j] = distances.from_uav(j);
  } else {
    // In increasing lower bound; a frontier whose bound reaches the n_max_tsp-th smallest distance found
    // so far cannot be among the n_max_tsp nearest, nor can any after it: it stays unreachable here.
    std::vector<std::pair<double, std::size_t>> order;
    for (std::size_t j = 0; j < frontiers.size(); ++j)
      if (frontiers[j].active) order.emplace_back(distances.from_uav_lower_bound(j), j);
    std::stable_sort(order.begin(), order.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    // With a rest leg, the rest_frontiers nearest beyond the candidates are needed too.
    const auto cap = static_cast<std::size_t>(std::max(config.n_max_tsp, 0)) +
                     (config.rest_weight > 0.0 ? static_cast<std::size_t>(config.rest_frontiers) : 0);
    std::priority_queue<double> nearest;  // the cap smallest distances found, largest on top
    for (const auto& [bound, j] : order) {
      if (cap == 0 || (nearest.size() == cap && bound >= nearest.top())) break;
      from_uav[j] = distances.from_uav(j);
      if (!(from_uav[j] >= 0.0 && std::isfinite(from_uav[j]))) continue;
      nearest.push(from_uav[j]);
      if (nearest.size() > cap) nearest.pop();
    }
  }
  const std::vector<std::size_t> candidates = selectCandidates(frontiers, from_uav, config);
  // Candidates topped up from beyond s_near were ordered by an estimate: their legs from the UAV are
  // priced by path (from_uav stays as it was for the rest, which it only orders).
  std::vector<double> leg_from_uav(frontiers.size(), kUnreachable);
  for (std::size_t j : candidates) {
    leg_from_uav[j] = from_uav[j];
    if (!distances.from_uav_path || from_uav[j] < config.s_near) continue;
    const double path = distances.from_uav_path(j);
    if (!(path >= 0.0 && std::isfinite(path)))
      return Result<GlobalTour>::Error("global planner: path distance from the UAV to frontier " +
                                       std::to_string(frontiers[j].id) + " must be finite and >= 0, got " +
                                       std::to_string(path));
    leg_from_uav[j] = path;
  }

  // The rest: the reachable active frontiers outside the candidates, nearest the UAV first.
  std::vector<std::size_t> rest;
  if (config.rest_weight > 0.0 && !candidates.empty()) {
    std::vector<bool> candidate(frontiers.size(), false);
    for (std::size_t j : candidates) candidate[j] = true;
    for (std::size_t j = 0; j < frontiers.size(); ++j)
      if (frontiers[j].active && !candidate[j] && from_uav[j] >= 0.0 && std::isfinite(from_uav[j])) rest.push_back(j);
    std::stable_sort(rest.begin(), rest.end(), [&](std::size_t a, std::size_t b) { return from_uav[a] < from_uav[b]; });
    if (rest.size() > static_cast<std::size_t>(config.rest_frontiers)) rest.resize(config.rest_frontiers);
  }

  const int n = static_cast<int>(candidates.size());
  const bool rest_node = !rest.empty();
  const int nodes = n + (rest_node ? 1 : 0);
  Eigen::MatrixXd cost = Eigen::MatrixXd::Zero(nodes + 1, nodes + 1);
  std::vector<double> xi_of(nodes, 0.0);
  for (int a = 0; a < n; ++a) {
    const FrontierSummary& f = frontiers[candidates[a]];
    cost(0, a + 1) = leg_from_uav[candidates[a]] / config.v_max;
    xi_of[a] = xi(config.omission, f.cell_count, f.duration, f.n_near);
    for (int b = 0; b < n; ++b) {
      if (a == b) continue;
      const double s = distances.between(candidates[a], candidates[b]);
      if (!(s >= 0.0 && std::isfinite(s)))
        return Result<GlobalTour>::Error("global planner: path distance from frontier " +
                                         std::to_string(f.id) + " to frontier " +
                                         std::to_string(frontiers[candidates[b]].id) +
                                         " must be finite and >= 0, got " + std::to_string(s));
      cost(a + 1, b + 1) = s / config.v_max;
    }
  }
  if (rest_node) {
    // Node n + 1 ends the tour: a candidate's leg to it is the way on to the nearest rest frontier (a rest
    // frontier it cannot reach does not count; none at all: no leg). Leaving it, or going to it first,
    // costs more than any tour that ends with it, so the solver puts it last.
    for (int a = 0; a < n; ++a) {
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t r : rest) {
        const double s = distances.between(candidates[a], r);
        if (s >= 0.0 && std::isfinite(s)) best = std::min(best, s);
      }
      cost(a + 1, n + 1) = std::isfinite(best) ? config.rest_weight * best / config.v_max : 0.0;
    }
    double sum_xi = 0.0;
    for (double x : xi_of) sum_xi += x;
    // Any tour with the rest node last costs at most the sum of all entries times (1 + lambda sum xi).
    const double never = 2.0 * (cost.sum() + 1.0) * (1.0 + config.lambda * sum_xi);
    cost(0, n + 1) = never;
    for (int b = 1; b <= n; ++b) cost(n + 1, b) = never;
  }

  const int max_exact = std::min(config.max_exact + (rest_node ? 1 : 0), kMaxExactFrontiers);
  // The hint in node numbers: its frontiers that are candidates now, in its order.
  std::map<unsigned, int> node_of;
  for (int a = 0; a < n; ++a) node_of.emplace(frontiers[candidates[a]].id, a + 1);
  std::vector<int> hint_nodes;
  for (unsigned id : hint)
    if (auto it = node_of.find(id); it != node_of.end()) hint_nodes.push_back(it->second);
  const TourResult solved = solve(cost, xi_of, config.lambda, max_exact, hint_nodes);
  if (!solved.status) return solved.status;
  GlobalTour tour;
  tour.cost = solved.cost;
  tour.lambda = config.lambda;
  tour.exact = solved.exact;
  int previous = 0;
  for (int node : solved.order) {
    if (node == n + 1 && rest_node) {
      tour.rest_leg = cost(previous, node);
      continue;
    }
    const std::size_t j = candidates[node - 1];
    tour.frontier_ids.push_back(frontiers[j].id);
    tour.indices.push_back(j);
    tour.waypoints.push_back(frontiers[j].average);
    tour.xi.push_back(xi_of[node - 1]);
    previous = node;
  }
  return tour;
}

}  // namespace go_feap::planning
