// fragg::Map -> sensor_msgs/PointCloud2 of the centres of its occupied voxels.
#pragma once

#include <ros/time.h>
#include <sensor_msgs/PointCloud2.h>

#include <string>
#include <vector>

#include "fragg_map/map.h"
#include "fragg_map/ros/height_band.h"

namespace fragg::ros {

/// An unorganised cloud (height 1) of the points `xyz` (x, y, z float triples, frame_id):
/// packed float32 fields x, y, z, point_step 12. The occupied and frontier clouds use it.
sensor_msgs::PointCloud2 packedXyzCloud(const std::vector<float>& xyz, const std::string& frame_id,
                                        const ::ros::Time& stamp);

/// An unorganised cloud (height 1) with packed float32 fields x, y, z (point_step 12) holding
/// the centre of every occupied voxel, in `frame_id`.
/// With `hide_speckles`, occupied cells without an occupied neighbour are left out
/// (octomap_server's filter_speckles); cells outside `heights` (occupancy_min_z / max_z) too.
sensor_msgs::PointCloud2 occupiedCloud(const fragg::Map& map, const std::string& frame_id,
                                       const ::ros::Time& stamp, bool hide_speckles = false,
                                       const HeightBand& heights = HeightBand());

}  // namespace fragg::ros
