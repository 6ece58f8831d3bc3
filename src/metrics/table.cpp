#include "go_feap/metrics/table.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numeric>
#include <sstream>
#include <tuple>

namespace go_feap::metrics {

Stats stats(const std::vector<double>& values) {
  Stats s;
  if (values.empty()) {
    s.avg = s.std = s.max = s.min = std::numeric_limits<double>::quiet_NaN();
    return s;
  }
  const double n = static_cast<double>(values.size());
  s.avg = std::accumulate(values.begin(), values.end(), 0.0) / n;
  double var = 0.0;
  for (double v : values) var += (v - s.avg) * (v - s.avg);
  s.std = std::sqrt(var / n);
  s.max = *std::max_element(values.begin(), values.end());
  s.min = *std::min_element(values.begin(), values.end());
  return s;
}

std::vector<TableRow> aggregate(const std::vector<Summary>& runs) {
  std::vector<std::pair<std::string, std::string>> keys;
  for (const Summary& s : runs)
    if (std::find(keys.begin(), keys.end(), std::make_pair(s.scene, s.planner)) == keys.end())
      keys.emplace_back(s.scene, s.planner);
  std::vector<TableRow> rows;
  for (const auto& [scene, planner] : keys) {
    TableRow row;
    row.scene = scene;
    row.planner = planner;
    std::vector<double> time, distance, coverage;
    std::map<std::string, BlockTime> blocks;
    for (const Summary& s : runs) {
      if (s.scene != scene || s.planner != planner) continue;
      ++row.runs;
      const bool finished = s.finish_reason == "complete";
      row.finished += finished;
      ++row.finish_reasons[s.finish_reason];
      row.finished_with_blacklisted += finished && s.blacklisted_frontiers > 0;
      // The time and distance of a run that did not finish (stopped at the time limit, stuck, diverged,
      // interrupted) measure where it stopped, not an exploration: a run stuck early would have looked fast.
      if (finished) {
        time.push_back(s.exploration_time_s);
        distance.push_back(s.flight_distance_m);
      }
      coverage.push_back(s.coverage);
      row.collisions += s.collisions;
      for (const auto& [name, b] : s.compute) {
        blocks[name].total_ms += b.total_ms;
        blocks[name].count += b.count;
      }
    }
    row.exploration_time_s = stats(time);
    row.flight_distance_m = stats(distance);
    const Stats c = stats(coverage);
    row.coverage_avg = c.avg;
    row.coverage_min = c.min;
    double total = 0.0;
    bool planned = false;
    for (const auto& [name, b] : blocks) {
      // Per call, over every call of the row's runs (as --perf prints it): a long run weighs by its calls, and a
      // run ended before its first plan adds none.
      if (b.count == 0) continue;
      row.compute_ms[name] = b.mean();
      if (isPlanningBlock(name)) total += b.mean(), planned = true;
    }
    if (planned) row.compute_ms["total"] = total;  // none without a planning call (no 0 ms figure)
    rows.push_back(std::move(row));
  }
  return rows;
}

std::vector<Comparison> compare(const std::vector<Summary>& runs) {
  // Scenes and, per scene, planners in order of first appearance; each (scene, planner, seed) once.
  std::vector<std::string> scenes;
  std::map<std::string, std::vector<std::string>> planners;
  std::map<std::tuple<std::string, std::string, std::uint64_t>, const Summary*> by_seed;
  for (const Summary& s : runs) {
    if (std::find(scenes.begin(), scenes.end(), s.scene) == scenes.end()) scenes.push_back(s.scene);
    std::vector<std::string>& p = planners[s.scene];
    if (std::find(p.begin(), p.end(), s.planner) == p.end()) p.push_back(s.planner);
    by_seed.emplace(std::make_tuple(s.scene, s.planner, s.seed), &s);
  }
  std::vector<Comparison> out;
  for (const std::string& scene : scenes) {
    const std::vector<std::string>& p = planners[scene];
    for (std::size_t b = 1; b < p.size(); ++b) {
      Comparison c;
      c.scene = scene;
      c.planner = p[0];
      c.baseline = p[b];
      std::vector<double> diffs;
      double time = 0.0, base_time = 0.0, distance = 0.0, base_distance = 0.0;
      for (const auto& [key, s] : by_seed) {
        if (std::get<0>(key) != scene || std::get<1>(key) != c.planner) continue;
        const auto base = by_seed.find(std::make_tuple(scene, c.baseline, std::get<2>(key)));
        if (base == by_seed.end()) continue;
        const Summary& o = *base->second;
        ++c.pairs;
        // Times compare only where both runs finished (as in the tables).
        if (s->finish_reason != "complete" || o.finish_reason != "complete") continue;
        ++c.both_finished;
        c.faster += s->exploration_time_s < o.exploration_time_s;
        time += s->exploration_time_s, base_time += o.exploration_time_s;
        distance += s->flight_distance_m, base_distance += o.flight_distance_m;
        diffs.push_back(s->exploration_time_s - o.exploration_time_s);
      }
      // No figure (NaN: null in JSON, "–" in Markdown) where there is nothing to compute it from.
      c.time_ratio = c.distance_ratio = c.time_diff_avg = c.time_diff_se = std::numeric_limits<double>::quiet_NaN();
      if (c.both_finished > 0) {
        if (base_time > 0.0) c.time_ratio = time / base_time;
        if (base_distance > 0.0) c.distance_ratio = distance / base_distance;
        const Stats d = stats(diffs);
        c.time_diff_avg = d.avg;
        const double n = static_cast<double>(c.both_finished);
        // Population std from stats(), turned into the sample std for the standard error.
        if (c.both_finished >= 2) c.time_diff_se = d.std * std::sqrt(n / (n - 1.0)) / std::sqrt(n);
      }
      out.push_back(std::move(c));
    }
  }
  return out;
}

std::string comparisonJson(const std::vector<Comparison>& comparisons) {
  nlohmann::json out = nlohmann::json::array();
  for (const Comparison& c : comparisons)
    out.push_back({{"scene", c.scene},
                   {"planner", c.planner},
                   {"baseline", c.baseline},
                   {"pairs", c.pairs},
                   {"both_finished", c.both_finished},
                   {"time_ratio", c.time_ratio},
                   {"distance_ratio", c.distance_ratio},
                   {"time_diff_s", {{"avg", c.time_diff_avg}, {"se", c.time_diff_se}}},
                   {"faster", c.faster}});
  return out.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);  // as summaryJson
}

