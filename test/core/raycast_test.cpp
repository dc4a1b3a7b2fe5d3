#include "fragg_map/raycast.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

namespace fragg {
namespace {

using Cells = std::vector<VoxelKey>;
auto tupleOf(const VoxelKey& k) { return std::make_tuple(k.x, k.y, k.z); }

struct Collect {
  Cells cells;
  std::vector<bool> hits;
  std::vector<int> entries;
  void operator()(const VoxelKey& k, bool hit, int entry) {
    cells.push_back(k);
    hits.push_back(hit);
    entries.push_back(entry);
  }
};

/// The entry codes say whether each cell is in the previous cell's block, and through which
/// face a new block was entered.
void expectEntriesMatchBlocks(const Collect& got, bool faces) {
  ASSERT_FALSE(got.entries.empty());
  EXPECT_EQ(got.entries[0], kUnknownBlock);
  for (size_t i = 1; i < got.cells.size(); ++i) {
    const BlockKey a = blockKeyOf(got.cells[i - 1]), b = blockKeyOf(got.cells[i]);
    if (a == b) {
      EXPECT_EQ(got.entries[i], kSameBlock) << i;
    } else if (!faces) {
      EXPECT_EQ(got.entries[i], kUnknownBlock) << i;
    } else {
      const int d[3] = {b.x - a.x, b.y - a.y, b.z - a.z};
      int face = -100;
      for (int axis = 0; axis < 3; ++axis)
        if (d[axis] != 0) face = blockFace(axis, d[axis]);
      EXPECT_EQ(got.entries[i], face) << i;
    }
  }
}

/// Does the segment a->b intersect the unit cube at `cell` grown by `grow` on every side? When
/// it does and `t_exit` is given, it receives the segment parameter where it leaves the cube.
bool segmentHitsCell(const float a[3], const float b[3], const VoxelKey& cell, double grow,
                     double* t_exit = nullptr) {
  double t0 = 0.0, t1 = 1.0;
  const int c[3] = {cell.x, cell.y, cell.z};
  for (int i = 0; i < 3; ++i) {
    const double lo = c[i] - grow, hi = c[i] + 1 + grow, d = double(b[i]) - a[i];
    if (std::fabs(d) < 1e-12) {
      if (a[i] < lo || a[i] > hi) return false;
      continue;
    }
    double ta = (lo - a[i]) / d, tb = (hi - a[i]) / d;
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return false;
  }
  if (t_exit) *t_exit = t1;
  return true;
}

TEST(RaycastTest, DdaVisitsExactlyTheCellsTheSegmentCrosses) {
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> u(-20.f, 20.f);
  int checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    RayVox ray{VoxelKey{0, 0, 0}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, true};
    if (trial % 4 == 0) ray.end_v[2] = ray.start_v[2];  // planar rays too
    Collect got;
    traverseDda(ray, got);
    ASSERT_FALSE(got.cells.empty());
    // Starts in the start cell, ends in the end cell, steps to a face neighbour each time.
    EXPECT_EQ(got.cells.front(), (VoxelKey{floorToInt(ray.start_v[0]), floorToInt(ray.start_v[1]),
                                           floorToInt(ray.start_v[2])}));
    EXPECT_EQ(got.cells.back(), (VoxelKey{floorToInt(ray.end_v[0]), floorToInt(ray.end_v[1]),
                                          floorToInt(ray.end_v[2])}));
    EXPECT_TRUE(got.hits.back());
    for (size_t i = 0; i + 1 < got.cells.size(); ++i) {
      EXPECT_FALSE(got.hits[i]);
      const VoxelKey &p = got.cells[i], &q = got.cells[i + 1];
      EXPECT_EQ(std::abs(p.x - q.x) + std::abs(p.y - q.y) + std::abs(p.z - q.z), 1);
    }
    expectEntriesMatchBlocks(got, /*faces=*/true);
    std::set<std::tuple<int, int, int>> visited;
    for (const auto& k : got.cells) visited.insert(tupleOf(k));
    EXPECT_EQ(visited.size(), got.cells.size()) << "a cell was visited twice";
    // Brute force over the bounding box: every cell the segment clearly crosses is visited,
    // and every visited cell is at least touched (tolerance for grazing edges and corners).
    int lo[3], hi[3];
    for (int i = 0; i < 3; ++i) {
      lo[i] = floorToInt(std::min(ray.start_v[i], ray.end_v[i])) - 1;
      hi[i] = floorToInt(std::max(ray.start_v[i], ray.end_v[i])) + 1;
    }
    for (int x = lo[0]; x <= hi[0]; ++x)
      for (int y = lo[1]; y <= hi[1]; ++y)
        for (int z = lo[2]; z <= hi[2]; ++z) {
          const VoxelKey k{x, y, z};
          const bool in = visited.count(tupleOf(k)) > 0;
          if (segmentHitsCell(ray.start_v, ray.end_v, k, -1e-3)) {
            EXPECT_TRUE(in) << "missed a crossed cell in trial " << trial;
          }
          if (in) {
            EXPECT_TRUE(segmentHitsCell(ray.start_v, ray.end_v, k, 1e-3));
          }
        }
    ++checked;
  }
  EXPECT_EQ(checked, 2000);
}

TEST(RaycastTest, FreeOnlyRayStopsBeforeItsEndCell) {
  RayVox ray{VoxelKey{10, -5, 3}, {0.5f, 0.5f, 0.5f}, {4.5f, 0.5f, 0.5f}, false};
  Collect got;
  traverseDda(ray, got);
  ASSERT_EQ(got.cells.size(), 4u);
  EXPECT_EQ(got.cells.front(), (VoxelKey{10, -5, 3}));
  EXPECT_EQ(got.cells.back(), (VoxelKey{13, -5, 3}));
  for (bool h : got.hits) EXPECT_FALSE(h);
}

TEST(RaycastTest, SameCellRayIsJustAHit) {
  RayVox ray{VoxelKey{0, 0, 0}, {0.1f, 0.2f, 0.3f}, {0.9f, 0.8f, 0.7f}, true};
  Collect got;
  traverseDda(ray, got);
  ASSERT_EQ(got.cells.size(), 1u);
  EXPECT_TRUE(got.hits[0]);
}

TEST(RaycastTest, BresenhamConnectsStartToEnd) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-30.f, 30.f);
  for (int trial = 0; trial < 500; ++trial) {
    RayVox ray{VoxelKey{-100, 200, 0}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, true};
    Collect got;
    traverseBresenham(ray, got);
    ASSERT_FALSE(got.cells.empty());
    EXPECT_EQ(got.cells.front(),
              (VoxelKey{-100 + floorToInt(ray.start_v[0]), 200 + floorToInt(ray.start_v[1]),
                        floorToInt(ray.start_v[2])}));
    EXPECT_EQ(got.cells.back(),
              (VoxelKey{-100 + floorToInt(ray.end_v[0]), 200 + floorToInt(ray.end_v[1]),
                        floorToInt(ray.end_v[2])}));
    expectEntriesMatchBlocks(got, /*faces=*/false);
    for (size_t i = 0; i + 1 < got.cells.size(); ++i) {
      const VoxelKey &p = got.cells[i], &q = got.cells[i + 1];
      EXPECT_LE(std::max({std::abs(p.x - q.x), std::abs(p.y - q.y), std::abs(p.z - q.z)}), 1);
      EXPECT_FALSE(p == q);
    }
  }
}

