// OctoMap binary (.bt) files, read and written with their failures named: the mapper's maps and the
// scenes' ground truth.
#pragma once

#include <octomap/OcTree.h>

#include <memory>
#include <string>

#include "go_feap/common/result.h"

namespace go_feap::map {

/// The tree of an OctoMap binary (.bt) file, each part checked before OctoMap reads it: the header lines,
/// the tree data's nesting (OctoMap's reader recursed without a limit on garbage that said every node had
/// children, and overflowed the stack) and the leaves' coordinates. An empty tree (a map saved before its
/// first scan: 'size 0', no data) is read as one. Errors name the file and what is wrong.
common::Result<std::unique_ptr<octomap::OcTree>> readOctree(const std::string& path);

/// Writes `tree` to `path` through a file beside it renamed over it once whole: a write that fails half way
/// leaves an earlier file whole.
common::Status writeOctree(const octomap::OcTree& tree, const std::string& path);

}  // namespace go_feap::map
