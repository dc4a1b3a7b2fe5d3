// Inputs of the paging tests: a LiDAR driving down a corridor and back, far enough that a
// small RAM budget pages blocks out and the way back pages them in again.
#pragma once

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "../test_dir.h"
#include "fragg_map/map.h"
#include "fragg_map/page_store.h"

namespace fragg::test {

/// Ground z = 0, ceiling z = 3, walls at |y| = 4 (x in even metres) or 3.5 (odd metres).
inline double corridorHit(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double best = INFINITY;
  auto plane = [&](int axis, double at) -> double {
    if (std::fabs(d[axis]) < 1e-12) return INFINITY;
    const double t = (at - o[axis]) / d[axis];
    return t > 1e-9 ? t : INFINITY;
  };
  best = std::min(best, plane(2, 0.0));
  best = std::min(best, plane(2, 3.0));
  for (double side : {-1.0, 1.0})
    for (double wall : {4.0, 3.5}) {
      const double t = plane(1, side * wall);
      if (!std::isfinite(t)) continue;
      const int metre = static_cast<int>(std::floor(o.x() + t * d.x()));
      const bool even = (metre % 2 + 2) % 2 == 0;
      if (even == (wall == 4.0)) best = std::min(best, t);
    }
  return best;
}

/// Pose of scan i of n: down the corridor (x 0 -> 40 m) in the first half, back in the second.
inline Eigen::Isometry3d corridorPose(int i, int n) {
  const int half = n / 2;
  const double x = i < half ? 40.0 * i / (half - 1) : 40.0 * (n - 1 - i) / (n - half - 1) + 0.37;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, 0.3 * std::sin(0.4 * i), 1.2);
  T.linear() =
      Eigen::AngleAxisd(0.1 * std::sin(0.3 * i), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

/// A 16-ring LiDAR scan (sensor frame) from `T_map_sensor`; returns beyond 15 m are dropped.
/// Two points ahead of the sensor at `T_map_sensor` (map (3, 1, 1) and (3, -1, 1.2)): a scan
/// small enough for any budget the tests set.
inline PointCloud twoPointScan(const Eigen::Isometry3d& T_map_sensor) {
  PointCloud few;
  for (const Eigen::Vector3d& p_map :
       {Eigen::Vector3d(3.0, 1.0, 1.0), Eigen::Vector3d(3.0, -1.0, 1.2)})
    few.points_S.push_back((T_map_sensor.inverse() * p_map).cast<float>());
  few.width = 2;
  few.height = 1;
  return few;
}

inline PointCloud corridorScan(const Eigen::Isometry3d& T_map_sensor) {
  PointCloud cloud;
  for (int ring = 0; ring < 16; ++ring) {
    const double el = (-15.0 + 2.0 * ring) * M_PI / 180.0;
    for (int a = 0; a < 360; ++a) {
      const double az = a * M_PI / 180.0;
      const Eigen::Vector3d d_S(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                                std::sin(el));
      const double t = corridorHit(T_map_sensor.translation(), T_map_sensor.linear() * d_S);
      if (t <= 15.0) cloud.points_S.push_back((d_S * t).cast<float>());
    }
  }
  cloud.width = static_cast<uint32_t>(cloud.points_S.size());
  cloud.height = 1;
  return cloud;
}

/// A RAM budget of `mb` for the corridor, paging out from 4 m around the sensor, committing
/// every `commit_every_scans` scans (never by time: deterministic). 10 MB holds ~4,800 blocks of
/// the corridor map's 8,359 and one scan's reach (up to ~3,900 blocks on the CPU): blocks page
/// out on the way down and back in on the way back.
inline PagingPolicy corridorBudget(double mb, uint64_t commit_every_scans) {
  PagingPolicy p;
  p.budget_mb = mb;
  p.radius_m = 4.0;
  p.commit_every_scans = commit_every_scans;
  p.commit_every_s = 0;
  return p;
}

inline SensorModel corridorSensor() { return SensorModel::autoFromCloud(0.0, 15.0); }

inline MapParams corridorParams(Backend backend = Backend::kCpu) {
  MapParams p;
  p.resolution_m = 0.1;
  p.backend = backend;
  return p;
}

/// Every block's cells equal in both maps (compared over the resident blocks: call
/// ensureAllResident on a paged map first); `why` names the first difference.
inline bool sameBlocks(const Map& a, const Map& b, std::string* why) {
  if (a.blockCount() != b.blockCount()) {
    *why =
        "block counts " + std::to_string(a.blockCount()) + " vs " + std::to_string(b.blockCount());
    return false;
  }
  const BlockView vb = b.blockView();
  bool same = true;
  a.forEachBlock([&](const BlockKey& k, const Block& block) {
    if (!same) return;
    const Block* other = vb.findBlock(k);
    if (!other) {
      same = false;
      *why = "block missing";
      return;
    }
    for (int c = 0; c < kCellsPerBlock && same; ++c)
      if (block.cells[c].hits != other->cells[c].hits ||
          block.cells[c].log_odds_fx != other->cells[c].log_odds_fx) {
        same = false;
        *why = "block (" + std::to_string(k.x) + "," + std::to_string(k.y) + "," +
               std::to_string(k.z) + ") cell " + std::to_string(c) + " differs";
      }
  });
  return same;
}

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

inline void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream(path, std::ios::binary) << bytes;
}

}  // namespace fragg::test
