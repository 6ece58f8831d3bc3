// The only translation unit of the world module that includes PCL (slow headers).
#include <pcl/console/print.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <filesystem>
#include <fstream>

#include "go_feap/world/scene_files.h"

namespace go_feap::world {

namespace fs = std::filesystem;

namespace {

common::Status checkPcdSize(pcl::PCDReader& reader, const std::string& path) {
  pcl::PCLPointCloud2 header;
  Eigen::Vector4f origin;
  Eigen::Quaternionf orientation;
  int version = 0, data_type = 0;
  unsigned int data_idx = 0;
  // PCL's header parser accepts text that is no PCD header at all; require the keywords.
  {
    std::ifstream in(path);
    std::string line;
    bool fields = false, data = false;
    for (int i = 0; i < 64 && std::getline(in, line) && !data; ++i) {
      fields |= line.rfind("FIELDS ", 0) == 0;
      data |= line.rfind("DATA ", 0) == 0;
    }
    if (!fields || !data) return common::Status::Error(path + ": corrupt PCD file (no FIELDS/DATA header)");
  }
  if (reader.readHeader(path, header, origin, orientation, version, data_type, data_idx) < 0 ||
      header.fields.empty() || header.point_step == 0)
    return common::Status::Error(path + ": corrupt PCD file (unreadable header)");
  const std::uintmax_t size = fs::file_size(path);
  const std::uintmax_t points = static_cast<std::uintmax_t>(header.width) * header.height;
  if (data_type == 1 && size < data_idx + points * header.point_step) {
    return common::Status::Error(path + ": truncated PCD file (header declares " + std::to_string(points) +
                                 " points, i.e. " + std::to_string(data_idx + points * header.point_step) +
                                 " bytes, but the file has " + std::to_string(size) + ")");
  }
  if (data_type == 2) {
    std::uint32_t sizes[2] = {0, 0};
    std::ifstream in(path, std::ios::binary);
    in.seekg(data_idx);
    in.read(reinterpret_cast<char*>(sizes), sizeof(sizes));
    if (!in || size < data_idx + 8 + static_cast<std::uintmax_t>(sizes[0]) ||
        sizes[1] != points * header.point_step)
      return common::Status::Error(path + ": truncated or corrupt compressed PCD file");
  }
  return common::Status::Ok();
}

}  // namespace

common::Result<std::vector<Vec3>> loadPointCloud(const std::string& path) {
  using R = common::Result<std::vector<Vec3>>;
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) return R::Error(path + ": file not found");
  const std::string ext = fs::path(path).extension().string();
  // PCL prints its own diagnostics; we return one message instead.
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  pcl::PCLPointCloud2 blob;
  int rc = -1;
  std::string kind;
  try {
    if (ext == ".pcd") {
      kind = "PCD";
      pcl::PCDReader reader;
      // PCL's binary reader maps the file and trusts the header (a truncated file
      // crashes it), so check the header against the file size first.
      if (auto st = checkPcdSize(reader, path); !st) return st;
      rc = reader.read(path, blob);
    } else if (ext == ".ply") {
      kind = "PLY";
      pcl::PLYReader reader;
      rc = reader.read(path, blob);
    } else {
      return R::Error(path + ": unknown point cloud extension '" + ext + "' (expected .pcd or .ply)");
    }
  } catch (const std::exception& e) {
    return R::Error(path + ": corrupt " + kind + " file (" + e.what() + ")");
  }
  if (rc < 0) return R::Error(path + ": corrupt or truncated " + kind + " file (the PCL reader refused it)");
  bool has_x = false, has_y = false, has_z = false;
  for (const auto& f : blob.fields) {
    has_x |= f.name == "x";
    has_y |= f.name == "y";
    has_z |= f.name == "z";
  }
  if (!(has_x && has_y && has_z)) return R::Error(path + ": " + kind + " file has no x, y, z fields");
  const std::size_t declared = static_cast<std::size_t>(blob.width) * blob.height;
  if (blob.data.size() < declared * blob.point_step)
    return R::Error(path + ": truncated " + kind + " file (header declares " + std::to_string(declared) +
                    " points, data holds fewer)");
  pcl::PointCloud<pcl::PointXYZ> cloud;
  try {
    pcl::fromPCLPointCloud2(blob, cloud);
  } catch (const std::exception& e) {
    return R::Error(path + ": corrupt " + kind + " file (" + e.what() + ")");
  }
  if (cloud.empty()) return R::Error(path + ": the cloud is empty");
  std::vector<Vec3> points;
  points.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      return R::Error(path + ": point " + std::to_string(i) + " is NaN or Inf");
    points.emplace_back(p.x, p.y, p.z);
  }
  return points;
}

common::Status saveScenePcd(const Scene& scene, const std::string& path) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  const auto& geo = scene.geometry();
  for (std::size_t l = 0; l < scene.occupied.size(); ++l) {
    if (!scene.occupied[l]) continue;
    const Vec3 c = geo.indexToCoord(geo.unlinear(l));
    cloud.push_back(pcl::PointXYZ(static_cast<float>(c.x()), static_cast<float>(c.y()), static_cast<float>(c.z())));
  }
  if (cloud.empty()) return common::Status::Error(path + ": scene '" + scene.name + "' has no occupied voxels to write");
  pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
  pcl::PCDWriter writer;
  if (writer.writeBinary(path, cloud) < 0) return common::Status::Error(path + ": cannot write PCD file");
  return common::Status::Ok();
}

}  // namespace go_feap::world
