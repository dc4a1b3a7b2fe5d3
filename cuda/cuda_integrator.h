// Integration of one scan on the device (DESIGN §3): prepare -> window -> ray -> apply, over
// the blocks the device block cache makes resident. Visible host blocks of the window are
// uploaded up front, the window's other host blocks are marked host-only (a ray that needs
// one reports it and the pass is redone), new blocks are allocated by the rays themselves.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "cuda_array.h"
#include "cuda_stream.h"
#include "device_block_cache.h"
#include "device_scan.h"
#include "fragg_map/internal/backend.h"
#include "kernels.h"
#include "mirrored_buffer.h"
#include "window_table.h"

namespace fragg::cuda {

class CudaIntegrator {
 public:
  CudaIntegrator(cudaStream_t stream, DeviceBlockCache& cache, int sm_count, int host_threads);

  /// Integrates (or removes) the scan; false, with nothing changed, when its rays span more
  /// blocks than the window table holds (the caller runs it elsewhere).
  bool update(const ScanInput& scan, ScanUpdate what, const UpdateSettings& how, BlockMap& blocks,
              InsertStats& stats);
  size_t deviceBytes() const { return scan_.deviceBytes() + window_.deviceBytes(); }
  /// MapParams::dynamic: the points (sensor frame) of the last integrated scan classified
  /// dynamic, in cloud order (as the CPU backend lists them).
  const std::vector<Eigen::Vector3f>& lastDynamicPoints() const { return dynamic_points_S_; }
  /// DeviceScan::gatherAutoSensorStats() on the scan's buffers.
  AutoSensorStats gatherAutoSensorStats(const PointCloud& cloud, bool staged_ahead) {
    return scan_.gatherAutoSensorStats(cloud, staged_ahead);
  }

 private:
  /// Uploads the window's visible host blocks and returns the keys of its other host blocks.
  std::vector<BlockKey> makeWindowResident(const ScanInput& scan, double resolution_m,
                                           BlockMap& blocks, InsertStats& stats);
  /// Keys of the window's host blocks without a slot.
  std::vector<BlockKey> hostOnlyInWindow(const BlockMap& blocks);
  /// MapParams::dynamic: classifies the hits on the device before the ray pass (uploading the
  /// host-only blocks the tests read, `host_only` updated), makes the dynamic ones free-only and
  /// lists their points.
  void classifyDynamicHits(const ScanInput& scan, const UpdateSettings& how, BlockMap& blocks,
                           std::vector<BlockKey>& host_only, InsertStats& stats);
  /// The dynamic kernels' arguments for this scan's window and rule.
  DynamicPassArgs dynamicArgs(const UpdateSettings& how) const;
  /// Ray pass, touched list and apply until a pass runs without a miss or an overflow.
  /// Returns the number of blocks the rays created; counts the passes redone in `stats`.
  uint32_t rayAndApply(ScanUpdate what, const UpdateSettings& how, BlockMap& blocks,
                       std::vector<BlockKey> host_only, InsertStats& stats);
  /// DeviceScan::stageAhead(), skipped when the device has no room for it.
  void stageNext(const PointCloud& cloud, bool auto_stats);
  /// After a pass that missed host-only blocks or ran out of slots: uploads the missed blocks
  /// and makes room for the others. With `paging`: first reads back the missed blocks of
  /// paged-out regions and makes the budget's room for the overflowed blocks (both may page
  /// other regions out; InvalidArgument when the scan cannot fit).
  void resolveMissesAndOverflow(BlockMap& blocks, const DevicePaging* paging);
  int32_t expectedNewBlocks() const {
    return std::max<int32_t>(1024, last_created_ + last_created_ / 4);
  }

  cudaStream_t stream_;
  DeviceBlockCache& cache_;
  int sm_count_;
  DeviceScan scan_;
  WindowTable window_;
  CudaEvent ray_start_, apply_start_, apply_end_;
  CudaEvent pass_done_;  ///< the pass's counters are back (staging of the next cloud may follow)
  int32_t last_created_ = 0;  ///< blocks the rays created last scan (sizes the room made)
  /// Paging: the blocks the scan's passes missed so far (kept resident while it runs).
  std::vector<BlockKey> missed_this_scan_;
  // MapParams::dynamic.
  DeviceArray<uint8_t> dynamic_flags_;        ///< per ray: a dynamic hit
  MirroredBuffer<uint32_t> dynamic_indices_;  ///< point indices of the dynamic hits
  DeviceArray<uint64_t> void_bits_;           ///< 8 words a slot: its void cells this scan
  std::vector<Eigen::Vector3f> dynamic_points_S_;
};

}  // namespace fragg::cuda
