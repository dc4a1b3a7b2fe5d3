#include "fuzz_targets.h"

namespace fragg::fuzz {

std::vector<Target> targets() {
  return {
      {"fgm", fgm},
      {"scan", scan},
      {"pcd", pcd},
      {"ply", ply},
      {"xyz", xyz},
      {"kitti_bin", kittiBin},
      {"scan_graph", scanGraph},
      {"poses", poses},
      {"waypoints", waypoints},
      {"obj", obj},
      {"insert", insertScan},
#ifdef FRAGG_FUZZ_HAVE_ROS_MSGS
      {"cloud_msg", cloudMsg},
#endif
  };
}

}  // namespace fragg::fuzz
