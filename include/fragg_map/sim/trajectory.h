// Trajectories: waypoints driven at a constant speed and sampled at the sensor rate, giving the
// ground-truth base pose and a drifting odometry estimate of it side by side.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <vector>

namespace fragg::sim {

struct TrajectorySpec {
  std::vector<Eigen::Vector3d> waypoints_m;  ///< map frame; z above ground when follow_ground
  double speed_mps = 1.0;
  double rate_hz = 10.0;
  bool follow_ground = false;     ///< base z = terrain height + waypoint z
  bool closed = false;            ///< drive back to the first waypoint (a loop)
  double heading_window_m = 1.0;  ///< heading = direction between s - w and s + w (smooth turns)
};

/// Odometry error model. Per step of length d (m) and turn a (rad):
///   translation error = drift_m_per_m * d * (bias + 0.5 * noise), bias a fixed unit vector in
///   the base xy plane; heading error = drift_rad_per_m * d * (1 + 0.5 * noise) +
///   drift_rad_per_rad * a * (1 + 0.5 * noise); noise standard normal, seeded.
struct DriftSpec {
  double drift_m_per_m = 0.0;
  double drift_rad_per_m = 0.0;
  double drift_rad_per_rad = 0.0;
};

struct PoseSample {
  double stamp_s = 0.0;
  Eigen::Isometry3d T_map_base = Eigen::Isometry3d::Identity();   ///< ground truth
  Eigen::Isometry3d T_odom_base = Eigen::Isometry3d::Identity();  ///< drifting odometry
};

/// Samples the trajectory every speed / rate metres from its start (at most max_frames
/// samples; 0 = the whole path). The base is level (roll = pitch = 0) and faces its direction
/// of travel. Odometry starts at the ground truth (map -> odom is the identity).
/// Throws InvalidArgument for fewer than two waypoints or a non-positive speed or rate.
std::vector<PoseSample> sampleTrajectory(const TrajectorySpec& spec,
                                         const std::function<double(double, double)>& ground_m,
                                         const DriftSpec& drift, uint64_t seed,
                                         size_t max_frames = 0);

}  // namespace fragg::sim
