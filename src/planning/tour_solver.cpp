#include "go_feap/planning/tour_solver.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>

namespace go_feap::planning {

using common::Status;

namespace {

TourResult failure(Status status) {
  TourResult r;
  r.status = std::move(status);
  return r;
}

// A full pass finding nothing to improve ends local search long before this; the cap only
// bounds the run time on adversarial inputs.
constexpr int kMaxLocalSearchPasses = 200;
// Or-opt relocates runs of any length on problems small enough to try every move, of up to
// kOrOptMaxRun consecutive nodes on larger ones.
constexpr int kOrOptMaxRun = 6;
// Extra greedy starts, each from one of the most promising first frontiers.
constexpr int kFirstNodeStarts = 12;
// Largest window of consecutive nodes reordered exactly, and the work budget per pass over
// all windows (see windowSize()).
constexpr int kMaxWindow = 8;
constexpr long kWindowWork = 1000000;
// Problems above kFullNeighbourhoodMax frontiers only try moves that create a leg to one of
// the kNeighbours cheapest successors or predecessors of a node.
constexpr int kNeighbours = 10;
constexpr int kFullNeighbourhoodMax = 40;
// Iterated local search: min(kMaxKicks, kKickWork / N^2) kicks of kKickMoves random node
// relocations each (100 up to N = 22, none from N = 224 on).
constexpr int kMaxKicks = 100;
constexpr long kKickWork = 50000;
constexpr int kKickMoves = 2;
constexpr unsigned kKickSeed = 20240601;

// An open path p[0] = 0, p[1..N] with prefix sums that give the change of J for a 2-opt
// or Or-opt move or a node insertion in O(1). Leg q (1 <= q <= n) runs p[q-1] -> p[q] and
// carries weight 1 + lambda * R[q], R[q] = sum of xi over p[q..n].
class OpenPath {
 public:
  OpenPath(const Eigen::MatrixXd& cost, const std::vector<double>& node_xi, double lambda)
      : c_(cost), x_(node_xi), lambda_(lambda) {}

  void assign(std::vector<int> p) {
    p_ = std::move(p);
    rebuild();
  }
  const std::vector<int>& path() const { return p_; }
  /// Position of node v on the path (0 for the UAV).
  int position(int v) const { return pos_[v]; }
  int size() const { return static_cast<int>(p_.size()) - 1; }
  double total() const { return pc_[size()]; }

  /// Change of J when p[i..j] (1 <= i < j <= n) is reversed.
  double twoOptDelta(int i, int j) const {
    const int n = size();
    const int last = std::min(j + 1, n);
    const double old_cost = pc_[last] - pc_[i - 1];
    double new_cost = d(p_[i - 1], p_[j]) * legWeight(r_[i]);
    new_cost += (1.0 + lambda_ * (r_[i] + r_[j + 1])) * (pa_[j] - pa_[i]) - lambda_ * (pb_[j] - pb_[i]);
    if (j < n) new_cost += d(p_[i], p_[j + 1]) * legWeight(r_[j + 1]);
    return new_cost - old_cost;
  }
  void applyTwoOpt(int i, int j) {
    std::reverse(p_.begin() + i, p_.begin() + j + 1);
    rebuild();
  }

