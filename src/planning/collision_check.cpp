#include "fragg_map/planning/collision_check.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <mutex>
#include <string>
#include <utility>

#include "collision_batch.h"
#include "fragg_map/errors.h"
#include "fragg_map/internal/backend_factory.h"
#include "fragg_map/internal/thread_count.h"
#include "mesh_collision.h"
#include "obstacle_index.h"

namespace fragg::planning {

namespace {

/// Milliseconds since the last lap (or construction), for CollisionStages.
class Lap {
 public:
  double ms() {
    const auto now = std::chrono::steady_clock::now();
    const double out = std::chrono::duration<double, std::milli>(now - t_).count();
    t_ = now;
    return out;
  }

 private:
  std::chrono::steady_clock::time_point t_ = std::chrono::steady_clock::now();
};

/// validatePose() for every pose of a batch, on `threads` threads: the first bad pose (by
/// index, whatever the threads) throws, named.
void validatePoses(const std::vector<Eigen::Isometry3d>& T_map_shape, int threads) {
  Eigen::Vector3d min_m, max_m;
  validatedPoseBox(T_map_shape, threads, &min_m, &max_m);
}

// Box, sphere, capsule: every obstacle cell of the shape's cell range gets the exact test
// against its cube shrunk by the touching epsilon.
CollisionResult checkPrimitive(const ObstacleMasksView& masks, const PrimitivePose& pose,
                               double resolution_m, bool count_cells) {
  const double half_m = 0.5 * resolution_m - kTouchEpsilon_m;
  CollisionResult result;
  forEachObstacleCell(masks, pose.lo, pose.hi, [&](const VoxelKey& k) {
    if (!primitiveOverlapsCell(pose, cellCentre(k, resolution_m), half_m)) return false;
    if (!result.collides) result.first_cell = k;
    result.collides = true;
    ++result.colliding_cells;
    return !count_cells;
  });
  return result;
}

std::vector<CollisionResult> checkOnCpu(const Map& map, const ObstacleIndex& index,
                                        const CollisionShape& shape,
                                        const std::vector<Eigen::Isometry3d>& T_map_shape,
                                        const CollisionOptions& options) {
  Lap lap;
  const ObstacleMasksView masks = index.view();
  std::vector<CollisionResult> results(T_map_shape.size());
  std::exception_ptr error;
  const int threads = threadCount(options.threads);
  const int64_t n = static_cast<int64_t>(T_map_shape.size());
  const bool mesh = shape.kind() == ShapeKind::kMesh;
  const PrimitiveShape primitive = primitiveShape(map, shape, options);
  int64_t first_bad = n;  // the first pose whose cells leave the key range
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads) reduction(min : first_bad)
  for (int64_t i = 0; i < n; ++i) {
    if (!mesh) {
      PrimitivePose pose;
      if (!preparePrimitivePose(primitive, T_map_shape[i].linear(), T_map_shape[i].translation(),
                                &pose)) {
        first_bad = std::min(first_bad, i);
        continue;
      }
      results[i] = checkPrimitive(masks, pose, map.resolution(), options.count_cells);
      continue;
    }
    try {
      results[i] = checkMeshPose(map, masks, shape, T_map_shape[i], options);
    } catch (...) {
#pragma omp critical(fragg_collision_error)
      if (!error) error = std::current_exception();
    }
  }
  if (first_bad < n) throw keyRangeError(static_cast<size_t>(first_bad));
  if (error) std::rethrow_exception(error);
  if (options.stages) options.stages->device_ms = lap.ms();
  return results;
}

#if FRAGG_HAVE_CUDA
CollisionResult resultOf(const CollisionAnswer& a) {
  CollisionResult r;
  r.collides = a.collides;
  r.colliding_cells = a.colliding_cells;
  r.first_cell = a.first_cell;
  return r;
}

// Poses a chunk when the device prepares them and options.device_chunk_poses is 0: the batch
// in four chunks (the pack of one overlaps the copy and kernel of the one before), at least
// this many poses each (a chunk's copy and launch cost some microseconds).
constexpr size_t kMinChunkPoses = 8192;

// The batch on CUDA over `obstacles`, in `scratch` (its device, stream and buffers).
std::vector<CollisionResult> checkOnCuda(const Map& map, DeviceScratch& scratch,
                                         const ObstacleSource& obstacles,
                                         const CollisionShape& shape,
                                         const std::vector<Eigen::Isometry3d>& T_map_shape,
                                         const CollisionOptions& options) {
  Lap lap;
  double pose_ms = 0.0;  // of the device path's packing
  const std::unique_ptr<CudaCollision> checker = makeCudaCollision(scratch);
  const int threads = threadCount(options.threads);
  const int64_t n = static_cast<int64_t>(T_map_shape.size());
  const double half_m = 0.5 * map.resolution() - kTouchEpsilon_m;
  std::vector<CollisionResult> results(T_map_shape.size());
  if (shape.kind() != ShapeKind::kMesh && options.pose_preparation == PosePreparation::kDevice) {
    // Only the rigid poses go to the device (packed on the batch's threads a chunk at a time
    // into the checker's pinned staging); the kernel prepares each pose as the host would.
    const size_t chunk = options.device_chunk_poses > 0
                             ? options.device_chunk_poses
                             : std::max(kMinChunkPoses, (T_map_shape.size() + 3) / 4);
    size_t first_bad = 0;
    const CollisionAnswer* answers = checker->checkRigidPoses(
        obstacles, T_map_shape.size(), primitiveShape(map, shape, options), half_m,
        options.count_cells, chunk,
        [&](size_t first, size_t count, RigidPose* out) {
          Lap pack;
          const int64_t m = static_cast<int64_t>(count);
#pragma omp parallel for schedule(static) num_threads(threads) if (m > 4096)
          for (int64_t i = 0; i < m; ++i) {
            const Eigen::Isometry3d& T = T_map_shape[first + i];
            out[i].R_map_shape = T.linear();
            out[i].t_map_shape = T.translation();
          }
          pose_ms += pack.ms();
        },
        &first_bad);
    const double call_ms = lap.ms();
    if (first_bad < T_map_shape.size()) throw keyRangeError(first_bad);
#pragma omp parallel for schedule(static) num_threads(threads) if (n > 16384)
    for (int64_t i = 0; i < n; ++i) results[i] = resultOf(answers[i]);
    if (options.stages) {
      options.stages->poses_ms = pose_ms;
      options.stages->device_ms = call_ms - pose_ms;
      options.stages->results_ms = lap.ms();
    }
    return results;
  }
  std::vector<CollisionAnswer> answers;
  if (shape.kind() == ShapeKind::kMesh) {
    const std::vector<MeshPose> mesh_poses = meshPoses(T_map_shape);
    pose_ms = lap.ms();
    answers = checker->checkMesh(obstacles, mesh_poses, meshCheck(map, shape, options));
  } else {
    // Prepared on the host, in parallel straight into the checker's pinned staging.
    const PrimitiveShape primitive = primitiveShape(map, shape, options);
    PrimitivePose* poses = checker->primitiveStaging(T_map_shape.size());
    int64_t first_bad = n;
#pragma omp parallel for schedule(static) num_threads(threads) reduction(min : first_bad)
    for (int64_t i = 0; i < n; ++i)
      if (!preparePrimitivePose(primitive, T_map_shape[i].linear(), T_map_shape[i].translation(),
                                &poses[i]))
        first_bad = std::min(first_bad, i);
    if (first_bad < n) throw keyRangeError(static_cast<size_t>(first_bad));
    pose_ms = lap.ms();
    answers = checker->checkPrimitives(obstacles, T_map_shape.size(), map.resolution(), half_m,
                                       options.count_cells);
  }
  const double call_ms = lap.ms();
#pragma omp parallel for schedule(static) num_threads(threads) if (n > 16384)
  for (int64_t i = 0; i < n; ++i) results[i] = resultOf(answers[i]);
  if (options.stages) {
    options.stages->poses_ms = pose_ms;
    options.stages->device_ms = call_ms;
    options.stages->results_ms = lap.ms();
  }
  return results;
}

// A host obstacle index on CUDA: uploaded into `scratch`.
std::vector<CollisionResult> checkIndexOnCuda(const Map& map, DeviceScratch& scratch,
                                              const ObstacleIndex& index,
                                              const CollisionShape& shape,
                                              const std::vector<Eigen::Isometry3d>& T_map_shape,
                                              const CollisionOptions& options) {
  ObstacleMasksHost masks;
  masks.keys = &index.tableKeys();
  masks.slots = &index.tableSlots();
  masks.masks = &index.masks();
  masks.default_word = index.defaultWord();
  ObstacleSource source;
  source.host = &masks;
  return checkOnCuda(map, scratch, source, shape, T_map_shape, options);
}
#endif

// The poses checked already; their translations lie in [min_m, max_m].
std::vector<CollisionResult> checkValidated(const Map& map, const CollisionShape& shape,
                                            const std::vector<Eigen::Isometry3d>& T_map_shape,
                                            const Eigen::Vector3d& min_m,
                                            const Eigen::Vector3d& max_m,
                                            const CollisionOptions& options, Backend backend) {
  const Backend use = resolveCollisionBackend(backend);
  if (T_map_shape.empty()) return {};
  Lap lap;
  BlockKey lo, hi;
  batchBlockRange(map, shape, min_m, max_m, options, &lo, &hi);
#if FRAGG_HAVE_CUDA
  if (use == Backend::kCuda) {
    // A map keeping its layers on the device: the kernels read its state masks in place, with
    // the map's own buffers (nothing classified or uploaded but the poses).
    if (const std::unique_ptr<DeviceViewLease> lease = map.deviceView(lo, hi)) {
      if (options.stages) options.stages->obstacles_ms = lap.ms();
      ObstacleSource source;
      source.device = layerObstacles(lease->view(), options.unknown_is_occupied);
      return checkOnCuda(map, lease->scratch(), source, shape, T_map_shape, options);
    }
    // Otherwise its host masks, indexed and uploaded to device 0 for this batch.
    const BlockView view = map.blockView();
    const ObstacleIndex index(view, lo, hi, options.unknown_is_occupied, options.threads);
    if (options.stages) options.stages->obstacles_ms = lap.ms();
    const std::unique_ptr<DeviceScratch> scratch = makeDeviceScratch(0);
    return checkIndexOnCuda(map, *scratch, index, shape, T_map_shape, options);
  }
#else
  (void)use;  // kCuda cannot be resolved without CUDA
#endif
  const BlockView view = map.blockView();
  const ObstacleIndex index(view, lo, hi, options.unknown_is_occupied, options.threads);
  if (options.stages) options.stages->obstacles_ms = lap.ms();
  return checkOnCpu(map, index, shape, T_map_shape, options);
}

}  // namespace

