// The auto sensor model's statistics (AutoSensorStats) as the device gathers them: one set of
// accumulators every thread block merges into with atomics. Doubles are kept as integer keys
// that sort as the doubles do, so that atomicMin / atomicMax merge them exactly; the sums and
// the count are integers already.
#pragma once

#include <cstdint>
#include <cstring>

#include "fragg_map/hd.h"
#include "fragg_map/internal/auto_sensor_stats.h"

namespace fragg::cuda {

/// An unsigned key in the order of the doubles (-0 and +0 apart; AutoSensorStats has no -0).
FRAGG_HD unsigned long long orderedKey(double v) {
#if defined(__CUDA_ARCH__)
  const unsigned long long b = static_cast<unsigned long long>(__double_as_longlong(v));
#else
  unsigned long long b;
  std::memcpy(&b, &v, sizeof b);
#endif
  return (b >> 63) ? ~b : (b | 0x8000000000000000ull);
}
FRAGG_HD double fromOrderedKey(unsigned long long k) {
  const unsigned long long b = (k >> 63) ? (k & 0x7fffffffffffffffull) : ~k;
#if defined(__CUDA_ARCH__)
  return __longlong_as_double(static_cast<long long>(b));
#else
  double v;
  std::memcpy(&v, &b, sizeof v);
  return v;
#endif
}

struct AutoStatsAccum {
  unsigned long long max_dist_key, sin_min_key, sin_max_key;
  unsigned long long dir_sum[3];  ///< two's complement: atomicAdd of the signed sums
  unsigned long long valid;
  unsigned long long tan_h_key[6], tan_v_key[6];
  int32_t fits[6];

  /// The statistics of no point.
  static AutoStatsAccum empty() { return from(AutoSensorStats{}); }
  static AutoStatsAccum from(const AutoSensorStats& s) {
    AutoStatsAccum a;
    a.max_dist_key = orderedKey(s.max_dist_m);
    a.sin_min_key = orderedKey(s.sin_min);
    a.sin_max_key = orderedKey(s.sin_max);
    for (int i = 0; i < 3; ++i) a.dir_sum[i] = static_cast<unsigned long long>(s.dir_sum_fx[i]);
    a.valid = s.valid;
    for (int k = 0; k < 6; ++k) {
      a.tan_h_key[k] = orderedKey(s.fit[k].tan_h);
      a.tan_v_key[k] = orderedKey(s.fit[k].tan_v);
      a.fits[k] = s.fit[k].fits;
    }
    return a;
  }
  AutoSensorStats stats() const {
    AutoSensorStats s;
    s.max_dist_m = fromOrderedKey(max_dist_key);
    s.sin_min = fromOrderedKey(sin_min_key);
    s.sin_max = fromOrderedKey(sin_max_key);
    for (int i = 0; i < 3; ++i) s.dir_sum_fx[i] = static_cast<int64_t>(dir_sum[i]);
    s.valid = valid;
    for (int k = 0; k < 6; ++k) {
      s.fit[k].tan_h = fromOrderedKey(tan_h_key[k]);
      s.fit[k].tan_v = fromOrderedKey(tan_v_key[k]);
      s.fit[k].fits = fits[k];
      if (!fits[k]) s.fit[k].fail();  // the threads whose points fitted raised the tangents
    }
    return s;
  }
};

}  // namespace fragg::cuda
