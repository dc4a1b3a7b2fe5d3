// The map server's autosave (issue 18): parameters autosave/path, autosave/period_s and
// file_root, and the one function that resolves the autosave file under file_root.
//
//   autosave/path: "autosave.fgm"   # relative: under file_root; "" (default): no autosave
//   autosave/period_s: 10           # a save every 10 s while the map changes; 0: on shutdown only
//   file_root: "/data/maps"         # default: $ROS_HOME/fragg_map ($HOME/.ros/fragg_map)
#pragma once

#include <xmlrpcpp/XmlRpcValue.h>

#include <string>
#include <vector>

namespace fragg::ros {

struct AutosaveParams {
  std::string path;       ///< resolved (absolute) .fgm file; empty: no autosave
  double period_s = 0.0;  ///< seconds between saves; 0: only on shutdown
  std::string file_root;  ///< folder that relative paths resolve in
  bool enabled() const { return !path.empty(); }
};

/// The names parseAutosaveParameters reads: the server's unknown-parameter check counts them.
const std::vector<std::string>& autosaveParameterNames();

/// $ROS_HOME/fragg_map, ROS_HOME defaulting to $HOME/.ros (as roslaunch's log folder does).
std::string defaultFileRoot();

/// `path` under `file_root`: an absolute path as it is, a relative one appended to file_root,
/// both normalised lexically ("a/../b" -> "b"). Throws fragg::InvalidArgument for an empty
/// path, a relative one that climbs out of file_root ("../x.fgm"), a relative file_root, and a
/// name not ending in .fgm (the autosave is a fragg_map map file).
std::string resolveAutosavePath(const std::string& path, const std::string& file_root);

/// Reads autosave/path, autosave/period_s and file_root from the private namespace as one
/// XmlRpcValue (absent names keep their defaults). Throws fragg::InvalidArgument naming the
/// parameter ('autosave/period_s') for a wrong type or value.
AutosaveParams parseAutosaveParameters(const XmlRpc::XmlRpcValue& params);

}  // namespace fragg::ros
