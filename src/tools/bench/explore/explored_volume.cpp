#include "bench/explore/explored_volume.h"

#include <omp.h>

#include <cmath>

#include "fragg_map/errors.h"
#include "fragg_map/internal/thread_count.h"

namespace fragg::explore {
namespace {

/// First key whose cell centre ((k + 0.5) res) is >= v, and last key whose centre is <= v.
int32_t firstKeyAtOrAbove(double v_m, double res_m) {
  return static_cast<int32_t>(std::ceil(v_m / res_m - 0.5));
}
int32_t lastKeyAtOrBelow(double v_m, double res_m) {
  return static_cast<int32_t>(std::floor(v_m / res_m - 0.5));
}

}  // namespace

ExploredVolume::ExploredVolume(const geometry::MeshBvh& scene, const Eigen::Vector3d& box_min_m,
                               const Eigen::Vector3d& box_max_m, double resolution_m, int threads)
    : resolution_m_(resolution_m), cell_m3_(resolution_m * resolution_m * resolution_m) {
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m))
    throw InvalidArgument("explored volume: resolution must be finite and > 0");
  if (!box_min_m.allFinite() || !box_max_m.allFinite() ||
      (box_min_m.array() >= box_max_m.array()).any())
    throw InvalidArgument("explored volume: box must be finite with min < max");
  lo_ = {firstKeyAtOrAbove(box_min_m.x(), resolution_m),
         firstKeyAtOrAbove(box_min_m.y(), resolution_m),
         firstKeyAtOrAbove(box_min_m.z(), resolution_m)};
  hi_ = {lastKeyAtOrBelow(box_max_m.x(), resolution_m),
         lastKeyAtOrBelow(box_max_m.y(), resolution_m),
         lastKeyAtOrBelow(box_max_m.z(), resolution_m)};
  nx_ = int64_t{hi_.x} - lo_.x + 1;
  ny_ = int64_t{hi_.y} - lo_.y + 1;
  nz_ = int64_t{hi_.z} - lo_.z + 1;
  if (nx_ <= 0 || ny_ <= 0 || nz_ <= 0)
    throw InvalidArgument("explored volume: the box holds no cell centre");
  const int64_t n = nx_ * ny_ * nz_;
  std::vector<uint8_t> outside(static_cast<size_t>(n), 0);
  const int n_threads = threadCount(threads);
#pragma omp parallel for schedule(dynamic, 4096) num_threads(n_threads)
  for (int64_t i = 0; i < n; ++i) {
    const int64_t x = i % nx_, y = (i / nx_) % ny_, z = i / (nx_ * ny_);
    const Eigen::Vector3f p(float((lo_.x + x + 0.5) * resolution_m),
                            float((lo_.y + y + 0.5) * resolution_m),
                            float((lo_.z + z + 0.5) * resolution_m));
    outside[size_t(i)] = scene.inside(p) ? 0 : 1;
  }
  reference_.assign(static_cast<size_t>(n), 0);
  uint64_t count = 0;
  for (int64_t i = 0; i < n; ++i) {
    uint8_t ref = outside[size_t(i)];
    if (!ref) {
      const int64_t x = i % nx_, y = (i / nx_) % ny_, z = i / (nx_ * ny_);
      const int64_t step[3] = {1, nx_, nx_ * ny_};
      const int64_t pos[3] = {x, y, z}, len[3] = {nx_, ny_, nz_};
      for (int a = 0; a < 3 && !ref; ++a) {
        if (pos[a] > 0 && outside[size_t(i - step[a])]) ref = 1;
        if (pos[a] + 1 < len[a] && outside[size_t(i + step[a])]) ref = 1;
      }
    }
    reference_[size_t(i)] = ref;
    count += ref;
  }
  reference_cells_ = count;
}

int64_t ExploredVolume::indexOf(const VoxelKey& k) const {
  if (k.x < lo_.x || k.y < lo_.y || k.z < lo_.z || k.x > hi_.x || k.y > hi_.y || k.z > hi_.z)
    return -1;
  return (int64_t{k.x} - lo_.x) + nx_ * ((int64_t{k.y} - lo_.y) + ny_ * (int64_t{k.z} - lo_.z));
}

uint64_t ExploredVolume::knownReferenceCells(const Map& map) const {
  if (std::abs(map.resolution() - resolution_m_) > 1e-12)
    throw InvalidArgument("explored volume: the map's resolution differs from the reference's");
  uint64_t known = 0;
  const BlockKey blo = blockKeyOf(lo_), bhi = blockKeyOf(hi_);
  map.forEachBlockIn(blo, bhi, [&](const BlockKey& b, const Block& block) {
    for (int c = 0; c < kCellsPerBlock; ++c) {
      const Cell& cell = block.cells[c];
      if (!cell.observed() || map.state(cell) == CellState::kUnknown) continue;
      const int64_t i = indexOf(voxelKeyOf(b, c));
      if (i >= 0 && reference_[size_t(i)]) ++known;
    }
  });
  return known;
}

}  // namespace fragg::explore
