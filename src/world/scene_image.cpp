#include "go_feap/world/scene_image.h"

#include <algorithm>
#include <vector>
#include <opencv2/imgproc.hpp>

namespace go_feap::world {

namespace {

// Turbo colour map as a 256-entry lookup table.
class HeightColours {
 public:
  HeightColours(double z0, double z1) : z0_(z0), z1_(z1) {
    cv::Mat1b ramp(1, 256);
    for (int i = 0; i < 256; ++i) ramp(0, i) = static_cast<unsigned char>(i);
    cv::applyColorMap(ramp, lut_, cv::COLORMAP_TURBO);
  }
  cv::Vec3b operator()(double z) const {
    const double t = std::clamp((z - z0_) / std::max(1e-9, z1_ - z0_), 0.0, 1.0);
    return lut_(0, static_cast<int>(t * 255.0));
  }

 private:
  double z0_, z1_;
  cv::Mat3b lut_;
};

}  // namespace

cv::Mat renderSceneImage(const Scene& scene, int target_width, double side_view_min_height) {
  const auto& geo = scene.geometry();
  Index3 lo, hi;
  geo.centreRange(scene.box, lo, hi);
  const Index3 n = hi - lo;
  const double res = geo.resolution();
  // The scale from the box's longest side, so that no side of either view is more than about target_width
  // pixels: whole pixels per voxel (ppv), or for a side longer than target_width voxels whole voxels per
  // pixel (vpp). It came from the x side alone: a box 1 voxel by 20,000 gave 900 pixels a voxel, an image
  // of 18,000,000 rows that OpenCV refused (48.6 GB) and the tool aborted.
  const int longest = std::max({1, n.x(), n.y(), n.z()});
  const int width = std::max(1, target_width);
  const int ppv = std::max(1, width / longest);
  const int vpp = (longest + width - 1) / width;  // 1 up to target_width voxels
  const Index3 cells((n.x() + vpp - 1) / vpp, (n.y() + vpp - 1) / vpp, (n.z() + vpp - 1) / vpp);  // pixel blocks
  const HeightColours colour(scene.box.min.z(), scene.box.max.z());
  // A lowest layer that is (almost) all occupied is a floor: leave it white in the views.
  const int floor_k = [&] {
    std::size_t occ = 0;
    for (int y = lo.y(); y < hi.y(); ++y)
      for (int x = lo.x(); x < hi.x(); ++x) occ += scene.occupied.at(Index3(x, y, lo.z())) != 0;
    return static_cast<double>(occ) >= 0.9 * n.x() * n.y() ? lo.z() : -1;
  }();

  // Both views walk the grid in memory order (x fastest), layer by layer, and paint each pixel block from
  // the first occupied voxel met: a column-by-column walk touched a new cache line per voxel, minutes for a
  // mostly empty 1e9-voxel scene.
  cv::Mat3b top(cells.y() * ppv, cells.x() * ppv, cv::Vec3b(255, 255, 255));
  std::vector<char> painted(static_cast<std::size_t>(cells.x()) * cells.y(), 0);
  for (int z = hi.z() - 1; z >= lo.z() && z != floor_k; --z) {
    const cv::Vec3b c = colour(geo.indexToCoord(Index3(lo.x(), lo.y(), z)).z());
    for (int y = lo.y(); y < hi.y(); ++y)
      for (int x = lo.x(); x < hi.x(); ++x) {
        const int u = (x - lo.x()) / vpp, v = (hi.y() - 1 - y) / vpp;  // image rows grow downwards, world y upwards
        char& done = painted[static_cast<std::size_t>(v) * cells.x() + u];
        if (done || !scene.occupied.at(Index3(x, y, z))) continue;
        done = 1;
        top(cv::Rect(u * ppv, v * ppv, ppv, ppv)) = c;
      }
  }
  const double ppm = ppv / (vpp * res);
  auto to_px = [&](const Vec3& p) {
    return cv::Point(static_cast<int>((p.x() - geo.origin().x() - lo.x() * res) * ppm),
                     static_cast<int>((hi.y() * res - (p.y() - geo.origin().y())) * ppm));
  };
  const cv::Point s = to_px(scene.start.position);
  const int rad = std::max(4, static_cast<int>(0.3 * ppm));
  cv::circle(top, s, rad, cv::Scalar(0, 0, 255), cv::FILLED, cv::LINE_AA);
  cv::circle(top, s, rad, cv::Scalar(0, 0, 0), 2, cv::LINE_AA);
  const cv::Point tip = s + cv::Point(static_cast<int>(2.5 * rad * std::cos(scene.start.yaw)),
                                      static_cast<int>(-2.5 * rad * std::sin(scene.start.yaw)));
  cv::line(top, s, tip, cv::Scalar(0, 0, 0), 2, cv::LINE_AA);
  cv::putText(top, scene.name + " (top view, colour = height)", cv::Point(8, 22), cv::FONT_HERSHEY_SIMPLEX, 0.6,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);

  if (scene.box.size().z() < side_view_min_height) return top;

  cv::Mat3b side(cells.z() * ppv, cells.x() * ppv, cv::Vec3b(255, 255, 255));
  std::vector<char> done(static_cast<std::size_t>(cells.x()), 0);
  int done_v = -1;  // the row of pixel blocks `done` is for
  for (int z = lo.z(); z < hi.z(); ++z) {
    if (z == floor_k) continue;
    const int v = (hi.z() - 1 - z) / vpp;
    if (v != done_v) std::fill(done.begin(), done.end(), 0), done_v = v;
    const cv::Vec3b base = colour(geo.indexToCoord(Index3(lo.x(), lo.y(), z)).z());
    for (int y = lo.y(); y < hi.y(); ++y)
      for (int x = lo.x(); x < hi.x(); ++x) {
        const int u = (x - lo.x()) / vpp;
        if (done[u] || !scene.occupied.at(Index3(x, y, z))) continue;
        done[u] = 1;
        // Shade by depth along y (near = dark), colour by height.
        cv::Vec3b c = base;
        const double shade = 0.55 + 0.45 * (y - lo.y()) / std::max(1, n.y() - 1);
        for (int k = 0; k < 3; ++k) c[k] = static_cast<unsigned char>(c[k] * shade);
        side(cv::Rect(u * ppv, v * ppv, ppv, ppv)) = c;
      }
  }
  cv::putText(side, "side view (looking along +y)", cv::Point(8, 22), cv::FONT_HERSHEY_SIMPLEX, 0.6,
              cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  cv::Mat out;
  cv::Mat3b gap(6, top.cols, cv::Vec3b(128, 128, 128));
  cv::vconcat(std::vector<cv::Mat>{top, gap, side}, out);
  return out;
}

}  // namespace go_feap::world
