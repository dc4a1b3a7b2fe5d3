// The scan store (DESIGN §5): every inserted scan, kept so that it can be removed and
// re-inserted with a corrected pose after a loop closure.
//
// Points are kept in the sensor frame, float32 as received by default (12 bytes a point), so
// that a map that keeps scans is the map of the received clouds (OctoMap's). As a memory
// option (`point_step_m` > 0) they are quantised to int16 at that step (6 bytes a point; a
// coarser step for a scan whose farthest point does not fit 16 bits at that step); the map then
// inserts the quantised cloud, so that a removal walks exactly the rays the insertion walked,
// and endpoints near a cell face can land in the neighbouring cell (at 1 mm and 5 cm cells
// 0.2-1.2 % of the cells differ from the map of the received points on real scans). Memory is
// bounded by `max_bytes`: beyond it the oldest scans' points go to `spill_dir` (read back when
// needed) or, without a spill folder, are dropped (that scan can no longer be removed or corrected;
// one warning).
#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "fragg_map/map_params.h"
#include "fragg_map/point_cloud.h"
#include "fragg_map/sensor_model.h"

namespace fragg {

/// A scan's insertion index over the map's life (0, 1, 2, ...).
using ScanId = uint64_t;
/// Longest frame id a kept scan records.
constexpr size_t kMaxSensorFrameChars = 1024;

/// Sensor-frame points as the store keeps them.
struct EncodedPoints {
  /// Metres per int16 unit; 0: the points are float32 as given (point_step_m = 0).
  double step_m = 0.0;
  uint32_t width = 0;
  uint32_t height = 1;
  uint64_t count = 0;
  /// count x 3 int16 (INT16_MIN triple = no return) or count x 3 float32.
  std::vector<uint8_t> data;

  size_t dataBytes() const { return count * (step_m > 0.0 ? 6 : 12); }
};

/// Quantises a cloud at `step_m` (0: float32 copy). Non-finite points (no return) are kept as
/// no-return markers; a point too far for 16 bits at the scan's step is moved along its ray to
/// the farthest representable distance (it lies beyond any useful range). `decoded`, when
/// given, receives decodePoints() of the result from the same pass.
EncodedPoints encodePoints(const PointCloud& cloud, double step_m, PointCloud* decoded = nullptr);
PointCloud decodePoints(const EncodedPoints& points);
/// The same into `out`, reusing its buffers (its free-only flags are cleared).
void decodePoints(const EncodedPoints& points, PointCloud* out);

/// How the scan was integrated: what a removal or a re-insertion must repeat exactly.
struct ScanRecord {
  ScanId id = 0;
  int64_t stamp_ns = 0;
  /// Frame id of the cloud (ROS: header.frame_id, no leading slash); empty when unknown.
  std::string sensor_frame;
  Eigen::Isometry3d T_map_sensor = Eigen::Isometry3d::Identity();
  SensorModel model;  ///< resolved (never auto), as integrated
  bool explicit_model = false;
  RayCast raycast = RayCast::kDda;
  bool clear_no_return_rays = false;
  bool free_cut_cell = false;  ///< MapParams::free_cut_cell when it was integrated
  uint64_t points = 0;         ///< points of the cloud
  /// False once cells the scan updated were changed by other means than scans (Map::clearBox,
  /// Map::writeCells): its removal would no longer undo its own updates.
  bool removable = true;
};

class ScanStore {
 public:
  explicit ScanStore(ScanStoreParams params = ScanStoreParams()) : params_(std::move(params)) {}
  /// Removes the spill files it wrote (a saved map holds every kept scan itself).
  ~ScanStore() { clear(); }
  ScanStore(const ScanStore&) = delete;
  ScanStore& operator=(const ScanStore&) = delete;

  const ScanStoreParams& params() const { return params_; }
  /// Keeps a scan (its id is the record's); enforces the memory budget.
  void add(const ScanRecord& record, EncodedPoints points);
  bool contains(ScanId id) const { return scans_.count(id) != 0; }
  const ScanRecord& record(ScanId id) const;  ///< throws InvalidArgument for an unknown id
  /// Whether the scan's points are still available (in memory or spilled).
  bool hasPoints(ScanId id) const;
  /// Whether the scan can be removed exactly: kept, points available, still removable.
  bool canRemove(ScanId id) const;
  void markUnremovable(ScanId id);
  /// The scan's points (read back from the spill folder if needed); throws InvalidArgument
  /// when they were dropped, IoError when a spill file is unreadable.
  EncodedPoints points(ScanId id) const;
  /// The scan's points where they are held in memory (no copy; valid until the store
  /// changes: add, erase, clear), else null.
  const EncodedPoints* pointsInMemory(ScanId id) const;
  void setPose(ScanId id, const Eigen::Isometry3d& T_map_sensor);
  void erase(ScanId id);
  void clear();

  size_t size() const { return scans_.size(); }
  std::vector<ScanId> ids() const;
  size_t memoryBytes() const { return memory_bytes_; }  ///< points held in memory
  size_t spilledCount() const;
  size_t droppedCount() const;

 private:
  enum class Where : uint8_t { kMemory, kSpilled, kDropped };
  struct Entry {
    ScanRecord record;
    Where where = Where::kMemory;
    EncodedPoints points;  ///< data empty unless kMemory
  };
  void enforceBudget();
  std::string spillPath(ScanId id) const;

  ScanStoreParams params_;
  std::map<ScanId, Entry> scans_;
  size_t memory_bytes_ = 0;
  bool warned_drop_ = false;
};

}  // namespace fragg
