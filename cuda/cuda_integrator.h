// The CUDA backend (DESIGN §3): the host map stays the map; the blocks a scan needs live in a
// device pool of slots (a write-back cache). Per scan: cloud upload and preparation on the
// device; a window table block -> slot over the rays' box; visible host blocks uploaded in one
// batch, new blocks allocated by the rays themselves; ray pass; apply over touched slots.
#pragma once

#include <memory>
#include <vector>

#include "device_memory.h"
#include "device_types.h"
#include "fragg_map/internal/cpu_integrator.h"
#include "fragg_map/internal/integrator.h"
#include "host_only_index.h"
#include "slot_pool.h"

namespace fragg::cuda {

class CudaIntegrator : public Integrator {
 public:
  explicit CudaIntegrator(const MapParams& params);
  ~CudaIntegrator() override;

  void integrate(const ScanInput& scan, const MapParams& params, const OccupancyModel& model,
                 uint64_t revision, BlockMap& blocks, InsertStats& stats) override;
  const char* name() const override { return "cuda"; }
  bool cullsOnItsOwn() const override { return true; }
  void syncToHost(BlockMap& blocks) override;
  void dropDeviceCopies() override;
  size_t deviceBytes() const override;
  size_t deviceEstimateBytes() const override {
    return size_t(estimate_blocks_) * SlotPool::bytesPerSlot();
  }
  std::shared_ptr<ChunkAllocator> hostAllocator() const override { return host_allocator_; }

 private:
  void sizePool(const SensorModel& model, double resolution_m);
  int32_t slotLimit() const;
  /// Makes `want` slots free if it can, `need` or more in any case: grows the pool, else
  /// evicts least recently used slots (never one used by the current scan). Throws
  /// CudaOutOfMemory when fewer than `need` can be had.
  void makeRoom(int32_t need, int32_t want, BlockMap& blocks);
  void evict(int32_t n, BlockMap& blocks);
  /// Transfer buffers for a batch of `n` blocks (staging: through pinned staging memory).
  void reserveTransfer(size_t n, bool staging);
  void writeBack(const std::vector<int32_t>& slots, BlockMap& blocks);
  std::vector<int32_t> upload(const std::vector<BlockIndex>& host_blocks, BlockMap& blocks);
  void setWindowEntries(const std::vector<int64_t>& index, const std::vector<int32_t>& value);
  /// Window entries from the resident slots, then `host_only` marked kWindowHostOnly.
  void fillWindow(const std::vector<BlockIndex>& host_only, const BlockMap& blocks);
  /// Takes the slots the rays allocated as resident, device-only blocks; returns how many.
  uint32_t adoptDeviceSlots(int32_t new_free_top);
  int32_t slotOf(BlockIndex i) const { return i < slot_of_block_.size() ? slot_of_block_[i] : -1; }
  void setSlotOf(BlockIndex i, int32_t slot);
  bool prepareOnDevice(const ScanInput& scan, const MapParams& params, InsertStats& stats);
  void integrateOnCpu(const ScanInput& scan, const MapParams& params, const OccupancyModel& model,
                      uint64_t revision, BlockMap& blocks, InsertStats& stats, const char* why);

  MapParams params_;
  std::shared_ptr<ChunkAllocator> host_allocator_;
  bool direct_uploads_;  ///< host blocks pinned: the upload kernel reads them in place
  int device_;           ///< selected before the stream is made
  int sm_count_ = 0;
  CudaStream stream_;
  cudaEvent_t ray_start_ = nullptr, apply_start_ = nullptr, apply_end_ = nullptr;
  SlotPool pool_;
  CpuIntegrator cpu_;  ///< for scans whose window would not fit
  uint32_t scan_ = 0;
  int64_t estimate_blocks_ = 0;
  int32_t last_created_ = 0;
  bool any_dirty_ = false;
  uint64_t evicted_ = 0, uploaded_ = 0;

  // Host side of residency.
  std::vector<BlockIndex> block_of_slot_;  ///< kNoBlock: free, or created on the device only
  std::vector<int32_t> slot_of_block_;     ///< by host block index; -1 when not resident
  HostOnlyIndex host_only_;                ///< host blocks without a slot
  bool host_only_stale_ = true;            ///< rebuild before the next scan

  // Per-scan buffers.
  VoxelKey ref_;
  float start_v_[3] = {0, 0, 0};
  PinnedArray<float> points_host_;
  DeviceArray<float> points_dev_;
  DeviceArray<RayEnd> rays_dev_;
  PreparedScan host_prepared_;
  DeviceArray<ScanCounters> counters_dev_;
  PinnedArray<ScanCounters> counters_host_;
  DeviceArray<int32_t> window_dev_;
  Window window_;
  DeviceArray<int32_t> miss_dev_;
  PinnedArray<int32_t> miss_host_;

  // Transfer buffers.
  PinnedArray<Block> staging_host_;
  DeviceArray<Block> staging_dev_;
  PinnedArray<Block*> ptrs_host_;
  DeviceArray<Block*> ptrs_dev_;
  PinnedArray<int32_t> slots_host_;
  DeviceArray<int32_t> slots_dev_;
  PinnedArray<BlockKey> keys_host_;
  DeviceArray<BlockKey> keys_dev_;
  PinnedArray<uint64_t> changed_host_;
  DeviceArray<uint64_t> changed_dev_;
  PinnedArray<int64_t> widx_host_;
  DeviceArray<int64_t> widx_dev_;
  PinnedArray<int32_t> wval_host_;
  DeviceArray<int32_t> wval_dev_;
  PinnedArray<uint32_t> last_used_host_;
  PinnedArray<uint8_t> dirty_host_;
};

}  // namespace fragg::cuda
