// The peer GPU mapper OHM (csiro-robotics/ohm, its CUDA GpuMap) behind a small interface, so that
// only ohm_engine.cpp sees OHM's and glm's headers. Built only when OHM_ROOT is given.
#pragma once

#include <memory>
#include <string>

#include "fragg_map/io/dataset.h"
#include "fragg_map/map.h"

namespace fragg::bench {

struct OhmOptions {
  double resolution_m = 0.05;
  double max_range_m = -1.0;  ///< longer rays are clipped to free-only rays; <= 0: no limit
  /// OctoMap's model (fragg's OccupancyParams: hit, miss, clamps; occupied at p >= 0.5) instead
  /// of OHM's own defaults.
  bool matched_model = true;
  OccupancyParams occupancy;
  size_t gpu_cache_mib = 8192;  ///< OHM's GPU layer cache (its own default: 1 GiB at most)
  double ray_segment_m = 0.0;   ///< GpuMap::setRaySegmentLength; 0 keeps OHM's default
  size_t expected_points = 200000;
  /// OHM's single-threaded CPU mapper (RayMapperOccupancy) instead of GpuMap: a check of the
  /// driver and of the map conversion on a machine without a GPU, not a speed figure.
  bool cpu = false;
};

/// Times of one scan: the whole call (rays to the map frame on the host, integrateRays, the
/// GPU queue finished) and the part from integrateRays on.
struct OhmScanTimes {
  double ms_total = 0;
  double ms_gpu = 0;
  size_t rays = 0;  ///< rays OHM accepted
};

class OhmEngine {
 public:
  /// An empty OHM map with a GpuMap on the first CUDA device (or the CPU mapper). Throws
  /// CudaError when OHM cannot use the GPU.
  explicit OhmEngine(const OhmOptions& options);
  ~OhmEngine();
  OhmEngine(const OhmEngine&) = delete;
  OhmEngine& operator=(const OhmEngine&) = delete;

  /// Integrates one scan: finite, non-zero points (as OctoMap's insertion takes them) moved to
  /// the map frame, one ray each from the sensor origin; returns once the GPU has finished, or
  /// with `wait` false as soon as OHM has queued the work (its own pipelining across calls).
  OhmScanTimes integrate(const Scan& scan, bool wait = true);

  /// Waits until the GPU has finished every queued integration.
  void finish();

  /// Writes the GPU cache back (GpuMap::syncVoxels) and returns the seconds it took.
  double syncToHost();

  /// OHM's observed cells as a fragg map (CPU backend, same resolution, the model of the
  /// options, unknown band 0): each cell keeps OHM's log-odds in fixed point, so that
  /// compareMaps with the OctoMap rule reads OHM's own occupied/free decision (value >= 0).
  /// Syncs first.
  Map toMap();

  /// OHM's occupancy model as used: "hit 0.7 miss 0.4 clamp [0.12, 0.97]".
  std::string describeModel() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace fragg::bench