void validate(const CollisionOptions& options) {
  if (!std::isfinite(options.margin_m) || options.margin_m < 0.0)
    throw InvalidArgument(
        fmt::format("collision margin must be finite and >= 0, got {}", options.margin_m));
  if (options.threads < 0)
    throw InvalidArgument(fmt::format("threads must be >= 0, got {}", options.threads));
}

void pageInForCollision(Map& map, const CollisionShape& shape,
                        const std::vector<Eigen::Isometry3d>& T_map_shape,
                        const CollisionOptions& options) {
  validate(options);
  validatePoses(T_map_shape, options.threads);
  if (T_map_shape.empty() || !map.pagingStats().enabled) return;
  Eigen::Vector3d lo = T_map_shape.front().translation(), hi = lo;
  for (const Eigen::Isometry3d& T : T_map_shape) {
    lo = lo.cwiseMin(T.translation());
    hi = hi.cwiseMax(T.translation());
  }
  // A margin grows box half extents (or, for a mesh, each cell) per axis: sqrt(3) margins at
  // most from the origin.
  const double reach_m =
      shape.boundingRadius() + std::sqrt(3.0) * options.margin_m + map.resolution();
  map.ensureResident(lo - Eigen::Vector3d::Constant(reach_m),
                     hi + Eigen::Vector3d::Constant(reach_m));
}

