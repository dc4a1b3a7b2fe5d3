// What an octomap_server user should know at start-up: the octomap_server parameters set here
// that fragg_map does not honour (filter_ground, colored_map), and why the octomap_msgs outputs
// are absent.
#pragma once

#include "fragg_map/ros/server_params.h"

namespace fragg::ros {

/// Logs one warning per octomap_server option set that has no effect here, and once that
/// octomap_binary / octomap_full are absent when the build had no octomap_msgs.
void logOctomapCompatNotes(const ServerParams& params);

}  // namespace fragg::ros