  /// Change of J when the run p[i..e] (1 <= i <= e <= n) is moved to follow p[k], for k
  /// outside [i - 1, e].
  double orOptDelta(int i, int e, int k) const {
    const int n = size();
    const double xs = r_[i] - r_[e + 1];
    const double run_len = pd_[e] - pd_[i];
    const double run_cost = pc_[e] - pc_[i];
    if (k > e) {  // later: p[0..i-1], p[e+1..k], run, p[k+1..n]
      const double old_cost = pc_[std::min(k + 1, n)] - pc_[i - 1];
      double new_cost = d(p_[i - 1], p_[e + 1]) * legWeight(r_[i]);
      new_cost += (pc_[k] - pc_[e + 1]) + lambda_ * xs * (pd_[k] - pd_[e + 1]);
      new_cost += d(p_[k], p_[i]) * legWeight(xs + r_[k + 1]);
      new_cost += run_cost + lambda_ * (r_[k + 1] - r_[e + 1]) * run_len;
      if (k < n) new_cost += d(p_[e], p_[k + 1]) * legWeight(r_[k + 1]);
      return new_cost - old_cost;
    }
    // earlier (k <= i - 2): p[0..k], run, p[k+1..i-1], p[e+1..n]
    const double old_cost = pc_[std::min(e + 1, n)] - pc_[k];
    double new_cost = d(p_[k], p_[i]) * legWeight(r_[k + 1]);
    new_cost += run_cost + lambda_ * (r_[k + 1] - xs - r_[e + 1]) * run_len;
    new_cost += d(p_[e], p_[k + 1]) * legWeight(r_[k + 1] - xs);
    new_cost += (pc_[i - 1] - pc_[k + 1]) - lambda_ * xs * (pd_[i - 1] - pd_[k + 1]);
    if (e < n) new_cost += d(p_[i - 1], p_[e + 1]) * legWeight(r_[e + 1]);
    return new_cost - old_cost;
  }
  void applyOrOpt(int i, int e, int k) {
    if (k > e) {
      std::rotate(p_.begin() + i, p_.begin() + e + 1, p_.begin() + k + 1);
    } else {
      std::rotate(p_.begin() + k + 1, p_.begin() + i, p_.begin() + e + 1);
    }
    rebuild();
  }

  /// Change of J when node v (not on the path) is inserted after p[k], 0 <= k <= n.
  double insertionDelta(int v, int k) const {
    const int n = size();
    double delta = d(p_[k], v) * legWeight(x_[v] + r_[k + 1]) + lambda_ * x_[v] * pd_[k];
    if (k < n) delta += d(v, p_[k + 1]) * legWeight(r_[k + 1]) - d(p_[k], p_[k + 1]) * legWeight(r_[k + 1]);
    return delta;
  }
  void insert(int v, int k) {
    p_.insert(p_.begin() + k + 1, v);
    rebuild();
  }

  /// Best order of the window p[a..b] (1 <= a <= b <= n, b - a < kMaxWindow) with the rest
  /// of the path fixed, by Held-Karp over the window: the legs before the window keep their
  /// weights (same set unvisited) and so does the leg leaving it, so only the window's own
  /// legs and its two connections change. Writes the order to `order` and returns the
  /// change of J (<= 0 up to rounding).
  double windowDelta(int a, int b, std::vector<int>& order) {
    const int n = size();
    const int w = b - a + 1;
    const std::size_t full = (std::size_t{1} << w) - 1;
    const double after = r_[b + 1];  // xi unvisited behind the window
    window_xi_.assign(full + 1, 0.0);
    for (std::size_t s = 1; s <= full; ++s)
      window_xi_[s] = window_xi_[s & (s - 1)] + x_[p_[a + __builtin_ctzll(s)]];
    const double inside = window_xi_[full];
    constexpr double kInf = std::numeric_limits<double>::infinity();
    window_dp_.assign((full + 1) * w, kInf);
    window_parent_.assign((full + 1) * w, -1);
    for (int k = 0; k < w; ++k)
      window_dp_[(std::size_t{1} << k) * w + k] = d(p_[a - 1], p_[a + k]) * legWeight(after + inside);
    for (std::size_t s = 1; s < full; ++s) {
      const double weight = legWeight(after + inside - window_xi_[s]);
      for (int j = 0; j < w; ++j) {
        const double base = window_dp_[s * w + j];
        if (!(s >> j & 1) || base == kInf) continue;
        for (int k = 0; k < w; ++k) {
          if (s >> k & 1) continue;
          const std::size_t t = (s | (std::size_t{1} << k)) * w + k;
          const double v = base + d(p_[a + j], p_[a + k]) * weight;
          if (v < window_dp_[t]) {
            window_dp_[t] = v;
            window_parent_[t] = static_cast<std::int8_t>(j);
          }
        }
      }
    }
    int last = -1;
    double best = kInf;
    for (int j = 0; j < w; ++j) {
      const double v = window_dp_[full * w + j] + (b < n ? d(p_[a + j], p_[b + 1]) * legWeight(after) : 0.0);
      if (v < best) best = v, last = j;
    }
    order.assign(w, 0);
    std::size_t s = full;
    for (int pos = w - 1, j = last; pos >= 0; --pos) {
      order[pos] = p_[a + j];
      const int prev = window_parent_[s * w + j];
      s &= ~(std::size_t{1} << j);
      j = prev;
    }
    return best - (pc_[std::min(b + 1, n)] - pc_[a - 1]);
  }
  void applyWindow(int a, const std::vector<int>& order) {
    std::copy(order.begin(), order.end(), p_.begin() + a);
    rebuild();
  }

