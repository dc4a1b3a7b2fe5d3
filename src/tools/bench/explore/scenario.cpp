#include "bench/explore/scenario.h"

#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"

namespace fragg::explore {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

bool finite(const Eigen::Vector3d& v) { return v.allFinite(); }

}  // namespace

void Scenario::validate() const {
  if (scene.mesh.size() == 0) throw InvalidArgument("scenario " + name + ": the scene is empty");
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m))
    throw InvalidArgument("resolution_m must be finite and > 0");
  if (!(integration_max_range_m > 0.0) || !std::isfinite(integration_max_range_m))
    throw InvalidArgument("integration_max_range_m must be finite and > 0");
  if (!finite(box_min_m) || !finite(box_max_m) || (box_min_m.array() >= box_max_m.array()).any())
    throw InvalidArgument("box: finite, and min < max on every axis");
  if (!finite(start_m) || !std::isfinite(start_yaw_rad))
    throw InvalidArgument("start pose must be finite");
  if ((start_m.array() < box_min_m.array()).any() || (start_m.array() > box_max_m.array()).any())
    throw InvalidArgument("start position lies outside the box");
  if (!(ground_height_m >= 0.0) || !std::isfinite(ground_height_m))
    throw InvalidArgument("ground_height_m must be finite and >= 0");
  if (ground_height_m == 0.0 && (!std::isfinite(min_sensor_z_m) || !std::isfinite(max_sensor_z_m) ||
                                 min_sensor_z_m > max_sensor_z_m))
    throw InvalidArgument("sensor height band: finite, min <= max");
  if (!(robot_radius_m > 0.0) || !std::isfinite(robot_radius_m))
    throw InvalidArgument("robot_radius_m must be finite and > 0");
  if (viewpoints.robot_m) throw InvalidArgument("viewpoints.robot_m is set by the explorer");
  if (sensor == ExploreSensor::kDepthCamera)
    depth.validate();
  else
    lidar.validate();
  clusters.validate();
  viewpoints.validate();
}

Scenario pipesScenario(const std::string& scenes_dir) {
  Scenario s;
  s.name = "pipes";
  s.scene = sim::loadScene(scenes_dir + "/pipes.json");
  s.sensor = ExploreSensor::kDepthCamera;
  // W2 (config/workloads/w2_depth.args): 640 x 480, 70 deg, 10 m, noise 1 mm at 1 m, 1 % dropout.
  s.depth.width = 640;
  s.depth.height = 480;
  s.depth.hfov_deg = 70.0;
  s.depth.max_range_m = 10.0;
  s.depth.noise_m = 0.001;
  s.depth.dropout = 0.01;
  s.seed = 202;
  s.resolution_m = 0.1;
  s.integration_max_range_m = 10.0;
  s.start_m = Eigen::Vector3d(-8.0, -2.0, 1.8);  // W2's first pose (the survey trajectory)
  s.start_yaw_rad = 0.0;
  s.box_min_m = Eigen::Vector3d(-10.0, -10.0, 0.0);  // inside the walls, floor and ceiling
  s.box_max_m = Eigen::Vector3d(10.0, 10.0, 6.0);
  s.ground_height_m = 0.0;
  s.min_sensor_z_m = 0.5;
  s.max_sensor_z_m = 5.5;
  s.robot_radius_m = 0.2;
  s.clusters.min_cells = 20;
  s.clusters.max_extent_m = 4.0;
  s.viewpoints.radii_m = {1.5, 3.0};
  s.viewpoints.angles = 8;
  s.viewpoints.heights_m = {0.0};  // replaced per cluster
  s.viewpoints.clearance_m = 0.3;
  s.viewpoints.sensor.kind = planning::GainSensor::Kind::kPinhole;
  // A quarter of fragg_map frontiers' default rays: the gains of every cluster's candidates
  // are computed at every step.
  s.viewpoints.sensor.columns = 32;
  s.viewpoints.sensor.rows = 24;
  s.viewpoints.sensor.horizontal_fov_rad = 70.0 * kDegToRad;
  s.viewpoints.sensor.vertical_fov_rad = 2.0 * std::atan(std::tan(35.0 * kDegToRad) * 480 / 640);
  s.viewpoints.sensor.max_range_m = 10.0;
  return s;
}

