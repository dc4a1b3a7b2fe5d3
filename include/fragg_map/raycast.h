// Ray traversal shared by the CPU and CUDA backends.
//
// OctoMap semantics: the cells from the sensor's cell up to (not including) the endpoint cell
// are free; the endpoint cell is a hit unless the ray was clipped at max range (then it is
// neither). A hit may carry a clearing margin (the sensor's range noise): free cells the ray
// leaves less than that distance before its endpoint are not visited. Coordinates come in voxel
// units (metres / resolution) relative to a reference voxel near the sensor, so float traversal
// keeps full precision anywhere on an int32 map.
#pragma once

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "fragg_map/hd.h"
#include "fragg_map/key.h"

namespace fragg {

/// How a visited cell relates to the previous one, passed to visitors so that they can follow
/// a block to its face neighbour instead of looking the new block up.
constexpr int kSameBlock = -1;     ///< same block as the previous cell
constexpr int kUnknownBlock = -2;  ///< first cell of the ray, or a diagonal move (Bresenham)
/// Otherwise: the face crossed into a new block, 2 * axis + (step > 0 ? 1 : 0).
FRAGG_HD int blockFace(int axis, int step) { return 2 * axis + (step > 0 ? 1 : 0); }

/// One ray in voxel units: `start_v` and `end_v` are relative to `ref` (a voxel key).
struct RayVox {
  VoxelKey ref;
  float start_v[3];
  float end_v[3];
  bool end_is_hit;
  /// Clearing margin of a hit, voxels: free cells whose exit point lies closer than this to
  /// the endpoint (along the ray) are skipped, so that range noise does not clear the surface
  /// that was hit. Ignored for free-only rays.
  float keep_v = 0.f;
  /// A free-only ray whose end cell is visited as free as well (a ray cut at max range under
  /// octomap_server's rule); ignored when `end_is_hit`.
  bool end_is_free = false;
};

/// Ray parameter (0 at the start, 1 at the end) beyond which a free cell's exit puts it inside
/// the clearing margin; above 1 when there is no margin.
FRAGG_HD float keepAfterT(const RayVox& ray) {
  if (!ray.end_is_hit || !(ray.keep_v > 0.f)) return 2.f;
  const float dx = ray.end_v[0] - ray.start_v[0];
  const float dy = ray.end_v[1] - ray.start_v[1];
  const float dz = ray.end_v[2] - ray.start_v[2];
  const float dxx = dx * dx, dyy = dy * dy, dzz = dz * dz;  // no contraction: same bits on GPU
  const float len = sqrtf(dxx + dyy + dzz);
  return len > 0.f ? 1.f - ray.keep_v / len : 2.f;
}

FRAGG_HD int floorToInt(float v) { return static_cast<int>(floorf(v)); }

/// Per-axis DDA state of one ray (scalars, so compilers keep it in registers). The ray
/// parameter of each boundary is computed from the ray's start (not accumulated step by
/// step), so a walk can jump over cells and land exactly where stepping would.
struct DdaAxis {
  int cur;        ///< absolute voxel key on this axis
  int step;       ///< +1, -1 or 0
  int remaining;  ///< steps left on this axis
  float t_max;    ///< ray parameter of the next boundary (INFINITY when none is left)
  float start_v;  ///< the ray's start on this axis, relative voxel units
  float inv_d;    ///< 1 / (end_v - start_v)
  int next_b;     ///< relative coordinate of the next boundary

  FRAGG_HD float boundaryT(int b) const { return (static_cast<float>(b) - start_v) * inv_d; }

