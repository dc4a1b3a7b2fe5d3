// A scan ready for ray casting: rays in voxel units relative to the sensor's voxel.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "fragg_map/frustum.h"
#include "fragg_map/insert_stats.h"
#include "fragg_map/internal/ray_prep.h"
#include "fragg_map/map_params.h"
#include "fragg_map/point_cloud.h"
#include "fragg_map/raycast.h"
#include "fragg_map/sensor_model.h"

namespace fragg {

/// PreparedScan::point_index of a ray with no point of the cloud behind it.
constexpr uint32_t kNoPointIndex = 0xffffffffu;

struct PreparedScan {
  VoxelKey ref;                  ///< the sensor origin's voxel
  float start_v[3] = {0, 0, 0};  ///< sensor origin relative to ref, voxel units, in [0, 1)
  std::vector<RayEnd> rays;
  /// With MapParams::dynamic enabled: the cloud index of each ray's point (else empty);
  /// kNoPointIndex for a no-return beam of the beam table (a free ray, never dynamic).
  std::vector<uint32_t> point_index;
  /// RayCast::kOctomap: the rays end in float metres (RayEnd::end_v) and are walked from
  /// `origin_m` by traverseOctomapKeys.
  bool octomap_keys = false;
  float origin_m[3] = {0, 0, 0};  ///< the sensor origin as float metres, map frame
  double resolution_m = 0.0;
  double inv_res = 0.0;  ///< 1.0 / resolution_m

  /// The end cell of ray `i` on axis `a`, relative to `ref`.
  int endCell(size_t i, int a) const {
    const int32_t ref_a = a == 0 ? ref.x : a == 1 ? ref.y : ref.z;
    return rayEndCell(rays[i], a, octomap_keys, inv_res, ref_a);
  }

  RayVox ray(size_t i) const {
    const RayEnd& e = rays[i];
    return RayVox{ref,
                  {start_v[0], start_v[1], start_v[2]},
                  {e.end_v[0], e.end_v[1], e.end_v[2]},
                  isHitCode(e.hit),
                  marginOfHitCode(e.hit),
                  e.hit == kFreeEndCode};
  }
  /// Ray `i` for traverseOctomapKeys (RayCast::kOctomap).
  RayMetres rayMetres(size_t i) const {
    const RayEnd& e = rays[i];
    return RayMetres{{origin_m[0], origin_m[1], origin_m[2]},
                     {e.end_v[0], e.end_v[1], e.end_v[2]},
                     resolution_m,
                     inv_res,
                     isHitCode(e.hit),
                     marginOfHitCode(e.hit),
                     e.hit == kFreeEndCode};
  }
};

/// The pose and sensor data the rays of one scan are built from; sets `ref` and `start_v`
/// of `out`. Throws InvalidArgument when the sensor origin is outside the int32 key range.
RayPrepParams rayPrepParams(const Eigen::Isometry3d& T_map_sensor, const SensorModel& model,
                            bool explicit_model, const MapParams& params, PreparedScan& out);

/// Transforms, filters and clips a cloud (OctoMap semantics: NaN/Inf and points closer than
/// min range dropped; points beyond max range become free-only rays ending at max range; points
/// marked free-only give free-only rays ending at the point).
/// `model` must be resolved (not auto); when `explicit_model` is set, points outside the
/// frustum are dropped and counted. Fills the point counters of `stats`.
void prepareScan(const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                 const SensorModel& model, const Frustum& frustum, bool explicit_model,
                 const MapParams& params, PreparedScan& out, InsertStats& stats);

}  // namespace fragg
