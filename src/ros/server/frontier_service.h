// ~get_frontiers (the exploration service): the map's frontier cells, their clusters and each
// cluster's best k viewpoints by information gain, computed in full on a copy of the map
// (planning::coarseStateMap at frontiers/coarse_cells > 1, else the observed cells as they are:
// map_copy.h) taken under its read lock, the query itself without the lock (fragg_map/planning:
// findFrontierCells, FrontierClusterer, clusterViewpoints), with the frontiers/* parameters where
// the request leaves an option out. The service has a thread of its own (service_threads.h). A
// fresh clusterer per call numbers the clusters 1, 2, ... by first cell, as `fragg_map frontiers`
// does on the saved map. Bad arguments (k < 1, a NaN or inverted box, an unknown sensor, a robot
// frame tf cannot place now ...) answer success=false with the reason; nothing is computed and the
// map is untouched.
#pragma once

#include <ros/node_handle.h>
#include <ros/service_server.h>
#include <tf2_ros/buffer.h>

#include <Eigen/Core>
#include <string>

#include "fragg_map/GetFrontiers.h"
#include "fragg_map/planning/frontier_cells.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/viewpoints.h"
#include "fragg_map/ros/server_params.h"
#include "server_stats.h"
#include "shared_map.h"

namespace fragg::ros {

class FrontierService {
 public:
  FrontierService(::ros::NodeHandle& private_nh, const ServerParams& params,
                  const tf2_ros::Buffer& tf, SharedMap* shared, ServerStats* stats);

  /// The request's options over the frontiers/* parameters, validated (throws
  /// fragg::InvalidArgument naming the bad field). The robot frame is left to the caller.
  struct Query {
    planning::FrontierFilter filter;
    planning::ClusterOptions clusters;
    planning::ViewpointOptions views;
  };
  static Query queryFrom(const fragg_map::GetFrontiers::Request& req, const FrontierParams& p);

 private:
  bool get(fragg_map::GetFrontiers::Request& req, fragg_map::GetFrontiers::Response& res);
  /// frontiers/coarse_cells 0: the coarse cell edge for the map's LiDAR (its beam spacing at
  /// the far range, capped by the sensor's max range), 1 while none is known; `note` says why.
  [[nodiscard]] int autoCoarseCells(const MapState& state, std::string* note) const;
  /// The origin of `frame` in the map frame now (the latest transform); throws
  /// fragg::InvalidArgument when tf cannot place it.
  Eigen::Vector3d robotPosition(const std::string& frame) const;

  const ServerParams params_;
  const tf2_ros::Buffer& tf_;
  SharedMap* shared_;
  ServerStats* stats_;
  ::ros::ServiceServer service_;
};

}  // namespace fragg::ros
