// Block culling against a frustum, with the paper's three savings made exact:
//  * plane-rejection memory: the test that rejected a block last time is tried first;
//  * rotation coherence: a block rejected within the last TTL scans by a margin larger than
//    the sensor's motion since then (translation + angle x distance) is still outside;
//  * translation coherence: a block behind the near plane stays behind when the sensor has
//    moved forward (the motion term is the signed advance along the plane normal).
// Because every margin is a distance bound, the visible set is the same with or without them.
#pragma once

#include <cmath>
#include <cstdint>

#include "fragg_map/frustum.h"
#include "fragg_map/hd.h"

namespace fragg {

constexpr int kMaxCoherenceTtl = 32;

/// What culling remembers per block between scans (kept in the block's metadata).
struct CullMemory {
  uint32_t scan = 0;     ///< scan index of the last rejection (0 = none)
  float margin_m = 0.f;  ///< margin of that rejection
  uint8_t test = 0xff;   ///< test index that rejected it (0xff = none)
};

/// Motion of the sensor from an earlier scan to the current one.
struct PastPose {
  bool valid = false;
  float translation_m = 0.f;               ///< |o_now - o_then|
  float rotation_rad = 0.f;                ///< angle of R_then^-1 R_now
  float advance_m[kMaxFrustumTests] = {};  ///< n_now . (o_now - o_then), plane tests
};

/// Everything a culling pass needs besides the frustum; plain data for the device.
struct CullContext {
  uint32_t scan = 1;  ///< index of this scan (>= 1)
  int ttl = 8;
  bool plane_memory = true;
  bool rotation_coherence = true;
  bool translation_coherence = true;
  PastPose past[kMaxCoherenceTtl];  ///< past[k]: the pose k scans ago (k >= 1)
};

struct CullCounters {
  uint64_t blocks_tested = 0;
  uint64_t blocks_visible = 0;
  uint64_t tests_run = 0;
  uint64_t saved_by_plane_memory = 0;
  uint64_t saved_by_rotation = 0;
  uint64_t saved_by_translation = 0;
  void add(const CullCounters& o) {
    blocks_tested += o.blocks_tested;
    blocks_visible += o.blocks_visible;
    tests_run += o.tests_run;
    saved_by_plane_memory += o.saved_by_plane_memory;
    saved_by_rotation += o.saved_by_rotation;
    saved_by_translation += o.saved_by_translation;
  }
};

/// Culls one block (centre `c` relative to the sensor origin, half edge `h`); updates its
/// memory and the counters. Returns true when the block is visible.
FRAGG_HD bool cullBlock(const Frustum& f, const CullContext& ctx, const float c[3], float h,
                        CullMemory& mem, CullCounters& n) {
  const float kEps = 1e-4f;
  ++n.blocks_tested;
  const uint32_t age = ctx.scan - mem.scan;
  if (mem.test < f.num_tests && mem.test < kMaxFrustumTests && mem.scan != 0 && age >= 1 &&
      age < static_cast<uint32_t>(ctx.ttl) && age < kMaxCoherenceTtl) {
    const PastPose& past = ctx.past[age];
    if (past.valid) {
      const float reach = sqrtf(dot3(c, c)) + h * 1.7320508f + past.translation_m;
      const bool plane = f.tests[mem.test] == FrustumTest::kPlane;
      if (plane && mem.test == kNearPlaneTest && f.is_pinhole) {
        if (ctx.translation_coherence &&
            mem.margin_m + past.advance_m[mem.test] > past.rotation_rad * reach + kEps) {
          ++n.saved_by_translation;
          return false;
        }
      } else if (ctx.rotation_coherence) {
        const float motion = plane ? past.rotation_rad * reach - past.advance_m[mem.test]
                                   : past.rotation_rad * reach + past.translation_m;
        if (mem.margin_m > motion + kEps) {
          ++n.saved_by_rotation;
          return false;
        }
      }
    }
  }
  int first = -1;
  if (ctx.plane_memory && mem.test < f.num_tests && mem.test < kMaxFrustumTests) {
    first = mem.test;
    ++n.tests_run;
    const float m = frustumTestMargin(f, first, c, h);
    if (m > 0.f) {
      n.saved_by_plane_memory += static_cast<uint64_t>(first);  // tests before it in order
      mem.scan = ctx.scan;
      mem.margin_m = m;
      return false;
    }
  }
  for (int i = 0; i < f.num_tests; ++i) {
    if (i == first) continue;
    ++n.tests_run;
    const float m = frustumTestMargin(f, i, c, h);
    if (m > 0.f) {
      mem.test = static_cast<uint8_t>(i);
      mem.scan = ctx.scan;
      mem.margin_m = m;
      return false;
    }
  }
  mem.test = 0xff;
  mem.scan = 0;
  ++n.blocks_visible;
  return true;
}

}  // namespace fragg