 private:
  double d(int a, int b) const { return c_(a, b); }
  double legWeight(double remaining_xi) const { return 1.0 + lambda_ * remaining_xi; }

  void rebuild() {
    const int n = size();
    pos_.resize(c_.rows());
    for (int q = 0; q <= n; ++q) pos_[p_[q]] = q;
    r_.assign(n + 2, 0.0);
    for (int q = n; q >= 1; --q) r_[q] = r_[q + 1] + x_[p_[q]];
    r_[0] = r_[1];
    pd_.assign(n + 1, 0.0);
    pc_.assign(n + 1, 0.0);
    pa_.assign(n + 1, 0.0);
    pb_.assign(n + 1, 0.0);
    for (int q = 1; q <= n; ++q) {
      const double fwd = d(p_[q - 1], p_[q]);
      // Column 0 is ignored (the API's word): the reversed first leg, back to the start, is never used
      // (only differences pa_[j] - pa_[i] with i >= 1 are), and an infinite value there made every 2-opt
      // delta inf - inf = NaN, switching 2-opt off.
      const double back = p_[q - 1] == 0 ? 0.0 : d(p_[q], p_[q - 1]);
      pd_[q] = pd_[q - 1] + fwd;
      pc_[q] = pc_[q - 1] + fwd * legWeight(r_[q]);
      pa_[q] = pa_[q - 1] + back;
      pb_[q] = pb_[q - 1] + back * r_[q];
    }
  }

