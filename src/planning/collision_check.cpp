#include "fragg_map/planning/collision_check.h"

#include <fmt/format.h>
#include <omp.h>

#include <algorithm>
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

/// Why `T_map_shape` is not a rigid pose (empty: it is one).
std::string poseError(const Eigen::Isometry3d& T_map_shape) {
  if (!T_map_shape.matrix().allFinite()) return "shape pose is not finite";
  const Eigen::Matrix3d R = T_map_shape.linear();
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (err > 1e-6 || R.determinant() < 0.0)
    return fmt::format("shape pose rotation is not a rotation (orthonormality error {})", err);
  return {};
}

/// validatePose() for every pose of a batch, on `threads` threads: the first bad pose (by
/// index, whatever the threads) throws.
void validatePoses(const std::vector<Eigen::Isometry3d>& T_map_shape, int threads) {
  const int64_t n = static_cast<int64_t>(T_map_shape.size());
  int64_t first_bad = n;
#pragma omp parallel for schedule(static) reduction(min          \
                                                    : first_bad) \
    num_threads(threadCount(threads)) if (n > 4096)
  for (int64_t i = 0; i < n; ++i)
    if (i < first_bad && !poseError(T_map_shape[i]).empty()) first_bad = i;
  if (first_bad < n) throw InvalidArgument(poseError(T_map_shape[first_bad]));
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
  const ObstacleMasksView masks = index.view();
  std::vector<CollisionResult> results(T_map_shape.size());
  std::exception_ptr error;
  const int threads = threadCount(options.threads);
  const int64_t n = static_cast<int64_t>(T_map_shape.size());
  const bool mesh = shape.kind() == ShapeKind::kMesh;
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads)
  for (int64_t i = 0; i < n; ++i) {
    try {
      results[i] =
          mesh ? checkMeshPose(map, masks, shape, T_map_shape[i], options)
               : checkPrimitive(masks, preparePrimitive(map, shape, T_map_shape[i], options),
                                map.resolution(), options.count_cells);
    } catch (...) {
#pragma omp critical(fragg_collision_error)
      if (!error) error = std::current_exception();
    }
  }
  if (error) std::rethrow_exception(error);
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

// The batch on CUDA over `obstacles`, in `scratch` (its device, stream and buffers).
std::vector<CollisionResult> checkOnCuda(const Map& map, DeviceScratch& scratch,
                                         const ObstacleSource& obstacles,
                                         const CollisionShape& shape,
                                         const std::vector<Eigen::Isometry3d>& T_map_shape,
                                         const CollisionOptions& options) {
  const std::unique_ptr<CudaCollision> checker = makeCudaCollision(scratch);
  std::vector<CollisionAnswer> answers;
  if (shape.kind() == ShapeKind::kMesh) {
    answers = checker->checkMesh(obstacles, meshPoses(T_map_shape), meshCheck(map, shape, options));
  } else {
    // Prepared in parallel straight into the checker's pinned staging.
    const int64_t n = static_cast<int64_t>(T_map_shape.size());
    PrimitivePose* poses = checker->primitiveStaging(T_map_shape.size());
#pragma omp parallel for schedule(static) num_threads(threadCount(options.threads))
    for (int64_t i = 0; i < n; ++i)
      poses[i] = preparePrimitive(map, shape, T_map_shape[i], options);
    answers =
        checker->checkPrimitives(obstacles, T_map_shape.size(), map.resolution(),
                                 0.5 * map.resolution() - kTouchEpsilon_m, options.count_cells);
  }
  const int64_t count = static_cast<int64_t>(answers.size());
  std::vector<CollisionResult> results(answers.size());
#pragma omp parallel for schedule(static) \
    num_threads(threadCount(options.threads)) if (count > 16384)
  for (int64_t i = 0; i < count; ++i) results[i] = resultOf(answers[i]);
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

std::vector<CollisionResult> checkValidated(const Map& map, const CollisionShape& shape,
                                            const std::vector<Eigen::Isometry3d>& T_map_shape,
                                            const CollisionOptions& options, Backend backend) {
  const Backend use = resolveCollisionBackend(backend);
  if (T_map_shape.empty()) return {};
  BlockKey lo, hi;
  batchBlockRange(map, shape, T_map_shape, options, &lo, &hi);
#if FRAGG_HAVE_CUDA
  if (use == Backend::kCuda) {
    // A map keeping its layers on the device: the kernels read its state masks in place, with
    // the map's own buffers (nothing classified or uploaded but the poses).
    if (const std::unique_ptr<DeviceViewLease> lease = map.deviceView(lo, hi)) {
      ObstacleSource source;
      source.device = layerObstacles(lease->view(), options.unknown_is_occupied);
      return checkOnCuda(map, lease->scratch(), source, shape, T_map_shape, options);
    }
    // Otherwise its host masks, indexed and uploaded to device 0 for this batch.
    const BlockView view = map.blockView();
    const ObstacleIndex index(view, lo, hi, options.unknown_is_occupied, options.threads);
    const std::unique_ptr<DeviceScratch> scratch = makeDeviceScratch(0);
    return checkIndexOnCuda(map, *scratch, index, shape, T_map_shape, options);
  }
#else
  (void)use;  // kCuda cannot be resolved without CUDA
#endif
  const BlockView view = map.blockView();
  const ObstacleIndex index(view, lo, hi, options.unknown_is_occupied, options.threads);
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
  return checkValidated(map, shape, {T_map_shape}, options, backend).front();
}

std::vector<CollisionResult> checkPoses(const Map& map, const CollisionShape& shape,
                                        const std::vector<Eigen::Isometry3d>& T_map_shape,
                                        const CollisionOptions& options, Backend backend) {
  validate(options);
  validatePoses(T_map_shape, options.threads);
  return checkValidated(map, shape, T_map_shape, options, backend);
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
