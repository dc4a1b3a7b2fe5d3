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

TEST(PagingMemory, AResidentBlockCostsNoMoreThanTheBudgetCountsForIt) {
#ifdef __GLIBC__
  // Free memory the allocator kept from earlier tests goes back first: blocks made below
  // must touch (and so count) every page they use, not reuse resident free pages.
  malloc_trim(0);
#endif
  const size_t before = residentBytes();
  if (before == 0) GTEST_SKIP() << "no /proc/self/statm";
  // A ground-like slab of blocks (128 x 128 x 2: 512 superblocks of 8 x 8 x 2 blocks), the
  // shape of a LiDAR map's surface, each made the way a scan makes it (cells written).
  constexpr int32_t kSide = 128, kLayers = 2;
  constexpr size_t kBlocks = size_t{kSide} * kSide * kLayers;
  BlockMap blocks;
  for (int32_t z = 0; z < kLayers; ++z)
    for (int32_t y = 0; y < kSide; ++y)
      for (int32_t x = 0; x < kSide; ++x) blocks.findOrCreate({x - 64, y - 64, z});
  ASSERT_EQ(blocks.size(), kBlocks);
  const size_t grown = residentBytes() - before;
  const double per_block = static_cast<double>(grown) / kBlocks;
  // Measured what was meant: the cells and the per-block arrays are resident.
  EXPECT_GE(per_block, static_cast<double>(sizeof(Block) + sizeof(BlockMeta)));
  EXPECT_LE(per_block, static_cast<double>(Pager::residentBlockBytes()))
      << "a resident block costs " << per_block << " bytes, the budget counts "
      << Pager::residentBlockBytes();
  RecordProperty("resident_bytes_per_block", std::to_string(per_block));
}

}  // namespace
}  // namespace fragg::test
