// Occupied / free / observed bit masks of 64 consecutive cells (one z layer of a block: cell
// index x + 8 y), the hot loop of every per-block output (markers, occupied cloud, projected
// map). SSE2 on x86-64 (16 cells per step), a branch-free scalar loop elsewhere; both give the
// same bits (layer_masks_test).
#pragma once

#include <cstddef>
#include <cstdint>

#include "fragg_map/cell.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace fragg::ros {

struct LayerMasks {
  uint64_t occupied = 0;  ///< log-odds > occupied_above_fx
  uint64_t free = 0;      ///< observed and log-odds < free_below_fx
  uint64_t observed = 0;  ///< log-odds != kUnobservedLogOdds
};

/// The portable reference.
inline LayerMasks layerMasksScalar(const fragg::Cell* cells, int16_t occupied_above_fx,
                                   int16_t free_below_fx) {
  LayerMasks m;
  for (int i = 0; i < 64; ++i) {
    const int16_t l = cells[i].log_odds_fx;
    const bool known = l != fragg::kUnobservedLogOdds;
    m.occupied |= uint64_t{l > occupied_above_fx} << i;
    m.free |= uint64_t{known && l < free_below_fx} << i;
    m.observed |= uint64_t{known} << i;
  }
  return m;
}

/// The masks of cells[0..63].
inline LayerMasks layerMasks(const fragg::Cell* cells, int16_t occupied_above_fx,
                             int16_t free_below_fx) {
#if defined(__SSE2__)
  static_assert(sizeof(fragg::Cell) == 4 && offsetof(fragg::Cell, log_odds_fx) == 2,
                "log-odds are the high half of a little-endian 32-bit cell");
  const __m128i above = _mm_set1_epi16(occupied_above_fx);
  const __m128i below = _mm_set1_epi16(free_below_fx);
  const __m128i unobserved = _mm_set1_epi16(fragg::kUnobservedLogOdds);
  const __m128i* p = reinterpret_cast<const __m128i*>(cells);
  LayerMasks m;
  uint64_t unknown = 0;
  for (int q = 0; q < 4; ++q, p += 4) {  // 16 cells: 4 loads of 4 cells
    // The log-odds sign-extended to 32 bits, packed back (exactly) to 8 x int16.
    const __m128i lo = _mm_packs_epi32(_mm_srai_epi32(_mm_loadu_si128(p + 0), 16),
                                       _mm_srai_epi32(_mm_loadu_si128(p + 1), 16));
    const __m128i hi = _mm_packs_epi32(_mm_srai_epi32(_mm_loadu_si128(p + 2), 16),
                                       _mm_srai_epi32(_mm_loadu_si128(p + 3), 16));
    const auto bits = [](__m128i a, __m128i b) {
      return static_cast<uint64_t>(static_cast<uint32_t>(_mm_movemask_epi8(_mm_packs_epi16(a, b))));
    };
    m.occupied |= bits(_mm_cmpgt_epi16(lo, above), _mm_cmpgt_epi16(hi, above)) << (16 * q);
    m.free |= bits(_mm_cmplt_epi16(lo, below), _mm_cmplt_epi16(hi, below)) << (16 * q);
    unknown |= bits(_mm_cmpeq_epi16(lo, unobserved), _mm_cmpeq_epi16(hi, unobserved)) << (16 * q);
  }
  m.observed = ~unknown;
  m.free &= m.observed;
  return m;
#else
  return layerMasksScalar(cells, occupied_above_fx, free_below_fx);
#endif
}

}  // namespace fragg::ros