  const Eigen::MatrixXd& c_;
  const std::vector<double>& x_;  // indexed by node, x_[0] = 0
  double lambda_;
  std::vector<int> p_;
  std::vector<int> pos_;                       // pos_[p_[q]] = q
  std::vector<double> r_;                      // r_[q]: xi still unvisited when leg q starts; r_[n + 1] = 0
  std::vector<double> pd_;                     // prefix sums of leg times
  std::vector<double> pc_;                     // prefix sums of weighted leg times (pc_[n] = J)
  std::vector<double> pa_;                     // prefix sums of reversed leg times c(p[q], p[q-1])
  std::vector<double> pb_;                     // prefix sums of reversed leg times times r_[q]
  std::vector<double> window_xi_, window_dp_;  // windowDelta() scratch
  std::vector<std::int8_t> window_parent_;
};

std::vector<double> nodeXi(const std::vector<double>& xi) {
  std::vector<double> x(xi.size() + 1, 0.0);
  std::copy(xi.begin(), xi.end(), x.begin() + 1);
  return x;
}

// Greedy path from the UAV: next is the unvisited node with the smallest
// cost(current, k) / (urgency of k). The urgency 1 / (nodes left) + lambda * xi_k follows
// Smith's ratio rule for weighted completion times; with lambda = 0 it is nearest neighbour.
std::vector<int> greedyPath(const Eigen::MatrixXd& cost, const std::vector<double>& x, double lambda,
                            bool use_ratio, int first = 0) {
  const int n = static_cast<int>(cost.rows()) - 1;
  std::vector<int> path{0};
  std::vector<bool> used(n + 1, false);
  if (first > 0) path.push_back(first), used[first] = true;
  for (int left = n - (first > 0); left > 0; --left) {
    const int cur = path.back();
    int best = -1;
    double best_score = std::numeric_limits<double>::infinity();
    for (int k = 1; k <= n; ++k) {
      if (used[k]) continue;
      const double score = use_ratio ? cost(cur, k) / (1.0 / left + lambda * x[k]) : cost(cur, k);
      if (best < 0 || score < best_score) {
        best = k;
        best_score = score;
      }
    }
    used[best] = true;
    path.push_back(best);
  }
  return path;
}

// Where node v (not on the path) is inserted at the least change of J: after p[k] for the returned k.
int cheapestInsertion(const OpenPath& path, int v) {
  int best_k = 0;
  double best_delta = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= path.size(); ++k) {
    const double delta = path.insertionDelta(v, k);
    if (delta < best_delta) {
      best_delta = delta;
      best_k = k;
    }
  }
  return best_k;
}

// `start` (0 first, then distinct frontier nodes) with every other node added by cheapest insertion (exact
// change of J), nearest the UAV first.
std::vector<int> insertRest(const Eigen::MatrixXd& cost, const std::vector<double>& x, double lambda,
                            std::vector<int> start) {
  const int n = static_cast<int>(cost.rows()) - 1;
  std::vector<bool> used(n + 1, false);
  for (int v : start) used[v] = true;
  std::vector<int> missing;
  for (int v = 1; v <= n; ++v)
    if (!used[v]) missing.push_back(v);
  std::stable_sort(missing.begin(), missing.end(), [&](int a, int b) { return cost(0, a) < cost(0, b); });
  OpenPath path(cost, x, lambda);
  path.assign(std::move(start));
  for (int v : missing) path.insert(v, cheapestInsertion(path, v));
  return path.path();
}

// Cheapest insertion from the UAV alone.
std::vector<int> insertionPath(const Eigen::MatrixXd& cost, const std::vector<double>& x, double lambda) {
  return insertRest(cost, x, lambda, {0});
}

// The hint's nodes in its order (repeats and nodes outside 1..N skipped), then the others by cheapest
// insertion; empty when the hint holds no node.
std::vector<int> hintedPath(const Eigen::MatrixXd& cost, const std::vector<double>& x, double lambda,
                            const std::vector<int>& hint) {
  const int n = static_cast<int>(cost.rows()) - 1;
  std::vector<bool> used(n + 1, false);
  std::vector<int> start{0};
  for (int v : hint)
    if (v >= 1 && v <= n && !used[v]) used[v] = true, start.push_back(v);
  if (start.size() == 1) return {};
  return insertRest(cost, x, lambda, std::move(start));
}

// Windows reordered exactly hold the most nodes w <= kMaxWindow with N 2^w w^2 <= kWindowWork,
// so that a pass over all windows costs about the same for every N.
int windowSize(int n) {
  int w = std::min(n, kMaxWindow);
  while (w > 2 && static_cast<long>(n) * (1L << w) * w * w > kWindowWork) --w;
  return w;
}

// Candidate lists: for each node the kNeighbours cheapest successors (frontiers) and
// predecessors (UAV included). On large problems a move is only tried when one of the legs
// it creates joins a node to one of these; smaller problems try every move.
struct Neighbours {
  std::vector<std::vector<int>> out, in;
  bool empty() const { return out.empty(); }
};

Neighbours nearestNeighbours(const Eigen::MatrixXd& cost) {
  const int n = static_cast<int>(cost.rows()) - 1;
  Neighbours nb;
  if (n <= kFullNeighbourhoodMax) return nb;
  nb.out.resize(n + 1);
  nb.in.resize(n + 1);
  std::vector<int> nodes;
  auto keepCheapest = [&](std::vector<int>& list, auto&& less) {
    const auto k = std::min<std::size_t>(kNeighbours, nodes.size());
    std::partial_sort(nodes.begin(), nodes.begin() + k, nodes.end(), less);
    list.assign(nodes.begin(), nodes.begin() + k);
  };
  for (int v = 0; v <= n; ++v) {
    nodes.clear();
    for (int u = 1; u <= n; ++u)
      if (u != v) nodes.push_back(u);
    keepCheapest(nb.out[v], [&](int a, int b) {
      return cost(v, a) < cost(v, b) || (cost(v, a) == cost(v, b) && a < b);
    });
    if (v == 0) continue;
    nodes.clear();
    for (int u = 0; u <= n; ++u)
      if (u != v) nodes.push_back(u);
    keepCheapest(nb.in[v], [&](int a, int b) {
      return cost(a, v) < cost(b, v) || (cost(a, v) == cost(b, v) && a < b);
    });
  }
  return nb;
}

// Local search to a local optimum of 2-opt, Or-opt and exact window reordering: the cheap
// first-improvement passes repeat until they stall, then a window pass; stops when that
// finds nothing either.
void improve(OpenPath& path, const Neighbours& nb) {
  const int n = path.size();
  const int max_run = nb.empty() ? n - 1 : std::min(n - 1, kOrOptMaxRun);
  const int w = windowSize(n);
  auto improves = [&](double delta) { return delta < -1e-12 * std::max(1.0, std::abs(path.total())); };
  bool improved = false;
  auto tryTwoOpt = [&](int i, int j) {
    if (j <= i || j > n || !improves(path.twoOptDelta(i, j))) return;
    path.applyTwoOpt(i, j);
    improved = true;
  };
  auto tryOrOpt = [&](int i, int e, int k) {
    if (k < 0 || k > n || (k >= i - 1 && k <= e) || !improves(path.orOptDelta(i, e, k))) return;
    path.applyOrOpt(i, e, k);
    improved = true;
  };
  std::vector<int> window_order;
  for (int pass = 0; pass < kMaxLocalSearchPasses; ++pass) {
    improved = false;
    for (int i = 1; i < n; ++i) {
      if (nb.empty()) {
        for (int j = i + 1; j <= n; ++j) tryTwoOpt(i, j);
        continue;
      }
      // New legs p[i-1] -> p[j] and p[i] -> p[j+1].
      for (int b : nb.out[path.path()[i - 1]]) tryTwoOpt(i, path.position(b));
      for (int b : nb.out[path.path()[i]]) tryTwoOpt(i, path.position(b) - 1);
    }
    for (int len = 1; len <= max_run; ++len) {
      for (int i = 1; i + len - 1 <= n; ++i) {
        const int e = i + len - 1;
        if (nb.empty()) {
          for (int k = 0; k <= n; ++k) tryOrOpt(i, e, k);
          continue;
        }
        // New legs p[k] -> p[i] and p[e] -> p[k+1], or the run moved to the end.
        for (int u : nb.in[path.path()[i]]) tryOrOpt(i, e, path.position(u));
        for (int b : nb.out[path.path()[e]]) tryOrOpt(i, e, path.position(b) - 1);
        tryOrOpt(i, e, n);
      }
    }
    if (improved) continue;
    for (int a = 1; a + w - 1 <= n; ++a) {
      if (improves(path.windowDelta(a, a + w - 1, window_order))) {
        path.applyWindow(a, window_order);
        improved = true;
      }
    }
    if (!improved) break;
  }
}

// The result for path p (p[0] = 0), its cost evaluated the same way for both solvers.
TourResult fromPath(const std::vector<int>& p, bool exact, const Eigen::MatrixXd& cost,
                    const std::vector<double>& xi, double lambda) {
  TourResult r;
  r.order.assign(p.begin() + 1, p.end());
  r.cost = tourCost(cost, xi, lambda, r.order);
  r.exact = exact;
  return r;
}

}  // namespace

