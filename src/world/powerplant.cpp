#include <random>

#include "go_feap/world/generators.h"
#include "go_feap/world/shapes.h"

namespace go_feap::world {

common::Status PowerplantConfig::validate() const {
  auto err = [](const char* key, const char* why) {
    return common::Status::Error(std::string("powerplant: ") + key + " " + why);
  };
  if (!(resolution > 0.0 && resolution <= 0.5)) return err("resolution", "must be in (0, 0.5] m");
  // The layout below is laid out for the paper's 33 x 31 x 26 m site; smaller sites would
  // make structures overlap the start area.
  if (!(size_x >= 30.0 && size_y >= 28.0 && height >= 20.0))
    return err("size_x/size_y/height", "must be at least 30 x 28 x 20 m");
  if (!(margin >= 0.0)) return err("margin", "must be >= 0");
  // Bounded like the maze's and a file scene's grid: a resolution of 0.01 m asked for 2.7e10 voxels.
  const double voxels = sceneVoxelCount({Vec3(-0.5 * size_x, -0.5 * size_y, 0.0), Vec3(0.5 * size_x, 0.5 * size_y, height)},
                                        resolution, margin);
  if (!(voxels <= kMaxSceneVoxels)) return err("size_x/size_y/height/resolution", "make a grid of more than 2^30 voxels");
  return common::Status::Ok();
}

namespace {

Aabb boxAt(double x0, double y0, double z0, double x1, double y1, double z1) {
  return {Vec3(x0, y0, z0), Vec3(x1, y1, z1)};
}

// Square column of side `w` centred at (x, y).
void column(Scene& s, double x, double y, double z0, double z1, double w = 0.3) {
  fillBox(s, boxAt(x - 0.5 * w, y - 0.5 * w, z0, x + 0.5 * w, y + 0.5 * w, z1));
}

// Boiler hall: four walls with doors and window bands, two open intermediate floors that
// each cover part of the footprint (overhangs with free space below), and a roof.
void boilerHall(Scene& s, std::mt19937_64& rng, double x0, double y0, double x1, double y1) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double h = 18.0 + 3.0 * u(rng), t = 0.3;
  fillBox(s, boxAt(x0, y0, 0, x1, y0 + t, h));
  fillBox(s, boxAt(x0, y1 - t, 0, x1, y1, h));
  fillBox(s, boxAt(x0, y0, 0, x0 + t, y1, h));
  fillBox(s, boxAt(x1 - t, y0, 0, x1, y1, h));
  fillBox(s, boxAt(x0, y0, h, x1, y1, h + t));
  // Doors: a large one on the east wall, one on the south wall.
  const double door_y = y0 + 2.0 + (y1 - y0 - 8.0) * u(rng);
  clearBox(s, boxAt(x1 - t - 0.1, door_y, 0.1, x1 + 0.1, door_y + 4.5, 6.0));
  const double door_x = x0 + 2.0 + (x1 - x0 - 7.0) * u(rng);
  clearBox(s, boxAt(door_x, y0 - 0.1, 0.1, door_x + 4.0, y0 + t + 0.1, 5.0));
  // Window bands high on the long walls.
  for (double z = 9.0; z + 2.0 < h; z += 6.0) {
    clearBox(s, boxAt(x0 + 1.5, y0 - 0.1, z, x1 - 1.5, y0 + t + 0.1, z + 1.8));
    clearBox(s, boxAt(x0 + 1.5, y1 - t - 0.1, z, x1 - 1.5, y1 + 0.1, z + 1.8));
  }
  // Intermediate floors: alternate halves so each is an overhang over open space.
  const double f1 = 6.0 + u(rng), f2 = 12.0 + u(rng);
  const double xm = 0.5 * (x0 + x1);
  fillBox(s, boxAt(x0, y0, f1, xm + 1.0, y1, f1 + 0.2));
  fillBox(s, boxAt(xm - 1.0, y0, f2, x1, y1, f2 + 0.2));
  // The boiler: a tall block on legs in the hall.
  const double bx = xm - 1.5, by = 0.5 * (y0 + y1) - 1.5;
  fillBox(s, boxAt(bx, by, 3.0, bx + 3.0, by + 3.0, f2 - 1.0));
  for (double lx : {bx + 0.2, bx + 2.8})
    for (double ly : {by + 0.2, by + 2.8}) column(s, lx, ly, 0.0, 3.0);
}

// Stair tower: four corner columns, a landing every 3 m alternating sides, a roof.
void stairTower(Scene& s, double cx, double cy, double h) {
  const double a = 1.5;
  for (double dx : {-a, a})
    for (double dy : {-a, a}) column(s, cx + dx, cy + dy, 0.0, h, 0.25);
  int k = 0;
  for (double z = 3.0; z < h; z += 3.0, ++k) {
    if (k % 2 == 0)
      fillBox(s, boxAt(cx - a, cy - a, z, cx, cy + a, z + 0.15));
    else
      fillBox(s, boxAt(cx, cy - a, z, cx + a, cy + a, z + 0.15));
  }
  fillBox(s, boxAt(cx - a, cy - a, h, cx + a, cy + a, h + 0.2));
}

// Pipe rack along x or y: column pairs every 4 m, cross beams at each level, pipes on top.
void pipeRack(Scene& s, std::mt19937_64& rng, const Vec3& from, double length, bool along_x,
              const std::vector<double>& levels) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Vec3 dir = along_x ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 side = along_x ? Vec3::UnitY() : Vec3::UnitX();
  const double half_w = 1.0, top = levels.back();
  for (double d = 0.0; d <= length + 1e-9; d += 4.0) {
    const Vec3 p = from + d * dir;
    for (double sgn : {-1.0, 1.0}) {
      const Vec3 c = p + sgn * half_w * side;
      column(s, c.x(), c.y(), 0.0, top + 0.2);
    }
    for (double z : levels) {
      const Vec3 a = p - half_w * side, b = p + half_w * side;
      fillBox(s, Aabb{Vec3(a.x(), a.y(), z) - Vec3(0.1, 0.1, 0.0), Vec3(b.x(), b.y(), z + 0.2) + Vec3(0.1, 0.1, 0.0)});
    }
  }
  for (double z : levels) {
    const int pipes = 2 + static_cast<int>(u(rng) * 2.0);
    for (int i = 0; i < pipes; ++i) {
      const double r = 0.15 + 0.15 * u(rng);
      const double off = -half_w + 0.3 + i * (2.0 * half_w - 0.6) / std::max(1, pipes - 1);
      const Vec3 a = from + off * side + Vec3(0, 0, z + 0.2 + r);
      fillPipe(s, a, a + length * dir, r);
    }
  }
}

}  // namespace

