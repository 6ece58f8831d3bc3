// Candidate viewpoints of a frontier (DESIGN §3.6, paper §III-A.3): positions sampled on rings around
// the frontier's average position, each with the yaw that sees the most of its cells.
#pragma once

#include <vector>

#include "go_feap/common/grid.h"
#include "go_feap/common/result.h"
#include "go_feap/frontier/frontier_finder.h"
#include "go_feap/map/esdf.h"
#include "go_feap/map/occupancy_map.h"

namespace go_feap::planning {

struct ViewpointConfig {
  std::vector<double> ring_radii = {1.0, 1.5, 2.0};  ///< m, horizontal distances from P_avg
  double angular_step = 0.2617993877991494;          ///< rad (15 deg); rounded so each ring closes evenly
  /// m, added to P_avg's height; results are clamped to the active band [z_min, z_max] (duplicates
  /// after clamping are sampled once).
  std::vector<double> height_offsets = {-0.5, 0.0, 0.5};
  /// m, ESDF distance a viewpoint needs; must not exceed the ESDF's max_distance (nothing passes then).
  double clearance = 0.4;
  double sensor_range = 4.5;         ///< m, cells farther from the viewpoint are not seen
  double hfov = 1.3962634015954636;  ///< rad, horizontal field of view of the depth camera (80 deg)
  double vfov = 1.0471975511965976;  ///< rad, vertical field of view (60 deg)
  int min_visible = 10;              ///< viewpoints seeing fewer frontier cells are dropped
  int yaw_samples = 16;              ///< yaws tried per position, evenly spaced over the full turn
  /// 0: N_view counts every cell. Otherwise a large frontier's N_view is counted on an even
  /// subset of at most this many of its cells and scaled to the whole frontier (ray casts
  /// dominate the sampler's cost).
  int max_evaluated_cells = 0;
  /// true: a viewpoint also needs the voxels `clearance` away along each axis to be known: the flight path
  /// search's rule (astar/known_clearance), at the viewpoints' clearance (0.4 m) rather than the search's
  /// (0.3 m). The two reach different voxels, so a viewpoint is not always a voxel the search may end at:
  /// the flight then ends within planner/goal_tolerance of it, or the plan fails and the frontier counts
  /// a failed attempt.
  bool known_clearance = false;

  /// Checks every key; the message names the bad one, e.g. "viewpoints: hfov must be in (0, pi)".
  common::Status validate() const;
  /// validate() plus clearance <= esdf.max_distance (distances are truncated there: a larger clearance
  /// passes no viewpoint, and every frontier would be blacklisted).
  common::Status validate(const map::EsdfConfig& esdf) const;
  /// Checks hfov and vfov against a depth camera: neither may exceed the camera's symmetric field of view,
  /// twice the angle from the principal point to the nearer image edge (the outer pixels' outer edges), by
  /// more than 1e-3 rad (a FOV written in rounded radians). A wider model scores viewpoints on frontier cells
  /// the camera does not see from them. The message names the key, e.g. "viewpoints: vfov (...) must not
  /// exceed the depth camera's (...)".
  common::Status fitsCamera(const map::DepthIntrinsics& K) const;
  /// Checks sensor_range against the mapper's: it must not exceed occupancy.max_range, past which returns
  /// are not mapped (viewpoints would be scored on cells a flight there does not map).
  common::Status fitsMapper(const map::OccupancyConfig& occupancy) const;
};

/// `a` wrapped to (-pi, pi].
double wrapAngle(double a);

/// The yaws tried at `position`: the first looks straight at `target` (horizontally), the others
/// follow at steps of 2 pi / yaw_samples, all wrapped to (-pi, pi]. A position on the target's vertical
/// axis starts at yaw 0.
std::vector<double> candidateYaws(const common::Vec3& position, const common::Vec3& target, int yaw_samples);

/// True when the centre of a cell at `cell_centre` lies within sensor_range of `position` and inside
/// the image of a level camera there looking along `yaw` (pinhole model: the horizontal and vertical
/// angles are measured in the image plane, atan(lateral / forward) <= hfov / 2 and
/// atan(up / forward) <= vfov / 2, so the visible region is the camera's rectangular frustum).
bool inView(const common::Vec3& position, double yaw, const common::Vec3& cell_centre,
            const ViewpointConfig& config);

/// True when no occupied voxel lies on the segment from `position` towards the cell's centre, stopped
/// one voxel (one resolution) short of the centre so that the cell's own neighbours behind the
/// frontier do not hide it; unknown voxels do not block (OccupancyMap::isLineFree). A segment leaving
/// the map is blocked.
bool lineOfSight(const common::Vec3& position, const common::Vec3& cell_centre, const map::OccupancyMap& map);

/// N_view: the cells (indices of map's grid) that are inView() and in lineOfSight() from `position`
/// looking along `yaw`. With stop_at > 0 the count stops there (the result is min(N_view, stop_at)):
/// callers that only compare it with a threshold save the remaining ray casts.
int countVisible(const common::Vec3& position, double yaw, const std::vector<common::Index3>& cells,
                 const map::OccupancyMap& map, const ViewpointConfig& config, int stop_at = 0);

/// Candidate viewpoints of `frontier`: for every ring radius, ring angle and clamped height offset a
/// position around frontier.average that is known free, has ESDF distance >= clearance, lies in
/// [z_min, z_max] and inside the map's exploration box shrunk by clearance on every side; its yaw is the candidateYaws() entry with the largest countVisible() (the earliest
/// on ties, so the one facing the frontier wins). Viewpoints seeing fewer than min_visible cells are
/// dropped; the rest are sorted by visible_cells, descending (ties in sampling order: radius, then
/// angle, then height). The frontier's cells must be indices of map's grid; `esdf` must share it.
/// An invalid config or an empty band gives no viewpoints.
std::vector<frontier::Viewpoint> sampleViewpoints(const frontier::Frontier& frontier,
                                                  const map::OccupancyMap& map, const map::Esdf& esdf,
                                                  double z_min, double z_max, const ViewpointConfig& config);

}  // namespace go_feap::planning