Status checkTourProblem(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda) {
  if (cost.rows() < 1 || cost.rows() != cost.cols())
    return Status::Error("tour: cost matrix must be square (N + 1) x (N + 1) with N >= 0, got " +
                         std::to_string(cost.rows()) + " x " + std::to_string(cost.cols()));
  const Eigen::Index n = cost.rows() - 1;
  if (static_cast<Eigen::Index>(xi.size()) != n)
    return Status::Error("tour: xi must have " + std::to_string(n) + " entries (one per frontier), got " +
                         std::to_string(xi.size()));
  if (!(lambda >= 0.0 && std::isfinite(lambda))) return Status::Error("tour: lambda must be finite and >= 0");
  for (Eigen::Index k = 0; k < n; ++k)
    if (!(xi[k] >= 0.0 && std::isfinite(xi[k])))
      return Status::Error("tour: xi of frontier " + std::to_string(k + 1) + " must be finite and >= 0");
  double max_cost = 0.0, sum_xi = 0.0;
  for (Eigen::Index i = 0; i <= n; ++i)
    for (Eigen::Index j = 1; j <= n; ++j) {
      if (i != j && !(cost(i, j) >= 0.0 && std::isfinite(cost(i, j))))
        return Status::Error("tour: cost(" + std::to_string(i) + ", " + std::to_string(j) +
                             ") must be finite and >= 0");
      if (i != j) max_cost = std::max(max_cost, cost(i, j));
    }
  for (double x : xi) sum_xi += x;
  // Every tour's cost is at most N legs of the largest cost at the largest weight. Where that bound is not
  // finite (travel times near 1e308 s, lambda xi near 1e300) the solvers' sums overflowed: every tour cost
  // infinity, the exact solver followed no parent and the heuristic kept no tour.
  const double bound = static_cast<double>(n) * max_cost * (1.0 + lambda * sum_xi);
  if (!(bound <= 1e300))
    return Status::Error("tour: costs, xi and lambda are too large: a tour's cost could overflow (bound " +
                         std::to_string(bound) + ")");
  return Status::Ok();
}