Scenario campusScenario(const std::string& scenes_dir) {
  Scenario s;
  s.name = "campus";
  s.scene = sim::loadScene(scenes_dir + "/campus.json");
  s.sensor = ExploreSensor::kLidar;
  // W1 (config/workloads/w1_lidar360.args): 128 x 1406, -25..15 deg, 80 m, 2 cm noise.
  s.lidar.beams = 128;
  s.lidar.azimuth_steps = 1406;
  s.lidar.elevation_min_deg = -25.0;
  s.lidar.elevation_max_deg = 15.0;
  s.lidar.max_range_m = 80.0;
  s.lidar.range_noise_m = 0.02;
  s.lidar.dropout = 0.0;
  s.seed = 101;
  s.resolution_m = 0.2;
  s.integration_max_range_m = 30.0;
  s.ground_height_m = 1.8;                       // W1's LiDAR mount
  s.start_m = Eigen::Vector3d(-30.0, 0.0, 0.0);  // W1's first pose (the street)
  s.start_m.z() = s.scene.terrain.heightAt(-30.0, 0.0) + s.ground_height_m;
  s.start_yaw_rad = 0.0;
  s.box_min_m = Eigen::Vector3d(-40.0, -25.0, -1.5);
  s.box_max_m = Eigen::Vector3d(40.0, 35.0, 4.0);
  s.robot_radius_m = 0.4;
  s.clusters.min_cells = 20;
  s.clusters.max_extent_m = 6.0;
  s.viewpoints.radii_m = {2.0, 5.0};
  s.viewpoints.angles = 8;
  s.viewpoints.heights_m = {0.0};  // replaced per cluster
  s.viewpoints.clearance_m = 0.5;
  s.viewpoints.sensor.kind = planning::GainSensor::Kind::kLidar;
  s.viewpoints.sensor.columns = 60;
  s.viewpoints.sensor.rows = 12;
  s.viewpoints.sensor.min_elevation_rad = -25.0 * kDegToRad;
  s.viewpoints.sensor.max_elevation_rad = 15.0 * kDegToRad;
  s.viewpoints.sensor.max_range_m = 15.0;
  return s;
}

Eigen::Isometry3d sensorPose(const Scenario& s, const Eigen::Vector3d& position_m, double yaw_rad) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = position_m;
  Eigen::Matrix3d R = Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()).matrix();
  if (s.sensor == ExploreSensor::kDepthCamera) {
    Eigen::Matrix3d optical;  // columns: optical x (right), y (down), z (forward) in the body
    optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;
    R = R * optical;
  }
  T.linear() = R;
  return T;
}

SensorModel integrationModel(const Scenario& s) {
  if (s.sensor == ExploreSensor::kDepthCamera) {
    const double hfov = s.depth.hfov_deg * kDegToRad;
    const double vfov = 2.0 * std::atan(std::tan(hfov / 2) * s.depth.height / s.depth.width);
    return SensorModel::pinhole(hfov, vfov, s.depth.min_range_m, s.integration_max_range_m,
                                OpticalAxis::kZForward);
  }
  return SensorModel::spinningLidar(s.lidar.elevation_min_deg * kDegToRad,
                                    s.lidar.elevation_max_deg * kDegToRad, s.lidar.min_range_m,
                                    s.integration_max_range_m);
}

PointCloud simulateScan(const Scenario& s, const geometry::MeshBvh& scene,
                        const Eigen::Isometry3d& T_map_sensor, uint64_t frame) {
  return s.sensor == ExploreSensor::kDepthCamera
             ? sim::simulateDepthCamera(scene, s.depth, T_map_sensor, s.seed, frame)
             : sim::simulateLidar(scene, s.lidar, T_map_sensor, s.seed, frame);
}

}  // namespace fragg::explore
