// fragg_map/MapServerNodelet: onInit builds a MapServer, nothing else.
#include <nodelet/nodelet.h>
#include <ros/console.h>

#include <memory>
#include <pluginlib/class_list_macros.hpp>
#include <string>

#include "map_server.h"

namespace fragg::ros {

class MapServerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      // The first argument that is not a remapping is a map file (as octomap_server's).
      std::string map_file;
      for (const std::string& arg : getMyArgv()) {
        if (arg.find(":=") != std::string::npos || arg.rfind("__", 0) == 0) continue;
        map_file = arg;
        break;
      }
      server_ = std::make_unique<MapServer>(getNodeHandle(), getPrivateNodeHandle(), map_file);
    } catch (const std::exception& e) {
      NODELET_FATAL("fragg_map: cannot start: %s", e.what());
      throw;  // a nodelet that cannot start must fail loudly
    }
  }

  std::unique_ptr<MapServer> server_;
};

}  // namespace fragg::ros

PLUGINLIB_EXPORT_CLASS(fragg::ros::MapServerNodelet, nodelet::Nodelet)
