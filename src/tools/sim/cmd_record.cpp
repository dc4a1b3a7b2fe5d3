// fragg_map_sim record SCENE.json: drives a sensor along one of the scene's trajectories and
// writes what it sees (KITTI-style folder, depth-image folder, ROS bag, scene OBJ).
#include <fmt/format.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/geometry/obj_file.h"
#include "fragg_map/sim/dataset_writers.h"
#include "fragg_map/sim/depth_camera.h"
#include "fragg_map/sim/lidar_sensor.h"
#include "fragg_map/sim/movers.h"
#include "fragg_map/sim/scene.h"
#include "sim/commands.h"
#ifdef FRAGG_HAVE_SIM_BAG
#include "fragg_map/sim/bag_writer.h"
#endif

namespace fragg::sim::tool {
namespace {

struct RecordOptions {
  std::string scene, trajectory, sensor = "lidar";
  uint64_t seed = 1;
  size_t frames = 0;
  LidarSpec lidar;
  DepthCameraSpec depth;
  DriftSpec drift;
  std::vector<double> mount;  // x y z in base_link
  double mount_pitch_deg = 0;
  std::string kitti, depth_folder, bag, obj;
  bool organised = false;
  double speed = 0, rate = 0;
};

// base_link -> sensor. A depth camera's frame is the optical frame (z forward, x right, y down).
Eigen::Isometry3d mountOf(const RecordOptions& o, bool lidar) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  if (!o.mount.empty()) {
    T.translation() = Eigen::Vector3d(o.mount[0], o.mount[1], o.mount[2]);
  } else if (lidar) {
    T.translation() = Eigen::Vector3d(0, 0, 1.8);
  }
  const Eigen::Matrix3d pitch =
      Eigen::AngleAxisd(o.mount_pitch_deg * M_PI / 180.0, Eigen::Vector3d::UnitY()).matrix();
  Eigen::Matrix3d optical = Eigen::Matrix3d::Identity();
  if (!lidar) optical << 0, 0, 1, -1, 0, 0, 0, -1, 0;  // columns: optical x, y, z in base
  T.linear() = pitch * optical;
  return T;
}

void runRecord(const RecordOptions& o) {
  const bool lidar = o.sensor == "lidar";
  if (!lidar && o.sensor != "depth")
    throw InvalidArgument("--sensor must be lidar or depth, not '" + o.sensor + "'");
  if (o.mount.size() != 0 && o.mount.size() != 3)
    throw InvalidArgument("--mount takes three numbers (x y z in base_link)");
  if (lidar)
    o.lidar.validate();
  else
    o.depth.validate();
  if (!lidar && !o.kitti.empty())
    throw InvalidArgument("--kitti is for the LiDAR; a depth camera writes --depth-folder");
  if (lidar && !o.depth_folder.empty())
    throw InvalidArgument("--depth-folder is for the depth camera; a LiDAR writes --kitti");
#ifndef FRAGG_HAVE_SIM_BAG
  if (!o.bag.empty())
    throw InvalidArgument("--bag: this fragg_map_sim was built without ROS (no bag writer)");
#endif
  if (o.kitti.empty() && o.depth_folder.empty() && o.bag.empty() && o.obj.empty())
    throw InvalidArgument("nothing to write: give --kitti, --depth-folder, --bag or --obj");

  Scene scene = loadScene(o.scene);
  const auto found = scene.trajectories.find(o.trajectory);
  if (found == scene.trajectories.end()) {
    std::string names;
    for (const auto& [name, spec] : scene.trajectories) names += " " + name;
    throw InvalidArgument("scene " + scene.name + " has no trajectory '" + o.trajectory +
                          "' (it has:" + (names.empty() ? " none" : names) + ")");
  }
  TrajectorySpec spec = found->second;
  if (o.speed > 0) spec.speed_mps = o.speed;
  if (o.rate > 0) spec.rate_hz = o.rate;
  const Terrain terrain = scene.terrain;
  const std::vector<PoseSample> poses = sampleTrajectory(
      spec, [&terrain](double x, double y) { return terrain.heightAt(x, y); }, o.drift, o.seed,
      o.frames);
  if (!o.obj.empty()) geometry::writeObj(scene.mesh, o.obj);  // the static truth
  const std::vector<MoverSpec> movers = scene.movers;
  const geometry::MeshBvh bvh(std::move(scene.mesh));
  const Eigen::Isometry3d T_base_sensor = mountOf(o, lidar);

  std::optional<KittiFolderWriter> kitti;
  std::optional<DepthFolderWriter> depth;
  if (!o.kitti.empty()) kitti.emplace(o.kitti, o.organised);
  if (!o.depth_folder.empty()) depth.emplace(o.depth_folder, o.depth.intrinsics());
#ifdef FRAGG_HAVE_SIM_BAG
  std::unique_ptr<SimBagWriter> bag;
  if (!o.bag.empty()) {
    BagNames names;
    names.sensor_frame = lidar ? "lidar" : "camera_depth_optical_frame";
    bag = std::make_unique<SimBagWriter>(o.bag, names, T_base_sensor, lidar);
  }
#endif
  double cast_s = 0;
  size_t points = 0, returns = 0, dynamic_returns = 0;
  std::vector<uint8_t> labels;
  for (size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Isometry3d T_map_sensor = poses[i].T_map_base * T_base_sensor;
    const Eigen::Isometry3d T_odom_sensor = poses[i].T_odom_base * T_base_sensor;
    const auto t0 = std::chrono::steady_clock::now();
    // The movers where they are at this frame's time (labels only for scenes with movers).
    std::optional<geometry::MeshBvh> mover_bvh;
    if (!movers.empty())
      mover_bvh.emplace(moversMeshAt(movers, poses[i].stamp_s, [&terrain](double x, double y) {
        return terrain.heightAt(x, y);
      }));
    const geometry::MeshBvh* mv = mover_bvh ? &*mover_bvh : nullptr;
    std::vector<uint8_t>* lb = mv ? &labels : nullptr;
    const PointCloud cloud =
        lidar ? simulateLidar(bvh, o.lidar, T_map_sensor, o.seed, i, mv, lb)
              : simulateDepthCamera(bvh, o.depth, T_map_sensor, o.seed, i, mv, lb);
    cast_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    points += cloud.size();
    for (const Eigen::Vector3f& p : cloud.points_S) returns += p.allFinite();
    if (lb)
      for (uint8_t l : labels) dynamic_returns += l;
    if (kitti) kitti->add(cloud, T_map_sensor, T_odom_sensor, poses[i].stamp_s, lb);
    if (depth) depth->add(cloud, T_map_sensor, T_odom_sensor, poses[i].stamp_s, lb);
#ifdef FRAGG_HAVE_SIM_BAG
    if (bag) bag->add(cloud, poses[i]);
#endif
  }
  if (kitti) kitti->finish();
  if (depth) depth->finish();
#ifdef FRAGG_HAVE_SIM_BAG
  if (bag) bag->finish();
#endif
  const size_t n = poses.size();
  std::printf("%s", fmt::format("{} / {}: {} frames of {} points ({:.1f} % returns), ray casting "
                                "{:.1f} ms/frame on {} triangles\n",
                                o.scene, o.trajectory, n, n ? points / n : 0,
                                points ? 100.0 * returns / points : 0.0, n ? 1e3 * cast_s / n : 0.0,
                                bvh.mesh().size())
                        .c_str());
  if (!movers.empty())
    std::printf("%s", fmt::format("{} movers: {} dynamic returns ({:.2f} % of the returns), "
                                  "labels in labels/*.dyn\n",
                                  movers.size(), dynamic_returns,
                                  returns ? 100.0 * dynamic_returns / returns : 0.0)
                          .c_str());
}

}  // namespace

