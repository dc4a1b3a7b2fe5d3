// Moving objects of a simulated scene (pedestrians, cars, doors) on scripted paths. They are
// not part of the scene's static mesh (Scene::mesh, the static ground truth): each frame the
// simulator builds their mesh at the frame's time and casts rays against both, labelling a
// return dynamic when a mover is the nearer surface. Deterministic: a mover's pose depends only
// on its spec and the time.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <string>
#include <vector>

#include "fragg_map/geometry/triangle_mesh.h"

namespace fragg::sim {

enum class MoverKind { kPedestrian, kCar, kDoor, kBox };

/// What a mover does after its last waypoint.
enum class MoverRepeat {
  kPingPong,  ///< walk the path back, then forth again (default)
  kLoop,      ///< drive back to the first waypoint and round again
  kOnce,      ///< stay at the last waypoint
};

struct MoverSpec {
  std::string name;
  MoverKind kind = MoverKind::kPedestrian;
  /// Box size: length (along the heading) x width x height, metres. Defaults by kind:
  /// pedestrian 0.5 x 0.5 x 1.75, car 4.5 x 1.8 x 1.5, door 1.0 (width) x 0.08 x 2.1.
  Eigen::Vector3d size_m = Eigen::Vector3d(0.5, 0.5, 1.75);
  // Path movers (pedestrian, car, box): waypoints in the map's xy plane, on the ground.
  std::vector<Eigen::Vector2d> waypoints_m;
  double speed_mps = 1.4;
  /// Seconds the mover stands at each waypoint (one value, or one a waypoint); > 0 makes a
  /// mover "stop for a while" in front of the sensor.
  std::vector<double> pause_s;
  double start_s = 0.0;  ///< waits at the first waypoint until then
  MoverRepeat repeat = MoverRepeat::kPingPong;
  // Doors: a panel of size_m hinged at `hinge_m` (xy, on the ground), swinging between
  // closed_yaw_deg and open_yaw_deg and back every period_s (closed at t = start_s).
  Eigen::Vector2d hinge_m = Eigen::Vector2d::Zero();
  double closed_yaw_deg = 0.0;
  double open_yaw_deg = 90.0;
  double period_s = 8.0;

  /// Throws InvalidArgument naming the bad field.
  void validate() const;
  /// Pose at time t_s: the position of its centre in the xy plane and its heading (rad). For
  /// a door: the hinge and the panel's yaw.
  void poseAt(double t_s, Eigen::Vector2d* xy_m, double* yaw_rad) const;
};

/// The closed solids of every mover at time t_s, standing on the ground `ground_m(x, y)`.
geometry::TriangleMesh moversMeshAt(const std::vector<MoverSpec>& movers, double t_s,
                                    const std::function<double(double, double)>& ground_m);

/// "pedestrian" | "car" | "door" | "box"; throws InvalidArgument otherwise.
MoverKind moverKindFromString(const std::string& s);

}  // namespace fragg::sim
