// What the paging budget counts for a resident block (Pager::residentBlockBytes) against what a
// block costs the process: the resident memory a host map grows by, per block. The budget is
// meant to hold on the process's resident memory (issue 36), so a block must not cost more than
// it is counted.
#include <gtest/gtest.h>

#ifdef __GLIBC__
#include <malloc.h>
#endif
#include <unistd.h>

#include <fstream>

#include "fragg_map/block_map.h"
#include "fragg_map/internal/pager.h"

namespace fragg::test {
namespace {

/// The process's resident memory (/proc/self/statm); 0 when it cannot be read.
size_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  size_t size = 0, resident = 0;
  if (!(statm >> size >> resident)) return 0;
  return resident * static_cast<size_t>(sysconf(_SC_PAGESIZE));
}

/// A ground-like slab of blocks (128 x 128 x 2: 512 superblocks of 8 x 8 x 2 blocks), the
/// shape of a LiDAR map's surface, each made the way a scan makes it (cells written), into
/// `blocks` (its arrays reserved for `reserve` blocks first when not 0); returns the resident
/// memory the process grew by, per block (0 when it cannot be read).
double slabBytesPerBlock(BlockMap& blocks, size_t reserve) {
#ifdef __GLIBC__
  // Free memory the allocator kept from earlier tests goes back first: blocks made below
  // must touch (and so count) every page they use, not reuse resident free pages.
  malloc_trim(0);
#endif
  const size_t before = residentBytes();
  if (before == 0) return 0;
  constexpr int32_t kSide = 128, kLayers = 2;
  constexpr size_t kBlocks = size_t{kSide} * kSide * kLayers;
  if (reserve > 0) EXPECT_GE(blocks.reserveSlots(reserve), reserve);
  for (int32_t z = 0; z < kLayers; ++z)
    for (int32_t y = 0; y < kSide; ++y)
      for (int32_t x = 0; x < kSide; ++x) blocks.findOrCreate({x - 64, y - 64, z});
  EXPECT_EQ(blocks.size(), kBlocks);
  return static_cast<double>(residentBytes() - before) / kBlocks;
}

TEST(PagingMemory, AResidentBlockCostsNoMoreThanTheBudgetCountsForIt) {
  BlockMap blocks;
  const double per_block = slabBytesPerBlock(blocks, 0);
  if (per_block == 0) GTEST_SKIP() << "no /proc/self/statm";
  // Measured what was meant: the cells and the per-block arrays are resident.
  EXPECT_GE(per_block, static_cast<double>(sizeof(Block) + sizeof(BlockMeta)));
  EXPECT_LE(per_block, static_cast<double>(Pager::residentBlockBytes()))
      << "a resident block costs " << per_block << " bytes, the budget counts "
      << Pager::residentBlockBytes();
  RecordProperty("resident_bytes_per_block", std::to_string(per_block));
}

TEST(PagingMemory, ABlockOfAMapReservedForItsBudgetCostsNoMoreThanTheReservedFigure) {
  // The arrays sized once for the budget's blocks (as Pager::reserveSlots does; here exactly
  // the slab's count, so that the index's slots, written when it is sized, are all counted):
  // nothing grows, nothing is left behind.
  BlockMap blocks;
  const double per_block = slabBytesPerBlock(blocks, size_t{128} * 128 * 2);
  if (per_block == 0) GTEST_SKIP() << "no /proc/self/statm";
  EXPECT_GE(per_block, static_cast<double>(sizeof(Block) + sizeof(BlockMeta)));
  EXPECT_LE(per_block, static_cast<double>(Pager::reservedBlockBytes()))
      << "a resident block costs " << per_block << " bytes, the budget counts "
      << Pager::reservedBlockBytes();
  EXPECT_LT(Pager::reservedBlockBytes(), Pager::residentBlockBytes());
  RecordProperty("reserved_resident_bytes_per_block", std::to_string(per_block));
}

}  // namespace
}  // namespace fragg::test
