#include "fragg_map/internal/height_filter.h"

#include <cmath>

namespace fragg {

size_t filterHeight(const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                    const HeightFilterParams& band, PointCloud* out) {
  const Eigen::Vector3d row_z = T_map_sensor.linear().row(2).transpose();
  const double origin_z_m = T_map_sensor.translation().z();
  const bool organised = cloud.organised();
  out->width = cloud.width;
  out->height = cloud.height;
  out->points_S.clear();
  out->points_S.reserve(cloud.size());
  out->free_only.clear();
  const bool flags = cloud.hasFreeOnly();
  if (flags) out->free_only.reserve(cloud.size());
  size_t dropped = 0;
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p_S = cloud.points_S[i];
    const double z_m = row_z.dot(p_S.cast<double>()) + origin_z_m;
    const bool in_band = (z_m >= band.min_z_m && z_m <= band.max_z_m) || !std::isfinite(z_m);
    if (!in_band) ++dropped;
    if (!in_band && !organised) continue;
    out->points_S.push_back(in_band ? p_S : Eigen::Vector3f::Zero());
    if (flags) out->free_only.push_back(cloud.free_only[i]);
  }
  if (!organised) {
    out->width = cloud.width == 0 ? 0 : static_cast<uint32_t>(out->points_S.size());
    out->height = 1;
  }
  return dropped;
}

}  // namespace fragg
