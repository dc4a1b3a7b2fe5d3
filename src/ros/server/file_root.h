// The folder the map server's file services (~save_map, ~load_map, ~truncate, ~merge) may read
// and write: anyone on the ROS network can call a service, so a requested path is resolved
// under `file_root` and refused when it leaves it. ROS-free (std::filesystem only), so any
// writer of the server (autosave too) can use it and it is tested without a ROS master.
#pragma once

#include <string>

#include "fragg_map/ros/autosave_params.h"

namespace fragg::ros {

// The default file_root, defaultFileRoot(): fragg_map/ros/autosave_params.h (the autosave
// resolves its path under the same folder).

/// Makes `root` (created with its parents when missing) an absolute, symlink-free folder path.
/// Throws fragg::IoError when it cannot be created or is not a folder.
std::string prepareFileRoot(const std::string& root);

/// The file `requested` names, as an absolute path under `root` (a prepared root, above):
/// a relative path resolves against `root`; an absolute one must already lie under it. `..`
/// components and symbolic links are resolved first (those in the existing part of the path),
/// and the result must still lie strictly inside `root`. Throws fragg::InvalidArgument (with
/// the reason and the root) for an empty path, a path that leaves `root` (through `..`, as an
/// absolute path elsewhere, or through a symlink), a path naming `root` itself, and a dangling
/// symlink. (A link swapped in between this check and the open is not caught: the guard is
/// against requests, not against local users who can write inside the root.)
std::string resolveUnderRoot(const std::string& root, const std::string& requested);

}  // namespace fragg::ros
