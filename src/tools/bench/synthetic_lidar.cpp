#include "bench/synthetic_lidar.h"

#include <omp.h>

#include <cmath>
#include <limits>
#include <random>

namespace fragg::bench {

SyntheticLidar::SyntheticLidar(const SyntheticLidarOptions& options) : options_(options) {
  std::mt19937 rng(options.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  // Buildings on both sides of a 150 m street along x, trees along the kerbs.
  for (int i = 0; i < 24; ++i) {
    const double x0 = -75.0 + 150.0 * i / 12.0 * 0.5 + 2.0 * u(rng);
    const double side = i % 2 ? 1.0 : -1.0;
    const double y0 = side * (9.0 + 4.0 * u(rng));
    const double w = 6.0 + 6.0 * u(rng), d = 8.0 + 10.0 * u(rng), h = 6.0 + 14.0 * u(rng);
    const double ylo = side > 0 ? y0 : y0 - d;
    boxes_.push_back({{x0, ylo, 0.0}, {x0 + w, ylo + d, h}});
  }
  for (int i = 0; i < 40; ++i) {
    const double x = -75.0 + 150.0 * u(rng);
    const double y = (i % 2 ? 1.0 : -1.0) * (6.0 + 1.0 * u(rng));
    trees_.push_back({{x, y}, 0.2 + 0.2 * u(rng), 4.0 + 4.0 * u(rng)});
  }
}

double SyntheticLidar::castRay(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
  double best = std::numeric_limits<double>::infinity();
  if (d.z() < -1e-9) best = -o.z() / d.z();  // ground plane z = 0
  for (const Box& b : boxes_) {
    double t0 = 0.0, t1 = best;
    bool hit = true;
    for (int a = 0; a < 3 && hit; ++a) {
      if (std::fabs(d[a]) < 1e-12) {
        hit = o[a] >= b.lo[a] && o[a] <= b.hi[a];
        continue;
      }
      double ta = (b.lo[a] - o[a]) / d[a], tb = (b.hi[a] - o[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      hit = t0 <= t1;
    }
    if (hit && t0 > 0.0) best = std::min(best, t0);
  }
  for (const Cylinder& c : trees_) {
    const Eigen::Vector2d oc = o.head<2>() - c.centre;
    const Eigen::Vector2d dh = d.head<2>();
    const double a = dh.squaredNorm(), b = 2 * oc.dot(dh),
                 cc = oc.squaredNorm() - c.radius * c.radius;
    const double disc = b * b - 4 * a * cc;
    if (a < 1e-12 || disc < 0) continue;
    const double t = (-b - std::sqrt(disc)) / (2 * a);
    if (t > 0 && t < best && o.z() + t * d.z() <= c.height && o.z() + t * d.z() >= 0) best = t;
  }
  return best;
}

Scan SyntheticLidar::scan(int index) const {
  const SyntheticLidarOptions& o = options_;
  Scan s;
  const double x = -60.0 + o.step_m * index;
  const double yaw = 0.15 * std::sin(0.05 * index);
  s.T_map_sensor = Eigen::Isometry3d::Identity();
  s.T_map_sensor.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  s.T_map_sensor.translation() = Eigen::Vector3d(x, 0.3 * std::sin(0.1 * index), o.sensor_height_m);
  s.stamp_ns = int64_t{index} * 100000000;
  s.source = "synthetic";
  s.cloud.width = o.azimuth_steps;
  s.cloud.height = o.beams;
  s.cloud.points_S.resize(size_t{1} * o.beams * o.azimuth_steps);
  const Eigen::Matrix3d R = s.T_map_sensor.linear();
  const Eigen::Vector3d origin = s.T_map_sensor.translation();
  const float nan = std::numeric_limits<float>::quiet_NaN();
#pragma omp parallel for schedule(static)
  for (int r = 0; r < o.beams; ++r) {
    const double el =
        (o.elevation_min_deg + (o.elevation_max_deg - o.elevation_min_deg) * r / (o.beams - 1)) *
        M_PI / 180.0;
    for (int k = 0; k < o.azimuth_steps; ++k) {
      const double az = 2 * M_PI * k / o.azimuth_steps;
      const Eigen::Vector3d d_S(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                std::sin(el));
      const double t = castRay(origin, R * d_S);
      s.cloud.points_S[size_t{1} * r * o.azimuth_steps + k] =
          t <= o.max_return_m ? Eigen::Vector3f((d_S * t).cast<float>())
                              : Eigen::Vector3f(nan, nan, nan);
    }
  }
  return s;
}

}  // namespace fragg::bench
