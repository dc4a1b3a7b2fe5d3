// No-return beams of an unorganised LiDAR cloud from the sensor's beam table
// (SensorModel::lidar_beams): the cloud's returns binned into (ring, column), the empty bins
// are the beams that returned nothing. NaN/Inf and (0,0,0) points -- a driver's no-return
// markers -- occupy no bin.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "fragg_map/map_params.h"
#include "fragg_map/point_cloud.h"
#include "fragg_map/sensor_model.h"

namespace fragg {

/// Whether a scan clears its no-return beams from the beam table: the option is on, the cloud
/// is unorganised (an organised cloud's NaN pixels say it directly) and the sensor has a table.
[[nodiscard]] inline bool clearsBeamNoReturns(bool clear_no_return_rays, const PointCloud& cloud,
                                              const SensorModel& model) {
  return clear_no_return_rays && !cloud.organised() && !model.lidar_beams.empty();
}

/// The unit directions (sensor frame), in ring-major order, of the beams of `beams` that no
/// return of `cloud` falls in. A return belongs to the ring of nearest elevation (none when
/// it lies outside the table by more than half a ring gap) and the column of nearest azimuth.
[[nodiscard]] std::vector<Eigen::Vector3d> emptyBeamDirections(const PointCloud& cloud,
                                                               const LidarBeams& beams);

}  // namespace fragg