std::string tableJson(const std::vector<TableRow>& rows) {
  nlohmann::json out = nlohmann::json::array();
  auto st = [](const Stats& s) { return nlohmann::json{{"avg", s.avg}, {"std", s.std}, {"max", s.max}, {"min", s.min}}; };
  for (const TableRow& r : rows) {
    nlohmann::json j;
    j["scene"] = r.scene;
    j["planner"] = r.planner;
    j["runs"] = r.runs;
    j["finished"] = r.finished;
    j["finished_with_blacklisted"] = r.finished_with_blacklisted;
    j["finish_reasons"] = r.finish_reasons;
    j["exploration_time_s"] = st(r.exploration_time_s);
    j["flight_distance_m"] = st(r.flight_distance_m);
    j["coverage"] = {{"avg", r.coverage_avg}, {"min", r.coverage_min}};
    j["collisions"] = r.collisions;
    j["compute_ms"] = r.compute_ms;
    out.push_back(j);
  }
  return out.dump(2, ' ', false, nlohmann::json::error_handler_t::replace);  // as summaryJson
}

namespace {

// A figure for a Markdown table at the stream's precision, or "–" where there is none (NaN).
struct Number {
  double value;
};
std::ostream& operator<<(std::ostream& os, Number n) {
  if (std::isnan(n.value)) return os << "–";
  return os << n.value;
}
Number number(double value) { return Number{value}; }

}  // namespace

std::string tableMarkdown(const std::vector<TableRow>& rows, const std::vector<Comparison>& comparisons) {
  std::ostringstream md;
  md << std::fixed;
  md << "### Exploration time (s) and flight distance (m) (Tables II/III)\n\n"
     << "| scene | planner | runs | finished | time avg | time std | time max | time min | distance avg | distance std "
        "| distance max | distance min | coverage avg (%) | coverage min (%) | collisions |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const TableRow& r : rows) {
    md << "| " << r.scene << " | " << r.planner << " | " << r.runs << " | " << r.finished;
    if (r.finished_with_blacklisted > 0) md << " (" << r.finished_with_blacklisted << " left blacklisted frontiers)";
    md << std::setprecision(1);
    for (const Stats* s : {&r.exploration_time_s, &r.flight_distance_m})
      md << " | " << number(s->avg) << " | " << number(s->std) << " | " << number(s->max) << " | " << number(s->min);
    md << " | " << 100.0 * r.coverage_avg << " | " << 100.0 * r.coverage_min << " | " << r.collisions << " |\n";
  }
  md << "\nTime and distance over the finished runs (std: population standard deviation); coverage and collisions "
        "over all runs.\n";
  for (const TableRow& r : rows) {
    if (r.finished == r.runs) continue;
    md << "\n" << r.scene << ", " << r.planner << ": " << r.runs - r.finished << " of " << r.runs
       << " runs did not finish (";
    const char* sep = "";
    for (const auto& [reason, n] : r.finish_reasons)
      if (reason != "complete") md << sep << n << " " << reason, sep = ", ";
    md << ").\n";
  }
  md << "\n### Compute per call, ms (Table IV)\n\n"
     << "| scene | planner | mapping | frontier | global | local | trajectory | total |\n"
     << "|---|---|---|---|---|---|---|---|\n";
  for (const TableRow& r : rows) {
    md << "| " << r.scene << " | " << r.planner << std::setprecision(2);
    for (const char* b : {"mapping", "frontier", "global", "local", "trajectory", "total"}) {
      const auto it = r.compute_ms.find(b);
      md << " | " << number(it == r.compute_ms.end() ? std::numeric_limits<double>::quiet_NaN() : it->second);
    }
    md << " |\n";
  }
  if (comparisons.empty()) return md.str();
  md << "\n### Paired by seed (same scene instance and start)\n\n"
     << "| scene | planner | against | pairs | both finished | time ratio | distance ratio | time difference (s) | "
        "standard error (s) | faster |\n"
     << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Comparison& c : comparisons)
    md << "| " << c.scene << " | " << c.planner << " | " << c.baseline << " | " << c.pairs << " | " << c.both_finished
       << std::setprecision(3) << " | " << number(c.time_ratio) << " | " << number(c.distance_ratio)
       << std::setprecision(1) << " | " << number(c.time_diff_avg) << " | " << number(c.time_diff_se) << " | "
       << c.faster << " of " << c.both_finished << " |\n";
  md << "\nOver the pairs where both runs finished.\n";
  return md.str();
}

}  // namespace go_feap::metrics
