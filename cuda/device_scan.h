// One scan on the device: the cloud uploaded and prepared into rays (on the device, or on the
// host for organised clouds whose no-return rays need their neighbours), the scan's counters,
// and the list of host-only blocks its rays asked for.
#pragma once

#include <cstdint>
#include <vector>

#include "auto_stats_accum.h"
#include "cuda_array.h"
#include "device_types.h"
#include "fragg_map/internal/backend.h"
#include "fragg_map/internal/prepared_scan.h"
#include "fragg_map/internal/thread_count.h"
#include "mirrored_buffer.h"

namespace fragg::cuda {

class DeviceScan {
 public:
  /// `host_threads`: threads of the points' copy into pinned staging (0: every core).
  DeviceScan(cudaStream_t stream, int host_threads)
      : stream_(stream), threads_(threadCount(host_threads)) {
    counters_.reserve(1);
  }

  /// Prepares the scan's rays on the device and fills the point counters of `stats`; the
  /// counters start with the pool's free-stack top `free_top`.
  void prepare(const ScanInput& scan, const MapParams& params, int32_t free_top,
               InsertStats& stats);

  /// Uploads the cloud's points and gathers the auto sensor model's statistics on the device
  /// (the bits of gatherAutoSensorStats()). The upload is kept for this cloud's prepare()
  /// when the scan says so (ScanInput::cloud_staged). `staged_ahead`: the caller says this is
  /// the cloud stageAhead() staged, unchanged; with its statistics staged too, only waits.
  AutoSensorStats gatherAutoSensorStats(const PointCloud& cloud, bool staged_ahead);

  /// A batch's next cloud, while the device still works on this scan (its rays and prepared
  /// points are elsewhere): its points are copied into pinned staging on the host now and
  /// uploaded on the stream behind this scan's work, with the auto model's statistics when
  /// `auto_stats`. The next scan uses them as if gatherAutoSensorStats() had just run on it.
  void stageAhead(const PointCloud& cloud, bool auto_stats);

  ScanCounters& counters() const { return counters_[0]; }
  ScanCounters* countersOnDevice() const { return counters_.device(); }
  void countersToDevice() const { counters_.toDevice(1, stream_); }
  void countersToHost() const { counters_.toHost(1, stream_); }
  /// Blocks [lo, hi] the rays can touch (the sensor's cell included, one cell of margin).
  void rayBlockBox(BlockKey* lo, BlockKey* hi) const;

  /// Room in the miss list for `n` host-only blocks.
  void reserveMisses(size_t n) { misses_.reserve(std::max<size_t>(n, 1)); }
  uint32_t missCapacity() const { return static_cast<uint32_t>(misses_.size()); }
  int32_t* missList() const { return misses_.device(); }
  /// The first `n` listed misses (window indices).
  std::vector<int32_t> misses(uint32_t n) const;

  VoxelKey ref() const { return prepared_.ref; }
  const float* startV() const { return prepared_.start_v; }
  /// The sensor origin in float metres and 1 / resolution (RayCast::kOctomap's rays).
  const float* originM() const { return prepared_.origin_m; }
  double invRes() const { return prepared_.inv_res; }
  const RayEnd* rays() const { return rays_.get(); }
  /// The rays, to be changed in place (MapParams::dynamic makes dynamic hits free-only).
  RayEnd* mutableRays() { return rays_.get(); }
  /// MapParams::dynamic: the cloud index of each ray's point (device memory).
  const uint32_t* rayPoints() const { return ray_points_.get(); }
  /// RayCast::kOctomap: the rays end in float metres (rayEndCell).
  bool octomapKeys() const { return prepared_.octomap_keys; }
  size_t deviceBytes() const {
    return rays_.bytes() + ray_points_.bytes() + points_.deviceBytes() + free_only_.deviceBytes() +
           misses_.deviceBytes();
  }

 private:
  /// Organised clouds with no-return rays: prepared on the host, rays uploaded.
  void prepareOnHost(const ScanInput& scan, const MapParams& params, InsertStats& stats);
  /// The cloud's points into points_ (pinned host copy, then the device).
  void uploadPoints(const PointCloud& cloud);
  /// The auto model's statistics of the `n` uploaded points, on their way to auto_stats_.
  void launchStats(size_t n);

  cudaStream_t stream_;
  int threads_;
  PreparedScan prepared_;  ///< ref and start; the rays too when prepared on the host
  MirroredBuffer<float> points_;
  /// The cloud whose points gatherAutoSensorStats() left in points_ (its point array and
  /// size); prepare() uses them only for a scan marked cloud_staged, then forgets them.
  const void* staged_points_ = nullptr;
  size_t staged_size_ = 0;
  /// The staged points came from stageAhead() (InsertStats::scans_staged).
  bool staged_ahead_ = false;
  /// stageAhead() left the staged cloud's statistics on their way to auto_stats_.
  bool stats_ahead_ = false;
  MirroredBuffer<AutoStatsAccum> auto_stats_;
  MirroredBuffer<uint8_t> free_only_;  ///< PointCloud::free_only, when the cloud has flags
  DeviceArray<RayEnd> rays_;
  DeviceArray<uint32_t> ray_points_;  ///< MapParams::dynamic: each ray's point index
  MirroredBuffer<ScanCounters> counters_;
  MirroredBuffer<int32_t> misses_;
};

}  // namespace fragg::cuda
