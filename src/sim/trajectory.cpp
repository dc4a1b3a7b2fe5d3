#include "fragg_map/sim/trajectory.h"

#include <algorithm>
#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/sim/random.h"

namespace fragg::sim {
namespace {

constexpr uint64_t kStreamDrift = 0xd41f7;

// Arc-length parametrised polyline (positions only).
class Polyline {
 public:
  Polyline(std::vector<Eigen::Vector3d> points, bool closed) : p_(std::move(points)) {
    if (closed) p_.push_back(p_.front());
    s_.push_back(0.0);
    for (size_t i = 1; i < p_.size(); ++i) s_.push_back(s_.back() + (p_[i] - p_[i - 1]).norm());
  }
  double length() const { return s_.back(); }
  Eigen::Vector3d at(double s) const {
    s = std::clamp(s, 0.0, length());
    const size_t i = std::upper_bound(s_.begin(), s_.end(), s) - s_.begin();
    if (i >= p_.size()) return p_.back();
    const double seg = s_[i] - s_[i - 1];
    const double f = seg > 0 ? (s - s_[i - 1]) / seg : 0.0;
    return p_[i - 1] + f * (p_[i] - p_[i - 1]);
  }

 private:
  std::vector<Eigen::Vector3d> p_;
  std::vector<double> s_;
};

double yawOf(const Eigen::Isometry3d& T) { return std::atan2(T.linear()(1, 0), T.linear()(0, 0)); }

}  // namespace

std::vector<PoseSample> sampleTrajectory(const TrajectorySpec& spec,
                                         const std::function<double(double, double)>& ground_m,
                                         const DriftSpec& drift, uint64_t seed, size_t max_frames) {
  if (spec.waypoints_m.size() < 2)
    throw InvalidArgument("trajectory: needs at least two waypoints");
  if (!(spec.speed_mps > 0) || !(spec.rate_hz > 0))
    throw InvalidArgument("trajectory: speed and rate must be > 0");
  const Polyline path(spec.waypoints_m, spec.closed);
  const double step_m = spec.speed_mps / spec.rate_hz;
  size_t frames = static_cast<size_t>(std::floor(path.length() / step_m + 1e-9)) + 1;
  if (max_frames > 0) frames = std::min(frames, max_frames);
  const double w = std::max(spec.heading_window_m, 1e-3);

  // Odometry bias direction in the base xy plane, fixed per seed.
  const double bias_angle = 2.0 * M_PI * uniform01(randomKey(seed, kStreamDrift, ~0ULL));
  const Eigen::Vector3d bias(std::cos(bias_angle), std::sin(bias_angle), 0.0);

  std::vector<PoseSample> out;
  out.reserve(frames);
  for (size_t i = 0; i < frames; ++i) {
    const double s = i * step_m;
    Eigen::Vector3d p = path.at(s);
    const Eigen::Vector3d ahead = path.at(s + w) - path.at(s - w);
    const double yaw = std::atan2(ahead.y(), ahead.x());
    if (spec.follow_ground) p.z() += ground_m(p.x(), p.y());
    PoseSample sample;
    sample.stamp_s = i / spec.rate_hz;
    sample.T_map_base.translation() = p;
    sample.T_map_base.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).matrix();
    if (i == 0) {
      sample.T_odom_base = sample.T_map_base;
    } else {
      const PoseSample& prev = out.back();
      const Eigen::Isometry3d delta = prev.T_map_base.inverse() * sample.T_map_base;
      const double d = delta.translation().norm();
      const double a = std::abs(yawOf(delta));
      auto noise = [&](uint64_t k) { return gaussian(randomKey(seed, kStreamDrift, i * 8 + k)); };
      const Eigen::Vector3d t_err =
          drift.drift_m_per_m * d * (bias + 0.5 * Eigen::Vector3d(noise(0), noise(1), 0.0));
      const double yaw_err = drift.drift_rad_per_m * d * (1.0 + 0.5 * noise(2)) +
                             drift.drift_rad_per_rad * a * (1.0 + 0.5 * noise(3));
      Eigen::Isometry3d measured = delta;
      measured.translation() += t_err;
      measured.linear() = Eigen::AngleAxisd(yaw_err, Eigen::Vector3d::UnitZ()) * delta.linear();
      sample.T_odom_base = prev.T_odom_base * measured;
    }
    out.push_back(sample);
  }
  return out;
}

}  // namespace fragg::sim
