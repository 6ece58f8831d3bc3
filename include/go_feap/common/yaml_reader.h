// Reads required parameters from YAML files with the interface of the nodelets' ParamReader
// (common/config_groups.h): "group/key" names a nested key; the first missing or mistyped key
// is remembered with the file's name. Files given later override earlier ones key by key (a
// planner mode laid over the defaults), as rosparam does when it loads them in that order.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "go_feap/common/result.h"

namespace go_feap::common {

class YamlReader {
 public:
  /// Loads `path`; a file that cannot be read or parsed is reported by ok()/error().
  explicit YamlReader(const std::string& path) : YamlReader(std::vector<std::string>{path}) {}
  /// Loads every file of `paths`; a key is taken from the last file that has it.
  explicit YamlReader(const std::vector<std::string>& paths);
  ~YamlReader();
  YamlReader(YamlReader&&) noexcept;

  YamlReader& get(const std::string& key, double& out);
  YamlReader& get(const std::string& key, int& out);
  YamlReader& get(const std::string& key, bool& out);
  YamlReader& get(const std::string& key, std::string& out);
  YamlReader& get(const std::string& key, std::vector<double>& out);
  YamlReader& getVec3(const std::string& key, Eigen::Vector3d& out);
  YamlReader& getMatrix4(const std::string& key, Eigen::Matrix4d& out);

  /// Whether any of the files has `key` ("group" or "group/key"), of whatever type.
  bool has(const std::string& key) const;

  bool ok() const { return error_.empty(); }
  /// "config/x.yaml: parameter 'group/key' is missing" (the first problem found), or empty.
  const std::string& error() const { return error_; }
  common::Status status() const { return ok() ? Status::Ok() : Status::Error(error_); }

 private:
  struct Impl;
  template <typename T>
  YamlReader& read(const std::string& key, T& out);
  void fail(const std::string& key, const std::string& why);
  std::unique_ptr<Impl> impl_;
  std::string error_;
};

}  // namespace go_feap::common
