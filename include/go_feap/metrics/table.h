// Aggregating run summaries into the paper's tables (Tables II–IV): exploration time and flight
// distance avg/std/max/min, coverage, collisions and per-block compute times, one row per
// (scene, planner), as table.json and table.md.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "go_feap/metrics/metrics.h"

namespace go_feap::metrics {

/// avg, population std, max and min of a series (all 0 for an empty one).
struct Stats {
  double avg = 0.0, std = 0.0, max = 0.0, min = 0.0;
};
Stats stats(const std::vector<double>& values);

struct TableRow {
  std::string scene, planner;
  int runs = 0;
  int finished = 0;  ///< runs that reached FINISHED(complete)
  Stats exploration_time_s, flight_distance_m;
  double coverage_avg = 0.0, coverage_min = 0.0;
  int collisions = 0;                      ///< total over the runs
  std::map<std::string, double> compute_ms;  ///< per block: mean over runs of each run's mean; "total" too
};

/// One row per (scene, planner), in order of first appearance in `runs`.
std::vector<TableRow> aggregate(const std::vector<Summary>& runs);

/// table.json: a list with one object per row: scene, planner, runs, finished, exploration_time_s and
/// flight_distance_m ({avg, std, max, min}), coverage ({avg, min}), collisions, compute_ms.
std::string tableJson(const std::vector<TableRow>& rows);
/// table.md: the same as Markdown tables (Tables II/III: time and distance; Table IV: compute).
std::string tableMarkdown(const std::vector<TableRow>& rows);

}  // namespace go_feap::metrics
