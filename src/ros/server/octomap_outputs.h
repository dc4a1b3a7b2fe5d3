// octomap_server's map outputs, built only with octomap_msgs (and liboctomap): the topics
// octomap_binary and octomap_full (octomap_msgs/Octomap) and the GetOctomap services of the
// same names, on the node's namespace as octomap_server has them. The messages hold what
// octomap_msgs' conversions hold: an OcTree of the map (interop/octomap_io.h toOcTree) as
// liboctomap serialises it, binary (maximum likelihood, pruned: the data of a .bt file) or
// full (every leaf's log-odds, unpruned). Built only for topics with subscribers; a late
// subscriber gets the current map when it connects (latched or not).
#pragma once

#include <ros/node_handle.h>
#include <ros/publisher.h>
#include <ros/service_server.h>

#include <mutex>

#include "fragg_map/ros/server_params.h"
#include "shared_map.h"

namespace fragg::ros {

class OctomapOutputs {
 public:
  OctomapOutputs(::ros::NodeHandle& nh, const ServerParams& params, SharedMap* shared);
  /// Both topics, where they have subscribers. Takes the map's read lock.
  void publish(const ::ros::Time& stamp);

 private:
  const ServerParams params_;
  SharedMap* shared_;
  std::mutex publish_mutex_;
  ::ros::Publisher binary_pub_, full_pub_;
  ::ros::ServiceServer binary_srv_, full_srv_;
};

}  // namespace fragg::ros
