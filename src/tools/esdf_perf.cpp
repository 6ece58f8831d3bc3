// go_feap_esdf_perf: times incremental ESDF updates on an empty 34 x 32 x 27 m grid at 0.1 m: a wall
// appearing and disappearing, a whole room at once, a scattered cloud of single obstacles and a block
// moving voxel by voxel, and states the memory per voxel and per m^3. Prints wall-clock and CPU time
// (the CPU time is the steadier on a loaded machine).
#include <chrono>
#include <cmath>
#include <ctime>
#include <iostream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "cli_args.h"
#include "go_feap/map/esdf.h"

namespace {

using go_feap::common::GridGeometry;
using go_feap::common::Index3;
using go_feap::common::Vec3;
using go_feap::map::Esdf;
using go_feap::map::EsdfConfig;

int usage(const char* why) {
  if (why) std::cerr << "go_feap_esdf_perf: " << why << "\n";
  std::cerr << "usage: go_feap_esdf_perf [--max-distance M] [--repeats N]\n"
               "Times ESDF updates on a 34 x 32 x 27 m grid at 0.1 m (default max_distance 2 m; the\n"
               "wall and room cases are repeated N times, default 5) and prints the memory used.\n";
  return 2;
}

// Wall-clock and process CPU milliseconds since construction.
class Stopwatch {
 public:
  Stopwatch() : wall_(std::chrono::steady_clock::now()), cpu_(std::clock()) {}
  double wallMs() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - wall_).count();
  }
  double cpuMs() const { return 1000.0 * static_cast<double>(std::clock() - cpu_) / CLOCKS_PER_SEC; }

 private:
  std::chrono::steady_clock::time_point wall_;
  std::clock_t cpu_;
};

struct Timing {
  double wall_ms = 0.0, cpu_ms = 0.0, max_wall_ms = 0.0;
  std::size_t changed = 0;
  int runs = 0;
  void time(Esdf& esdf, const std::vector<std::size_t>& inserted, const std::vector<std::size_t>& removed) {
    const Stopwatch w;
    changed = esdf.update(inserted, removed);
    const double ms = w.wallMs();
    wall_ms += ms;
    cpu_ms += w.cpuMs();
    max_wall_ms = std::max(max_wall_ms, ms);
    ++runs;
  }
};

std::ostream& operator<<(std::ostream& os, const Timing& t) {
  return os << t.wall_ms / t.runs << " ms (CPU " << t.cpu_ms / t.runs << " ms, " << t.changed
            << " distances changed)";
}

}  // namespace

