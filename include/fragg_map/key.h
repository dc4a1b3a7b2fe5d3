// Voxel and block keys: int32 per axis, key = floor(p / resolution). Blocks are 8^3 voxels.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>

#include "fragg_map/hd.h"

namespace fragg {

constexpr int kBlockBits = 3;
constexpr int kBlockSize = 1 << kBlockBits;  // voxels per block edge
constexpr int kBlockMask = kBlockSize - 1;
constexpr int kCellsPerBlock = kBlockSize * kBlockSize * kBlockSize;

struct VoxelKey {
  int32_t x = 0, y = 0, z = 0;
  FRAGG_HD bool operator==(const VoxelKey& o) const { return x == o.x && y == o.y && z == o.z; }
  FRAGG_HD bool operator!=(const VoxelKey& o) const { return !(*this == o); }
};

struct BlockKey {
  int32_t x = 0, y = 0, z = 0;
  FRAGG_HD bool operator==(const BlockKey& o) const { return x == o.x && y == o.y && z == o.z; }
  FRAGG_HD bool operator!=(const BlockKey& o) const { return !(*this == o); }
};

/// The centre of voxel index `k` along one axis, metres: (k + 0.5) * resolution, in double
/// (Map::centerOf per axis; the server's occupied cloud writes these as float).
FRAGG_HD double voxelCenterM(int32_t k, double resolution_m) {
  return (static_cast<double>(k) + 0.5) * resolution_m;
}

/// Block holding a voxel (floor division by 8, right for negative keys).
FRAGG_HD BlockKey blockKeyOf(const VoxelKey& v) {
  return {v.x >> kBlockBits, v.y >> kBlockBits, v.z >> kBlockBits};
}

/// Index of a voxel inside its block, x fastest.
FRAGG_HD int cellIndexOf(const VoxelKey& v) {
  return (v.x & kBlockMask) | ((v.y & kBlockMask) << kBlockBits) |
         ((v.z & kBlockMask) << (2 * kBlockBits));
}

/// Voxel key of cell `cell_index` in block `b`. (A multiplication, not `b.x << kBlockBits`:
/// shifting a negative value left is undefined in C++17, UBSan reports it; same code.)
FRAGG_HD VoxelKey voxelKeyOf(const BlockKey& b, int cell_index) {
  return {b.x * kBlockSize + (cell_index & kBlockMask),
          b.y * kBlockSize + ((cell_index >> kBlockBits) & kBlockMask),
          b.z * kBlockSize + ((cell_index >> (2 * kBlockBits)) & kBlockMask)};
}

/// The spatial hash of a block key (host and device): large odd multipliers (as in Teschner et
/// al. spatial hashing), mixed into 64 bits.
[[nodiscard]] FRAGG_HD uint64_t blockKeyHash64(const BlockKey& k) {
  uint64_t h = static_cast<uint64_t>(static_cast<uint32_t>(k.x)) * 73856093ULL;
  h ^= static_cast<uint64_t>(static_cast<uint32_t>(k.y)) * 19349669ULL << 21;
  h ^= static_cast<uint64_t>(static_cast<uint32_t>(k.z)) * 83492791ULL << 42;
  h ^= h >> 29;
  h *= 0xbf58476d1ce4e5b9ULL;
  return h ^ (h >> 32);
}

struct BlockKeyHash {
  size_t operator()(const BlockKey& k) const noexcept {
    return static_cast<size_t>(blockKeyHash64(k));
  }
};

struct VoxelKeyHash {
  size_t operator()(const VoxelKey& k) const noexcept {
    return BlockKeyHash()(BlockKey{k.x, k.y, k.z});
  }
};

}  // namespace fragg
