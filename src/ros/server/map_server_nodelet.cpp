// fragg_map/MapServerNodelet: onInit builds a MapServer, nothing else.
#include <nodelet/nodelet.h>
#include <ros/console.h>

#include <memory>
#include <pluginlib/class_list_macros.hpp>

#include "map_server.h"

namespace fragg::ros {

class MapServerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      server_ = std::make_unique<MapServer>(getNodeHandle(), getPrivateNodeHandle());
    } catch (const std::exception& e) {
      NODELET_FATAL("fragg_map: cannot start: %s", e.what());
      throw;  // a nodelet that cannot start must fail loudly
    }
  }

  std::unique_ptr<MapServer> server_;
};

}  // namespace fragg::ros

PLUGINLIB_EXPORT_CLASS(fragg::ros::MapServerNodelet, nodelet::Nodelet)