common::Result<Scene> generatePowerplant(const PowerplantConfig& config, std::uint64_t seed) {
  if (auto st = config.validate(); !st) return st;
  const double hx = 0.5 * config.size_x, hy = 0.5 * config.size_y, H = config.height;
  const Aabb box{Vec3(-hx, -hy, 0.0), Vec3(hx, hy, H)};
  Scene s = makeEmptyScene("powerplant", box, config.resolution, config.margin);
  s.seed = seed;
  s.seeded = true;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double r = config.resolution;

  fillBox(s, boxAt(-hx, -hy, 0.0, hx, hy, 0.5 * r));  // ground

  // Boiler hall in the west half.
  const double jx = u(rng), jy = u(rng);
  boilerHall(s, rng, -hx + 2.5 + jx, -hy + 4.5 + jy, -hx + 14.5 + jx, -hy + 19.5 + jy);

  // Chimney: a tall hollow tube, capped (its inside is a sealed cavity, not observable).
  const double cx = -hx + 8.0 + u(rng), cy = hy - 5.0 + 0.5 * u(rng);
  fillVerticalCylinder(s, cx, cy, 1.8, 0.0, H - 1.0 + 0.5 * u(rng), 0.3);
  fillVerticalCylinder(s, cx, cy, 1.8, H - 2.0, H - 1.8, 0.0);

  // Tanks in the east: two vertical cylinders and a spherical tank on legs.
  const double tx = hx - 5.0 + 0.5 * u(rng);
  fillVerticalCylinder(s, tx, -hy + 5.0 + 0.5 * u(rng), 2.2, 0.0, 8.0 + 2.0 * u(rng));
  fillVerticalCylinder(s, tx, -hy + 11.5 + 0.5 * u(rng), 2.0, 0.0, 6.0 + 1.5 * u(rng));
  const Vec3 sphere(hx - 5.5, hy - 6.0 + 0.5 * u(rng), 6.0 + 0.5 * u(rng));
  fillSphere(s, sphere, 2.5);
  for (double dx : {-1.8, 1.8})
    for (double dy : {-1.8, 1.8}) column(s, sphere.x() + dx, sphere.y() + dy, 0.0, sphere.z(), 0.3);

  // Pipe racks at several heights, one along y between hall and tanks, one along x.
  const double rack_x = 1.5 + u(rng);
  pipeRack(s, rng, Vec3(rack_x, -hy + 4.0, 0.0), 2.0 * hy - 10.0, false, {4.0, 8.0 + 0.5 * u(rng), 12.0});
  pipeRack(s, rng, Vec3(rack_x + 3.0, 2.0 + 0.5 * u(rng), 0.0), hx - rack_x - 9.0, true, {5.0, 9.5});

  // Stair towers next to the hall and next to the tanks.
  stairTower(s, -hx + 16.5 + 0.3 * u(rng), -hy + 21.5 + 0.3 * u(rng), 18.0 + 2.0 * u(rng));
  stairTower(s, hx - 10.0 + 0.3 * u(rng), -hy + 3.0 + 0.3 * u(rng), 12.0 + 2.0 * u(rng));

  // Elevated platform on columns: an overhang with open space beneath.
  const double px = 5.0 + u(rng), py = hy - 9.0 + u(rng), pz = 7.0 + u(rng);
  fillBox(s, boxAt(px, py, pz, px + 6.0, py + 5.0, pz + 0.3));
  for (double dx : {0.3, 5.7})
    for (double dy : {0.3, 4.7}) column(s, px + dx, py + dy, 0.0, pz);
  // A cantilevered gallery on the chimney side, higher up.
  fillBox(s, boxAt(cx + 1.8, cy - 1.5, 15.0, cx + 5.0, cy + 1.5, 15.3));

  s.start.position = Vec3(0.0, -hy + 1.5, 1.5);
  s.start.yaw = M_PI / 2.0;
  if (auto st = validateScene(s); !st) return st;
  return s;
}

}  // namespace go_feap::world