double tourCost(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda,
                const std::vector<int>& order) {
  const int n = static_cast<int>(xi.size());
  std::vector<bool> seen(n + 1, false);
  if (static_cast<int>(order.size()) != n || cost.rows() != n + 1 || cost.cols() != n + 1)
    return std::numeric_limits<double>::quiet_NaN();
  double remaining = 0.0;
  for (int k : order) {
    if (k < 1 || k > n || seen[k]) return std::numeric_limits<double>::quiet_NaN();
    seen[k] = true;
    remaining += xi[k - 1];
  }
  double j = 0.0;
  int prev = 0;
  for (int k : order) {
    j += cost(prev, k) * (1.0 + lambda * remaining);
    remaining -= xi[k - 1];
    prev = k;
  }
  return j;
}

std::vector<int> insertCheapest(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda,
                                const std::vector<int>& path, int v) {
  const int n = static_cast<int>(xi.size());
  std::vector<bool> on(n + 1, false);
  for (int k : path) {
    if (k < 1 || k > n || on[k]) throw std::invalid_argument("insertCheapest: a node out of range or repeated");
    on[k] = true;
  }
  if (v < 1 || v > n || on[v]) throw std::invalid_argument("insertCheapest: the node to insert is out of range or on the path");
  const std::vector<double> x = nodeXi(xi);
  OpenPath open(cost, x, lambda);
  std::vector<int> p{0};
  p.insert(p.end(), path.begin(), path.end());
  open.assign(std::move(p));
  open.insert(v, cheapestInsertion(open, v));
  return std::vector<int>(open.path().begin() + 1, open.path().end());
}

TourResult solveExact(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda) {
  if (Status s = checkTourProblem(cost, xi, lambda); !s) return failure(s);
  const int n = static_cast<int>(xi.size());
  if (n > kMaxExactFrontiers)
    return failure(Status::Error("tour: exact solver takes at most " + std::to_string(kMaxExactFrontiers) +
                                 " frontiers, got " + std::to_string(n)));
  if (n == 0) return fromPath({0}, true, cost, xi, lambda);

  // State (S, j): frontiers S visited (bit b = node b + 1), ending at node j + 1.
  const std::size_t full = (std::size_t{1} << n) - 1;
  std::vector<double> subset_xi(full + 1, 0.0);
  for (std::size_t s = 1; s <= full; ++s) {
    const int low = __builtin_ctzll(s);
    subset_xi[s] = subset_xi[s & (s - 1)] + xi[low];
  }
  const double total_xi = subset_xi[full];
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::vector<double> dp((full + 1) * n, kInf);
  std::vector<std::int8_t> parent((full + 1) * n, -1);
  for (int k = 0; k < n; ++k) dp[(std::size_t{1} << k) * n + k] = cost(0, k + 1) * (1.0 + lambda * total_xi);

  for (std::size_t s = 1; s < full; ++s) {
    const double weight = 1.0 + lambda * (total_xi - subset_xi[s]);
    for (int j = 0; j < n; ++j) {
      const double base = dp[s * n + j];
      if (!(s >> j & 1) || base == kInf) continue;
      for (int k = 0; k < n; ++k) {
        if (s >> k & 1) continue;
        const std::size_t t = (s | (std::size_t{1} << k)) * n + k;
        const double v = base + cost(j + 1, k + 1) * weight;
        if (v < dp[t]) {
          dp[t] = v;
          parent[t] = static_cast<std::int8_t>(j);
        }
      }
    }
  }

  int last = 0;
  for (int j = 1; j < n; ++j)
    if (dp[full * n + j] < dp[full * n + last]) last = j;
  std::vector<int> path(n + 1, 0);
  std::size_t s = full;
  for (int pos = n, j = last; pos >= 1; --pos) {
    path[pos] = j + 1;
    const int prev = parent[s * n + j];
    s &= ~(std::size_t{1} << j);
    j = prev;
  }
  return fromPath(path, true, cost, xi, lambda);
}

