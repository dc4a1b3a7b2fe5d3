// The input of the insertion fuzz target (fuzz_insert.cpp) decoded into what Map::insert takes:
// shared by the fuzz target, the corpus replay and the gpu test that replays the same corpus
// through the CUDA backend.
//
// Layout (little-endian; a short input is padded with zero bytes):
//   byte 0   flags: bit 0 Bresenham, bits 1-2 sensor (0 auto, 1 lidar, 2 pinhole, 3 auto), bit 3
//            keep scans (then insert again, correct and remove), bit 4 organised cloud with
//            no-return clearing, bit 5 a range noise, bit 6 skip saturated blocks off
//   byte 1   resolution: 0-3 pick 0.01 / 0.05 / 0.2 / 1 m, otherwise the float32 at bytes 2-5
//   bytes 2-5    float32 resolution (when byte 1 > 3)
//   bytes 6-9    float32 max range (<= 0: none, the farthest point)
//   bytes 10-37  float32 sensor position x y z, quaternion w x y z (normalised; unusable:
//                identity rotation)
//   bytes 38-    float32 points x y z (at most kMaxInsertPoints)
// A resource bound of the harness, not of the map: the map's memory follows the cells the rays
// reach (by design, as OctoMap's), so a positive max range is cut to kMaxInsertRayV voxels, and
// a point between kMaxInsertRayV and 2^26 voxels from the sensor is moved along its direction to
// kMaxInsertRayV voxels (nearer ones and far ones, which the map drops, stay as they are).
#pragma once

#include <Eigen/Geometry>
#include <cstddef>
#include <cstdint>

#include "fragg_map/map.h"
#include "fragg_map/map_params.h"
#include "fragg_map/point_cloud.h"
#include "fragg_map/sensor_model.h"

namespace fragg::fuzz {

constexpr size_t kMaxInsertPoints = 256;
constexpr double kMaxInsertRayV = 2048.0;

struct InsertInput {
  MapParams params;  ///< CPU backend, one thread; the caller may change the backend
  SensorModel sensor;
  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  PointCloud cloud;
  /// Insert a second scan, correct the first one's pose and remove it (params.scans.keep).
  bool correct_and_remove = false;
};

/// Decodes any bytes (none are refused here: bad values reach Map's own checks).
InsertInput decodeInsertInput(const uint8_t* data, size_t size);

/// After the first insertion (scan `first`), with `in.correct_and_remove`: a second insertion a
/// little further on, a correction of the first scan's pose and its removal. Throws what Map
/// throws.
void correctAndRemove(const InsertInput& in, ScanId first, Map& map);

/// The operations of the target on `map`: the insertion, then correctAndRemove. Returns the
/// first insertion's statistics. Throws what Map throws.
InsertStats runInsertInput(const InsertInput& in, Map& map);

}  // namespace fragg::fuzz
