// go_feap_tsp_perf: times the global planner's tour solvers on random instances: frontiers
// in a 20 x 20 x 3 m box at 2 m/s, every direction of a pair up to 30% longer than the
// straight line (asymmetric, like A* path lengths), xi in [0, 3) s, lambda in [0, 0.5) 1/s.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "cli_args.h"
#include "go_feap/planning/tour_solver.h"

namespace {

using go_feap::planning::TourResult;

int usage(const char* why) {
  if (why) std::cerr << "go_feap_tsp_perf: " << why << "\n";
  std::cerr << "usage: go_feap_tsp_perf [--repeats R] [--seed S]\n"
               "Prints mean / max ms of the exact (Held-Karp) solver for N = 4..12 frontiers and of\n"
               "the heuristic for N = 12 (with its gap to the exact optimum), 50, 100 and 300, over R\n"
               "(default 20) random instances each.\n";
  return 2;
}

struct Instance {
  Eigen::MatrixXd cost;
  std::vector<double> xi;
  double lambda = 0.0;
};

Instance randomInstance(int n, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> pts(n + 1);
  for (auto& p : pts) p = Eigen::Vector3d(20.0 * u(rng), 20.0 * u(rng), 3.0 * u(rng));
  Instance in;
  in.cost = Eigen::MatrixXd::Zero(n + 1, n + 1);
  for (int i = 0; i <= n; ++i)
    for (int j = 1; j <= n; ++j)
      if (i != j) in.cost(i, j) = (pts[i] - pts[j]).norm() / 2.0 * (1.0 + 0.3 * u(rng));
  in.xi.resize(n);
  for (double& x : in.xi) x = 3.0 * u(rng);
  in.lambda = 0.5 * u(rng);
  return in;
}

template <typename Solver>
double timeMs(const Instance& in, Solver solver, TourResult& result) {
  const auto t0 = std::chrono::steady_clock::now();
  result = solver(in.cost, in.xi, in.lambda);
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  std::map<std::string, std::string> args;
  bool help = false;
  const std::string err = go_feap::tools::parseArgs(argc, argv, {{"--repeats", true}, {"--seed", true}}, args, help);
  if (help) return usage(nullptr), 0;  // as the other tools: --help is no error (it exited 2)
  if (!err.empty()) return usage(err.c_str());
  unsigned long long repeats = 20, seed = 1;
  if (args.count("--repeats") && (!go_feap::tools::parseCount(args["--repeats"], repeats) || repeats == 0))
    return usage("--repeats needs a whole number > 0");
  if (args.count("--seed") && !go_feap::tools::parseCount(args["--seed"], seed))
    return usage("--seed needs a whole number >= 0");

  std::mt19937_64 rng(seed);
  std::printf("%-10s %5s %10s %10s %12s %12s\n", "solver", "N", "mean_ms", "max_ms", "mean_gap_%",
              "max_gap_%");
  auto report = [](const char* name, int n, double sum, double max, int count, const char* gaps) {
    std::printf("%-10s %5d %10.3f %10.3f%s\n", name, n, sum / count, max, gaps);
  };
  for (int n = 4; n <= 12; ++n) {
    double sum = 0.0, max = 0.0;
    for (unsigned long long r = 0; r < repeats; ++r) {
      const Instance in = randomInstance(n, rng);
      TourResult result;
      const double ms = timeMs(in, go_feap::planning::solveExact, result);
      if (!result.status) return std::cerr << result.status.message() << "\n", 1;
      sum += ms, max = std::max(max, ms);
    }
    report("exact", n, sum, max, static_cast<int>(repeats), "");
  }
  for (int n : {12, 50, 100, 300}) {
    double sum = 0.0, max = 0.0, gap_sum = 0.0, gap_max = 0.0;
    for (unsigned long long r = 0; r < repeats; ++r) {
      const Instance in = randomInstance(n, rng);
      TourResult result;
      const double ms = timeMs(
          in, [](const auto& c, const auto& x, double l) { return go_feap::planning::solveHeuristic(c, x, l); }, result);
      if (!result.status) return std::cerr << result.status.message() << "\n", 1;
      sum += ms, max = std::max(max, ms);
      if (n <= go_feap::planning::kMaxExactFrontiers) {
        const double gap =
            100.0 * (result.cost / go_feap::planning::solveExact(in.cost, in.xi, in.lambda).cost - 1.0);
        gap_sum += gap, gap_max = std::max(gap_max, gap);
      }
    }
    char gaps[64] = "";
    if (n <= go_feap::planning::kMaxExactFrontiers)
      std::snprintf(gaps, sizeof(gaps), " %12.3f %12.3f", gap_sum / repeats, gap_max);
    report("heuristic", n, sum, max, static_cast<int>(repeats), gaps);
  }
  // Warm start (a replan): the same instance again, hinted with the tour just found.
  for (int n : {50, 100, 300}) {
    double sum = 0.0, max = 0.0;
    for (unsigned long long r = 0; r < repeats; ++r) {
      const Instance in = randomInstance(n, rng);
      const TourResult cold = go_feap::planning::solveHeuristic(in.cost, in.xi, in.lambda);
      TourResult result;
      const double ms = timeMs(
          in,
          [&](const auto& c, const auto& x, double l) { return go_feap::planning::solveHeuristic(c, x, l, cold.order); },
          result);
      if (!result.status) return std::cerr << result.status.message() << "\n", 1;
      sum += ms, max = std::max(max, ms);
    }
    report("warm", n, sum, max, static_cast<int>(repeats), "");
  }
  return 0;
}
