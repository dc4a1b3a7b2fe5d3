#include "fragg_map/map.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <string>

#include "fragg_map/errors.h"
#include "fragg_map/internal/auto_sensor.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/internal/cpu_backend.h"
#include "fragg_map/internal/culler.h"
#include "fragg_map/internal/frustum_builder.h"
#include "fragg_map/internal/height_filter.h"
#include "fragg_map/internal/host_view_gate.h"
#include "fragg_map/internal/no_return_beams.h"
#include "fragg_map/internal/pager.h"
#include "fragg_map/internal/reserve_headroom.h"
#include "fragg_map/internal/rigid_pose.h"
#include "fragg_map/log.h"

namespace fragg {

namespace {
const MapParams& validated(const MapParams& p) {
  p.validate();
  return p;
}

void validatePose(const Eigen::Isometry3d& T) { requireRigidPose(T, "sensor pose", 1e-4); }

/// Map::insert's argument checks (InvalidArgument).
void validateInsert(const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                    const SensorModel& sensor, const std::string& sensor_frame,
                    const MapParams& params) {
  validatePose(T_map_sensor);
  sensor.validate();
  if (sensor_frame.size() > kMaxSensorFrameChars)
    throw InvalidArgument("sensor frame id longer than " + std::to_string(kMaxSensorFrameChars) +
                          " characters");
  if (cloud.empty()) throw InvalidArgument("point cloud is empty");
  // A point left out of the height band would read as a beam with no return.
  if (params.height_filter.active() &&
      clearsBeamNoReturns(params.clear_no_return_rays, cloud, sensor))
    throw InvalidArgument(
        "clear_no_return_rays with a LiDAR beam table (sensor.lidar_rings) and an unorganised "
        "cloud cannot be combined with height_filter: give an organised cloud or no band");
  if (cloud.hasFreeOnly() && cloud.free_only.size() != cloud.size())
    throw InvalidArgument("point cloud has " + std::to_string(cloud.free_only.size()) +
                          " free-only flags for " + std::to_string(cloud.size()) + " points");
}

/// Blocks the scan's rays can reach: its points and sensor, within its max range of the sensor
/// (the whole range ball with no-return rays), widened by two cells.
void rayBlockBounds(const PointCloud& cloud, const ScanRecord& how, double resolution_m,
                    BlockKey* lo, BlockKey* hi) {
  const Eigen::Vector3d o = how.T_map_sensor.translation();
  const Eigen::Vector3d reach = Eigen::Vector3d::Constant(how.model.max_range_m + 2 * resolution_m);
  Eigen::Vector3d mn = o, mx = o;
  if (how.clear_no_return_rays && (cloud.organised() || !how.model.lidar_beams.empty())) {
    mn = o - reach;
    mx = o + reach;
  } else {
    const Eigen::Matrix3d R = how.T_map_sensor.linear();
    for (const Eigen::Vector3f& p : cloud.points_S) {
      if (!p.allFinite()) continue;
      const Eigen::Vector3d q = R * p.cast<double>() + o;
      mn = mn.cwiseMin(q);
      mx = mx.cwiseMax(q);
    }
    mn = (mn.array() - 2 * resolution_m).max((o - reach).array()).matrix();
    mx = (mx.array() + 2 * resolution_m).min((o + reach).array()).matrix();
  }
  auto blockOf = [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d v =
        (p / resolution_m).array().floor().cwiseMax(-2147483648.0).cwiseMin(2147483647.0);
    return blockKeyOf(VoxelKey{static_cast<int32_t>(v.x()), static_cast<int32_t>(v.y()),
                               static_cast<int32_t>(v.z())});
  };
  *lo = blockOf(mn);
  *hi = blockOf(mx);
}

double farthestPoint(const PointCloud& cloud) {
  double r2 = 0.0;
  for (const auto& p : cloud.points_S)
    if (p.allFinite()) r2 = std::max(r2, static_cast<double>(p.squaredNorm()));
  return std::max(1.0, std::ceil(std::sqrt(r2)));
}
}  // namespace

void Map::bumpViewEpoch() {
  static std::atomic<uint64_t> counter{0};
  view_epoch_ = ++counter;
}

Map::Map(const MapParams& params)
    : params_(validated(params)), model_(OccupancyModel::fromParams(params.occupancy)) {
  bumpViewEpoch();
  BackendChoice choice = makeBackend(params_);
  backend_ = std::move(choice.backend);
  backend_reason_ = std::move(choice.reason);
  blocks_ = BlockMap(backend_->hostAllocator());
  sync_mutex_ = std::make_unique<std::mutex>();
  host_view_gate_ = std::make_shared<HostViewGate>();
  view_mutex_ = std::make_unique<std::mutex>();
  culler_ = std::make_unique<Culler>(params_.culling);
  scan_store_ = std::make_unique<ScanStore>(params_.scans);
}

Map::~Map() { closePaging(); }
Map::Map(Map&&) noexcept = default;
Map& Map::operator=(Map&& other) noexcept {
  if (this != &other) closePaging();  // this map's store gets its last commit
  params_ = std::move(other.params_);
  model_ = std::move(other.model_);
  backend_ = std::move(other.backend_);
  backend_reason_ = std::move(other.backend_reason_);
  blocks_ = std::move(other.blocks_);
  sync_mutex_ = std::move(other.sync_mutex_);
  host_view_gate_ = std::move(other.host_view_gate_);
  view_mutex_ = std::move(other.view_mutex_);
  culler_ = std::move(other.culler_);
  revision_ = other.revision_;
  view_epoch_ = other.view_epoch_;
  scans_ = other.scans_;
  next_scan_id_ = other.next_scan_id_;
  scan_store_ = std::move(other.scan_store_);
  region_ = std::move(other.region_);
  pager_ = std::move(other.pager_);
  return *this;
}

InsertStats Map::insert(const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                        const SensorModel& sensor, int64_t stamp_ns,
                        const std::string& sensor_frame) {
  validateInsert(cloud, T_map_sensor, sensor, sensor_frame, params_);
  return insertChecked(cloud, T_map_sensor, sensor, stamp_ns, sensor_frame, false, nullptr);
}

const std::vector<Eigen::Vector3f>& Map::lastDynamicPoints_S() const {
  return backend_->lastDynamicPoints();
}

std::vector<InsertStats> Map::insertSequence(const std::vector<ScanToInsert>& scans) {
  for (size_t i = 0; i < scans.size(); ++i) {
    const ScanToInsert& s = scans[i];
    try {
      if (!s.cloud) throw InvalidArgument("no point cloud");
      validateInsert(*s.cloud, s.T_map_sensor, s.sensor, s.sensor_frame, params_);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("scan " + std::to_string(i) + " of the sequence: " + e.what());
    }
  }
  // The next cloud can be staged only when it is the cloud the map integrates.
  const bool stageable =
      !params_.height_filter.active() && !(params_.scans.keep && params_.scans.point_step_m > 0.0);
  std::vector<InsertStats> out;
  out.reserve(scans.size());
  for (size_t i = 0; i < scans.size(); ++i) {
    const ScanToInsert& s = scans[i];
    const ScanToInsert* next = stageable && i + 1 < scans.size() ? &scans[i + 1] : nullptr;
    out.push_back(insertChecked(*s.cloud, s.T_map_sensor, s.sensor, s.stamp_ns, s.sensor_frame,
                                stageable && i > 0, next));
  }
  return out;
}

InsertStats Map::insertChecked(const PointCloud& cloud, const Eigen::Isometry3d& T_map_sensor,
                               const SensorModel& sensor, int64_t stamp_ns,
                               const std::string& sensor_frame, bool staged_ahead,
                               const ScanToInsert* next) {
  const auto t0 = std::chrono::steady_clock::now();
  // The height band first: a kept scan holds the points that were integrated.
  const bool by_height = params_.height_filter.active();
  const bool beam_no_returns = clearsBeamNoReturns(params_.clear_no_return_rays, cloud, sensor);
  PointCloud in_band;
  const uint64_t dropped_height =
      by_height ? filterHeight(cloud, T_map_sensor, params_.height_filter, &in_band) : 0;
  const PointCloud& filtered = by_height ? in_band : cloud;
  const bool keep = params_.scans.keep;
  // A kept scan is integrated as it is kept, so that its removal is exact: float32 points
  // (point_step_m = 0) are the cloud itself; quantised ones are integrated quantised.
  EncodedPoints kept;
  PointCloud quantised;
  const bool quantise = keep && params_.scans.point_step_m > 0.0;
  if (keep)
    kept = encodePoints(filtered, params_.scans.point_step_m, quantise ? &quantised : nullptr);
  if (quantise) quantised.free_only = filtered.free_only;
  const PointCloud& used = quantise ? quantised : filtered;

  ScanRecord how;
  how.id = next_scan_id_;
  how.stamp_ns = stamp_ns;
  how.sensor_frame = sensor_frame;
  how.T_map_sensor = T_map_sensor;
  how.explicit_model = sensor.type != SensorType::kAuto;
  bool staged = false;  // the backend gathered the auto model's statistics (and kept the cloud)
  if (how.explicit_model) {
    how.model = sensor;
  } else {
    AutoSensorStats auto_stats;
    staged = backend_->autoSensorStats(used, &auto_stats, staged_ahead);
    if (!staged) auto_stats = gatherAutoSensorStats(used);
    how.model = resolveAutoSensor(sensor, used, auto_stats);
  }
  if (how.model.max_range_m <= 0.0) how.model.max_range_m = farthestPoint(used);
  how.raycast = params_.raycast;
  how.clear_no_return_rays = params_.clear_no_return_rays;
  how.free_cut_cell = params_.free_cut_cell;
  const double seconds_model =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // insertSequence passes `next` only when `used` is the caller's cloud (no band, no quantising).
  const PointCloud* stage_next = next ? next->cloud : nullptr;
  InsertStats stats =
      integrateScan(used, how, /*remove=*/false, /*host_cull=*/true, staged || staged_ahead,
                    stage_next, stage_next && next->sensor.type == SensorType::kAuto);
  stats.seconds_cull += seconds_model;
  if (keep) {
    // The store keeps points, not free-only flags: such a scan cannot be walked again.
    if (std::any_of(filtered.free_only.begin(), filtered.free_only.end(),
                    [](uint8_t f) { return f != 0; }))
      how.removable = false;
    // Nor the beam table its no-return rays came from.
    if (beam_no_returns) how.removable = false;
    scan_store_->add(how, std::move(kept));
  }
  ++next_scan_id_;
  ++scans_;
  stats.scan_id = how.id;
  stats.sensor = how.model;
  // Dropped by height: left out of an unorganised cloud, (0,0,0) pixels (counted invalid by
  // the integrator) in an organised one.
  stats.dropped_height = dropped_height;
  if (filtered.organised())
    stats.dropped_invalid -= std::min<uint64_t>(stats.dropped_invalid, dropped_height);
  else
    stats.points_in += dropped_height;
  if (pager_) pageAfterScan(T_map_sensor.translation());
  stats.seconds_total =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

InsertStats Map::integrateScan(const PointCloud& cloud, const ScanRecord& how, bool remove,
                               bool host_cull, bool cloud_staged, const PointCloud* stage_next,
                               bool stage_next_auto_stats) {
  const auto t = std::chrono::steady_clock::now();  // frustum and culling
  MapParams params = params_;
  params.raycast = how.raycast;
  params.clear_no_return_rays = how.clear_no_return_rays;
  params.free_cut_cell = how.free_cut_cell;
  InsertStats stats;
  PageInKeys page_in, page_in_around;
  PagedOutSaturated paged_out_saturated;
  DevicePaging device_paging;  // set for a backend that reports the blocks its rays reach
  size_t device_read = 0;
  BlockKey lo, hi;  // the rays' block box (paging)
  if (pager_) {
    // Every block the rays can reach is resident before the backend creates one: the CPU
    // backend asks for exactly the blocks its rays mark, the CUDA backend for the blocks its
    // rays reach; any other backend (and a removal, which creates none) gets the scan's whole
    // box first.
    rayBlockBounds(cloud, how, params_.resolution_m, &lo, &hi);
    const bool reports = backend_->reportsReachedBlocks();
    if (!remove && (backend_->pagesInMarkedBlocks() || reports)) {
      pager_->touch(lo, hi, scans_ + 1);
      page_in = [this](const std::vector<BlockKey>& keys) { pageInKeys(keys); };
      if (params_.dynamic.enabled)
        page_in_around = [this](const std::vector<BlockKey>& keys) {
          pageInKeysAndNeighbours(keys);
        };
      const Pager* pager = pager_.get();
      paged_out_saturated = [pager](const BlockKey& key) {
        return pager->isPagedOutSaturated(key);
      };
      if (reports) device_paging = devicePaging(&device_read);
    } else {
      pageInBlocks(lo, hi);
    }
  }
  const Frustum frustum = buildFrustum(how.model, how.T_map_sensor, params_.resolution_m);
  CullContext cull;
  if (backend_->cullsOnItsOwn()) {
    cull = culler_->beginScan(frustum, how.model, how.T_map_sensor);
  } else if (!host_cull) {
    // The CPU backend's rays do not depend on culling: it only counts (InsertStats::culling).
    // Corrections skip it; their scans are not part of the sensor's motion either.
    cull = culler_->context(frustum, how.T_map_sensor);
  } else {
    stats.culling =
        culler_->cull(frustum, how.model, how.T_map_sensor, params_.resolution_m, blocks_, nullptr);
    cull = culler_->context(frustum, how.T_map_sensor);
  }
  stats.seconds_cull = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();

  const ScanInput scan{cloud, how.T_map_sensor, how.model, frustum, how.explicit_model,
                       cull,  cloud_staged};
  UpdateSettings settings{params, model_, revision_ + 1, page_in ? &page_in : nullptr,
                          page_in ? &paged_out_saturated : nullptr};
  if (device_paging.make_room) settings.device_paging = &device_paging;
  if (page_in_around) settings.page_in_around = &page_in_around;
  settings.stage_next = stage_next;
  settings.stage_next_auto_stats = stage_next_auto_stats;
  const ScanUpdate what = remove ? ScanUpdate::kRemove : ScanUpdate::kIntegrate;
  // Readers may be writing the cache back (they share the map): not while the scan runs.
  std::lock_guard<std::mutex> lock(*sync_mutex_);
  auto run = [&](InsertStats& into) {
    if (what == ScanUpdate::kRemove)
      backend_->remove(scan, settings, blocks_, into);
    else
      backend_->integrate(scan, settings, blocks_, into);
  };
  try {
    // The regions the device's rays pass through are paged in before its pass (the misses
    // that redo it are then rare), as the CPU backend pages in what its rays mark.
    if (settings.device_paging) pageInAhead(cloud, how, lo, hi, &device_read);
    run(stats);
  } catch (const CudaOutOfMemory& e) {
    // The device backend applies a scan all at once or not at all: the map is intact.
    fallBackToCpu(e.what());
    settings.device_paging = nullptr;  // the CPU backend pages in what its rays mark
    InsertStats cpu_stats;
    cpu_stats.culling = stats.culling;
    cpu_stats.seconds_cull = stats.seconds_cull;
    run(cpu_stats);
    stats = cpu_stats;
  }
  // The room the next scan makes ahead (Map::pageAfterScan), as the CPU backend's page-in notes.
  if (settings.device_paging) pager_->noteScanIncoming(device_read + stats.blocks_created);
  ++revision_;
  stats.seconds_total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  return stats;
}

void Map::requireRemovable(ScanId id) const {
  if (!params_.scans.keep && scan_store_->size() == 0)
    throw InvalidArgument("this map keeps no scans (scans.keep was off when they were inserted)");
  if (!scan_store_->record(id).removable)  // record() throws for an unknown index
    throw InvalidArgument("scan " + std::to_string(id) +
                          " can no longer be removed exactly: a clear box (or a direct edit of "
                          "the map) changed cells it had updated");
}

void Map::markScansWhere(
    const std::function<bool(const Eigen::Vector3d& origin_map, double reach_m)>& reaches) {
  for (ScanId id : scan_store_->ids()) {
    const ScanRecord& r = scan_store_->record(id);
    // The scan's rays stay within max range of its sensor (plus a cell's diagonal margin).
    const double reach = r.model.max_range_m + 2.0 * params_.resolution_m;
    if (reaches(r.T_map_sensor.translation(), reach)) scan_store_->markUnremovable(id);
  }
}

void Map::markScansTouching(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map) {
  // A box around the sphere the rays stay in, against the box.
  markScansWhere([&](const Eigen::Vector3d& o, double reach) {
    return (o.array() + reach >= min_map.array()).all() &&
           (o.array() - reach <= max_map.array()).all();
  });
}

InsertStats Map::remove(ScanId id) {
  const auto t0 = std::chrono::steady_clock::now();
  requireRemovable(id);
  const ScanRecord how = scan_store_->record(id);
  PointCloud cloud;
  if (const EncodedPoints* in_memory = scan_store_->pointsInMemory(id))
    decodePoints(*in_memory, &cloud);
  else
    decodePoints(scan_store_->points(id), &cloud);  // spilled: read back
  InsertStats stats = integrateScan(cloud, how, /*remove=*/true, /*host_cull=*/false);
  scan_store_->erase(id);
  if (scans_ > 0) --scans_;
  if (pager_) pageAfterScan(how.T_map_sensor.translation());
  stats.scan_id = id;
  stats.sensor = how.model;
  stats.seconds_total =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

CorrectionStats Map::correctPoses(const std::map<ScanId, Eigen::Isometry3d>& T_map_sensor_new) {
  const auto t0 = std::chrono::steady_clock::now();
  // Everything is checked (and spilled points read) before the map changes; points held in
  // memory are decoded in place (setPose changes records only).
  std::vector<EncodedPoints> read_back;
  read_back.reserve(T_map_sensor_new.size());
  std::vector<const EncodedPoints*> points;
  for (const auto& [id, T] : T_map_sensor_new) {
    requireRemovable(id);
    try {
      validatePose(T);
    } catch (const InvalidArgument& e) {
      throw InvalidArgument("scan " + std::to_string(id) + ": " + e.what());
    }
    const EncodedPoints* in_memory = scan_store_->pointsInMemory(id);
    if (!in_memory) read_back.push_back(scan_store_->points(id));
    points.push_back(in_memory ? in_memory : &read_back.back());
  }
  CorrectionStats out;
  out.scans = T_map_sensor_new.size();
  std::vector<std::pair<ScanId, Eigen::Isometry3d>> moves(T_map_sensor_new.begin(),
                                                          T_map_sensor_new.end());
  // Every removal, then every insertion: 2n steps, each scan's points decoded once per pass
  // (once in all for a single scan). The backend stages the next step's cloud while it works
  // on the current one (UpdateSettings::stage_next).
  const size_t n = moves.size(), steps = 2 * n;
  PointCloud cloud, following;
  if (n > 0) decodePoints(*points[0], &cloud);
  for (size_t step = 0; step < steps; ++step) {
    const size_t k = step % n;
    const bool last = step + 1 == steps;
    const bool same_next = !last && (step + 1) % n == k;  // one scan: its insertion follows
    if (!last && !same_next) decodePoints(*points[(step + 1) % n], &following);
    const PointCloud* stage = last ? nullptr : same_next ? &cloud : &following;
    const bool removal = step < n;
    if (!removal) scan_store_->setPose(moves[k].first, moves[k].second);
    const InsertStats s = integrateScan(cloud, scan_store_->record(moves[k].first), removal, false,
                                        /*cloud_staged=*/step > 0, stage);
    (removal ? out.removal : out.insertion).add(s);
    if (!last && !same_next) std::swap(cloud, following);
  }
  out.seconds_total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

VoxelKey Map::keyOf(const Eigen::Vector3d& p_map) const {
  const Eigen::Vector3d v = p_map / params_.resolution_m;
  if (!v.allFinite() || v.cwiseAbs().maxCoeff() >= 2147483647.0)
    throw InvalidArgument("point is outside the map's key range");
  return {static_cast<int32_t>(std::floor(v.x())), static_cast<int32_t>(std::floor(v.y())),
          static_cast<int32_t>(std::floor(v.z()))};
}

Eigen::Vector3d Map::centerOf(const VoxelKey& key) const {
  const double r = params_.resolution_m;
  return {voxelCenterM(key.x, r), voxelCenterM(key.y, r), voxelCenterM(key.z, r)};
}

void Map::fallBackToCpu(const std::string& why) {
  backend_->cache().invalidateAll(blocks_);
  backend_ = std::make_unique<CpuBackend>(params_.threads);
  backend_reason_ = "cpu: fell back from CUDA (" + why + ")";
  logMessage(LogLevel::kWarning, "GPU memory exhausted, continuing on the CPU backend: " + why);
}

CellState Map::query(const Eigen::Vector3d& p_map) const {
  const Cell* c = findCell(keyOf(p_map));
  return c ? model_.state(*c) : CellState::kUnknown;
}

const Cell* Map::findCell(const VoxelKey& key) const { return hostBlocks().findCell(key); }

CellState Map::query(const Eigen::Vector3d& p_map) {
  const Cell* c = findCell(keyOf(p_map));
  return c ? model_.state(*c) : CellState::kUnknown;
}

const Cell* Map::findCell(const VoxelKey& key) {
  if (pager_) pageInBlocks(blockKeyOf(key), blockKeyOf(key));
  return hostBlocks().findCell(key);
}

std::vector<BlockIndex> Map::beginBoxEdit(const Eigen::Vector3d& min_map,
                                          const Eigen::Vector3d& max_map, VoxelKey* lo,
                                          VoxelKey* hi) {
  if (!min_map.allFinite() || !max_map.allFinite())
    throw InvalidArgument("clear box corners must be finite");
  if ((min_map.array() > max_map.array()).any())
    throw InvalidArgument("clear box min corner must not exceed the max corner");
  *lo = keyOf(min_map);
  *hi = keyOf(max_map);
  const BlockKey blo = blockKeyOf(*lo), bhi = blockKeyOf(*hi);
  pageInBlocks(blo, bhi);
  backend_->cache().invalidate(blo, bhi, blocks_);
  markScansTouching(min_map, max_map);
  std::vector<BlockIndex> hit;
  blocks_.forEachInBox(blo, bhi, [&](BlockIndex i) { hit.push_back(i); });
  ++revision_;
  return hit;
}

void Map::clearBox(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map) {
  VoxelKey lo, hi;
  const std::vector<BlockIndex> hit = beginBoxEdit(min_map, max_map, &lo, &hi);
  clearCellsWhere(hit, [&](const VoxelKey& v) {
    return v.x >= lo.x && v.x <= hi.x && v.y >= lo.y && v.y <= hi.y && v.z >= lo.z && v.z <= hi.z;
  });
}

uint64_t Map::freeBox(const Eigen::Vector3d& min_map, const Eigen::Vector3d& max_map) {
  VoxelKey lo, hi;
  const std::vector<BlockIndex> hit = beginBoxEdit(min_map, max_map, &lo, &hi);
  const int16_t free_fx = model_.min_fx;
  uint64_t set = 0;
  for (BlockIndex i : hit) {
    const BlockKey key = blocks_.meta(i).key;
    Block& b = blocks_.block(i);
    BlockStateMasks& masks = blocks_.masks(i);  // kept current, as every writer does
    const BlockStateMasks masks_before = masks;
    bool changed = false, occupied_changed = false, state_changed = false;
    for (int c = 0; c < kCellsPerBlock; ++c) {
      Cell& cell = b.cells[c];
      if (!cell.observed()) continue;
      const VoxelKey v = voxelKeyOf(key, c);
      if (v.x < lo.x || v.x > hi.x || v.y < lo.y || v.y > hi.y || v.z < lo.z || v.z > hi.z)
        continue;
      ++set;
      if (cell.log_odds_fx == free_fx) continue;
      Cell freed = cell;
      freed.log_odds_fx = free_fx;
      occupied_changed |= model_.state(cell) == CellState::kOccupied;
      state_changed |= model_.stateDiffers(cell, freed);
      cell = freed;
      masks.set(c, model_.state(freed));
      changed = true;
    }
    if (!changed) continue;
    BlockMeta& m = blocks_.meta(i);
    m.changed_at = revision_;  // also ends free_saturated_at's claim
    if (occupied_changed) m.occupied_at = revision_;
    if (state_changed) m.state_at = revision_;
    if (masks != masks_before) blocks_.noteMasksChanged(i, revision_);
  }
  return set;
}

uint64_t Map::clearCellsWhere(const std::vector<BlockIndex>& blocks,
                              const std::function<bool(const VoxelKey&)>& inside,
                              uint64_t* blocks_erased) {
  uint64_t cleared = 0;
  for (BlockIndex i : blocks) {
    const BlockKey key = blocks_.meta(i).key;
    Block& b = blocks_.block(i);
    BlockStateMasks& masks = blocks_.masks(i);
    const BlockStateMasks masks_before = masks;
    bool any_left = false, any_cleared = false;
    for (int c = 0; c < kCellsPerBlock; ++c) {
      if (inside(voxelKeyOf(key, c))) {
        any_cleared |= b.cells[c].observed();
        cleared += b.cells[c].observed() ? 1 : 0;
        b.cells[c] = Cell();
        masks.set(c, CellState::kUnknown);
      } else {
        any_left |= b.cells[c].observed();
      }
    }
    if (any_left) {
      // Only blocks that lost a cell are listed by changedBlocksSince.
      if (any_cleared) {
        BlockMeta& m = blocks_.meta(i);
        m.changed_at = m.occupied_at = m.state_at = revision_;
        if (masks != masks_before) blocks_.noteMasksChanged(i, revision_);
      }
    } else {
      blocks_.erase(key);
      if (pager_) pager_->noteErased(key);
      bumpViewEpoch();
      if (blocks_erased) ++*blocks_erased;
    }
  }
  return cleared;
}

void Map::writeCells(const std::function<void(CellWriter&)>& edit) {
  for (ScanId id : scan_store_->ids()) scan_store_->markUnremovable(id);
  pageInAllBlocks();  // the edit may write anywhere
  backend_->cache().invalidateAll(blocks_);
  ++revision_;
  CellWriter writer(blocks_, model_, revision_);
  edit(writer);
}

void Map::reset() {
  backend_->cache().invalidateAll(blocks_);
  if (pager_) pager_->forgetAll(blocks_);
  blocks_.clear();
  culler_->reset();
  scan_store_->clear();
  ++revision_;
  bumpViewEpoch();
  scans_ = 0;
  next_scan_id_ = 0;
}

void Map::writeBack() const {
  {
    std::lock_guard<std::mutex> lock(*sync_mutex_);
    if (!backend_->cache().needsSync()) return;
  }
  // Once no hostBlockView() is read (sync_mutex_ is not held while waiting for them: a reader
  // holding a view may take it, e.g. deviceChangesPending()).
  host_view_gate_->exclusive([&] {
    std::lock_guard<std::mutex> lock(*sync_mutex_);
    backend_->cache().sync(blocks_);
  });
}

const BlockMap& Map::hostBlocks() const {
  writeBack();
  return blocks_;
}

BlockView Map::hostBlockView() const {
  // No reader writes back while the view lives (the insertion, which writes blocks_ under
  // sync_mutex_, runs under the map's write lock: never beside a reader).
  return BlockView(blocks_, host_view_gate_->pin());
}

bool Map::deviceChangesPending() const {
  std::lock_guard<std::mutex> lock(*sync_mutex_);
  return backend_->cache().needsSync();
}

bool Map::writeBackSome(size_t max_blocks) {
  bool more = false;
  host_view_gate_->exclusive([&] {
    std::lock_guard<std::mutex> lock(*sync_mutex_);
    more = backend_->cache().syncSome(blocks_, max_blocks);
  });
  return more;
}

const char* Map::backendName() const { return backend_->name(); }

bool Map::masksChangedSince(uint64_t revision, std::vector<BlockKey>* keys,
                            std::vector<BlockStateMasks>* masks) const {
  std::lock_guard<std::mutex> lock(*sync_mutex_);
  std::vector<BlockIndex> host;
  if (!blocks_.masksChangedSince(revision, &host)) return false;
  // The backend's copies are the newer ones; the host's serve the blocks it holds no longer.
  // Written into the caller's vectors (a reader that keeps them reuses their pages).
  keys->clear();
  masks->clear();
  backend_->masksChangedSince(revision, keys, masks);
  BlockKeyTable listed;  // the device's keys, where the host lists blocks too
  if (!keys->empty() && !host.empty()) {
    listed.reserve(keys->size() + host.size());
    for (uint32_t i = 0; i < keys->size(); ++i) listed.insert((*keys)[i], i);
  }
  if (keys->empty()) {  // every changed block is on the host (a CPU map): copied in parallel
    const int64_t n = static_cast<int64_t>(host.size());
    reserveWithHeadroom(keys, host.size());
    reserveWithHeadroom(masks, host.size());
    keys->resize(host.size());
    masks->resize(host.size());
#pragma omp parallel for schedule(static) if (n > 4096)
    for (int64_t j = 0; j < n; ++j) {
      (*keys)[j] = blocks_.meta(host[j]).key;
      (*masks)[j] = blocks_.masks(host[j]);
    }
    return true;
  }
  reserveWithHeadroom(keys, keys->size() + host.size());
  reserveWithHeadroom(masks, masks->size() + host.size());
  for (const BlockIndex b : host) {
    const BlockKey& k = blocks_.meta(b).key;
    if (listed.size() != 0 && listed.find(k) != BlockKeyTable::kNone) continue;
    keys->push_back(k);
    masks->push_back(blocks_.masks(b));
  }
  return true;
}

std::unique_ptr<DeviceViewLease> Map::deviceView(const std::vector<BlockKey>& keys) const {
  ViewScope scope;
  scope.keys = &keys;
  return deviceViewOf(scope);
}

std::unique_ptr<DeviceViewLease> Map::deviceView(const BlockKey& lo, const BlockKey& hi) const {
  ViewScope scope;
  scope.lo = lo;
  scope.hi = hi;
  return deviceViewOf(scope);
}

std::unique_ptr<DeviceViewLease> Map::deviceViewOf(const ViewScope& scope) const {
  std::unique_lock<std::mutex> view_lock(*view_mutex_);
  DeviceLayerView view;
  DeviceScratch* scratch = nullptr;
  {
    std::lock_guard<std::mutex> lock(*sync_mutex_);
    if (!backend_->deviceView(scope, blocks_, revision_, &view)) return nullptr;
    scratch = backend_->deviceScratch();
  }
  if (!scratch) return nullptr;
  return std::make_unique<DeviceViewLease>(std::move(view_lock), view, *scratch);
}

size_t Map::knownVoxelCount() const {
  const BlockMap& host = hostBlocks();
  // Slot order (the arena's, not the index's) on every thread: a LiDAR map of 212 k blocks
  // (434 MB of cells) took 141 ms walked through the index on one thread of the 2-core machine.
  const long slots = static_cast<long>(host.slotCount());
  size_t n = 0;
#pragma omp parallel for schedule(static) reduction(+ : n) if (slots > 4096)
  for (long i = 0; i < slots; ++i) {
    if (!host.liveAt(static_cast<BlockIndex>(i))) continue;
    size_t in_block = 0;
    for (const Cell& c : host.block(static_cast<BlockIndex>(i)).cells) in_block += c.observed();
    n += in_block;
  }
  return n;
}

MemoryStats Map::memoryAsHeld() const {
  MemoryStats m;
  {
    std::lock_guard<std::mutex> lock(*sync_mutex_);  // not while another reader writes back
    m.host_block_bytes = blocks_.hostBytes();
  }
  m.device_bytes = backend_->deviceBytes();
  m.device_estimate_bytes = backend_->deviceEstimateBytes();
  m.scan_store_bytes = scan_store_->memoryBytes();
  return m;
}

MemoryStats Map::memory() const {
  (void)hostBlocks();  // the device's changes written back first
  MemoryStats m = memoryAsHeld();
  m.blocks = blocks_.size();
  m.known_voxels = knownVoxelCount();
  return m;
}

}  // namespace fragg
