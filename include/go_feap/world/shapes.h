// Solid primitives rasterised into a scene: a voxel is filled when its centre lies inside.
#pragma once

#include "go_feap/world/scene.h"

namespace go_feap::world {

/// Fills the axis-aligned box [box.min, box.max].
void fillBox(Scene& scene, const Aabb& box);

/// Fills a vertical cylinder of radius `radius` around (cx, cy) from z0 to z1. With
/// `wall` > 0 only a shell of that thickness is filled (a hollow tube).
void fillVerticalCylinder(Scene& scene, double cx, double cy, double radius, double z0, double z1,
                          double wall = 0.0);

/// Fills a horizontal cylinder (a pipe) of radius `radius` from `a` to `b`; a and b must
/// share their z and differ along x or y only.
void fillPipe(Scene& scene, const Vec3& a, const Vec3& b, double radius);

/// Fills a ball.
void fillSphere(Scene& scene, const Vec3& centre, double radius);

/// Clears (sets free) the axis-aligned box: doors and windows cut into walls.
void clearBox(Scene& scene, const Aabb& box);

}  // namespace go_feap::world
