#include "go_feap/planning/local_planner.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>

#include "go_feap/planning/viewpoints.h"

namespace go_feap::planning {

using common::Result;
using common::Status;
using common::Vec3;
using frontier::Viewpoint;

namespace {

bool positiveFinite(double v) { return v > 0.0 && std::isfinite(v); }

// Within same_target_distance and same_target_yaw of the viewpoint: the same target, or at it.
bool samePose(const Vec3& p, double yaw, const Viewpoint& vp, const LocalPlannerConfig& config) {
  return (p - vp.position).norm() <= config.same_target_distance &&
         std::abs(wrapAngle(yaw - vp.yaw)) <= config.same_target_yaw;
}

}  // namespace

Status LocalPlannerConfig::validate() const {
  auto err = [](const char* key, const char* why) {
    return Status::Error(std::string("local: ") + key + " " + why);  // the keys are local/*
  };
  if (k_frontiers < 1) return err("k_frontiers", "must be >= 1");
  if (top_k < 1) return err("top_k", "must be >= 1");
  if (!(d_near >= 0.0 && std::isfinite(d_near))) return err("d_near", "must be finite and >= 0");
  if (!positiveFinite(v_max)) return err("v_max", "must be > 0");
  if (!positiveFinite(yaw_rate_max)) return err("yaw_rate_max", "must be > 0");
  if (window_size < 1) return err("window_size", "must be >= 1");
  if (!(clutter_threshold >= 0.0 && clutter_threshold <= 1.0))
    return err("clutter_threshold", "must be in [0, 1]");
  if (!positiveFinite(max_range)) return err("max_range", "must be > 0");
  if (!positiveFinite(min_dist)) return err("min_dist", "must be > 0");
  if (!(commit_time >= 0.0 && std::isfinite(commit_time))) return err("commit_time", "must be finite and >= 0");
  if (!(replan_period >= 0.0 && std::isfinite(replan_period))) return err("replan_period", "must be finite and >= 0");
  if (!(min_view_fraction >= 0.0 && min_view_fraction <= 1.0)) return err("min_view_fraction", "must be in [0, 1]");
  if (!(same_target_distance >= 0.0 && std::isfinite(same_target_distance)))
    return err("same_target_distance", "must be finite and >= 0");
  if (!(same_target_yaw >= 0.0 && std::isfinite(same_target_yaw))) return err("same_target_yaw", "must be finite and >= 0");
  if (!(a_max >= 0.0 && std::isfinite(a_max))) return err("a_max", "must be finite and >= 0");
  if (!(reached_speed > 0.0 && std::isfinite(reached_speed))) return err("reached_speed", "must be finite and > 0");
  if (!(settled_tilt > 0.0 && settled_tilt <= 1.5707963267948966))
    return err("settled_tilt", "must be in (0, pi/2]");
  if (!(settled_speed >= 0.0 && std::isfinite(settled_speed)))
    return err("settled_speed", "must be finite and >= 0");
  if (max_visits < 1) return err("max_visits", "must be >= 1");
  if (max_choices < 0) return err("max_choices", "must be >= 0");
  if (!positiveFinite(choice_window)) return err("choice_window", "must be finite and > 0");
  if (!(choice_radius >= 0.0 && std::isfinite(choice_radius))) return err("choice_radius", "must be finite and >= 0");
  if (!(scan_step > 0.0 && scan_step < 3.14159)) return err("scan_step", "must be in (0, pi)");
  return Status::Ok();
}

Result<double> obstacleRatio(const cv::Mat& depth, double max_range) {
  if (depth.empty()) return Result<double>::Error("obstacle ratio: empty depth image");
  if (!positiveFinite(max_range)) return Result<double>::Error("obstacle ratio: max_range must be > 0");
  std::size_t close = 0;
  if (depth.type() == CV_32FC1) {
    // A return nearer than max_range, or -inf (REP 117: a surface too near to measure). NaN fails every
    // comparison and +inf the last: no separate finiteness test (the loop vectorises).
    const auto max_m = static_cast<float>(max_range);
    constexpr float kNear = -std::numeric_limits<float>::infinity();
    for (int v = 0; v < depth.rows; ++v) {
      const float* row = depth.ptr<float>(v);
      for (int u = 0; u < depth.cols; ++u)
        close += static_cast<std::size_t>(((row[u] > 0.0f) | (row[u] == kNear)) & (row[u] < max_m));
    }
  } else if (depth.type() == CV_16UC1) {
    const double max_mm = max_range * 1000.0;
    for (int v = 0; v < depth.rows; ++v) {
      const std::uint16_t* row = depth.ptr<std::uint16_t>(v);
      for (int u = 0; u < depth.cols; ++u)
        if (row[u] > 0 && row[u] < max_mm) ++close;
    }
  } else {
    return Result<double>::Error("obstacle ratio: depth image must be CV_32FC1 (m) or CV_16UC1 (mm)");
  }
  return static_cast<double>(close) / static_cast<double>(depth.total());
}

ObstacleWindow::ObstacleWindow(int window_size, double clutter_threshold)
    : window_size_(static_cast<std::size_t>(std::max(1, window_size))), threshold_(clutter_threshold) {}

bool ObstacleWindow::push(double ratio) {
  if (!(ratio >= 0.0 && ratio <= 1.0)) return false;
  ratios_.push_back(ratio);
  while (ratios_.size() > window_size_) ratios_.pop_front();
  return true;
}

double ObstacleWindow::mean() const {
  if (ratios_.empty()) return 0.0;
  double sum = 0.0;
  for (double r : ratios_) sum += r;
  return sum / static_cast<double>(ratios_.size());
}

bool ObstacleWindow::cluttered() const { return !ratios_.empty() && mean() > threshold_; }

FrontierType classifyFrontier(double path_distance, const ObstacleWindow& window,
                              const LocalPlannerConfig& config) {
  return path_distance < config.d_near || window.cluttered() ? FrontierType::kNearOrCluttered
                                                             : FrontierType::kOpen;
}

double steeringRate(const Vec3& position, double yaw, const Viewpoint& viewpoint,
                    const LocalPlannerConfig& config) {
  const double cost_yaw = std::abs(wrapAngle(viewpoint.yaw - yaw)) / config.yaw_rate_max;
  const double cost_dist = std::max((viewpoint.position - position).norm(), config.min_dist) / config.v_max;
  return cost_yaw / cost_dist;
}

std::vector<Viewpoint> filterViewpoints(const std::vector<Viewpoint>& viewpoints, FrontierType type,
                                        const Vec3& position, double yaw, const LocalPlannerConfig& config) {
  struct Ranked {
    double key;
    const Viewpoint* vp;
  };
  std::vector<Ranked> ranked;
  ranked.reserve(viewpoints.size());
  int best = 0;
  for (const Viewpoint& vp : viewpoints) best = std::max(best, vp.visible_cells);
  const double floor = type == FrontierType::kNearOrCluttered ? config.min_view_fraction * best : 0.0;
  for (const Viewpoint& vp : viewpoints)
    if (vp.visible_cells >= floor) ranked.push_back(
        {type == FrontierType::kNearOrCluttered ? steeringRate(position, yaw, vp, config) : 0.0, &vp});
  std::stable_sort(ranked.begin(), ranked.end(), [](const Ranked& a, const Ranked& b) {
    if (a.key != b.key) return a.key > b.key;
    return a.vp->visible_cells > b.vp->visible_cells;
  });
  std::vector<Viewpoint> out;
  const std::size_t n = std::min(ranked.size(), static_cast<std::size_t>(std::max(0, config.top_k)));
  for (std::size_t i = 0; i < n; ++i) out.push_back(*ranked[i].vp);
  return out;
}

namespace {
double turnTime(double yaw_a, double yaw_b, const LocalPlannerConfig& config) {
  return std::abs(wrapAngle(yaw_b - yaw_a)) / config.yaw_rate_max;
}
}  // namespace

double edgeCost(double dist, double yaw_a, double yaw_b, const LocalPlannerConfig& config) {
  return std::max(dist / config.v_max, turnTime(yaw_a, yaw_b, config));
}

double startCost(const Vec3& position, const Vec3& velocity, double yaw, const Viewpoint& target, double dist,
                 const LocalPlannerConfig& config) {
  double cancel = 0.0;  // s, braking the velocity that does not lead to the target
  if (config.a_max > 0.0) {
    const Vec3 offset = target.position - position;
    const double along = offset.norm() > 1e-6 ? velocity.dot(offset.normalized()) : 0.0;
    cancel = (velocity.norm() - along) / config.a_max;
  }
  return std::max(dist / config.v_max + cancel, turnTime(yaw, target.yaw, config));
}

Result<LocalPlan> planLocal(const Vec3& position, const Vec3& velocity, double yaw, const std::vector<frontier::Frontier>& tour,
                            const std::vector<FrontierType>& types, const LocalPlannerConfig& config,
                            const DistanceFn& distance) {
  if (Status s = config.validate(); !s) return s;
  if (types.size() != tour.size())
    return Result<LocalPlan>::Error("local planner: " + std::to_string(types.size()) +
                                    " frontier types for " + std::to_string(tour.size()) + " tour frontiers");
  LocalPlan plan;
  std::vector<unsigned> ids;
  for (std::size_t j = 0;
       j < tour.size() && plan.layers.size() < static_cast<std::size_t>(config.k_frontiers); ++j) {
    if (tour[j].viewpoints.empty()) continue;
    plan.layers.push_back(filterViewpoints(tour[j].viewpoints, types[j], position, yaw, config));
    ids.push_back(tour[j].id);
  }
  if (plan.layers.empty()) return Result<LocalPlan>::Error("local planner: no tour frontier has viewpoints");

  auto dist = [&](const Vec3& a, const Vec3& b) { return distance ? distance(a, b) : (b - a).norm(); };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // cost[i][v]: cheapest time from the start to viewpoint v of layer i; parent[i][v] its predecessor.
  std::vector<std::vector<double>> cost(plan.layers.size());
  std::vector<std::vector<int>> parent(plan.layers.size());
  for (std::size_t i = 0; i < plan.layers.size(); ++i) {
    const std::vector<Viewpoint>& layer = plan.layers[i];
    cost[i].assign(layer.size(), kInf);
    parent[i].assign(layer.size(), -1);
    for (std::size_t v = 0; v < layer.size(); ++v) {
      if (i == 0) {
        const double d = dist(position, layer[v].position);
        if (std::isfinite(d)) cost[0][v] = startCost(position, velocity, yaw, layer[v], d, config);
        continue;
      }
      const std::vector<Viewpoint>& prev = plan.layers[i - 1];
      for (std::size_t u = 0; u < prev.size(); ++u) {
        if (!std::isfinite(cost[i - 1][u])) continue;
        const double d = dist(prev[u].position, layer[v].position);
        if (!std::isfinite(d)) continue;
        const double c = cost[i - 1][u] + edgeCost(d, prev[u].yaw, layer[v].yaw, config);
        if (c < cost[i][v]) {
          cost[i][v] = c;
          parent[i][v] = static_cast<int>(u);
        }
      }
    }
  }
  const std::vector<double>& last = cost.back();
  const auto best = std::min_element(last.begin(), last.end());
  if (best == last.end() || !std::isfinite(*best))
    return Result<LocalPlan>::Error("local planner: no finite path through the viewpoint layers");

  plan.cost = *best;
  std::vector<int> chosen(plan.layers.size());
  chosen.back() = static_cast<int>(best - last.begin());
  for (std::size_t i = plan.layers.size() - 1; i > 0; --i)
    chosen[i - 1] = parent[i][static_cast<std::size_t>(chosen[i])];
  for (std::size_t i = 0; i < plan.layers.size(); ++i)
    plan.path.push_back(plan.layers[i][static_cast<std::size_t>(chosen[i])]);
  plan.frontier_ids = std::move(ids);
  return plan;
}

CurrentTarget assessTarget(const frontier::Viewpoint& target, double committed_at,
                           const common::Vec3& position, double yaw, double speed, double tilt,
                           const std::vector<frontier::Frontier>& frontiers, const map::OccupancyMap& map,
                           const ViewpointConfig& viewpoint_config, double cluster_extent,
                           const LocalPlannerConfig& config) {
  CurrentTarget c;
  c.viewpoint = target;
  c.committed_at = committed_at;
  c.reached = targetReached(position, yaw, speed, target, config);
  c.settled = std::abs(tilt) < config.settled_tilt || speed < config.settled_speed;
  c.remaining_visible = viewpoint_config.min_visible;
  if (!c.reached)
    c.remaining_visible = remainingVisible(target, frontiers, map, viewpoint_config, cluster_extent);
  return c;
}

void VisitedViewpoints::add(const Viewpoint& reached, const LocalPlannerConfig& config) {
  for (Visit& v : visits_)
    if (samePose(v.position, v.yaw, reached, config)) {
      ++v.count;
      return;
    }
  visits_.push_back({reached.position, reached.yaw, 1});
}

namespace {
// Within choice_radius and same_target_yaw: choices of the same place.
bool samePlace(const Vec3& p, double yaw, const Viewpoint& vp, const LocalPlannerConfig& config) {
  return (p - vp.position).norm() <= config.choice_radius && std::abs(wrapAngle(yaw - vp.yaw)) <= config.same_target_yaw;
}
}  // namespace

bool VisitedViewpoints::choose(const Viewpoint& chosen, double t, const LocalPlannerConfig& config) {
  if (config.max_choices == 0) return false;
  // Choices older than the window go, and so do choices stamped after t: the clock went back (a bag
  // played again, a simulator restarted), and they belong to the run before.
  choices_.erase(std::remove_if(choices_.begin(), choices_.end(),
                                [&](const Choice& c) { return c.t < t - config.choice_window || c.t > t; }),
                 choices_.end());
  choices_.push_back({chosen.position, chosen.yaw, t});
  const auto same = std::count_if(choices_.begin(), choices_.end(),
                                  [&](const Choice& c) { return samePlace(c.position, c.yaw, chosen, config); });
  if (same < config.max_choices) return false;
  exhausted_places_.push_back(choices_.back());
  return true;
}

bool VisitedViewpoints::exhausted(const Viewpoint& viewpoint, const LocalPlannerConfig& config) const {
  for (const Visit& v : visits_)
    if (v.count >= config.max_visits && samePose(v.position, v.yaw, viewpoint, config)) return true;
  for (const Choice& c : exhausted_places_)
    if (samePlace(c.position, c.yaw, viewpoint, config)) return true;
  return false;
}

frontier::Viewpoint scanTarget(const common::Vec3& position, double yaw, const LocalPlannerConfig& config) {
  frontier::Viewpoint vp;
  vp.position = position;
  vp.yaw = wrapAngle(yaw + config.scan_step);
  return vp;
}

double tiltOf(const Eigen::Quaterniond& attitude) {
  const double norm = attitude.norm();
  if (!(norm > 0.0) || !std::isfinite(norm)) return std::numeric_limits<double>::quiet_NaN();
  const Vec3 body_z = attitude.normalized() * Vec3::UnitZ();
  return std::acos(std::clamp(body_z.z(), -1.0, 1.0));
}

bool targetReached(const common::Vec3& position, double yaw, double speed, const frontier::Viewpoint& target,
                   const LocalPlannerConfig& config) {
  return samePose(position, yaw, target, config) && speed < config.reached_speed;
}

double pathCost(const Astar& astar, const common::Vec3& position, const common::Vec3& velocity, double yaw,
                const frontier::Viewpoint& target, const LocalPlannerConfig& config) {
  return startCost(position, velocity, yaw, target, pathDistance(astar, position, target.position).metres, config);
}

TargetDecision decideTarget(const CurrentTarget* current, const frontier::Viewpoint& proposal,
                            const std::function<double(const frontier::Viewpoint&)>& cost, double t,
                            int min_visible, const LocalPlannerConfig& config) {
  if (!current) return TargetDecision::kSwitch;
  const bool same = samePose(proposal.position, proposal.yaw, current->viewpoint, config);
  if (same)
    return current->reached && current->settled ? TargetDecision::kReachedInVain : TargetDecision::kKeep;
  if (current->remaining_visible < min_visible || current->reached) return TargetDecision::kSwitch;
  if (!current->quicker && t - current->committed_at >= config.commit_time &&
      cost(proposal) < cost(current->viewpoint))
    return TargetDecision::kSwitchQuicker;
  return TargetDecision::kKeep;
}

bool planDue(const CurrentTarget* current, double t, double last_plan, int min_visible,
             const LocalPlannerConfig& config) {
  if (!(config.replan_period > 0.0)) return true;
  if (!current || current->reached || current->remaining_visible < min_visible) return true;
  if (current->quicker || t - current->committed_at < config.commit_time) return false;
  return t - last_plan >= config.replan_period;
}

int remainingVisible(const frontier::Viewpoint& viewpoint, const std::vector<frontier::Frontier>& frontiers,
                     const map::OccupancyMap& map, const ViewpointConfig& config, double cluster_extent) {
  std::vector<common::Index3> cells;
  const double reach = config.sensor_range + cluster_extent;
  for (const frontier::Frontier& f : frontiers)
    if ((f.average - viewpoint.position).norm() <= reach) cells.insert(cells.end(), f.cells.begin(), f.cells.end());
  return countVisible(viewpoint.position, viewpoint.yaw, cells, map, config, config.min_visible);
}

const std::vector<frontier::Viewpoint>& ViewpointCache::get(const frontier::Frontier& frontier,
                                                            const map::OccupancyMap& map, const map::Esdf& esdf,
                                                            double z_min, double z_max, const ViewpointConfig& config) {
  auto it = entries_.find(frontier.id);
  if (it != entries_.end() && it->second.z_min == z_min && it->second.z_max == z_max &&
      it->second.average == frontier.average) {
    ++hits_;
    auto& vps = it->second.viewpoints;
    vps.erase(std::remove_if(vps.begin(), vps.end(),
                             [&](const frontier::Viewpoint& vp) {
                               return map.state(vp.position) != map::VoxelState::kFree ||
                                      !(esdf.distance(vp.position) >= config.clearance);
                             }),
              vps.end());
    return vps;
  }
  ++misses_;
  Entry& e = entries_[frontier.id];
  e.z_min = z_min;
  e.z_max = z_max;
  e.average = frontier.average;
  // Sampling reads the map at the ring positions (up to the farthest radius and height offset from the
  // frontier's average, which lies among its cells; heights clamped into the band), their clearance round
  // them, and the lines from them to the cells. The cells' own bounds, not frontier.box: a frontier built
  // from a message may not carry its box (the LocalPlanner nodelet's did not, and every reach sat at the
  // origin).
  const auto& geo = map.geometry();
  common::Aabb cells{common::Vec3::Constant(std::numeric_limits<double>::infinity()),
                     common::Vec3::Constant(-std::numeric_limits<double>::infinity())};
  for (const common::Index3& c : frontier.cells) cells.extend(geo.indexToCoord(c));
  cells.extend(frontier.average);
  double ring = 0.0, height = 0.0, offset_min = 0.0, offset_max = 0.0;
  for (double r : config.ring_radii) ring = std::max(ring, std::abs(r));
  for (double h : config.height_offsets) {
    height = std::max(height, std::abs(h));
    offset_min = std::min(offset_min, h);
    offset_max = std::max(offset_max, h);
  }
  const double grow = std::hypot(ring, height) + config.clearance + geo.resolution();
  e.reach = cells.expanded(0.5 * geo.resolution() + grow);
  // Heights clamped into the band (a frontier far above or below it) lie outside the grown box.
  const double margin = config.clearance + geo.resolution();
  if (std::isfinite(z_min) && std::isfinite(z_max) && z_min <= z_max) {
    const double lowest = std::clamp(frontier.average.z() + offset_min, z_min, z_max);
    const double highest = std::clamp(frontier.average.z() + offset_max, z_min, z_max);
    e.reach.min.z() = std::min(e.reach.min.z(), lowest - margin);
    e.reach.max.z() = std::max(e.reach.max.z(), highest + margin);
  }
  e.viewpoints = sampleViewpoints(frontier, map, esdf, z_min, z_max, config);
  return e.viewpoints;
}

namespace {

// Whether two boxes share a point (a NaN bound overlaps everything).
bool overlap(const common::Aabb& a, const common::Aabb& b) {
  return !((a.max.array() < b.min.array()).any() || (a.min.array() > b.max.array()).any());
}

}  // namespace

void ViewpointCache::forgetChanged(const common::GridGeometry& geometry, const std::vector<std::size_t>& changed) {
  if (changed.empty() || entries_.empty()) return;
  std::vector<common::Vec3> centres;
  centres.reserve(changed.size());
  common::Aabb all{common::Vec3::Constant(std::numeric_limits<double>::infinity()),
                   common::Vec3::Constant(-std::numeric_limits<double>::infinity())};
  for (std::size_t l : changed) {
    centres.push_back(geometry.indexToCoord(geometry.unlinear(l)));
    all.extend(centres.back());
  }
  for (auto it = entries_.begin(); it != entries_.end();) {
    const common::Aabb& r = it->second.reach;
    const bool touched =
        overlap(all, r) && std::any_of(centres.begin(), centres.end(), [&](const common::Vec3& c) { return r.contains(c); });
    it = touched ? entries_.erase(it) : std::next(it);
  }
}

void ViewpointCache::forgetChanged(const common::Aabb& changed) {
  for (auto it = entries_.begin(); it != entries_.end();) {
    // NaN bounds overlap everything: such a change forgets all.
    it = overlap(changed, it->second.reach) ? entries_.erase(it) : std::next(it);
  }
}

TargetStep stepTarget(const CurrentTarget* current, const frontier::Viewpoint& proposal,
                      const std::function<double(const frontier::Viewpoint&)>& cost, double t, int min_visible,
                      const LocalPlannerConfig& config, VisitedViewpoints& visited) {
  TargetStep step;
  step.decision = decideTarget(current, proposal, cost, t, min_visible, config);
  if (step.decision == TargetDecision::kKeep) return step;
  if (current && current->reached) visited.add(current->viewpoint, config);
  // Only a target replacing another counts: after a failed plan the same target is chosen anew, which the
  // failed attempts on its frontier already count.
  if (step.decision != TargetDecision::kReachedInVain && current) step.exhausted = visited.choose(proposal, t, config);
  return step;
}

void ViewpointCache::forgetFor(const frontier::MapUpdateNote& note, std::uint64_t last_sequence,
                               std::uint64_t map_sequence, const common::GridGeometry& geometry,
                               const std::vector<std::size_t>& map_changed) {
  switch (frontier::updatePath(note, last_sequence, map_sequence)) {
    case frontier::UpdatePath::kRecomputed: entries_.clear(); break;
    case frontier::UpdatePath::kListed: forgetChanged(geometry, map_changed); break;
    case frontier::UpdatePath::kBoxed: forgetChanged(common::Aabb{note.changed_min, note.changed_max}); break;
    case frontier::UpdatePath::kUnchanged: break;
  }
}

void ViewpointCache::retain(const std::vector<std::uint32_t>& ids) {
  std::unordered_map<std::uint32_t, Entry> kept;
  for (std::uint32_t id : ids) {
    auto it = entries_.find(id);
    if (it != entries_.end()) kept.emplace(id, std::move(it->second));
  }
  entries_.swap(kept);
}

common::Result<LocalPlan> chooseLocalTarget(const common::Vec3& position, const common::Vec3& velocity, double yaw,
                                            std::vector<frontier::Frontier> tour, double z_min, double z_max,
                                            const map::OccupancyMap& map, const map::Esdf& esdf, const Astar& astar,
                                            const ObstacleWindow& window, const ViewpointConfig& viewpoint_config,
                                            const LocalPlannerConfig& config, ViewpointCache* cache,
                                            const VisitedViewpoints* visited) {
  std::vector<frontier::Frontier> ordered;
  std::vector<FrontierType> types;
  for (frontier::Frontier& f : tour) {
    if (static_cast<int>(ordered.size()) >= config.k_frontiers) break;
    f.viewpoints = cache ? cache->get(f, map, esdf, z_min, z_max, viewpoint_config)
                         : sampleViewpoints(f, map, esdf, z_min, z_max, viewpoint_config);
    if (visited)
      f.viewpoints.erase(std::remove_if(f.viewpoints.begin(), f.viewpoints.end(),
                                        [&](const Viewpoint& vp) { return visited->exhausted(vp, config); }),
                         f.viewpoints.end());
    if (f.viewpoints.empty()) continue;
    // A path is never shorter than the straight line: only a frontier within d_near of the UAV in a
    // straight line needs the search to be typed.
    const double straight = (f.average - position).norm();
    const double d = straight >= config.d_near ? straight : pathDistance(astar, position, f.average).metres;
    types.push_back(classifyFrontier(d, window, config));
    ordered.push_back(std::move(f));
  }
  if (ordered.empty()) return common::Result<LocalPlan>::Error("no viewpoint found for the first tour frontiers");
  return planLocal(position, velocity, yaw, ordered, types, config);
}

}  // namespace go_feap::planning
