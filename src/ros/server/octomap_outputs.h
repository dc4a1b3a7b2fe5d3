// octomap_server's map outputs, built only with octomap_msgs (and liboctomap): the topics
// octomap_binary and octomap_full (octomap_msgs/Octomap) and the GetOctomap services of the
// same names, on the node's namespace as octomap_server has them. The messages hold what
// octomap_msgs' conversions hold: an OcTree of the map (interop/octomap_io.h toOcTree) as
// liboctomap serialises it, binary (maximum likelihood, pruned: the data of a .bt file) or
// full (every leaf's log-odds, unpruned). Built only for topics with subscribers; a late
// subscriber gets the current map when it connects (latched or not). After a cloud they go out
// at most at `map_rate` (as the other whole-map outputs); a steady timer sends the map held
// back once the clouds stop.
#pragma once

#include <ros/node_handle.h>
#include <ros/publisher.h>
#include <ros/service_server.h>
#include <ros/steady_timer.h>

#include <mutex>

#include "fragg_map/ros/rate_throttle.h"
#include "fragg_map/ros/server_params.h"
#include "shared_map.h"

namespace fragg::ros {

class OctomapOutputs {
 public:
  OctomapOutputs(::ros::NodeHandle& nh, const ServerParams& params, SharedMap* shared);
  /// Both topics, where they have subscribers, at once (reset, load, clear, corrections).
  /// Takes the map's read lock.
  void publish(const ::ros::Time& stamp);
  /// After a cloud: as publish when map_rate lets an update out, else held back (pending).
  void publishAfterInsert(const ::ros::Time& stamp);

 private:
  void publishIfDue(const ::ros::Time& stamp, bool throttled);
  /// Callers hold publish_mutex_ and the map's read lock.
  void publishLocked(const fragg::Map& map, const ::ros::Time& stamp, double now_s);
  /// Timer: what map_rate held back, once due (never waits for the map).
  void flushPending(const ::ros::SteadyTimerEvent& event);

  const ServerParams params_;
  SharedMap* shared_;
  std::mutex publish_mutex_;
  /// map_rate (under publish_mutex_): whether a cloud's map is held back, with its stamp.
  HeldBackUpdate<::ros::Time> held_;
  ::ros::SteadyTimer flush_timer_;
  ::ros::Publisher binary_pub_, full_pub_;
  ::ros::ServiceServer binary_srv_, full_srv_;
};

}  // namespace fragg::ros