TEST(RaycastTest, ClearingMarginSkipsTheFreeCellsItsRayLeavesNearTheHit) {
  // Along x from 0.5 to 10.3: free cells 0..9, hit in cell 10. Cell 9 is left at x = 10, 0.3
  // voxels before the end; cell 8 at x = 9, 1.3 before.
  RayVox ray{VoxelKey{0, 0, 0}, {0.5f, 0.5f, 0.5f}, {10.3f, 0.5f, 0.5f}, true};
  for (float keep : {0.f, 0.2f, 0.5f, 1.5f, 50.f}) {
    ray.keep_v = keep;
    Collect got;
    const int visited = traverseDda(ray, got);
    const int free_expected = keep < 0.3f ? 10 : (keep < 1.3f ? 9 : (keep < 2.3f ? 8 : 0));
    ASSERT_EQ(got.cells.size(), static_cast<size_t>(free_expected + 1)) << keep;
    EXPECT_EQ(visited, free_expected + 1);
    EXPECT_EQ(got.cells.back(), (VoxelKey{10, 0, 0}));
    EXPECT_TRUE(got.hits.back());
    for (int i = 0; i < free_expected; ++i) {
      EXPECT_EQ(got.cells[i], (VoxelKey{i, 0, 0}));
      EXPECT_FALSE(got.hits[i]);
    }
    // After skipped cells the hit cannot follow a block face from its predecessor.
    if (free_expected < 10) {
      EXPECT_EQ(got.entries.back(), kUnknownBlock) << keep;
    }
  }
  // A free-only ray (clipped at max range) has no surface to protect: the margin is ignored.
  ray.end_is_hit = false;
  ray.keep_v = 5.f;
  Collect free_only;
  traverseDda(ray, free_only);
  EXPECT_EQ(free_only.cells.size(), 10u);
}

