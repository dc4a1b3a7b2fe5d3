// Counter-based random numbers: a value depends only on (seed, stream, index), never on the
// order in which threads draw them, so simulations are deterministic on any core count.
#pragma once

#include <cmath>
#include <cstdint>

namespace fragg::sim {

/// SplitMix64 finaliser.
inline uint64_t mix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

inline uint64_t randomKey(uint64_t seed, uint64_t stream, uint64_t index) {
  return mix64(mix64(mix64(seed) ^ stream) ^ index);
}

/// Uniform in (0, 1).
inline double uniform01(uint64_t key) { return ((key >> 11) + 0.5) * (1.0 / 9007199254740992.0); }

/// Standard normal (Box-Muller over two derived keys).
inline double gaussian(uint64_t key) {
  const double u1 = uniform01(mix64(key ^ 0x1234567ULL)),
               u2 = uniform01(mix64(key ^ 0x89abcdefULL));
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

}  // namespace fragg::sim
