// Pictures of a scene for people: a top view coloured by height, plus a side view when
// the scene is tall.
#pragma once

#include <opencv2/core.hpp>

#include "go_feap/world/scene.h"

namespace go_feap::world {

/// Top view of the exploration box: each column shows the height of its highest occupied
/// voxel (turbo colour map, blue low, red high; white = nothing above the floor layer);
/// the start is a black-ringed disc with a heading tick. For scenes taller than
/// `side_view_min_height` metres a side view (looking along +y, highest occupancy
/// coloured by height) is appended below. Pixels per metre are chosen so the image is
/// about `target_width` pixels wide.
cv::Mat renderSceneImage(const Scene& scene, int target_width = 900, double side_view_min_height = 5.0);

}  // namespace go_feap::world
