// Information gain along one ray (internal; shared by the CPU gain code in fragg_map_planning
// and the CUDA gain kernel, FRAGG_HD, so both walk the same cells): the walk on the insertion's
// DDA (raycast.h), the yaw rotation of a sensor ray, and the entropy a cell adds. A batch of
// viewpoints as a backend gets it (MapBackend::viewpointGains).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "fragg_map/cell.h"
#include "fragg_map/hd.h"
#include "fragg_map/key.h"
#include "fragg_map/occupancy.h"
#include "fragg_map/raycast.h"

namespace fragg {

/// Viewpoints sharing one sensor: origin i is (origins_v[3i], [3i+1], [3i+2]) in voxel units
/// (position / resolution), its yaw as cos/sin; rays are unit directions in the sensor frame
/// (x forward, z up), 3 doubles each; every ray runs for length_v voxels.
struct GainBatch {
  std::vector<double> origins_v, cos_yaw, sin_yaw, rays_sensor;
  double length_v = 0.0;
  size_t viewpoints() const { return cos_yaw.size(); }
  size_t rays() const { return rays_sensor.size() / 3; }
};

/// Ray `in` turned by the yaw (about z), in the map frame. Plain products and sums (no FMA in
/// either build), so the host and the device get the same bits.
FRAGG_HD void yawRotate(double c, double s, const double* in, double* out) {
  out[0] = c * in[0] - s * in[1];
  out[1] = s * in[0] + c * in[1];
  out[2] = in[2];
}

/// Entropy (bits) a cell adds to a gain: 1 for never observed (or a missing block), H(p)
/// inside the unknown band, 0 for free and occupied cells.
FRAGG_HD double cellGainBits(const OccupancyModel& model, const Cell* cell) {
  if (!cell || !cell->observed()) return 1.0;
  if (model.state(*cell) != CellState::kUnknown) return 0.0;
  const double p = 1.0 - 1.0 / (1.0 + exp(static_cast<double>(cell->log_odds_fx) / kLogOddsScale));
  if (p <= 0.0 || p >= 1.0) return 0.0;
  return -(p * log2(p) + (1.0 - p) * log2(1.0 - p));
}

/// One ray's walk on the insertion's traversal (raycast.h's DdaAxis and ddaStep: float voxel
/// units relative to the start's cell, ties to the later axis, the step counts fixed up front),
/// from the cell of `start_v` to the cell of `end_v` (voxel units, the map frame), both
/// visited. cell() is the current cell; next() steps to the following one and returns its
/// entry code (kSameBlock, or the block face crossed); done() says the end cell is reached.
struct GainWalk {
  DdaAxis x, y, z;

  /// No ray yet (a lane of the queued CUDA kernels before it takes one).
  GainWalk() = default;
  FRAGG_HD GainWalk(const double* start_v, const double* end_v) {
    int ref[3];
    float s[3], e[3];
    for (int a = 0; a < 3; ++a) {
      ref[a] = static_cast<int>(floor(start_v[a]));
      s[a] = static_cast<float>(start_v[a] - ref[a]);
      e[a] = static_cast<float>(end_v[a] - ref[a]);
    }
    x.init(ref[0], s[0], e[0]);
    y.init(ref[1], s[1], e[1]);
    z.init(ref[2], s[2], e[2]);
  }
  /// A ray of `length_v` voxels from `origin_v` along unit `dir`.
  FRAGG_HD static GainWalk along(const double* origin_v, const double* dir, double length_v) {
    const double end_v[3] = {origin_v[0] + length_v * dir[0], origin_v[1] + length_v * dir[1],
                             origin_v[2] + length_v * dir[2]};
    return GainWalk(origin_v, end_v);
  }
  [[nodiscard]] FRAGG_HD VoxelKey cell() const { return VoxelKey{x.cur, y.cur, z.cur}; }
  [[nodiscard]] FRAGG_HD bool done() const {
    return x.remaining == 0 && y.remaining == 0 && z.remaining == 0;
  }
  FRAGG_HD int next() { return ddaStep(x, y, z); }
};

/// The pooled gain kernels' directory of one viewpoint: an entry for every map block that its
/// box of cells (the voxel keys lo + [0, dims), dims >= 1) touches, from blockKeyOf(lo) to
/// blockKeyOf(lo + dims - 1), x fastest. The host sizes the directories by entries() and the
/// device looks blocks up by indexOf(), so the two agree by construction.
struct PoolDirectory {
  int32_t first[3];   ///< the box's lowest block key
  int32_t blocks[3];  ///< blocks along each axis (>= 1)

  /// The directory over the box lo[0..2] + [0, dims[0..2]).
  FRAGG_HD static PoolDirectory over(const int32_t* lo, const int32_t* dims) {
    PoolDirectory d;
    for (int a = 0; a < 3; ++a) {
      // 64-bit: lo + dims - 1 may pass int32 for a box at the key range's edge.
      const int64_t top = int64_t(lo[a]) + dims[a] - 1;
      d.first[a] = lo[a] >> kBlockBits;
      d.blocks[a] = static_cast<int32_t>((top >> kBlockBits) - d.first[a] + 1);
    }
    return d;
  }
  /// Entries of the directory (4 bytes each on the device).
  [[nodiscard]] FRAGG_HD uint64_t entries() const {
    return uint64_t(blocks[0]) * uint64_t(blocks[1]) * uint64_t(blocks[2]);
  }
  /// The entry of block `b`, -1 when b lies outside the box's blocks.
  [[nodiscard]] FRAGG_HD int64_t indexOf(const BlockKey& b) const {
    const int64_t i[3] = {int64_t(b.x) - first[0], int64_t(b.y) - first[1],
                          int64_t(b.z) - first[2]};
    for (int a = 0; a < 3; ++a)
      if (i[a] < 0 || i[a] >= blocks[a]) return -1;
    return (i[2] * blocks[1] + i[1]) * blocks[0] + i[0];
  }
};

/// A pooled directory entry: no bitmap yet (kPoolEmpty, what a cleared directory holds), being
/// taken by another lane (kPoolBusy), the pool ran out (kPoolOverflow), else the bitmap's index
/// in the pool + 1.
constexpr uint32_t kPoolEmpty = 0u;
constexpr uint32_t kPoolBusy = 0xffffffffu;
constexpr uint32_t kPoolOverflow = 0xfffffffeu;
/// The most bitmaps a pool may hold: every index + 1 stays below kPoolOverflow.
constexpr uint64_t kPoolMaxBlocks = uint64_t(1) << 31;

/// The entry the lane that took a directory entry publishes: the pool's `taken`-th bitmap
/// (the counter's old value) + 1, or kPoolOverflow when the pool of `pool_blocks` has no such
/// bitmap.
[[nodiscard]] FRAGG_HD uint32_t poolEntryOf(uint32_t taken, uint32_t pool_blocks) {
  return taken < pool_blocks ? taken + 1u : kPoolOverflow;
}

/// The pool bitmap a published entry names, -1 for one naming none (kPoolEmpty, kPoolBusy,
/// kPoolOverflow: a reader must wait out kPoolBusy before asking).
[[nodiscard]] FRAGG_HD int64_t poolBitmapOf(uint32_t entry) {
  if (entry == kPoolEmpty || entry == kPoolBusy || entry == kPoolOverflow) return -1;
  return int64_t(entry) - 1;
}

}  // namespace fragg
