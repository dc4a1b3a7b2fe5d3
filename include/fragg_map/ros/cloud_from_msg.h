// sensor_msgs/PointCloud2 -> fragg::PointCloud (fragg_map_ros, stateless).
//
// Packed little-endian float32 x, y, z at offsets 0, 4, 8 (the common LiDAR and depth-camera
// layout) are copied point by point with memcpy (one memcpy for the whole cloud when
// point_step is 12); any other layout (other offsets, float64 fields, other byte order) goes
// through a strided field reader. Organised clouds (height > 1) stay organised, NaN included.
#pragma once

#include <sensor_msgs/PointCloud2.h>

#include <cstddef>
#include <string>

#include "fragg_map/point_cloud.h"

namespace fragg::ros {

/// How a message was converted (for statistics and tests).
enum class CloudLayout { kPackedFloat32, kStrided };

/// Converts `msg` into a cloud in the message's own frame. Throws fragg::InvalidArgument
/// naming the problem for a malformed message: a missing x, y or z field, a field that is not
/// FLOAT32 or FLOAT64 (e.g. INT16), a field ending past point_step, row_step smaller than
/// width x point_step, data shorter than the points it declares, no points at all (these
/// messages start "malformed PointCloud2: "); and for a well-formed cloud without a finite
/// point ("... no finite point among N (all NaN or Inf)", not called malformed). `layout`
/// (optional) tells which path converted it.
fragg::PointCloud cloudFromMsg(const sensor_msgs::PointCloud2& msg, CloudLayout* layout = nullptr);
/// The same into `out`, every field overwritten, its point buffer reused: within its capacity
/// no new buffer is taken (a server converting clouds of one size writes into pages it already
/// has; a fresh 2 MiB buffer faults in at ~3.7 ms on the 2-core VM). The same exceptions; after
/// one `out` holds no valid cloud.
void cloudFromMsg(const sensor_msgs::PointCloud2& msg, fragg::PointCloud* out,
                  CloudLayout* layout = nullptr);

/// Points of `cloud` with finite coordinates.
size_t finitePointCount(const fragg::PointCloud& cloud);

}  // namespace fragg::ros
