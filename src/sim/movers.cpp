#include "fragg_map/sim/movers.h"

#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/sim/primitives.h"

namespace fragg::sim {
namespace {

double pauseAt(const MoverSpec& m, size_t i) {
  if (m.pause_s.empty()) return 0.0;
  return m.pause_s.size() == 1 ? m.pause_s[0] : m.pause_s[i];
}

// The waypoints one cycle visits, in order: the path, then back (ping-pong) or to the start
// (loop). Each entry is a waypoint index.
std::vector<size_t> cycleOf(const MoverSpec& m) {
  std::vector<size_t> order;
  const size_t n = m.waypoints_m.size();
  for (size_t i = 0; i < n; ++i) order.push_back(i);
  if (m.repeat == MoverRepeat::kPingPong)
    for (size_t i = n - 1; i-- > 0;) order.push_back(i);
  else if (m.repeat == MoverRepeat::kLoop)
    order.push_back(0);
  return order;
}

}  // namespace

MoverKind moverKindFromString(const std::string& s) {
  if (s == "pedestrian") return MoverKind::kPedestrian;
  if (s == "car") return MoverKind::kCar;
  if (s == "door") return MoverKind::kDoor;
  if (s == "box") return MoverKind::kBox;
  throw InvalidArgument("unknown mover type '" + s + "' (pedestrian, car, door, box)");
}

void MoverSpec::validate() const {
  if (!(size_m.minCoeff() > 0) || !size_m.allFinite())
    throw InvalidArgument("mover '" + name + "': size must be three positive numbers");
  if (kind == MoverKind::kDoor) {
    if (!(period_s > 0) || !std::isfinite(period_s))
      throw InvalidArgument("mover '" + name + "': period must be > 0 s");
    return;
  }
  if (waypoints_m.size() < 2)
    throw InvalidArgument("mover '" + name + "': needs at least two waypoints");
  if (!(speed_mps > 0) || !std::isfinite(speed_mps))
    throw InvalidArgument("mover '" + name + "': speed must be > 0 m/s");
  if (!pause_s.empty() && pause_s.size() != 1 && pause_s.size() != waypoints_m.size())
    throw InvalidArgument("mover '" + name + "': pause takes one value or one a waypoint");
  for (double p : pause_s)
    if (!(p >= 0) || !std::isfinite(p))
      throw InvalidArgument("mover '" + name + "': pauses must be >= 0 s");
  for (size_t i = 1; i < waypoints_m.size(); ++i)
    if ((waypoints_m[i] - waypoints_m[i - 1]).norm() <= 0)
      throw InvalidArgument("mover '" + name + "': consecutive waypoints must differ");
}

void MoverSpec::poseAt(double t_s, Eigen::Vector2d* xy_m, double* yaw_rad) const {
  const double t = std::max(0.0, t_s - start_s);
  if (kind == MoverKind::kDoor) {
    // Closed -> open over the first half period, back over the second (a triangle wave).
    const double phase = std::fmod(t, period_s) / period_s;
    const double open = phase < 0.5 ? 2 * phase : 2 * (1 - phase);
    *xy_m = hinge_m;
    *yaw_rad = (closed_yaw_deg + (open_yaw_deg - closed_yaw_deg) * open) * M_PI / 180.0;
    return;
  }
  const std::vector<size_t> order = cycleOf(*this);
  // One cycle: for each leg, the pause at its start waypoint, then the drive.
  double cycle_s = 0.0;
  for (size_t k = 0; k + 1 < order.size(); ++k)
    cycle_s += pauseAt(*this, order[k]) +
               (waypoints_m[order[k + 1]] - waypoints_m[order[k]]).norm() / speed_mps;
  double left = t;
  if (repeat != MoverRepeat::kOnce) left = std::fmod(t, cycle_s);
  for (size_t k = 0; k + 1 < order.size(); ++k) {
    const Eigen::Vector2d a = waypoints_m[order[k]], b = waypoints_m[order[k + 1]];
    const double leg_s = (b - a).norm() / speed_mps;
    *yaw_rad = std::atan2(b.y() - a.y(), b.x() - a.x());
    const double pause = pauseAt(*this, order[k]);
    if (left < pause) {
      *xy_m = a;
      return;
    }
    left -= pause;
    if (left < leg_s) {
      *xy_m = a + (b - a) * (left / leg_s);
      return;
    }
    left -= leg_s;
  }
  *xy_m = waypoints_m[order.back()];  // kOnce: stays at the end
}

geometry::TriangleMesh moversMeshAt(const std::vector<MoverSpec>& movers, double t_s,
                                    const std::function<double(double, double)>& ground_m) {
  geometry::TriangleMesh mesh;
  for (const MoverSpec& m : movers) {
    Eigen::Vector2d xy;
    double yaw = 0;
    m.poseAt(t_s, &xy, &yaw);
    const Eigen::Vector3d half = 0.5 * m.size_m;
    Eigen::Vector2d centre = xy;
    if (m.kind == MoverKind::kDoor)  // the panel reaches from the hinge along its yaw
      centre += half.x() * Eigen::Vector2d(std::cos(yaw), std::sin(yaw));
    const double z0 = ground_m(centre.x(), centre.y());
    // A little clearance above the ground (doors swing over their sill).
    const double lift = m.kind == MoverKind::kDoor ? 0.02 : 0.0;
    mesh.append(
        makeOrientedBox(Eigen::Vector3d(centre.x(), centre.y(), z0 + lift + half.z()), half, yaw));
  }
  return mesh;
}

}  // namespace fragg::sim
