// The window table (DESIGN §3 step 3): a dense int32 table block -> slot over the box of
// blocks a scan's rays can reach, so that a ray finds its block's slot with one load.
// Entries: a slot, kWindowEmpty (no block: a ray allocates one) or kWindowHostOnly.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "cuda_array.h"
#include "device_types.h"
#include "fragg_map/key.h"
#include "mirrored_buffer.h"

namespace fragg::cuda {

class WindowTable {
 public:
  /// Largest table (entries, 4 bytes each); a scan whose rays span more goes to the CPU.
  static constexpr int64_t kMaxEntries = int64_t(1) << 27;

  explicit WindowTable(cudaStream_t stream) : stream_(stream) {}

  /// Sets the table's box to blocks [lo, hi]; false (nothing changed) when it would hold
  /// more than kMaxEntries.
  bool shape(const BlockKey& lo, const BlockKey& hi);
  /// Every entry from the resident slots, then `host_only` keys marked kWindowHostOnly, then
  /// the empty entries of the `paged_out` boxes (regions with a paged-out block, each a box of
  /// the same edge) too. Returns how many entries may be kWindowHostOnly (at most).
  size_t fill(const SlotArrays& slots, const std::vector<BlockKey>& host_only,
              const std::vector<std::pair<BlockKey, BlockKey>>& paged_out = {});

  const Window& window() const { return window_; }
  BlockKey lo() const { return {window_.lo[0], window_.lo[1], window_.lo[2]}; }
  BlockKey hi() const {
    return {window_.lo[0] + window_.dim[0] - 1, window_.lo[1] + window_.dim[1] - 1,
            window_.lo[2] + window_.dim[2] - 1};
  }
  bool contains(const BlockKey& key) const { return window_.indexOf(key) >= 0; }
  size_t deviceBytes() const {
    return entries_.bytes() + entry_index_.deviceBytes() + entry_value_.deviceBytes() +
           box_first_.deviceBytes();
  }

 private:
  cudaStream_t stream_;
  Window window_;
  DeviceArray<int32_t> entries_;
  MirroredBuffer<int64_t> entry_index_;  ///< entries set after the fill ...
  MirroredBuffer<int32_t> entry_value_;  ///< ... and their values
  MirroredBuffer<BlockKey> box_first_;   ///< first blocks of the paged-out boxes
};

}  // namespace fragg::cuda
