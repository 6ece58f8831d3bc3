// Open-path frontier tour with omission penalty (DESIGN §3.5, paper eqs. 3-5): exact
// Held-Karp dynamic programming for the small candidate sets of GO-FEAP, and a local-search
// heuristic with the same objective for large sets (baseline modes) and as a fallback.
//
// Problem. Node 0 is the UAV, nodes 1..N are frontiers. cost(i, j) is the travel time (s)
// from node i to node j; it may be asymmetric. Column 0 and the diagonal are ignored (the
// tour is an open path that starts at the UAV and never returns, eq. 3). xi[k - 1] >= 0 is
// the omission likelihood of node k (s, see omission.h) and lambda >= 0 (1/s) its weight.
// A visiting order k_1..k_N (with k_0 = 0) arriving at k_m at time t_{k_m} costs
//
//   J = t_{k_N} + lambda * sum_k xi_k * t_k
//     = sum_m cost(k_{m-1}, k_m) * (1 + lambda * sum_{q >= m} xi_{k_q}),
//
// i.e. every leg is weighted by one plus lambda times the omission likelihood still
// unvisited when the leg starts (including its destination). The second form depends only
// on the set already visited, which is what makes the subset DP exact. With lambda = 0 J is
// the length (in time) of the shortest open path: FUEL's ATSP.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "go_feap/common/result.h"

namespace go_feap::planning {

/// Largest number of frontiers solveExact() accepts: it keeps 2^N * N states (16 -> 9 MB,
/// tens of milliseconds).
constexpr int kMaxExactFrontiers = 16;

struct TourResult {
  std::vector<int> order;  ///< frontier nodes 1..N of the cost matrix, in visiting order
  double cost = 0.0;       ///< J of `order` (s), as tourCost() computes it
  bool exact = false;      ///< true when `order` is optimal (Held-Karp)
  common::Status status = common::Status::Ok();  ///< an error leaves order empty
};

/// Ok when `cost` is square (N + 1) x (N + 1) with N >= 0, its entries outside column 0 and
/// the diagonal are finite and >= 0, xi has N finite entries >= 0, and lambda is finite and
/// >= 0; otherwise an error naming what is wrong.
common::Status checkTourProblem(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda);

/// J of `order`, which must be a permutation of 1..N of a problem that passes
/// checkTourProblem(); NaN when `order` is not such a permutation.
double tourCost(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda,
                const std::vector<int>& order);

/// `path` (distinct frontier nodes of 1..N in visiting order from the UAV, not all of them) with node `v`
/// (1..N, not on it) inserted where J of the path changes least, J of a path counting the xi of its own
/// nodes: the step that builds solveHeuristic()'s insertion start and completes its warm start. Throws
/// std::invalid_argument for a node out of range or repeated (the problem must pass checkTourProblem()).
std::vector<int> insertCheapest(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda,
                                const std::vector<int>& path, int v);

/// Optimal order by Held-Karp DP over subsets. Refuses (error status) invalid problems and
/// N > kMaxExactFrontiers. Ties are broken deterministically.
TourResult solveExact(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda);

/// Heuristic with the same objective: nearest-neighbour, ratio-greedy
/// (cost / (1 / n_left + lambda * xi)), cheapest-insertion and 12 fixed-first-frontier greedy
/// starts, each improved to a local optimum of 2-opt (segment reversal), Or-opt (moving a run
/// of nodes) and exact Held-Karp reordering of sliding windows of up to 8 nodes; then
/// iterated local search (kicks of two node relocations) from the best, up to 100 kicks for
/// small N and none from N = 224 on. Every move is evaluated on J itself in O(1); above 40
/// frontiers moves are restricted to 10-nearest candidate lists, so N = 300 takes about
/// 0.1-0.3 s. Deterministic: the kicks come from a fixed-seed generator, so the same problem
/// always gives the same tour. Refuses invalid problems.
///
/// `hint` warm-starts it: a visiting order of some of the nodes (1..N; others and repeats are
/// ignored), typically the last call's tour. The missing nodes are added by cheapest insertion
/// and only that path and the nearest-neighbour path are improved, before the same kicks: a
/// replan of a slowly changing problem costs one local search instead of 15.
TourResult solveHeuristic(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda,
                          const std::vector<int>& hint = {});

/// solveHeuristic()'s local search alone from `order` (a permutation of 1..N, else an error): 2-opt,
/// Or-opt and window moves, each taken when its O(1) change of J is negative, until none is; no other
/// start and no kicks. The result is never worse than `order`, and up to 40 frontiers a local optimum
/// of every 2-opt and Or-opt move.
TourResult improveTour(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda,
                       const std::vector<int>& order);

/// solveExact() when N <= max_exact (at most kMaxExactFrontiers), solveHeuristic() (with `hint`)
/// otherwise.
TourResult solve(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda, int max_exact,
                 const std::vector<int>& hint = {});

}  // namespace go_feap::planning