void addRecordCommand(CLI::App& app) {
  auto o = std::make_shared<RecordOptions>();
  CLI::App* c = app.add_subcommand(
      "record", "Drive a sensor along a scene trajectory and write what it sees");
  c->add_option("scene", o->scene, "Scene file (JSON)")->required();
  c->add_option("--trajectory", o->trajectory, "Trajectory name in the scene file")->required();
  c->add_option("--sensor", o->sensor, "lidar | depth")->capture_default_str();
  c->add_option("--seed", o->seed, "Noise, dropout and drift seed")->capture_default_str();
  c->add_option("--frames", o->frames, "At most this many frames (0 = the whole trajectory)")
      ->capture_default_str();
  c->add_option("--speed", o->speed, "Override the trajectory's speed (m/s)");
  c->add_option("--rate", o->rate, "Override the trajectory's frame rate (Hz)");
  // LiDAR
  c->add_option("--beams", o->lidar.beams, "LiDAR beams (16, 32, 64, 128...)")
      ->capture_default_str();
  c->add_option("--azimuth-steps", o->lidar.azimuth_steps, "LiDAR columns per revolution")
      ->capture_default_str();
  c->add_option("--elevation-min", o->lidar.elevation_min_deg, "Lowest beam (deg)")
      ->capture_default_str();
  c->add_option("--elevation-max", o->lidar.elevation_max_deg, "Highest beam (deg)")
      ->capture_default_str();
  c->add_option("--lidar-max-range", o->lidar.max_range_m, "No return beyond this (m)")
      ->capture_default_str();
  c->add_option("--range-noise", o->lidar.range_noise_m, "LiDAR range noise std (m)")
      ->capture_default_str();
  c->add_option("--lidar-dropout", o->lidar.dropout, "Probability of a lost LiDAR return")
      ->capture_default_str();
  // Depth camera
  c->add_option("--width", o->depth.width, "Depth image width")->capture_default_str();
  c->add_option("--height", o->depth.height, "Depth image height")->capture_default_str();
  c->add_option("--hfov", o->depth.hfov_deg, "Horizontal field of view (deg)")
      ->capture_default_str();
  c->add_option("--depth-max-range", o->depth.max_range_m, "No return beyond this depth (m)")
      ->capture_default_str();
  c->add_option("--depth-noise", o->depth.noise_m, "Depth noise std at 1 m (grows with z^2)")
      ->capture_default_str();
  c->add_option("--depth-dropout", o->depth.dropout, "Probability of a lost pixel")
      ->capture_default_str();
  // Mount and odometry
  c->add_option("--mount", o->mount,
                "Sensor position in base_link: x y z (default LiDAR 0 0 "
                "1.8, camera 0 0 0)")
      ->expected(3);
  c->add_option("--mount-pitch", o->mount_pitch_deg, "Sensor pitch, positive looks down (deg)")
      ->capture_default_str();
  c->add_option("--drift-m-per-m", o->drift.drift_m_per_m,
                "Odometry translation error per metre travelled")
      ->capture_default_str();
  c->add_option("--drift-rad-per-m", o->drift.drift_rad_per_m,
                "Odometry heading error per metre travelled")
      ->capture_default_str();
  c->add_option("--drift-rad-per-rad", o->drift.drift_rad_per_rad,
                "Odometry heading error per radian turned")
      ->capture_default_str();
  // Outputs
  c->add_option("--kitti", o->kitti,
                "LiDAR: KITTI-style folder (velodyne/*.bin, poses.txt = ground truth, "
                "poses_odom.txt, calib.txt, times.txt)");
  c->add_flag("--organised", o->organised,
              "With --kitti: also organised/*.pcd (NaN = no return) + TUM poses.txt");
  c->add_option("--depth-folder", o->depth_folder,
                "Depth camera: depth/*.pgm (mm), pose.txt (ground truth), pose_odom.txt, "
                "intrinsics.txt");
  c->add_option("--bag", o->bag,
                "ROS bag: PointCloud2, /tf (map->odom->base_link, drifting odometry), "
                "/tf_static, ground-truth pose and path (ROS builds only)");
  c->add_option("--obj", o->obj, "Also write the scene's ground truth as OBJ");
  c->callback([o] { runRecord(*o); });
}

}  // namespace fragg::sim::tool
