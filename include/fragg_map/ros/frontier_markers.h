// Frontiers as ROS messages (the server's `frontiers` and `frontier_cells` topics):
// a visualization_msgs/MarkerArray with one CUBE_LIST per cluster (ns "frontier_cells", id =
// the cluster id, one colour per cluster) and one ARROW per viewpoint (ns "viewpoints") along
// its yaw, coloured by gain (red: the lowest gain drawn, green: the highest); and a
// PointCloud2 of frontier cell centres. Both are bounded by `max_cells`: beyond it an even
// subsample (every n-th cell) is sent, so that a LiDAR map with tens of millions of frontier
// cells does not flood the topic.
#pragma once

#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_msgs/ColorRGBA.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdint>
#include <string>
#include <vector>

#include "fragg_map/key.h"
#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/viewpoints.h"

namespace fragg::ros {

/// Step of the even subsample that keeps at most `max_cells` of `cells` (1: all of them;
/// 0 when max_cells is 0 and there are cells: none is kept).
uint64_t subsampleStride(uint64_t cells, uint64_t max_cells);

/// A colour per cluster id (golden-ratio hues), opaque.
std_msgs::ColorRGBA clusterColor(uint64_t id);

struct FrontierMarkerInput {
  const std::vector<planning::FrontierCluster>* clusters = nullptr;
  /// Per cluster (same length as clusters, or empty: no arrows).
  const std::vector<std::vector<planning::Viewpoint>>* views = nullptr;
  double resolution_m = 0.0;  ///< cube size and cell centres ((key + 0.5) * resolution)
};

/// DELETEALL first (the array replaces the previous one), then the cluster cubes (at most
/// `max_cells` cells over all clusters) and the viewpoint arrows. `cells_drawn` (optional)
/// receives the number of cubes. Throws fragg::InvalidArgument when views and clusters
/// disagree in length or the resolution is not > 0.
visualization_msgs::MarkerArray frontierMarkers(const FrontierMarkerInput& in,
                                                const std::string& frame_id,
                                                const ::ros::Time& stamp, uint64_t max_cells,
                                                uint64_t* cells_drawn = nullptr);

/// Unorganised float32 x, y, z cloud of the centres of `cells` (at most `max_cells`).
sensor_msgs::PointCloud2 frontierCloud(const std::vector<VoxelKey>& cells, double resolution_m,
                                       const std::string& frame_id, const ::ros::Time& stamp,
                                       uint64_t max_cells);

}  // namespace fragg::ros
