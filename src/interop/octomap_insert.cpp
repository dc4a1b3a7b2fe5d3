#include "fragg_map/interop/octomap_insert.h"

#include <chrono>

namespace fragg {

double insertIntoOcTree(octomap::OcTree& tree, const Scan& scan, double max_range_m) {
  octomap::Pointcloud pc;
  pc.reserve(scan.cloud.size());
  for (const Eigen::Vector3f& p : scan.cloud.points_S) {
    if (!p.allFinite() || p.squaredNorm() == 0.f) continue;
    const Eigen::Vector3d q = scan.T_map_sensor * p.cast<double>();
    pc.push_back(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
  }
  const Eigen::Vector3d o = scan.T_map_sensor.translation();
  const auto t0 = std::chrono::steady_clock::now();
  tree.insertPointCloud(pc, octomap::point3d(o.x(), o.y(), o.z()), max_range_m);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace fragg
