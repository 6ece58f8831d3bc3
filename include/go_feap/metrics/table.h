// Aggregating run summaries into the paper's tables (Tables II–IV): exploration time and flight
// distance avg/std/max/min, coverage, collisions and per-block compute times, one row per
// (scene, planner), as table.json and table.md.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "go_feap/metrics/metrics.h"

namespace go_feap::metrics {

/// avg, population std, max and min of a series (all NaN for an empty one: written null in JSON, "–" in
/// Markdown).
struct Stats {
  double avg = 0.0, std = 0.0, max = 0.0, min = 0.0;
};
Stats stats(const std::vector<double>& values);

struct TableRow {
  std::string scene, planner;
  int runs = 0;
  int finished = 0;  ///< runs that reached FINISHED(complete)
  int finished_with_blacklisted = 0;  ///< of those, runs that left blacklisted frontiers unexplored
  /// runs per finish_reason: "complete" (the finished ones), and the FINISHED states and stops that are not
  /// (time_limit, stuck, aborted; max_sim_time, diverged, interrupted from the bench)
  std::map<std::string, int> finish_reasons;
  /// Over the finished runs only (NaN without any): a run that stopped otherwise (time limit, stuck,
  /// diverged, interrupted) did not explore the scene in that time.
  Stats exploration_time_s, flight_distance_m;
  double coverage_avg = 0.0, coverage_min = 0.0;  ///< over all runs
  int collisions = 0;                      ///< total over the runs
  /// per block: mean per call over every call of the runs (runs weigh by their calls); "total" (the planning
  /// blocks' sum: per replan) too. A block no run called has no entry.
  std::map<std::string, double> compute_ms;
};

/// One row per (scene, planner), in order of first appearance in `runs`.
std::vector<TableRow> aggregate(const std::vector<Summary>& runs);

/// A planner against a baseline on the same scene, paired by seed (the same seed is the same scene
/// instance and start): the comparison the per-planner averages blur, since seeds differ far more
/// from each other than planners do on one seed.
struct Comparison {
  std::string scene, planner, baseline;
  int pairs = 0;          ///< seeds both ran (a seed run twice by one planner pairs its first run)
  int both_finished = 0;  ///< pairs where both runs reached FINISHED(complete): the figures below are over these
  /// planner's mean exploration time over the pairs that both finished / the baseline's (NaN without any)
  double time_ratio = 0.0;
  double distance_ratio = 0.0;  ///< likewise for the flight distance
  /// per pair, planner's time - baseline's: mean (NaN without pairs), and its standard error (sample std /
  /// sqrt(pairs); NaN below 2 pairs)
  double time_diff_avg = 0.0, time_diff_se = 0.0;
  int faster = 0;  ///< pairs where the planner's time is below the baseline's
};

/// Per scene, the first planner in `runs` (order of first appearance) against each other planner of
/// that scene, over the seeds both ran; in order of first appearance. Empty where a scene has one planner.
std::vector<Comparison> compare(const std::vector<Summary>& runs);

/// table.json: a list with one object per row: scene, planner, runs, finished, finished_with_blacklisted,
/// finish_reasons ({reason: runs}), exploration_time_s and flight_distance_m ({avg, std, max, min}), coverage
/// ({avg, min}), collisions, compute_ms.
std::string tableJson(const std::vector<TableRow>& rows);
/// table.md: the same as Markdown tables (Tables II/III: time and distance; Table IV: compute), and
/// with `comparisons` a third table of them (paired by seed).
std::string tableMarkdown(const std::vector<TableRow>& rows, const std::vector<Comparison>& comparisons = {});
/// comparison.json: a list with one object per comparison: scene, planner, baseline, pairs,
/// both_finished, time_ratio, distance_ratio, time_diff_s ({avg, se}), faster.
std::string comparisonJson(const std::vector<Comparison>& comparisons);

}  // namespace go_feap::metrics