int main(int argc, char** argv) {
  std::map<std::string, std::string> args;
  bool help = false;
  const std::string error =
      go_feap::tools::parseArgs(argc, argv, {{"--max-distance", true}, {"--repeats", true}}, args, help);
  if (help) return usage(nullptr), 0;
  if (!error.empty()) return usage(error.c_str());
  EsdfConfig config;
  unsigned long long repeats = 5;
  if (args.count("--max-distance") && !go_feap::tools::parseNumber(args["--max-distance"], config.max_distance))
    return usage("--max-distance must be a number");
  if (args.count("--repeats") && (!go_feap::tools::parseCount(args["--repeats"], repeats) || repeats == 0))
    return usage("--repeats must be a positive integer");

  const GridGeometry g = GridGeometry::covering({Vec3(-17, -16, 0), Vec3(17, 16, 27)}, 0.1);
  if (const auto s = config.validate(g); !s) {
    std::cerr << "go_feap_esdf_perf: " << s.message() << "\n";
    return 1;
  }
  const Stopwatch alloc;
  Esdf esdf(g, config);
  std::cout << "grid " << g.dims().transpose() << " (" << g.size() / 1e6 << " M voxels) at " << g.resolution()
            << " m, max_distance " << config.max_distance << " m, allocated in " << alloc.wallMs() << " ms\n";
  const Index3 c = g.dims() / 2;
  auto box = [&](const Index3& lo, const Index3& size, std::vector<std::size_t>& out) {
    for (int z = lo.z(); z < lo.z() + size.z(); ++z)
      for (int y = lo.y(); y < lo.y() + size.y(); ++y)
        for (int x = lo.x(); x < lo.x() + size.x(); ++x) out.push_back(g.linear(Index3(x, y, z)));
  };

  // A 2 x 2 m wall, one voxel thick, in the middle of the grid.
  std::vector<std::size_t> wall;
  box(Index3(c.x(), c.y() - 10, c.z() - 10), Index3(1, 20, 20), wall);
  Timing wall_in, wall_out;
  for (unsigned long long r = 0; r < repeats; ++r) {
    wall_in.time(esdf, wall, {});
    wall_out.time(esdf, {}, wall);
  }
  std::cout << "2 x 2 m wall (" << wall.size() << " voxels): insert " << wall_in << ", remove " << wall_out
            << "\n";

  // A 10 x 10 x 3 m room (floor, ceiling, four walls) at once, as a first depth frame in a room
  // would add it (in fact a frame sees only part of it).
  std::vector<std::size_t> room;
  const Index3 lo = c - Index3(50, 50, 15);
  box(lo, Index3(100, 100, 1), room);
  box(lo + Index3(0, 0, 29), Index3(100, 100, 1), room);
  box(lo + Index3(0, 0, 1), Index3(1, 100, 28), room);
  box(lo + Index3(99, 0, 1), Index3(1, 100, 28), room);
  box(lo + Index3(1, 0, 1), Index3(98, 1, 28), room);
  box(lo + Index3(1, 99, 1), Index3(98, 1, 28), room);
  Timing room_in, room_out;
  for (unsigned long long r = 0; r < repeats; ++r) {
    room_in.time(esdf, room, {});
    room_out.time(esdf, {}, room);
  }
  std::cout << "10 x 10 x 3 m room (" << room.size() << " voxels): insert " << room_in << ", remove "
            << room_out << "\n";

  // 1000 single voxels scattered in a 10 m cube: heavily overlapping balls, the worst case per voxel.
  std::mt19937 rng(1);
  std::vector<std::size_t> cloud;
  for (int i = 0; i < 1000; ++i)
    cloud.push_back(g.linear(Index3(c.x() - 50 + static_cast<int>(rng() % 100),
                                    c.y() - 50 + static_cast<int>(rng() % 100),
                                    c.z() - 50 + static_cast<int>(rng() % 100))));
  Timing cloud_in, cloud_out;
  cloud_in.time(esdf, cloud, {});
  cloud_out.time(esdf, {}, cloud);
  std::cout << "1000 scattered voxels: insert " << cloud_in << ", remove " << cloud_out << "\n";

  // A 1 m block moving by one voxel per update: 100 voxels appear in front, 100 vanish behind.
  std::vector<std::size_t> block;
  box(c, Index3(10, 10, 10), block);
  esdf.update(block, {});
  Timing moving;
  for (int s = 1; s <= 100; ++s) {
    std::vector<std::size_t> in, out;
    box(c + Index3(s + 9, 0, 0), Index3(1, 10, 10), in);
    box(c + Index3(s - 1, 0, 0), Index3(1, 10, 10), out);
    moving.time(esdf, in, out);
  }
  std::cout << "1 m block moving 1 voxel per update, 100 updates: mean " << moving << ", max "
            << moving.max_wall_ms << " ms\n";

  const double bytes = static_cast<double>(esdf.memoryBytes());
  const double per_voxel = bytes / static_cast<double>(g.size());
  std::cout << "memory " << bytes / 1e6 << " MB: " << per_voxel << " bytes per voxel, "
            << per_voxel / std::pow(g.resolution(), 3) / 1e3 << " kB per m^3\n";
  return 0;
}
