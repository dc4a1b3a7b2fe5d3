// Sensor models: what a sensor can see from its own frame. They size the frustum used for
// block culling and GPU residency.
#pragma once

#include <Eigen/Core>
#include <string>

#include "fragg_map/lidar_beams.h"
#include "fragg_map/point_cloud.h"

namespace fragg {

enum class SensorType : uint8_t {
  kAuto = 0,           ///< derived from each cloud's own angular extent
  kSpinningLidar = 1,  ///< 360 degrees of azimuth about the sensor z axis
  kPinhole = 2,        ///< a pyramid about the sensor's optical axis
};

const char* toString(SensorType t);
/// Parses "auto", "lidar" / "spinning_lidar", "pinhole" / "depth"; throws InvalidArgument.
SensorType sensorTypeFromString(const std::string& s);

/// Axis conventions for the pinhole model in the sensor frame.
enum class OpticalAxis : uint8_t {
  kZForward = 0,  ///< camera optical frame: z forward, x right, y down (REP 103 "_optical")
  kXForward = 1,  ///< body frame: x forward, y left, z up
};

/// Largest range noise figures a model accepts (SensorModel::validate).
constexpr double kMaxRangeNoiseM = 10.0;
constexpr double kMaxRangeNoiseQuadraticPerM = 1.0;

struct SensorModel {
  SensorType type = SensorType::kAuto;
  // Pinhole: full fields of view and the axis convention.
  double hfov_rad = 0.0;
  double vfov_rad = 0.0;
  OpticalAxis optical_axis = OpticalAxis::kZForward;
  /// Pyramid basis in the sensor frame (unit vectors), set from `optical_axis` by `pinhole()`
  /// and from the cloud by `resolveAutoSensor()`; hfov spans `right_S`, vfov spans
  /// forward x right.
  Eigen::Vector3d forward_S{0.0, 0.0, 1.0};
  Eigen::Vector3d right_S{1.0, 0.0, 0.0};
  // Spinning LiDAR: elevation limits about the sensor xy plane.
  double elevation_min_rad = 0.0;
  double elevation_max_rad = 0.0;
  // Both: ranges in metres. max_range_m <= 0 means "no limit" (the farthest point).
  double min_range_m = 0.0;
  double max_range_m = -1.0;
  // Range noise (one standard deviation) at range r: range_noise_m + range_noise_quadratic_per_m
  // * r^2 (LiDAR: about constant; structured light / stereo depth: grows with r^2). A hit keeps
  // free-space updates out of the last sigma(r) metres before it, so that the surface it
  // measured is not cleared by its own noise or by neighbouring rays. 0 (default): OctoMap's
  // behaviour, every cell up to the hit cell is free.
  double range_noise_m = 0.0;
  double range_noise_quadratic_per_m = 0.0;
  /// A LiDAR's beams (empty: unknown). With MapParams::clear_no_return_rays, the beams of an
  /// unorganised cloud that returned nothing clear free space to max_range_m
  /// (prepareScan; an organised cloud's NaN pixels are used instead). LiDAR or auto only;
  /// an explicit LiDAR's rings lie within its elevation limits.
  LidarBeams lidar_beams;

  /// sigma(r) above; 0 when the model has no noise.
  double rangeNoiseAt(double range_m) const {
    return range_noise_m + range_noise_quadratic_per_m * range_m * range_m;
  }

  static SensorModel autoFromCloud(double min_range_m = 0.0, double max_range_m = -1.0);
  static SensorModel pinhole(double hfov_rad, double vfov_rad, double min_range_m,
                             double max_range_m, OpticalAxis axis = OpticalAxis::kZForward);
  static SensorModel spinningLidar(double elevation_min_rad, double elevation_max_rad,
                                   double min_range_m, double max_range_m);

  /// Throws InvalidArgument naming the bad field.
  void validate() const;
  std::string describe() const;
};

/// The explicit model an `auto` sensor resolves to for this cloud: a spinning LiDAR when the
/// points surround the sensor, else a pinhole whose pyramid holds every valid point.
/// `max_range_m` <= 0 becomes the distance of the farthest valid point.
SensorModel resolveAutoSensor(const SensorModel& model, const PointCloud& cloud);

/// Paper formula (1)-(4): voxels in a frustum of depth D with full field of view `fov_rad`
/// whose near base is at distance `near_m` from the sensor.
double frustumVoxelEstimate(double fov_rad, double depth_m, double near_m, double resolution_m);

}  // namespace fragg
