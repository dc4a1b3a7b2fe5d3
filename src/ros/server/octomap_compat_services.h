// octomap_server's service names and types on the private handle, for its clients unchanged:
// ~reset (std_srvs/Empty) and ~clear_bbx (octomap_msgs/BoundingBoxQuery: fragg_map's
// BoundingBoxQuery.srv has the same fields, hence the same md5sum). Both run MapServices'
// work; a refused request (a bad box) answers false, which the client sees as a failed call.
#pragma once

#include <ros/node_handle.h>
#include <ros/service_server.h>
#include <std_srvs/Empty.h>

#include "fragg_map/BoundingBoxQuery.h"
#include "map_services.h"

namespace fragg::ros {

class OctomapCompatServices {
 public:
  OctomapCompatServices(::ros::NodeHandle& private_nh, MapServices* services);

 private:
  bool reset(std_srvs::Empty::Request& req, std_srvs::Empty::Response& res);
  bool clearBbx(fragg_map::BoundingBoxQuery::Request& req,
                fragg_map::BoundingBoxQuery::Response& res);

  MapServices* services_;
  ::ros::ServiceServer reset_, clear_bbx_;
};

}  // namespace fragg::ros
