#include "go_feap/metrics/table.h"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numeric>
#include <sstream>

namespace go_feap::metrics {

Stats stats(const std::vector<double>& values) {
  Stats s;
  if (values.empty()) return s;
  const double n = static_cast<double>(values.size());
  s.avg = std::accumulate(values.begin(), values.end(), 0.0) / n;
  double var = 0.0;
  for (double v : values) var += (v - s.avg) * (v - s.avg);
  s.std = std::sqrt(var / n);
  s.max = *std::max_element(values.begin(), values.end());
  s.min = *std::min_element(values.begin(), values.end());
  return s;
}

namespace {
const char* const kPlanningBlocks[] = {"frontier", "global", "local", "trajectory"};
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
    std::map<std::string, std::vector<double>> blocks;
    for (const Summary& s : runs) {
      if (s.scene != scene || s.planner != planner) continue;
      ++row.runs;
      row.finished += s.finish_reason == "complete";
      time.push_back(s.exploration_time_s);
      distance.push_back(s.flight_distance_m);
      coverage.push_back(s.coverage);
      row.collisions += s.collisions;
      for (const auto& [name, b] : s.compute) blocks[name].push_back(b.mean());
    }
    row.exploration_time_s = stats(time);
    row.flight_distance_m = stats(distance);
    const Stats c = stats(coverage);
    row.coverage_avg = c.avg;
    row.coverage_min = c.min;
    double total = 0.0;
    for (const auto& [name, values] : blocks) {
      // A run that never ran a block counts as 0 ms for it.
      const double mean = std::accumulate(values.begin(), values.end(), 0.0) / row.runs;
      row.compute_ms[name] = mean;
      if (std::find(std::begin(kPlanningBlocks), std::end(kPlanningBlocks), name) != std::end(kPlanningBlocks))
        total += mean;
    }
    row.compute_ms["total"] = total;
    rows.push_back(std::move(row));
  }
  return rows;
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
    j["exploration_time_s"] = st(r.exploration_time_s);
    j["flight_distance_m"] = st(r.flight_distance_m);
    j["coverage"] = {{"avg", r.coverage_avg}, {"min", r.coverage_min}};
    j["collisions"] = r.collisions;
    j["compute_ms"] = r.compute_ms;
    out.push_back(j);
  }
  return out.dump(2);
}

std::string tableMarkdown(const std::vector<TableRow>& rows) {
  std::ostringstream md;
  md << std::fixed;
  md << "### Exploration time (s) and flight distance (m) (Tables II/III)\n\n"
     << "| scene | planner | runs | finished | time avg | time std | time max | time min | distance avg | distance std "
        "| distance max | distance min | coverage avg (%) | coverage min (%) | collisions |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const TableRow& r : rows) {
    md << "| " << r.scene << " | " << r.planner << " | " << r.runs << " | " << r.finished << std::setprecision(1);
    for (const Stats* s : {&r.exploration_time_s, &r.flight_distance_m})
      md << " | " << s->avg << " | " << s->std << " | " << s->max << " | " << s->min;
    md << " | " << 100.0 * r.coverage_avg << " | " << 100.0 * r.coverage_min << " | " << r.collisions << " |\n";
  }
  md << "\n### Compute per call, ms (Table IV)\n\n"
     << "| scene | planner | mapping | frontier | global | local | trajectory | total |\n"
     << "|---|---|---|---|---|---|---|---|\n";
  for (const TableRow& r : rows) {
    md << "| " << r.scene << " | " << r.planner << std::setprecision(2);
    for (const char* b : {"mapping", "frontier", "global", "local", "trajectory", "total"}) {
      const auto it = r.compute_ms.find(b);
      md << " | " << (it == r.compute_ms.end() ? 0.0 : it->second);
    }
    md << " |\n";
  }
  return md.str();
}

}  // namespace go_feap::metrics
