#include "pinned_allocator.h"

#include "cuda_check.h"

namespace fragg::cuda {

namespace {
class PinnedChunkAllocator : public ChunkAllocator {
 public:
  void* allocate(size_t bytes) override {
    void* p = nullptr;
    FRAGG_CUDA_CHECK(cudaHostAlloc(&p, bytes, cudaHostAllocPortable));
    return p;
  }
  void deallocate(void* p, size_t) override { cudaFreeHost(p); }
  const char* name() const override { return "pinned"; }
};
}  // namespace

std::shared_ptr<ChunkAllocator> pinnedChunkAllocator() {
  return std::make_shared<PinnedChunkAllocator>();
}

}  // namespace fragg::cuda
