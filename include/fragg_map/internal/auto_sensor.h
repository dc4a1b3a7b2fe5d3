// Resolving an `auto` sensor model (sensor_model.h's resolveAutoSensor) in two steps, so that a
// backend can gather the statistics where the points are (MapBackend::autoSensorStats).
#pragma once

#include "fragg_map/internal/auto_sensor_stats.h"
#include "fragg_map/point_cloud.h"
#include "fragg_map/sensor_model.h"

namespace fragg {

/// The six sensor axes and their pinhole bases (what addAutoSensorPoint() needs).
const SensorAxisTable& sensorAxisTable();

/// One pass over the cloud on the host (OpenMP over fixed chunks; any thread count gives the
/// same bits).
AutoSensorStats gatherAutoSensorStats(const PointCloud& cloud);

/// The explicit model from the cloud's statistics; `cloud` is read again only for a camera
/// cloud whose mean direction snaps to no sensor axis (a second pass around that axis).
SensorModel resolveAutoSensor(const SensorModel& model, const PointCloud& cloud,
                              const AutoSensorStats& stats);

}  // namespace fragg
