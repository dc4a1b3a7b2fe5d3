// Start-up notes for octomap_server users.
#include "octomap_compat_notes.h"

#include <ros/console.h>

namespace fragg::ros {

void logOctomapCompatNotes(const ServerParams& params) {
  const OctomapCompatParams& o = params.octomap;
  if (o.filter_ground && params.map.scans.keep)
    ROS_INFO(
        "fragg_map: filter_ground with keep_scans: scans with ground points are kept but cannot "
        "be corrected (~correct_poses); set keep_scans: false to keep no scans");
  if (o.colored_map && o.height_map)
    ROS_WARN(
        "fragg_map: colored_map and height_map are both set, which contradict each other: "
        "markers are coloured by height (as octomap_server does)");
#if !FRAGG_HAVE_OCTOMAP_MSGS
  ROS_INFO(
      "fragg_map: no octomap_binary / octomap_full topics or services: this build found no "
      "octomap_msgs (ros.org's ROS ships it, Debian does not; rebuild with it installed)");
#endif
}

}  // namespace fragg::ros
