// What an octomap_server user should know at start-up: the octomap_server parameters set here
// that fragg_map does not honour (colored_map) or honours with a limit (filter_ground with kept
// scans), and why the octomap_msgs outputs are absent.
#pragma once

#include "fragg_map/ros/server_params.h"

namespace fragg::ros {

/// Logs one line per octomap_server option set that has no effect or a limit here, and once that
/// octomap_binary / octomap_full are absent when the build had no octomap_msgs.
void logOctomapCompatNotes(const ServerParams& params);

}  // namespace fragg::ros
