// Host blocks in page-locked memory, so that the copy engines move them without staging.
#pragma once

#include <memory>

#include "fragg_map/block_map.h"

namespace fragg::cuda {

std::shared_ptr<ChunkAllocator> pinnedChunkAllocator();

}  // namespace fragg::cuda
