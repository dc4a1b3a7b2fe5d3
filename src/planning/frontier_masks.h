// Bit-parallel frontier test (internal to fragg_map_planning). A block's free and unknown cells
// as 512-bit masks (from the map's state masks, state_masks.h), one 64-bit word per z slab, bit
// y * 8 + x (so bit i of the mask is cell index i, cellIndexOf). The frontier cells of a block
// follow from the unknown masks of the 27 blocks around it: the unknown cells are dilated by one
// cell (x, then y, then z: the 3 x 3 x 3 box is separable) and ANDed with the block's free cells.
// Shared by the CPU path and the CUDA path (FRAGG_HD), so both give the same bits.
#pragma once

#include <cstdint>

#include "fragg_map/cell.h"
#include "fragg_map/hd.h"
#include "fragg_map/key.h"
#include "fragg_map/occupancy.h"
#include "fragg_map/state_masks.h"

namespace fragg::planning {

constexpr int kMaskWords = kCellsPerBlock / 64;  // 8 slabs of 64 cells
static_assert(kBlockSize == 8, "the frontier masks assume 8^3 blocks");

/// Which cells of a block are free and which unknown (the rest are occupied).
struct StateMasks {
  uint64_t free[kMaskWords];
  uint64_t unknown[kMaskWords];
};

/// Frontier cells of a block, bit i = cell index i.
struct FrontierBits {
  uint64_t words[kMaskWords];
};

/// The free and unknown masks of a block's state masks (the map's layer, state_masks.h).
FRAGG_HD StateMasks statesOf(const BlockStateMasks& m) {
  StateMasks s;
  for (int w = 0; w < kMaskWords; ++w) {
    s.free[w] = m.free[w];
    s.unknown[w] = m.unknownWord(w);
  }
  return s;
}

FRAGG_HD bool operator==(const StateMasks& a, const StateMasks& b) {
  for (int w = 0; w < kMaskWords; ++w)
    if (a.free[w] != b.free[w] || a.unknown[w] != b.unknown[w]) return false;
  return true;
}

FRAGG_HD bool anyBit(const FrontierBits& f) {
  uint64_t any = 0;
  for (int w = 0; w < kMaskWords; ++w) any |= f.words[w];
  return any != 0;
}

namespace mask_detail {

constexpr uint64_t kColumn0 = 0x0101010101010101ULL;  // cells with x = 0
constexpr uint64_t kColumn7 = kColumn0 << 7;          // cells with x = 7

/// Slab `c` dilated by one cell along x, with the same slab of the blocks at x - 1 (`left`)
/// and x + 1 (`right`).
FRAGG_HD uint64_t dilateX(uint64_t c, uint64_t left, uint64_t right) {
  return c | ((c << 1) & ~kColumn0) | ((c >> 1) & ~kColumn7) | ((left >> 7) & kColumn0) |
         ((right << 7) & kColumn7);
}

/// An x-dilated slab dilated along y, with the x-dilated slabs of the blocks at y - 1 and y + 1.
FRAGG_HD uint64_t dilateY(uint64_t c, uint64_t below, uint64_t above) {
  return c | (c << 8) | (c >> 8) | (below >> 56) | (above << 56);
}

}  // namespace mask_detail

/// Which of the 27 blocks around a block (bit (dz + 1) * 9 + (dy + 1) * 3 + (dx + 1), 13: the
/// block itself) may see their frontier cells change when its states go from `old` (nullptr:
/// no block, all unknown) to `fresh`: the block itself whenever a state changed, a neighbour
/// only when an unknown cell came or went on the face, edge or corner they share (a frontier
/// cell looks one cell across a border, at unknown cells only).
FRAGG_HD uint32_t neighboursReached(const StateMasks* old, const StateMasks& fresh) {
  using namespace mask_detail;
  uint64_t diff[kMaskWords], any_diff = 0, any_free = 0;
  for (int w = 0; w < kMaskWords; ++w) {
    diff[w] = (old ? old->unknown[w] : ~uint64_t(0)) ^ fresh.unknown[w];
    any_diff |= diff[w];
    any_free |= (old ? old->free[w] : 0) ^ fresh.free[w];
  }
  if (!any_diff) return any_free ? 1u << 13 : 0u;
  constexpr uint64_t kRow0 = 0xFFULL, kRow7 = kRow0 << 56;
  uint32_t bits = 0;
  for (int dz = -1; dz <= 1; ++dz) {
    const int w0 = dz > 0 ? kMaskWords - 1 : 0, w1 = dz < 0 ? 0 : kMaskWords - 1;
    for (int dy = -1; dy <= 1; ++dy) {
      const uint64_t ym = dy < 0 ? kRow0 : (dy > 0 ? kRow7 : ~uint64_t(0));
      for (int dx = -1; dx <= 1; ++dx) {
        const uint64_t xm = dx < 0 ? kColumn0 : (dx > 0 ? kColumn7 : ~uint64_t(0));
        uint64_t hit = 0;
        for (int w = w0; w <= w1; ++w) hit |= diff[w] & xm & ym;
        if (hit) bits |= 1u << ((dz + 1) * 9 + (dy + 1) * 3 + (dx + 1));
      }
    }
  }
  return bits;
}

/// Word `w` of a block's unknown and free masks, from the tracker's copy (StateMasks) or the
/// map's layer (BlockStateMasks): frontierBitsOf reads either.
FRAGG_HD uint64_t unknownWordOf(const StateMasks& m, int w) { return m.unknown[w]; }
FRAGG_HD uint64_t unknownWordOf(const BlockStateMasks& m, int w) { return m.unknownWord(w); }
FRAGG_HD uint64_t freeWordOf(const StateMasks& m, int w) { return m.free[w]; }
FRAGG_HD uint64_t freeWordOf(const BlockStateMasks& m, int w) { return m.free[w]; }

/// Frontier cells of the centre block given the state masks of the 27 blocks around it,
/// index (dz + 1) * 9 + (dy + 1) * 3 + (dx + 1) (13: the centre); nullptr = missing block
/// (all unknown; a missing centre has no free cell, so no frontier). `Masks`: StateMasks or
/// BlockStateMasks (the same bits from either).
template <class Masks>
FRAGG_HD FrontierBits frontierBitsOf(const Masks* const around[27]) {
  using namespace mask_detail;
  FrontierBits out{};
  const Masks* centre = around[13];
  if (!centre) return out;
  uint64_t any_free = 0;
  for (int w = 0; w < kMaskWords; ++w) any_free |= freeWordOf(*centre, w);
  if (!any_free) return out;
  // planes[i]: the unknown cells of slab z = i - 1 (z = -1 and 8 from the blocks below and
  // above) dilated along x and y.
  uint64_t planes[kMaskWords + 2];
  for (int i = 0; i < kMaskWords + 2; ++i) {
    const int layer = i == 0 ? 0 : (i == kMaskWords + 1 ? 2 : 1);
    const int slab = i == 0 ? kMaskWords - 1 : (i == kMaskWords + 1 ? 0 : i - 1);
    uint64_t rows[3];
    for (int dy = 0; dy < 3; ++dy) {
      const Masks* const* row = around + layer * 9 + dy * 3;
      const uint64_t l = row[0] ? unknownWordOf(*row[0], slab) : ~uint64_t(0);
      const uint64_t c = row[1] ? unknownWordOf(*row[1], slab) : ~uint64_t(0);
      const uint64_t r = row[2] ? unknownWordOf(*row[2], slab) : ~uint64_t(0);
      rows[dy] = dilateX(c, l, r);
    }
    planes[i] = dilateY(rows[1], rows[0], rows[2]);
  }
  for (int z = 0; z < kMaskWords; ++z)
    out.words[z] = freeWordOf(*centre, z) & (planes[z] | planes[z + 1] | planes[z + 2]);
  return out;
}

}  // namespace fragg::planning
