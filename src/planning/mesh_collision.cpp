#include "mesh_collision.h"

#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "collision_pose.h"
#include "fragg_map/geometry/cube_overlap.h"

namespace fragg::planning {

CollisionResult checkMeshPose(const Map& map, const ObstacleMasksView& masks,
                              const CollisionShape& shape, const Eigen::Isometry3d& T_map_shape,
                              const CollisionOptions& options) {
  const geometry::MeshBvh& bvh = *shape.meshBvh();
  const geometry::TriangleMesh& mesh = bvh.mesh();
  const Eigen::Matrix3d R = T_map_shape.linear();
  const Eigen::Vector3d t = T_map_shape.translation();
  std::vector<Eigen::Vector3d> vertices_map(mesh.vertices_m.size());
  Eigen::AlignedBox3d bounds_map;
  for (size_t i = 0; i < vertices_map.size(); ++i) {
    vertices_map[i] = transformPoint(R, t, mesh.vertices_m[i].cast<double>());
    bounds_map.extend(vertices_map[i]);
  }
  const double grow_m = options.margin_m;
  const VoxelKey lo = map.keyOf(bounds_map.min() - Eigen::Vector3d::Constant(grow_m));
  const VoxelKey hi = map.keyOf(bounds_map.max() + Eigen::Vector3d::Constant(grow_m));

  // Obstacle cells in scan order, and where each is in that list.
  std::vector<VoxelKey> cells;
  forEachObstacleCell(masks, lo, hi, [&](const VoxelKey& k) {
    cells.push_back(k);
    return false;
  });
  CollisionResult result;
  if (cells.empty()) return result;
  std::unordered_map<VoxelKey, uint32_t, VoxelKeyHash> index_of;
  index_of.reserve(cells.size());
  for (uint32_t i = 0; i < cells.size(); ++i) index_of.emplace(cells[i], i);

  // Cells a triangle cuts (the cube grown by the margin, shrunk by the touching epsilon).
  const double res_m = map.resolution();
  const double half_m = 0.5 * res_m + grow_m - kTouchEpsilon_m;
  std::vector<uint8_t> cut(cells.size(), 0);
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d &a = vertices_map[t[0]], &b = vertices_map[t[1]], &c = vertices_map[t[2]];
    const Eigen::Vector3d tri_lo = a.cwiseMin(b).cwiseMin(c) - Eigen::Vector3d::Constant(grow_m);
    const Eigen::Vector3d tri_hi = a.cwiseMax(b).cwiseMax(c) + Eigen::Vector3d::Constant(grow_m);
    const VoxelKey kl = map.keyOf(tri_lo), kh = map.keyOf(tri_hi);
    const auto test = [&](uint32_t i) {
      if (!cut[i] && geometry::triangleCubeOverlap(a, b, c, cellCentre(cells[i], res_m), half_m))
        cut[i] = 1;
    };
    const double range_cells =
        double(kh.x - kl.x + 1) * double(kh.y - kl.y + 1) * double(kh.z - kl.z + 1);
    if (range_cells > double(cells.size())) {  // large triangle: walk the obstacle list
      for (uint32_t i = 0; i < cells.size(); ++i) {
        const VoxelKey& k = cells[i];
        if (k.x >= kl.x && k.x <= kh.x && k.y >= kl.y && k.y <= kh.y && k.z >= kl.z && k.z <= kh.z)
          test(i);
      }
      continue;
    }
    for (int64_t z = kl.z; z <= kh.z; ++z)
      for (int64_t y = kl.y; y <= kh.y; ++y)
        for (int64_t x = kl.x; x <= kh.x; ++x) {
          const auto it = index_of.find(
              {static_cast<int32_t>(x), static_cast<int32_t>(y), static_cast<int32_t>(z)});
          if (it != index_of.end()) test(it->second);
        }
  }

  // A cell no triangle cuts is wholly inside or wholly outside: its centre decides.
  const Eigen::Isometry3d T_shape_map = T_map_shape.inverse();
  const Eigen::Matrix3d R_inv = T_shape_map.linear();
  const Eigen::Vector3d t_inv = T_shape_map.translation();
  for (uint32_t i = 0; i < cells.size(); ++i) {
    const bool collides =
        cut[i] ||
        (shape.meshClosed() &&
         bvh.inside(transformPoint(R_inv, t_inv, cellCentre(cells[i], res_m)).cast<float>()));
    if (!collides) continue;
    if (!result.collides) result.first_cell = cells[i];
    result.collides = true;
    ++result.colliding_cells;
    if (!options.count_cells) break;
  }
  return result;
}

}  // namespace fragg::planning
