#include "window_table.h"

#include "kernels.h"

namespace fragg::cuda {

bool WindowTable::shape(const BlockKey& lo, const BlockKey& hi) {
  const int32_t l[3] = {lo.x, lo.y, lo.z}, h[3] = {hi.x, hi.y, hi.z};
  Window w;
  int64_t entries = 1;
  for (int a = 0; a < 3; ++a) {
    w.lo[a] = l[a];
    w.dim[a] = h[a] - l[a] + 1;
    entries *= w.dim[a];
  }
  if (entries > kMaxEntries) return false;
  entries_.reserve(size_t(entries));
  w.entries = entries_.get();
  window_ = w;
  return true;
}

void WindowTable::fill(const SlotArrays& slots, const std::vector<BlockKey>& host_only) {
  launchWindowFill(window_, slots, stream_);
  const size_t n = host_only.size();
  if (n == 0) return;
  entry_index_.reserve(n);
  entry_value_.reserve(n);
  for (size_t j = 0; j < n; ++j) {
    entry_index_[j] = window_.indexOf(host_only[j]);
    entry_value_[j] = kWindowHostOnly;
  }
  entry_index_.toDevice(n, stream_);
  entry_value_.toDevice(n, stream_);
  launchWindowSet(window_, entry_index_.device(), entry_value_.device(), uint32_t(n), stream_);
  FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));  // the pinned lists are reused
}

}  // namespace fragg::cuda
