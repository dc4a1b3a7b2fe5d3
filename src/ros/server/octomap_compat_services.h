// octomap_server's service names and types on the private handle, for its clients unchanged:
// ~reset (std_srvs/Empty) and ~clear_bbx (octomap_msgs/BoundingBoxQuery: fragg_map's
// BoundingBoxQuery.srv has the same fields, hence the same md5sum; by default the known cells in
// the box become free, as octomap_server's, see clear_bbx_free). Both run MapServices'
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
  /// `clear_bbx_free`: ~clear_bbx sets the known cells in the box free (octomap_server's rule)
  /// instead of making them unknown.
  OctomapCompatServices(::ros::NodeHandle& private_nh, MapServices* services, bool clear_bbx_free);

 private:
  bool reset(std_srvs::Empty::Request& req, std_srvs::Empty::Response& res);
  bool clearBbx(fragg_map::BoundingBoxQuery::Request& req,
                fragg_map::BoundingBoxQuery::Response& res);

  MapServices* services_;
  bool clear_bbx_free_;
  ::ros::ServiceServer reset_, clear_bbx_;
};

}  // namespace fragg::ros
