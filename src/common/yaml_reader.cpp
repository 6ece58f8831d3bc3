#include "go_feap/common/yaml_reader.h"

#include <yaml-cpp/yaml.h>

#include <optional>
#include <sstream>

namespace go_feap::common {

struct YamlReader::Impl {
  std::vector<std::pair<std::string, YAML::Node>> files;
};

YamlReader::YamlReader(const std::vector<std::string>& paths) : impl_(std::make_unique<Impl>()) {
  for (const std::string& path : paths) {
    try {
      impl_->files.emplace_back(path, YAML::LoadFile(path));
    } catch (const std::exception& e) {
      if (error_.empty()) error_ = path + ": cannot be read as YAML (" + e.what() + ")";
    }
  }
  if (paths.empty()) error_ = "no YAML file given";
}

YamlReader::~YamlReader() = default;
YamlReader::YamlReader(YamlReader&&) noexcept = default;

void YamlReader::fail(const std::string& key, const std::string& why) {
  if (!error_.empty()) return;
  std::string files;
  for (const auto& f : impl_->files) files += (files.empty() ? "" : " + ") + f.first;
  error_ = files + ": parameter '" + key + "' " + why;
}

namespace {

// The node at "a/b/c" in the last of `files` that has it. Lookups go through const handles (which never
// create keys) and reset() rebinds the handle instead of assigning through it.
std::optional<YAML::Node> lookup(const std::vector<std::pair<std::string, YAML::Node>>& files, const std::string& key) {
  for (auto f = files.rbegin(); f != files.rend(); ++f) {
    YAML::Node node;
    node.reset(f->second);
    std::stringstream parts(key);
    std::string part;
    bool present = true;
    while (present && std::getline(parts, part, '/')) {
      const YAML::Node& here = node;
      // YAML::Node() is a defined null node, not an absent one: a key under a scalar is tested apart.
      const YAML::Node child = here.IsMap() ? here[part] : YAML::Node(YAML::NodeType::Undefined);
      if (!here.IsMap() || !child) {
        present = false;
      } else {
        node.reset(child);
      }
    }
    if (present) return node;
  }
  return std::nullopt;
}

}  // namespace

bool YamlReader::has(const std::string& key) const { return lookup(impl_->files, key).has_value(); }

template <typename T>
YamlReader& YamlReader::read(const std::string& key, T& out) {
  if (!error_.empty()) return *this;
  const std::optional<YAML::Node> found = lookup(impl_->files, key);
  if (!found) {
    fail(key, "is missing");
    return *this;
  }
  const YAML::Node& node = *found;
  try {
    out = node.as<T>();
  } catch (const std::exception&) {
    fail(key, "has the wrong type");
  }
  return *this;
}

YamlReader& YamlReader::get(const std::string& key, double& out) { return read(key, out); }
YamlReader& YamlReader::get(const std::string& key, int& out) { return read(key, out); }
YamlReader& YamlReader::get(const std::string& key, bool& out) { return read(key, out); }
YamlReader& YamlReader::get(const std::string& key, std::string& out) { return read(key, out); }
YamlReader& YamlReader::get(const std::string& key, std::vector<double>& out) { return read(key, out); }

YamlReader& YamlReader::getVec3(const std::string& key, Eigen::Vector3d& out) {
  std::vector<double> v;
  read(key, v);
  if (!ok()) return *this;
  if (v.size() != 3) return fail(key, "must hold 3 numbers"), *this;
  out = Eigen::Vector3d(v[0], v[1], v[2]);
  return *this;
}

YamlReader& YamlReader::getMatrix4(const std::string& key, Eigen::Matrix4d& out) {
  std::vector<double> v;
  read(key, v);
  if (!ok()) return *this;
  if (v.size() != 16) return fail(key, "must hold 16 numbers (row-major 4x4)"), *this;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) out(r, c) = v[4 * r + c];
  return *this;
}

}  // namespace go_feap::common
