// A simulated pinhole depth camera: one ray through each pixel centre, the measured value is the
// depth along the optical axis (as Kinect-style cameras give). Organised cloud in the camera
// optical frame (z forward, x right, y down), NaN where a pixel has no return.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/io/depth_image.h"
#include "fragg_map/point_cloud.h"

namespace fragg::sim {

struct DepthCameraSpec {
  int width = 640;
  int height = 480;
  double hfov_deg = 60.0;  ///< horizontal; square pixels (fy = fx)
  double min_range_m = 0.2;
  double max_range_m = 10.0;  ///< depth beyond this gives no return
  double noise_m = 0.0;       ///< depth standard deviation at 1 m; grows with depth squared
  double dropout = 0.0;       ///< probability that a pixel is lost

  void validate() const;  ///< throws InvalidArgument naming the bad field
  /// fx = fy = (width / 2) / tan(hfov / 2), principal point at the image centre.
  DepthIntrinsics intrinsics() const;
};

/// One frame from pose T_map_camera (optical frame). Deterministic in (seed, frame, pixel).
/// With `movers`, as simulateLidar: rays meet the nearer of both meshes and
/// `dynamic_labels` flags (1) each pixel whose return is from a mover.
PointCloud simulateDepthCamera(const geometry::MeshBvh& scene, const DepthCameraSpec& spec,
                               const Eigen::Isometry3d& T_map_camera, uint64_t seed, uint64_t frame,
                               const geometry::MeshBvh* movers = nullptr,
                               std::vector<uint8_t>* dynamic_labels = nullptr);

/// The 16-bit depth image of an organised optical-frame cloud (NaN -> 0), with `scale_m` per
/// unit (1 mm by default); depths that do not fit in 16 bits become 0.
DepthImage toDepthImage(const PointCloud& cloud_C, double scale_m = 0.001);

}  // namespace fragg::sim