/// Distance (voxels) from where the segment a->b leaves `cell` to b; -1 when it misses it.
double exitToEnd(const float a[3], const float b[3], const VoxelKey& cell) {
  double t_exit = 0.0;
  if (!segmentHitsCell(a, b, cell, 0.0, &t_exit)) return -1.0;
  double len2 = 0.0;
  for (int i = 0; i < 3; ++i) len2 += (double(b[i]) - a[i]) * (double(b[i]) - a[i]);
  return (1.0 - t_exit) * std::sqrt(len2);
}

/// Walks `ray` without and with the clearing margin `keep_v`; checks what holds for any
/// traversal: the return value counts the visits, the margin only drops free cells from the
/// end of the walk, and the hit stays.
template <class Walk>
std::pair<Collect, Collect> plainAndKept(RayVox ray, float keep_v, Walk walk) {
  Collect plain, kept;
  ray.keep_v = 0.f;
  walk(ray, plain);
  ray.keep_v = keep_v;
  const int visited = walk(ray, kept);
  EXPECT_EQ(visited, static_cast<int>(kept.cells.size()));
  EXPECT_GE(kept.cells.size(), 1u);
  EXPECT_LE(kept.cells.size(), plain.cells.size());
  if (kept.cells.empty() || kept.cells.size() > plain.cells.size()) return {plain, kept};
  for (size_t i = 0; i + 1 < kept.cells.size(); ++i) EXPECT_EQ(kept.cells[i], plain.cells[i]);
  EXPECT_EQ(kept.cells.back(), plain.cells.back());
  EXPECT_TRUE(kept.hits.back());
  return {plain, kept};
}

const auto dda = [](const RayVox& r, Collect& c) { return traverseDda(r, c); };
const auto bresenham = [](const RayVox& r, Collect& c) { return traverseBresenham(r, c); };

TEST(RaycastTest, ClearingMarginKeepsExactlyTheCellsLeftOutsideIt) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-20.f, 20.f), m(0.f, 3.f);
  int skipped_total = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    RayVox ray{VoxelKey{5, -7, 9}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, true};
    ray.keep_v = m(rng);  // used by the checks below
    const auto [plain, kept] = plainAndKept(ray, ray.keep_v, dda);
    ASSERT_FALSE(kept.cells.empty());
    const size_t free_kept = kept.cells.size() - 1;
    // Kept cells are left at least the margin before the end, skipped ones less (float
    // traversal: a tolerance of 1e-3 voxels).
    const float a[3] = {ray.start_v[0], ray.start_v[1], ray.start_v[2]};
    const float b[3] = {ray.end_v[0], ray.end_v[1], ray.end_v[2]};
    auto rel = [&](const VoxelKey& k) { return VoxelKey{k.x - 5, k.y + 7, k.z - 9}; };
    for (size_t i = 0; i + 1 < plain.cells.size(); ++i) {
      const double left = exitToEnd(a, b, rel(plain.cells[i]));
      ASSERT_GE(left, 0.0);
      if (i < free_kept) {
        EXPECT_GE(left, ray.keep_v - 1e-3) << trial << " cell " << i;
      } else {
        EXPECT_LE(left, ray.keep_v + 1e-3) << trial << " cell " << i;
        ++skipped_total;
      }
    }
  }
  EXPECT_GT(skipped_total, 2000);  // the margins did skip cells
}

