// The dynamic-scene rule's tests (MapParams::dynamic) written once for both backends: the hit
// classification over a cell reader and the surround test's bitwise erosion of 512-bit block
// masks. The CPU (dynamic_classifier.cpp) reads the host map; the CUDA kernels
// (cuda/dynamic_kernels.cu) read the device slots through the window: the same code, so that
// both classify the same hits and make the same cells void.
#pragma once

#include <cstdint>

#include "fragg_map/cell.h"
#include "fragg_map/dynamic_rule.h"
#include "fragg_map/hd.h"
#include "fragg_map/key.h"

namespace fragg::dynamic_eval {

constexpr int kWords = kCellsPerBlock / 64;  ///< 64-bit words of a block's cell mask
static_assert(kWords == kBlockSize && kBlockSize == 8, "a word is one z layer of 8 x 8 cells");

/// kPassThrough: every cell within the rule's radius of `v` (Chebyshev, `v` included) has been
/// observed. `cells.find(v)`: the cell, or null where the map has no block (unobserved).
template <class Reader>
[[nodiscard]] FRAGG_HD bool observedAround(const VoxelKey& v, Reader& cells,
                                           const DynamicRule& rule) {
  const int r = rule.known_radius_cells;
  for (int dz = -r; dz <= r; ++dz)
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        const Cell* n = cells.find(VoxelKey{v.x + dx, v.y + dy, v.z + dz});
        if (!n || !n->observed()) return false;
      }
  return true;
}

/// Whether a hit in cell `end` is dynamic (see isDynamicHit in dynamic_classifier.h).
template <class Reader>
[[nodiscard]] FRAGG_HD bool dynamicAt(const VoxelKey& end, Reader& cells, const DynamicRule& rule) {
  const Cell* c = cells.find(end);
  if (!rule.surround) return c && rule.isVoid(*c) && observedAround(end, cells, rule);
  if (!c || !rule.seenFreeBefore(*c)) return false;
  if (rule.isVoid(*c)) return true;
  // Free with confidence all around (over earlier scans): space that no static surface borders.
  const int r = rule.known_radius_cells;
  for (int dz = -r; dz <= r; ++dz)
    for (int dy = -r; dy <= r; ++dy)
      for (int dx = -r; dx <= r; ++dx) {
        const Cell* n = cells.find(VoxelKey{end.x + dx, end.y + dy, end.z + dz});
        if (!n || !rule.seenFreeBefore(*n)) return false;
      }
  return true;
}

/// The seen-free mask of a block (see surroundedCells): not hit by the scan, and passed through
/// by it or known (occupied or free) before it. `free_marks` / `hit_marks`: the scan's marks
/// (null: none); `occupied` / `free`: the block's state masks (null: no block).
FRAGG_HD void seenFreeMask(const uint64_t* free_marks, const uint64_t* hit_marks,
                           const uint64_t* occupied, const uint64_t* free, uint64_t* out) {
  for (int w = 0; w < kWords; ++w) {
    uint64_t m = free_marks ? free_marks[w] : 0;
    if (occupied) m |= occupied[w] | free[w];
    if (hit_marks) m &= ~hit_marks[w];
    out[w] = m;
  }
}

// Bitwise erosion of a block's 512-bit mask (word w = the layer z = w; bit x + 8 y) by a cube
// of radius r <= 2 < a block, from the masks of the block (mid) and its neighbours below (lo)
// and above (hi) along one axis: out bit = AND of the mask over [-r, r] along that axis.
constexpr uint64_t kColumns = 0x0101010101010101ull;  // x = 0 in every row

/// Columns x < k of every row.
FRAGG_HD constexpr uint64_t columnsBelow(int k) { return ((uint64_t{1} << k) - 1) * kColumns; }

/// Erosion along x.
FRAGG_HD void erodeX(const uint64_t* lo, const uint64_t* mid, const uint64_t* hi, int r,
                     uint64_t* out) {
  for (int w = 0; w < kWords; ++w) {
    uint64_t e = mid[w];
    for (int d = 1; d <= r; ++d) {
      const uint64_t below = columnsBelow(8 - d);
      e &= ((mid[w] >> d) & below) | ((hi[w] << (8 - d)) & ~below);                      // x + d
      e &= ((mid[w] << d) & ~columnsBelow(d)) | ((lo[w] >> (8 - d)) & columnsBelow(d));  // x - d
    }
    out[w] = e;
  }
}

/// Erosion along y.
FRAGG_HD void erodeY(const uint64_t* lo, const uint64_t* mid, const uint64_t* hi, int r,
                     uint64_t* out) {
  for (int w = 0; w < kWords; ++w) {
    uint64_t e = mid[w];
    for (int d = 1; d <= r; ++d) {
      e &= (mid[w] >> (8 * d)) | (hi[w] << (8 * (8 - d)));  // y + d
      e &= (mid[w] << (8 * d)) | (lo[w] >> (8 * (8 - d)));  // y - d
    }
    out[w] = e;
  }
}

/// Erosion along z.
FRAGG_HD void erodeZ(const uint64_t* lo, const uint64_t* mid, const uint64_t* hi, int r,
                     uint64_t* out) {
  for (int w = 0; w < kWords; ++w) {
    uint64_t e = mid[w];
    for (int d = 1; d <= r; ++d) {
      e &= w + d < kWords ? mid[w + d] : hi[w + d - kWords];
      e &= w - d >= 0 ? mid[w - d] : lo[w - d + kWords];
    }
    out[w] = e;
  }
}

/// The surround test of one block: `around[n]` the seen-free masks of the 27 blocks around it
/// (n = (dz + 1) * 9 + (dy + 1) * 3 + (dx + 1)), `candidates` its passed-through cells; `out`
/// gets the candidates whose every neighbour within r <= 2 cells is seen free. The cube's
/// minimum filter is separable: along x for the 3 x 3 block columns, then y, then z.
FRAGG_HD void surroundedMask(const uint64_t* const* around, int r, const uint64_t* candidates,
                             uint64_t* out) {
  uint64_t along_x[9][kWords], along_y[3][kWords], eroded[kWords];
  for (int n = 0; n < 9; ++n)
    erodeX(around[n * 3], around[n * 3 + 1], around[n * 3 + 2], r, along_x[n]);
  for (int n = 0; n < 3; ++n)
    erodeY(along_x[n * 3], along_x[n * 3 + 1], along_x[n * 3 + 2], r, along_y[n]);
  erodeZ(along_y[0], along_y[1], along_y[2], r, eroded);
  for (int w = 0; w < kWords; ++w) out[w] = candidates[w] & eroded[w];
}

}  // namespace fragg::dynamic_eval