void validatePose(const Eigen::Isometry3d& T_map_shape) {
  const std::string error = poseError(T_map_shape);
  if (!error.empty()) throw InvalidArgument(error);
}

Backend resolveCollisionBackend(Backend requested, std::string* why) {
  if (requested == Backend::kCpu) {
    if (why) *why = "cpu: requested";
    return Backend::kCpu;
  }
  // Asked once per process (the device properties are slow to read, and batches ask often).
  static const std::pair<std::string, std::string> kDevice = [] {
    std::string why;
    std::string name = cudaDeviceName(0, &why);
    return std::make_pair(name, why);
  }();
  const std::string& device = kDevice.first;
  const std::string& why_not = kDevice.second;
  if (!device.empty()) {
    if (why)
      *why = fmt::format("{}: CUDA device 0 ({})",
                         requested == Backend::kAuto ? "auto" : "requested", device);
    return Backend::kCuda;
  }
  if (requested == Backend::kCuda)
    throw InvalidArgument("collision backend cuda requested, but " + why_not);
  if (why) *why = "auto: CPU (" + why_not + ")";
  return Backend::kCpu;
}

CollisionResult checkPose(const Map& map, const CollisionShape& shape,
                          const Eigen::Isometry3d& T_map_shape, const CollisionOptions& options,
                          Backend backend) {
  validate(options);
  validatePose(T_map_shape);
  return checkValidated(map, shape, {T_map_shape}, T_map_shape.translation(),
                        T_map_shape.translation(), options, backend)
      .front();
}