TourResult solveHeuristic(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda,
                          const std::vector<int>& hint) {
  if (Status s = checkTourProblem(cost, xi, lambda); !s) return failure(s);
  const int n = static_cast<int>(xi.size());
  if (n == 0) return fromPath({0}, false, cost, xi, lambda);
  const std::vector<double> x = nodeXi(xi);

  std::vector<std::vector<int>> starts;
  std::vector<int> warm = hintedPath(cost, x, lambda, hint);
  if (!warm.empty()) {
    // A warm start (the last tour, new frontiers inserted) is near a local optimum already, and a tour
    // no better than the greedy path is left by the comparison below.
    starts = {std::move(warm), greedyPath(cost, x, lambda, false)};
  } else {
    starts = {greedyPath(cost, x, lambda, false), greedyPath(cost, x, lambda, true), insertionPath(cost, x, lambda)};
    // Local optima of asymmetric instances differ mostly in how they begin, so greedy paths
    // also start from each of the most promising first frontiers.
    std::vector<int> firsts(n);
    std::iota(firsts.begin(), firsts.end(), 1);
    std::stable_sort(firsts.begin(), firsts.end(), [&](int a, int b) {
      return cost(0, a) / (1.0 / n + lambda * x[a]) < cost(0, b) / (1.0 / n + lambda * x[b]);
    });
    firsts.resize(std::min(n, kFirstNodeStarts));
    for (int first : firsts) starts.push_back(greedyPath(cost, x, lambda, true, first));
  }
  const Neighbours nb = nearestNeighbours(cost);
  OpenPath path(cost, x, lambda);
  std::vector<int> best;
  double best_cost = std::numeric_limits<double>::infinity();
  for (const auto& start : starts) {
    path.assign(start);
    improve(path, nb);
    if (path.total() < best_cost) {
      best_cost = path.total();
      best = path.path();
    }
  }
  // Iterated local search from the best local optimum: each kick relocates two nodes, then
  // local search runs again; a better result replaces the best.
  const int kicks = static_cast<int>(std::min<long>(kMaxKicks, kKickWork / (static_cast<long>(n) * n)));
  std::mt19937 rng(kKickSeed);  // fixed seed: the same problem always gives the same tour
  for (int t = 0; t < kicks && n >= 3; ++t) {
    path.assign(best);
    for (int m = 0; m < kKickMoves; ++m) {
      const int i = 1 + static_cast<int>(rng() % n);
      const int k = static_cast<int>(rng() % (n + 1));
      if (k != i && k != i - 1) path.applyOrOpt(i, i, k);
    }
    improve(path, nb);
    if (path.total() < best_cost) {
      best_cost = path.total();
      best = path.path();
    }
  }
  return fromPath(best, false, cost, xi, lambda);
}

TourResult improveTour(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda,
                       const std::vector<int>& order) {
  if (Status s = checkTourProblem(cost, xi, lambda); !s) return failure(s);
  const int n = static_cast<int>(xi.size());
  std::vector<char> seen(n + 1, 0);
  bool permutation = static_cast<int>(order.size()) == n;
  for (int v : order) permutation = permutation && v >= 1 && v <= n && !seen[v]++;
  if (!permutation) return failure(Status::Error("improveTour: the order must visit each of the nodes 1..N once"));
  std::vector<int> p{0};
  p.insert(p.end(), order.begin(), order.end());
  const std::vector<double> x = nodeXi(xi);  // OpenPath keeps a reference
  OpenPath path(cost, x, lambda);
  path.assign(p);
  if (n > 0) improve(path, nearestNeighbours(cost));
  return fromPath(path.path(), false, cost, xi, lambda);
}

TourResult solve(const Eigen::MatrixXd& cost, const std::vector<double>& xi, double lambda, int max_exact,
                 const std::vector<int>& hint) {
  if (static_cast<int>(xi.size()) <= std::min(max_exact, kMaxExactFrontiers))
    return solveExact(cost, xi, lambda);
  return solveHeuristic(cost, xi, lambda, hint);
}

}  // namespace go_feap::planning