  FRAGG_HD void init(int ref, float start, float end_v) {
    const int s = floorToInt(start), e = floorToInt(end_v);
    start_v = start;
    cur = ref + s;
    step = e > s ? 1 : (e < s ? -1 : 0);
    remaining = e > s ? e - s : s - e;
    if (step != 0) {
      // A span far below a cell (|end_v - start| < 1 / FLT_MAX, e.g. a direction component of
      // 1e-40 voxels that still crosses the boundary the start lies on) has no finite
      // reciprocal, and a boundary parameter 0 * inf would be NaN, which no compare orders:
      // the walk would step an exhausted axis and leave the ray's box. The largest finite
      // reciprocal of the same sign keeps every boundary parameter of such an axis (it has
      // one boundary, between start and end) finite, in [0, 1] and exact at 0.
      const float span = end_v - start;
      inv_d = 1.f / span;
      if (!(fabsf(inv_d) <= FLT_MAX)) inv_d = span < 0.f ? -FLT_MAX : FLT_MAX;
      next_b = step > 0 ? s + 1 : s;
      t_max = boundaryT(next_b);
    } else {
      inv_d = 0.f;
      next_b = 0;
      t_max = INFINITY;
    }
  }
  /// Steps to the next cell; returns true when that cell is in a new block.
  FRAGG_HD bool advance() {
    cur += step;
    --remaining;
    next_b += step;
    t_max = remaining ? boundaryT(next_b) : INFINITY;
    return (cur & kBlockMask) == (step > 0 ? 0 : kBlockMask);
  }
  /// `k` steps at once (k <= remaining).
  FRAGG_HD void advanceBy(int k) {
    cur += k * step;
    remaining -= k;
    next_b += k * step;
    t_max = remaining ? boundaryT(next_b) : INFINITY;
  }
  /// Steps until this axis leaves the current block (meaningful when step != 0).
  FRAGG_HD int stepsToBlockFace() const {
    return step > 0 ? kBlockMask - (cur & kBlockMask) + 1 : (cur & kBlockMask) + 1;
  }
};

/// A visitor may skip the rest of a block: when it has a member `bool skippingBlock() const`
/// that returns true after a free cell's visit, traverseDda jumps to the next block (or the
/// endpoint) without visiting the cells in between (ddaLeaveBlock). The cells it lands on are
/// the ones stepping would reach; only the visits are left out. The
/// backends use it for blocks in which a miss changes nothing (every cell at the lower clamp).
template <class V, class = void>
struct CanSkipBlock : std::false_type {};
template <class V>
struct CanSkipBlock<V, std::void_t<decltype(std::declval<const V&>().skippingBlock())>>
    : std::true_type {};

/// One DDA step: the smallest t_max advances; ties go to the later axis, as in OctoMap's
/// computeRayKeys. An exhausted axis has an infinite t_max, and an axis with steps left a
/// finite one, so an exhausted axis is never chosen while steps remain. Returns the entry code
/// of the new cell (kSameBlock or the face crossed).
FRAGG_HD int ddaStep(DdaAxis& x, DdaAxis& y, DdaAxis& z) {
  if (x.t_max < y.t_max) {
    if (x.t_max < z.t_max) return x.advance() ? blockFace(0, x.step) : kSameBlock;
    return z.advance() ? blockFace(2, z.step) : kSameBlock;
  }
  if (y.t_max < z.t_max) return y.advance() ? blockFace(1, y.step) : kSameBlock;
  return z.advance() ? blockFace(2, z.step) : kSameBlock;
}

/// Walks from the current cell to the first cell of the next block (or to the endpoint's cell
/// when the ray ends in this block) without visiting anything in between: the same cells and
/// state as calling ddaStep until it reports a new block, in O(1) per axis. The steps of the
/// three axes form one sequence ordered by (t, later axis first on ties); the first step that
/// leaves the block is the smallest of the axes' face crossings, and every earlier step of the
/// other axes stays inside the block. Decrements `total` by the steps taken; returns the entry
/// code of the cell reached (kSameBlock when the ray ended inside the block).
FRAGG_HD int ddaLeaveBlock(DdaAxis& x, DdaAxis& y, DdaAxis& z, int& total) {
  // Every axis is named, never indexed at run time: on the device an array of pointers to
  // x, y, z would move all three (the whole walk's state) from registers to local memory.
  int exit_axis = -1, exit_steps = 0;
  float exit_t = INFINITY;
  const auto consider = [&](const DdaAxis& d, int a) {
    if (d.step == 0) return;
    const int k = d.stepsToBlockFace();
    if (k > d.remaining) return;
    const float t = d.boundaryT(d.next_b + (k - 1) * d.step);
    if (t <= exit_t) {  // ties go to the later axis
      exit_axis = a;
      exit_steps = k;
      exit_t = t;
    }
  };
  consider(x, 0);
  consider(y, 1);
  consider(z, 2);
  if (exit_axis < 0) {  // the ray ends in this block
    total -= x.remaining + y.remaining + z.remaining;
    x.advanceBy(x.remaining);
    y.advanceBy(y.remaining);
    z.advanceBy(z.remaining);
    return kSameBlock;
  }
  // The other axes' steps before the exit, then the exit axis's.
  const auto follow = [&](DdaAxis& d, int b) {
    if (b == exit_axis) {
      d.advanceBy(exit_steps);
      total -= exit_steps;
      return;
    }
    while (d.remaining > 0 && (d.t_max < exit_t || (d.t_max == exit_t && b > exit_axis))) {
      d.advance();
      --total;
    }
  };
  follow(x, 0);
  follow(y, 1);
  follow(z, 2);
  const int exit_step = exit_axis == 0 ? x.step : exit_axis == 1 ? y.step : z.step;
  return blockFace(exit_axis, exit_step);
}

/// A part of one ray's walk, so that several threads can share a long ray (the CUDA ray pass).
/// The pieces are cut at the steps of the ray's major axis (the one with the most steps, the
/// first of equals): a piece holds the cells from the one the major axis's step `first_major`
/// enters (the ray's first cell when 0) up to, not including, the one its step `end_major`
/// enters; the piece with `end_major` >= the major axis's step count runs to the endpoint and
/// visits the hit. Pieces [0, a), [a, b), ..., [z, end) hold every cell of the whole walk once.
struct DdaPiece {
  int first_major = 0;
  int end_major = 0x7fffffff;  ///< the default piece is the whole walk
};

/// The major axis (0, 1, 2) of a walk whose axes take `sx`, `sy`, `sz` steps.
FRAGG_HD int ddaMajorAxis(int sx, int sy, int sz) {
  return sx >= sy ? (sx >= sz ? 0 : 2) : (sy >= sz ? 1 : 2);
}

/// Steps the major axis of `ray`'s walk takes (0 when the ray starts and ends in one cell).
FRAGG_HD int ddaMajorSteps(const RayVox& ray) {
  int most = 0;
  for (int a = 0; a < 3; ++a) {
    const int d = floorToInt(ray.end_v[a]) - floorToInt(ray.start_v[a]);
    most = d > most ? d : (-d > most ? -d : most);
  }
  return most;
}

/// How many steps axis `d` (index `a`, at the ray's start) takes before the major axis (index
/// `m`) crosses its boundary at ray parameter `t_m`: its boundaries at a smaller parameter, and
/// those at the same one when a > m (ddaStep: ties go to the later axis). The walk's steps are
/// the three axes' boundaries merged in that order, so this is exactly where stepping stands.
FRAGG_HD int ddaStepsBefore(const DdaAxis& d, int a, int m, float t_m) {
  if (d.step == 0 || d.remaining == 0) return 0;
  // First guess from where the ray is on this axis at t_m; then the same compares as ddaStep.
  const float u = d.start_v + t_m / d.inv_d;
  float guess =
      ceilf(d.step > 0 ? u - static_cast<float>(d.next_b) : static_cast<float>(d.next_b) - u);
  guess = guess < 0.f ? 0.f : guess;
  int i = guess > static_cast<float>(d.remaining) ? d.remaining : static_cast<int>(guess);
  const auto before = [&](int k) {
    const float t = d.boundaryT(d.next_b + k * d.step);
    return t < t_m || (t == t_m && a > m);
  };
  while (i > 0 && !before(i - 1)) --i;
  while (i < d.remaining && before(i)) ++i;
  return i;
}

/// The steps each axis (at the ray's start) has taken right after the major axis's step
/// `j` >= 1, in `c[3]`. The axes are passed by name (see ddaLeaveBlock).
FRAGG_HD void ddaStepsAtMajorStep(const DdaAxis& x, const DdaAxis& y, const DdaAxis& z, int m,
                                  int j, int c[3]) {
  const float t_m = m == 0   ? x.boundaryT(x.next_b + (j - 1) * x.step)
                    : m == 1 ? y.boundaryT(y.next_b + (j - 1) * y.step)
                             : z.boundaryT(z.next_b + (j - 1) * z.step);
  c[0] = m == 0 ? j : ddaStepsBefore(x, 0, m, t_m);
  c[1] = m == 1 ? j : ddaStepsBefore(y, 1, m, t_m);
  c[2] = m == 2 ? j : ddaStepsBefore(z, 2, m, t_m);
}

namespace detail {
/// The walk of traverseDda / traverseDdaPiece; `kWhole` compiles the piece logic out (the CPU
/// backend's and the one-thread-a-ray kernel's walk, whose inner loop must stay as it was).
template <bool kWhole, class Visit>
FRAGG_HD int traverseDdaSteps(const RayVox& ray, const DdaPiece& piece, Visit& visit) {
  DdaAxis x, y, z;
  x.init(ray.ref.x, ray.start_v[0], ray.end_v[0]);
  y.init(ray.ref.y, ray.start_v[1], ray.end_v[1]);
  z.init(ray.ref.z, ray.start_v[2], ray.end_v[2]);
  int total = x.remaining + y.remaining + z.remaining;
  bool last_piece = true;
  int total_end = 0;  // the walk stops when this many steps are left
  if constexpr (!kWhole) {
    const int m = ddaMajorAxis(x.remaining, y.remaining, z.remaining);
    const int major_steps = m == 0 ? x.remaining : m == 1 ? y.remaining : z.remaining;
    last_piece = piece.end_major >= major_steps;
    if (!last_piece) {
      int c[3];
      ddaStepsAtMajorStep(x, y, z, m, piece.end_major, c);
      total_end = total - (c[0] + c[1] + c[2]);
    }
    if (piece.first_major > 0) {
      int c[3];
      ddaStepsAtMajorStep(x, y, z, m, piece.first_major, c);
      x.advanceBy(c[0]);
      y.advanceBy(c[1]);
      z.advanceBy(c[2]);
      total -= c[0] + c[1] + c[2];
    }
  }
  const float keep_after_t = keepAfterT(ray);
  const bool has_margin = keep_after_t <= 1.f;  // else no cell is ever inside it
  int visited = 0;
  int entry = kUnknownBlock;
  bool skipped = false;
  while (total > total_end) {
    // The current cell's exit parameter is the smallest t_max (an axis with steps left has a
    // finite one). Exits grow along the ray, so once inside the margin, every later free cell
    // is too: the walk only follows the axes from there.
    if (has_margin && fminf(x.t_max, fminf(y.t_max, z.t_max)) > keep_after_t) {
      skipped = true;
    } else {
      visit(VoxelKey{x.cur, y.cur, z.cur}, false, entry);
      ++visited;
      if constexpr (CanSkipBlock<Visit>::value) {
        if (visit.skippingBlock()) {  // the rest of the block, unvisited
          entry = ddaLeaveBlock(x, y, z, total);
          continue;
        }
      }
    }
    entry = ddaStep(x, y, z);
    --total;
  }
  if (last_piece && (ray.end_is_hit || ray.end_is_free)) {
    visit(VoxelKey{x.cur, y.cur, z.cur}, ray.end_is_hit, skipped ? kUnknownBlock : entry);
    ++visited;
  }
  return visited;
}
}  // namespace detail

/// traverseDda over one piece of the walk (DdaPiece); the first cell of a piece that does not
/// start the ray comes with kUnknownBlock. Returns how many cells it visited.
template <class Visit>
FRAGG_HD int traverseDdaPiece(const RayVox& ray, const DdaPiece& piece, Visit& visit) {
  return detail::traverseDdaSteps<false>(ray, piece, visit);
}

/// Exact 3D DDA (Amanatides & Woo). Visits every cell the segment passes through, in order,
/// 6-connected; the per-axis step counts are fixed up front, so the walk always ends in the
/// endpoint's cell. `visit(key, is_hit, entry)` is called once per cell (entry: kSameBlock,
/// kUnknownBlock or the face crossed into a new block) except the free cells inside a hit's
/// clearing margin (then the hit comes with kUnknownBlock); returns how many cells it visited.
template <class Visit>
FRAGG_HD int traverseDda(const RayVox& ray, Visit& visit) {
  return detail::traverseDdaSteps<true>(ray, DdaPiece{}, visit);
}

FRAGG_HD int absInt(int v) { return v < 0 ? -v : v; }

/// 3D Bresenham line between the start and end cells (26-connected, integer only). Calls
/// `visit(key, is_hit, entry)` like traverseDda (entry is kSameBlock or kUnknownBlock) and
/// returns how many cells it visited. A clearing margin is measured at the major axis's cell
/// boundaries: the free cell of step i is skipped when the ray crosses the major axis's next
/// boundary inside the margin.
template <class Visit>
FRAGG_HD int traverseBresenham(const RayVox& ray, Visit& visit) {
  int cur[3], d[3], s[3];
  for (int a = 0; a < 3; ++a) {
    cur[a] = floorToInt(ray.start_v[a]);
    const int e = floorToInt(ray.end_v[a]);
    d[a] = absInt(e - cur[a]);
    s[a] = e > cur[a] ? 1 : (e < cur[a] ? -1 : 0);
  }
  const int major = d[0] >= d[1] ? (d[0] >= d[2] ? 0 : 2) : (d[1] >= d[2] ? 1 : 2);
  const int a1 = (major + 1) % 3, a2 = (major + 2) % 3;
  int err1 = 2 * d[a1] - d[major];
  int err2 = 2 * d[a2] - d[major];
  const VoxelKey& r = ray.ref;
  const float keep_after_t = keepAfterT(ray);
  const bool has_margin = keep_after_t <= 1.f;  // else no cell is ever inside it
  const int major0 = cur[major];
  const float major_len = ray.end_v[major] - ray.start_v[major];
  VoxelKey previous{};
  int entry = kUnknownBlock;
  int visited = 0;
  for (int i = 0; i < d[major]; ++i) {
    const VoxelKey key{r.x + cur[0], r.y + cur[1], r.z + cur[2]};
    bool in_margin = false;
    if (has_margin) {  // the major axis's next boundary, as a ray parameter
      const float boundary_v = static_cast<float>(major0 + (s[major] > 0 ? i + 1 : -i));
      in_margin = (boundary_v - ray.start_v[major]) / major_len > keep_after_t;
    }
    if (!in_margin) {
      if (visited > 0)
        entry = ((key.x ^ previous.x) | (key.y ^ previous.y) | (key.z ^ previous.z)) & ~kBlockMask
                    ? kUnknownBlock
                    : kSameBlock;
      visit(key, false, entry);
      previous = key;
      ++visited;
    }
    if (err1 > 0) {
      cur[a1] += s[a1];
      err1 -= 2 * d[major];
    }
    if (err2 > 0) {
      cur[a2] += s[a2];
      err2 -= 2 * d[major];
    }
    err1 += 2 * d[a1];
    err2 += 2 * d[a2];
    cur[major] += s[major];
  }
  if (ray.end_is_hit || ray.end_is_free) {
    const VoxelKey key{r.x + cur[0], r.y + cur[1], r.z + cur[2]};
    if (visited > 0)
      entry = ((key.x ^ previous.x) | (key.y ^ previous.y) | (key.z ^ previous.z)) & ~kBlockMask
                  ? kUnknownBlock
                  : kSameBlock;
    visit(key, ray.end_is_hit, entry);
    ++visited;
  }
  return visited;
}

}  // namespace fragg
