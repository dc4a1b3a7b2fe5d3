// Exploration scenarios for fragg_map_explore: a simulator scene, the sensor that explores it
// (the depth camera of W2 or the LiDAR of W1, config/workloads/*.args), the map resolution, the
// start pose, the box to explore and the frontier, cluster and viewpoint settings.
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>

#include "fragg_map/planning/frontier_clusters.h"
#include "fragg_map/planning/viewpoints.h"
#include "fragg_map/point_cloud.h"
#include "fragg_map/sensor_model.h"
#include "fragg_map/sim/depth_camera.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "fragg_map/sim/scene.h"

namespace fragg::geometry {
class MeshBvh;
}

namespace fragg::explore {

enum class ExploreSensor { kDepthCamera, kLidar };

struct Scenario {
  std::string name;
  sim::Scene scene;
  ExploreSensor sensor = ExploreSensor::kDepthCamera;
  sim::DepthCameraSpec depth;  ///< level camera (pitch and roll zero), yaw from the viewpoint
  sim::LidarSpec lidar;        ///< level LiDAR, yaw from the viewpoint
  uint64_t seed = 1;           ///< noise and dropout of the simulated sensor
  double resolution_m = 0.1;
  double integration_max_range_m = 10.0;  ///< sensor model max range for insertion
  Eigen::Vector3d start_m = Eigen::Vector3d::Zero();
  double start_yaw_rad = 0.0;
  /// The explored region: frontier cells outside it are ignored, and the explored volume is
  /// measured inside it (cell centres in [box_min_m, box_max_m]).
  Eigen::Vector3d box_min_m = Eigen::Vector3d::Zero(), box_max_m = Eigen::Vector3d::Zero();
  /// > 0: a ground robot; viewpoints are placed this far above the terrain under the cluster
  /// centroid. 0: a flying sensor; viewpoints at the centroid's height, clamped to
  /// [min_sensor_z_m, max_sensor_z_m].
  double ground_height_m = 0.0;
  double min_sensor_z_m = 0.0, max_sensor_z_m = 0.0;
  /// Radius of the sphere moved along a straight path to a viewpoint (checked against the
  /// known occupied cells).
  double robot_radius_m = 0.2;
  planning::ClusterOptions clusters;
  /// Rings (radii, angles), clearance and gain sensor of the candidates; the explorer sets the
  /// heights per cluster and keeps every candidate (top_k ignored); robot_m must stay unset.
  planning::ViewpointOptions viewpoints;

  /// Throws InvalidArgument naming the bad field (also checks the sensor and viewpoint options,
  /// a start pose outside the box, and an empty scene).
  void validate() const;
};

/// The pump room (config/scenes/pipes.json) with W2's depth camera (640 x 480, 70 deg, 10 m),
/// 10 cm cells, starting at W2's first pose.
Scenario pipesScenario(const std::string& scenes_dir);
/// The campus (config/scenes/campus.json) with W1's LiDAR (128 x 1406, -25..15 deg, integrated
/// to 30 m), 20 cm cells, a 80 x 60 m box around the street, a ground robot (1.8 m).
Scenario campusScenario(const std::string& scenes_dir);

/// The sensor's pose at a position and yaw (map frame; a depth camera's optical frame).
Eigen::Isometry3d sensorPose(const Scenario& s, const Eigen::Vector3d& position_m, double yaw_rad);
/// The sensor model the map integrates the scans with.
SensorModel integrationModel(const Scenario& s);
/// One simulated scan from the pose (frame = index, for the noise).
PointCloud simulateScan(const Scenario& s, const geometry::MeshBvh& scene,
                        const Eigen::Isometry3d& T_map_sensor, uint64_t frame);

}  // namespace fragg::explore
