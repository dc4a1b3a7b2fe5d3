// A backend that integrates scans into the host map (CPU) or its device cache (CUDA).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <vector>

#include "fragg_map/block_map.h"
#include "fragg_map/culling.h"
#include "fragg_map/frustum.h"
#include "fragg_map/insert_stats.h"
#include "fragg_map/map_params.h"
#include "fragg_map/occupancy.h"
#include "fragg_map/point_cloud.h"
#include "fragg_map/sensor_model.h"

namespace fragg {

/// One scan as the map hands it to a backend (the sensor model is resolved, not auto).
struct ScanInput {
  const PointCloud& cloud;  ///< sensor frame
  const Eigen::Isometry3d& T_map_sensor;
  const SensorModel& model;
  const Frustum& frustum;
  bool explicit_model;
  const CullContext& cull;  ///< coherence context of this scan
  /// Loop closure: walk the same rays and undo the scan's updates (OccupancyModel::unapply)
  /// instead of applying them; blocks that do not exist are not created.
  bool remove = false;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  /// Ray casts the scan (each cell updated at most once, hit wins) and applies the updates
  /// (or undoes them when `scan.remove`),
  /// stamping changed blocks with `revision`. Fills the point and traversal counters and the
  /// prepare / ray cast / apply times of `stats`.
  virtual void integrate(const ScanInput& scan, const MapParams& params,
                         const OccupancyModel& model, uint64_t revision, BlockMap& blocks,
                         InsertStats& stats) = 0;
  virtual const char* name() const = 0;
  /// Whether the backend culls the blocks it needs itself (else the map's host culler runs
  /// over the host blocks in the frustum's box).
  virtual bool cullsOnItsOwn() const { return false; }
  /// Writes changes held on the device back into `blocks` (a write-back cache); after it the
  /// host map is complete. Cheap when nothing changed since the last call.
  virtual void syncToHost(BlockMap& blocks) { (void)blocks; }
  /// Forgets every device copy of a block, after syncToHost(), before the host map is
  /// changed directly (load, clear box, reset, import).
  virtual void dropDeviceCopies() {}
  virtual size_t deviceBytes() const { return 0; }
  /// The paper's formula (1): the sensor's visible volume in blocks, as device bytes.
  virtual size_t deviceEstimateBytes() const { return 0; }
  /// Where the host map's blocks are allocated (pinned memory for the CUDA backend).
  virtual std::shared_ptr<ChunkAllocator> hostAllocator() const { return plainChunkAllocator(); }
};

}  // namespace fragg
