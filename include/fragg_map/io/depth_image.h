// Depth images (binary PGM, 16-bit millimetres) and their back-projection to an organised
// cloud in the camera optical frame (z forward, x right, y down).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fragg_map/point_cloud.h"

namespace fragg {

/// Pinhole intrinsics in pixels; depth_scale_m converts a raw depth value to metres.
/// Defaults: the Kinect v1 of the NYU Depth v2 / slambook2 frames.
struct DepthIntrinsics {
  double fx = 518.0;
  double fy = 519.0;
  double cx = 325.5;
  double cy = 253.5;
  double depth_scale_m = 0.001;
};

struct DepthImage {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint16_t> depth;  ///< row-major, raw units; 0 = no measurement
};

/// Binary PGM (P5): 16-bit big-endian samples when maxval > 255, else 8-bit.
DepthImage readPgm(const std::string& path);

/// "fx fy cx cy [depth_scale_m]" on the first data line ('#' comments allowed).
DepthIntrinsics readDepthIntrinsics(const std::string& path);

/// Organised width x height cloud; pixels with depth 0 become NaN (no return).
PointCloud depthToCloud(const DepthImage& image, const DepthIntrinsics& intrinsics);

}  // namespace fragg
