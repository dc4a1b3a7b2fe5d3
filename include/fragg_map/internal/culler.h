// Host-side block culling: keeps the pose history that coherence needs and runs cullBlock()
// over the host map's blocks in the frustum's bounding box.
#pragma once

#include <Eigen/Geometry>
#include <vector>

#include "fragg_map/block_map.h"
#include "fragg_map/culling.h"
#include "fragg_map/frustum.h"
#include "fragg_map/map_params.h"
#include "fragg_map/sensor_model.h"

namespace fragg {

class Culler {
 public:
  explicit Culler(const CullingParams& params) : params_(params) {}

  /// Culls the blocks of `blocks` against `f` (built from `model` at `T_map_sensor`) and
  /// appends the visible ones to `visible` (when not null).
  CullCounters cull(const Frustum& f, const SensorModel& model,
                    const Eigen::Isometry3d& T_map_sensor, double resolution_m, BlockMap& blocks,
                    std::vector<BlockIndex>* visible);

  /// Starts a scan: records its pose for coherence and returns its context (what a backend
  /// that culls its own blocks needs). cull() calls it.
  CullContext beginScan(const Frustum& f, const SensorModel& model,
                        const Eigen::Isometry3d& T_map_sensor);

  /// Context for the current scan (also what a device-side culling pass would upload).
  CullContext context(const Frustum& f, const Eigen::Isometry3d& T_map_sensor) const;

  /// Forgets every past pose (after reset, load, or a change of sensor model).
  void reset();

 private:
  bool sameModel(const SensorModel& m) const;

  CullingParams params_;
  uint32_t scan_ = 0;
  bool have_model_ = false;
  SensorModel last_model_;
  struct PastSensorPose {
    bool valid = false;
    Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  };
  PastSensorPose history_[kMaxCoherenceTtl];  // indexed by scan % kMaxCoherenceTtl
};

}  // namespace fragg
