#include "window_table.h"

#include <algorithm>

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

size_t WindowTable::fill(const SlotArrays& slots, const std::vector<BlockKey>& host_only,
                         const std::vector<std::pair<BlockKey, BlockKey>>& paged_out) {
  launchWindowFill(window_, slots, stream_);
  const size_t n = host_only.size();
  if (n > 0) {
    entry_index_.reserve(n);
    entry_value_.reserve(n);
    for (size_t j = 0; j < n; ++j) {
      entry_index_[j] = window_.indexOf(host_only[j]);
      entry_value_[j] = kWindowHostOnly;
    }
    entry_index_.toDevice(n, stream_);
    entry_value_.toDevice(n, stream_);
    launchWindowSet(window_, entry_index_.device(), entry_value_.device(), uint32_t(n), stream_);
  }
  size_t marked = n;
  const size_t boxes = paged_out.size();
  if (boxes > 0) {
    const int32_t edge = paged_out[0].second.x - paged_out[0].first.x + 1;
    box_first_.reserve(boxes);
    const BlockKey wlo = lo(), whi = hi();
    for (size_t j = 0; j < boxes; ++j) {
      const BlockKey &f = paged_out[j].first, &l = paged_out[j].second;
      if (l.x - f.x + 1 != edge || l.y - f.y + 1 != edge || l.z - f.z + 1 != edge)
        throw CudaError("paged-out regions of different sizes (paging bug)");
      box_first_[j] = f;
      // The box's entries inside the window.
      size_t inside = 1;
      const int32_t bf[3] = {f.x, f.y, f.z}, bl[3] = {l.x, l.y, l.z};
      const int32_t wl[3] = {wlo.x, wlo.y, wlo.z}, wh[3] = {whi.x, whi.y, whi.z};
      for (int a = 0; a < 3; ++a)
        inside *= size_t(std::max(0, std::min(bl[a], wh[a]) - std::max(bf[a], wl[a]) + 1));
      marked += inside;
    }
    box_first_.toDevice(boxes, stream_);
    launchWindowMarkBoxes(window_, box_first_.device(), uint32_t(boxes), edge, stream_);
  }
  if (n > 0 || boxes > 0)
    FRAGG_CUDA_CHECK(cudaStreamSynchronize(stream_));  // the pinned lists are reused
  return marked;
}

}  // namespace fragg::cuda
