// ~reset and ~clear_bbx: octomap_server's types, fragg_map's work.
#include "octomap_compat_services.h"

#include <ros/console.h>

#include <exception>

namespace fragg::ros {

OctomapCompatServices::OctomapCompatServices(::ros::NodeHandle& private_nh, MapServices* services,
                                             bool clear_bbx_free)
    : services_(services), clear_bbx_free_(clear_bbx_free) {
  reset_ = private_nh.advertiseService("reset", &OctomapCompatServices::reset, this);
  clear_bbx_ = private_nh.advertiseService("clear_bbx", &OctomapCompatServices::clearBbx, this);
}

bool OctomapCompatServices::reset(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  try {
    services_->resetMap();
    return true;
  } catch (const std::exception& e) {
    ROS_WARN("fragg_map: reset failed: %s", e.what());
    return false;
  }
}

bool OctomapCompatServices::clearBbx(fragg_map::BoundingBoxQuery::Request& req,
                                     fragg_map::BoundingBoxQuery::Response&) {
  try {
    const Eigen::Vector3d min_m(req.min.x, req.min.y, req.min.z),
        max_m(req.max.x, req.max.y, req.max.z);
    const std::string done =
        clear_bbx_free_ ? services_->freeBox(min_m, max_m) : services_->clearBox(min_m, max_m);
    ROS_INFO("fragg_map: clear_bbx: %s", done.c_str());
    return true;
  } catch (const std::exception& e) {
    ROS_WARN("fragg_map: clear_bbx refused: %s", e.what());
    return false;
  }
}

}  // namespace fragg::ros