TEST(RaycastTest, BresenhamClearingMarginDropsTheLastFreeCells) {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> u(-20.f, 20.f), m(0.f, 3.f);
  for (int trial = 0; trial < 500; ++trial) {
    RayVox ray{VoxelKey{0, 0, 0}, {u(rng), u(rng), u(rng)}, {u(rng), u(rng), u(rng)}, true};
    ray.keep_v = m(rng);  // used by the checks below
    const auto [plain, kept] = plainAndKept(ray, ray.keep_v, bresenham);
    ASSERT_LE(kept.cells.size(), plain.cells.size());
    expectEntriesMatchBlocks(kept, /*faces=*/false);
    // The cells dropped lie within the margin of the end along the major axis (+1 cell).
    const size_t dropped = plain.cells.size() - kept.cells.size();
    float d_major = 0.f, len2 = 0.f;
    for (int a = 0; a < 3; ++a) {
      const float d = ray.end_v[a] - ray.start_v[a];
      len2 += d * d;
      d_major = std::max(d_major, std::fabs(d));
    }
    EXPECT_LE(static_cast<float>(dropped), ray.keep_v * d_major / std::sqrt(len2) + 1.001f);
  }
}

/// Skips the rest of every block whose key hashes into the chosen half (after a free visit).
struct SkipSomeBlocks : Collect {
  bool skip = false;
  static bool skipped(const BlockKey& b) {
    return ((static_cast<uint32_t>(b.x) * 73856093u) ^ (static_cast<uint32_t>(b.y) * 19349669u) ^
            (static_cast<uint32_t>(b.z) * 83492791u)) %
               3 !=
           0;
  }
  void operator()(const VoxelKey& k, bool hit, int entry) {
    Collect::operator()(k, hit, entry);
    skip = !hit && skipped(blockKeyOf(k));
  }
  bool skippingBlock() const { return skip; }
};

TEST(RaycastTest, LeavingABlockInOneJumpLandsWhereSteppingDoes) {
  // Reference: the full walk, then of each run of cells in a skipped block only the first
  // kept (the hit always). The jumping walk must give exactly that sequence, entry codes
  // included, for rays of every direction and length, with and without clearing margins.
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-40.f, 40.f), frac(0.f, 1.f);
  size_t jumped_cells = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    RayVox ray{VoxelKey{int(rng() % 64) - 32, int(rng() % 64) - 32, -5},
               {frac(rng), frac(rng), frac(rng)},
               {u(rng), u(rng), u(rng) / 4},
               trial % 3 != 0,
               trial % 5 == 0 ? 1.5f : 0.f};
    if (trial % 7 == 0) ray.end_v[2] = ray.start_v[2] + 0.25f;  // flat rays: ties and zero steps
    Collect all;
    traverseDda(ray, all);
    Collect want;
    for (size_t i = 0; i < all.cells.size(); ++i) {
      const bool same_block_as_previous =
          i > 0 && blockKeyOf(all.cells[i]) == blockKeyOf(all.cells[i - 1]);
      const bool previous_skips =
          i > 0 && !all.hits[i - 1] && SkipSomeBlocks::skipped(blockKeyOf(all.cells[i - 1]));
      // A cell is left out when a kept cell before it in the same run of its block skips.
      if (!all.hits[i] && same_block_as_previous && previous_skips) continue;
      if (all.hits[i] && same_block_as_previous && previous_skips) {
        want(all.cells[i], true, kSameBlock);
        continue;
      }
      want(all.cells[i], all.hits[i], all.entries[i]);
    }
    SkipSomeBlocks got;
    const int visited = traverseDda(ray, got);
    ASSERT_EQ(got.cells.size(), want.cells.size()) << "trial " << trial;
    EXPECT_EQ(visited, static_cast<int>(got.cells.size()));
    for (size_t i = 0; i < got.cells.size(); ++i) {
      ASSERT_EQ(tupleOf(got.cells[i]), tupleOf(want.cells[i]))
          << "trial " << trial << " cell " << i;
      EXPECT_EQ(got.hits[i], want.hits[i]) << "trial " << trial << " cell " << i;
      // After a jump the entry code names the face crossed into the new block.
      if (i > 0 && blockKeyOf(got.cells[i]) != blockKeyOf(got.cells[i - 1]) && !got.hits[i]) {
        EXPECT_EQ(got.entries[i], want.entries[i]) << "trial " << trial << " cell " << i;
      }
    }
    jumped_cells += all.cells.size() - got.cells.size();
  }
  EXPECT_GT(jumped_cells, 20000u);
}

