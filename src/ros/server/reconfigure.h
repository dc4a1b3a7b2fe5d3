// The map server's dynamic_reconfigure server (cfg/MapServer.cfg: octomap_server's names for
// the parameters the node can change while it runs). A change is checked as at start-up
// (reconfigure_params.h) and handed to `apply`; a refused one is logged and the server's
// values are set back, so clients read what the node uses.
#pragma once

#include <dynamic_reconfigure/server.h>
#include <ros/node_handle.h>

#include <boost/thread/recursive_mutex.hpp>
#include <functional>

#include "fragg_map/MapServerConfig.h"
#include "fragg_map/ros/reconfigure_params.h"
#include "fragg_map/ros/server_params.h"

namespace fragg::ros {

class ReconfigureServer {
 public:
  using ApplyFn = std::function<void(const ServerParams&)>;

  /// Advertises ~set_parameters (and the description and update topics) with the values of
  /// `current`; `apply` gets the server's parameters with a client's change applied.
  ReconfigureServer(::ros::NodeHandle& private_nh, const ServerParams& current, ApplyFn apply);

 private:
  void onChange(fragg_map::MapServerConfig& config, uint32_t level);

  ServerParams params_;
  ApplyFn apply_;
  bool started_ = false;  ///< the first call (setCallback's) only repeats the start-up values
  boost::recursive_mutex mutex_;
  dynamic_reconfigure::Server<fragg_map::MapServerConfig> server_;
};

}  // namespace fragg::ros
