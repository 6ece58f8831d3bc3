#include "go_feap/ros/exploration_params.h"

namespace go_feap::ros_params {

void readFrontierConfig(ParamReader& p, frontier::FrontierConfig& c) {
  p.get("frontier/min_cluster_cells", c.min_cluster_cells).get("frontier/max_cluster_extent", c.max_cluster_extent);
  p.get("frontier/s_near", c.s_near);
}

void readOmissionConfig(ParamReader& p, planning::OmissionConfig& c) {
  p.get("omission/alpha_max", c.alpha_max).get("omission/c_small", c.c_small).get("omission/w_t", c.w_t);
  p.get("omission/t_max", c.t_max).get("omission/n_t", c.n_t).get("omission/n_max", c.n_max);
}

void readBox(ParamReader& p, common::Aabb& box) {
  p.getVec3("exploration_box/min", box.min).getVec3("exploration_box/max", box.max);
}

}  // namespace go_feap::ros_params

namespace go_feap::ros_params {

void readGlobalPlannerConfig(ParamReader& p, planning::GlobalPlannerConfig& c) {
  p.get("global/s_near", c.s_near).get("global/n_min_tsp", c.n_min_tsp).get("global/n_max_tsp", c.n_max_tsp);
  p.get("global/lambda", c.lambda).get("global/v_max", c.v_max).get("global/max_exact", c.max_exact);
  readOmissionConfig(p, c.omission);
}

void readAstarConfig(ParamReader& p, planning::AstarConfig& c) {
  p.get("astar/clearance", c.clearance).get("astar/unknown_is_free", c.unknown_is_free);
  p.get("astar/max_expansions", c.max_expansions).get("astar/tie_breaker", c.tie_breaker);
}

}  // namespace go_feap::ros_params