/// A random ray as the jump test draws them: every direction and length, flat rays (ties,
/// axes without steps), hits and free-only rays, some with a clearing margin.
RayVox randomRay(std::mt19937& rng, int trial) {
  std::uniform_real_distribution<float> u(-40.f, 40.f), frac(0.f, 1.f);
  RayVox ray{VoxelKey{int(rng() % 64) - 32, int(rng() % 64) - 32, -5},
             {frac(rng), frac(rng), frac(rng)},
             {u(rng), u(rng), u(rng) / 4},
             trial % 3 != 0,
             trial % 5 == 0 ? 1.5f : 0.f};
  if (trial % 7 == 0) ray.end_v[2] = ray.start_v[2] + 0.25f;
  if (trial % 11 == 0) ray.end_v[0] = ray.start_v[0] + float(trial % 5) - 2.f;  // exact ties
  return ray;
}

TEST(RaycastTest, PiecesOfAWalkAreTheWholeWalkCutAtMajorSteps) {
  // Pieces of every length laid end to end give the whole walk's cells, hits and entry codes
  // (a piece's first cell comes with kUnknownBlock), each cell once; only the last piece has
  // the hit; the visit counts add up.
  std::mt19937 rng(11);
  size_t pieces_walked = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const RayVox ray = randomRay(rng, trial);
    Collect whole;
    const int whole_visited = traverseDda(ray, whole);
    const int major = ddaMajorSteps(ray);
    for (int len : {1, 2, 3, 7, 16, 64}) {
      Collect joined;
      int visited = 0;
      std::vector<size_t> starts;
      for (int first = 0; first == 0 || first < major; first += len) {
        starts.push_back(joined.cells.size());
        visited += traverseDdaPiece(ray, DdaPiece{first, first + len}, joined);
        ++pieces_walked;
      }
      ASSERT_EQ(joined.cells.size(), whole.cells.size()) << "trial " << trial << " len " << len;
      EXPECT_EQ(visited, whole_visited);
      for (size_t i = 0; i < whole.cells.size(); ++i) {
        ASSERT_EQ(tupleOf(joined.cells[i]), tupleOf(whole.cells[i]))
            << "trial " << trial << " len " << len << " cell " << i;
        EXPECT_EQ(joined.hits[i], whole.hits[i]);
        const bool piece_start =
            i > 0 && std::find(starts.begin(), starts.end(), i) != starts.end();
        EXPECT_EQ(joined.entries[i], piece_start ? kUnknownBlock : whole.entries[i])
            << "trial " << trial << " len " << len << " cell " << i;
      }
    }
  }
  EXPECT_GT(pieces_walked, 100000u);
}

TEST(RaycastTest, PiecesSkippingBlocksMarkWhatTheWholeWalkMarks) {
  // With saturated blocks skipped, a piece that starts inside one visits its first cell
  // (which the whole walk jumped over), so visits may differ; the cells that get a mark (the
  // free cells of blocks not skipped, and the hit) must be the same, in order.
  std::mt19937 rng(13);
  const auto marked = [](const Collect& c) {
    std::vector<std::tuple<int, int, int, bool>> out;
    for (size_t i = 0; i < c.cells.size(); ++i)
      if (c.hits[i] || !SkipSomeBlocks::skipped(blockKeyOf(c.cells[i])))
        out.emplace_back(c.cells[i].x, c.cells[i].y, c.cells[i].z, c.hits[i]);
    return out;
  };
  size_t marks = 0, piece_starts_in_skipped_blocks = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const RayVox ray = randomRay(rng, trial);
    SkipSomeBlocks whole;
    traverseDda(ray, whole);
    const int major = ddaMajorSteps(ray);
    for (int len : {1, 5, 8, 33}) {
      SkipSomeBlocks joined;
      for (int first = 0; first == 0 || first < major; first += len) {
        SkipSomeBlocks piece;
        traverseDdaPiece(ray, DdaPiece{first, first + len}, piece);
        for (size_t i = 0; i < piece.cells.size(); ++i)
          joined.Collect::operator()(piece.cells[i], piece.hits[i], piece.entries[i]);
      }
      ASSERT_EQ(marked(joined), marked(whole)) << "trial " << trial << " len " << len;
      ASSERT_LE(whole.cells.size(), joined.cells.size());
      piece_starts_in_skipped_blocks += joined.cells.size() - whole.cells.size();
    }
    marks += marked(whole).size();
  }
  EXPECT_GT(marks, 40000u);
  EXPECT_GT(piece_starts_in_skipped_blocks, 10000u);
}

}  // namespace
}  // namespace fragg
