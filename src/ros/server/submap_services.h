// ~truncate and ~merge: sub-maps cut out of the map into a .fgm file, and .fgm sub-maps (or
// maps of another robot) merged back in (fragg_map/submap.h). Both take the map's write lock
// for their edit (~truncate with keep only reads); the changed blocks' markers and
// projected_map are republished after an edit. Paths are .fgm files under params.file_root
// (file_root.h: relative paths resolve there, paths leading out are refused). Bad
// arguments answer success=false with the reason and leave the map (and the file system)
// untouched.
#pragma once

#include <ros/node_handle.h>
#include <ros/service_server.h>

#include <functional>

#include "fragg_map/Merge.h"
#include "fragg_map/Truncate.h"
#include "fragg_map/ros/server_params.h"
#include "shared_map.h"

namespace fragg::ros {

class SubmapServices {
 public:
  /// `on_map_changed` runs (map unlocked) after a truncation that removed cells or a merge.
  SubmapServices(::ros::NodeHandle& private_nh, const ServerParams& params, SharedMap* shared,
                 std::function<void()> on_map_changed);

 private:
  bool truncate(fragg_map::Truncate::Request& req, fragg_map::Truncate::Response& res);
  bool merge(fragg_map::Merge::Request& req, fragg_map::Merge::Response& res);

  const ServerParams params_;
  SharedMap* shared_;
  std::function<void()> on_map_changed_;
  ::ros::ServiceServer truncate_, merge_;
};

}  // namespace fragg::ros
