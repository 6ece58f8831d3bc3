// Parameter groups shared by several exploration nodelets (config/exploration.yaml).
#pragma once

#include "go_feap/frontier/frontier_finder.h"
#include "go_feap/planning/astar.h"
#include "go_feap/planning/global_planner.h"
#include "go_feap/planning/omission.h"
#include "go_feap/ros/params.h"

namespace go_feap::ros_params {

void readFrontierConfig(ParamReader& p, frontier::FrontierConfig& c);
void readOmissionConfig(ParamReader& p, planning::OmissionConfig& c);
void readGlobalPlannerConfig(ParamReader& p, planning::GlobalPlannerConfig& c);
void readAstarConfig(ParamReader& p, planning::AstarConfig& c);
/// exploration_box/min and exploration_box/max.
void readBox(ParamReader& p, common::Aabb& box);

}  // namespace go_feap::ros_params