std::vector<CollisionResult> checkPoses(const Map& map, const CollisionShape& shape,
                                        const std::vector<Eigen::Isometry3d>& T_map_shape,
                                        const CollisionOptions& options, Backend backend) {
  validate(options);
  // The poses checked and their box found in one pass.
  Lap lap;
  if (options.stages) *options.stages = CollisionStages();
  Eigen::Vector3d min_m, max_m;
  validatedPoseBox(T_map_shape, options.threads, &min_m, &max_m);
  if (options.stages) options.stages->validate_ms = lap.ms();
  return checkValidated(map, shape, T_map_shape, min_m, max_m, options, backend);
}

PreparedMap::PreparedMap(const Map& map, bool unknown_is_occupied, int threads)
    : map_(&map), revision_(map.revision()), unknown_is_occupied_(unknown_is_occupied) {
  if (threads < 0) throw InvalidArgument(fmt::format("threads must be >= 0, got {}", threads));
  const BlockView view = map.blockView();
  const BlockKey lo{INT32_MIN, INT32_MIN, INT32_MIN}, hi{INT32_MAX, INT32_MAX, INT32_MAX};
  index_ = std::make_shared<const ObstacleIndex>(view, lo, hi, unknown_is_occupied, threads);
}

size_t PreparedMap::blockCount() const { return index_->blockCount(); }

std::vector<CollisionResult> checkPoses(const PreparedMap& prepared, const CollisionShape& shape,
                                        const std::vector<Eigen::Isometry3d>& T_map_shape,
                                        const CollisionOptions& options, Backend backend) {
  validate(options);
  if (options.stages) *options.stages = CollisionStages();  // the CUDA stages filled only
  validatePoses(T_map_shape, options.threads);
  if (options.unknown_is_occupied != prepared.unknownIsOccupied())
    throw InvalidArgument("the prepared map was classified for the other unknown_is_occupied");
  if (prepared.map().revision() != prepared.revision())
    throw InvalidArgument("the map changed since it was prepared for collision checks");
  const Backend use = resolveCollisionBackend(backend);
  if (T_map_shape.empty()) return {};
#if FRAGG_HAVE_CUDA
  if (use == Backend::kCuda) {
    // The prepared index is uploaded into the prepared map's own scratch (made once).
    std::lock_guard<std::mutex> lock(*prepared.scratch_mutex_);
    if (!prepared.scratch_) prepared.scratch_ = makeDeviceScratch(0);
    return checkIndexOnCuda(prepared.map(), *prepared.scratch_, *prepared.index_, shape,
                            T_map_shape, options);
  }
#else
  (void)use;
#endif
  return checkOnCpu(prepared.map(), *prepared.index_, shape, T_map_shape, options);
}

}  // namespace fragg::planning
