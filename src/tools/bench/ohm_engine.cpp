#include "bench/ohm_engine.h"

#include <fmt/format.h>
#include <gputil/gpuQueue.h>
#include <ohm/MapChunk.h>
#include <ohm/MapLayer.h>
#include <ohm/MapLayout.h>
#include <ohm/OccupancyMap.h>
#include <ohm/RayFilter.h>
#include <ohm/RayFlag.h>
#include <ohm/RayMapperOccupancy.h>
#include <ohm/VoxelBlock.h>
#include <ohm/VoxelBuffer.h>
#include <ohm/VoxelOccupancy.h>
#include <ohmgpu/GpuCache.h>
#include <ohmgpu/GpuMap.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <glm/glm.hpp>
#include <memory>
#include <vector>

#include "fragg_map/cell_writer.h"
#include "fragg_map/errors.h"

namespace fragg::bench {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// OHM's float log-odds in fragg's fixed point, clamped to the int16 range (INT16_MIN is
/// fragg's "unobserved").
int16_t fixedPointOf(float log_odds) {
  const double fx = std::round(static_cast<double>(log_odds) * kLogOddsScale);
  return static_cast<int16_t>(
      std::clamp(fx, static_cast<double>(kUnobservedLogOdds) + 1, static_cast<double>(INT16_MAX)));
}

}  // namespace

struct OhmEngine::Impl {
  OhmOptions options;
  // No compression (OHM's default flag kCompressed runs a background compression thread that
  // would share the host with the timed loop); no voxel mean, no extra layers.
  ohm::OccupancyMap map;
  std::unique_ptr<ohm::GpuMap> gpu_map;  ///< null with options.cpu
  std::unique_ptr<ohm::RayMapperOccupancy> cpu_mapper;
  ohm::RayMapper* mapper = nullptr;
  std::vector<glm::dvec3> rays;  ///< origin/end pairs, reused across scans

  explicit Impl(const OhmOptions& o)
      : options(o), map(o.resolution_m, glm::u8vec3(0, 0, 0), ohm::MapFlag::kNone) {
    if (o.cpu) {
      cpu_mapper = std::make_unique<ohm::RayMapperOccupancy>(&map);
      mapper = cpu_mapper.get();
    } else {
      gpu_map =
          std::make_unique<ohm::GpuMap>(&map, true, static_cast<unsigned>(2 * o.expected_points),
                                        o.gpu_cache_mib * size_t{1024} * 1024);
      mapper = gpu_map.get();
    }
  }
};

OhmEngine::OhmEngine(const OhmOptions& options) {
  if (!(options.resolution_m > 0)) throw InvalidArgument("OHM: resolution must be > 0");
  impl_ = std::make_unique<Impl>(options);
  if (impl_->gpu_map && !impl_->gpu_map->gpuOk())
    throw CudaError("OHM: GpuMap could not initialise its CUDA program (gpuOk() is false)");
  ohm::OccupancyMap& map = impl_->map;
  if (options.matched_model) {
    const OccupancyParams& p = options.occupancy;
    map.setHitProbability(static_cast<float>(p.prob_hit));
    map.setMissProbability(static_cast<float>(p.prob_miss));
    map.setMinVoxelProbability(static_cast<float>(p.clamp_min));
    map.setMaxVoxelProbability(static_cast<float>(p.clamp_max));
    map.setSaturateAtMinValue(false);
    map.setSaturateAtMaxValue(false);
    map.setOccupancyThresholdProbability(0.5f);
  }
  if (options.max_range_m > 0) {
    const double max_range_m = options.max_range_m;
    // Rays longer than the range end free at the range, as OctoMap's maxrange and fragg's clip.
    const ohm::RayFilterFunction clip = [max_range_m](glm::dvec3* start, glm::dvec3* end,
                                                      unsigned* flags) {
      return ohm::clipRayFilter(start, end, flags, max_range_m);
    };
    map.setRayFilter(clip);
    if (impl_->gpu_map) impl_->gpu_map->setRayFilter(clip);
  }
  if (options.ray_segment_m > 0 && impl_->gpu_map)
    impl_->gpu_map->setRaySegmentLength(options.ray_segment_m);
  impl_->rays.reserve(2 * options.expected_points);
}

OhmEngine::~OhmEngine() = default;

OhmScanTimes OhmEngine::integrate(const Scan& scan, bool wait) {
  OhmScanTimes t;
  const auto t0 = Clock::now();
  std::vector<glm::dvec3>& rays = impl_->rays;
  rays.clear();
  const Eigen::Vector3d o = scan.T_map_sensor.translation();
  const glm::dvec3 origin(o.x(), o.y(), o.z());
  for (const Eigen::Vector3f& p_S : scan.cloud.points_S) {
    if (!p_S.allFinite() || p_S.squaredNorm() == 0.f) continue;
    const Eigen::Vector3d p_M = scan.T_map_sensor * p_S.cast<double>();
    rays.push_back(origin);
    rays.emplace_back(p_M.x(), p_M.y(), p_M.z());
  }
  const auto t1 = Clock::now();
  t.rays =
      impl_->mapper->integrateRays(rays.data(), rays.size(), nullptr, nullptr, ohm::kRfDefault);
  if (wait) finish();
  t.ms_gpu = msSince(t1);
  t.ms_total = msSince(t0);
  if (t.rays == 0 && !rays.empty())
    throw CudaError(fmt::format("OHM: integrateRays accepted none of {} rays", rays.size() / 2));
  return t;
}

void OhmEngine::finish() {
  if (impl_->gpu_map) impl_->gpu_map->gpuCache()->gpuQueue().finish();
}

double OhmEngine::syncToHost() {
  const auto t0 = Clock::now();
  if (impl_->gpu_map) impl_->gpu_map->syncVoxels();
  return msSince(t0) / 1e3;
}

Map OhmEngine::toMap() {
  syncToHost();
  const ohm::OccupancyMap& map = impl_->map;
  MapParams params;
  params.resolution_m = impl_->options.resolution_m;
  params.occupancy = impl_->options.occupancy;
  params.occupancy.unknown_band = 0.0;
  params.backend = Backend::kCpu;
  Map out(params);
  const int layer_index = map.layout().occupancyLayer();
  if (layer_index < 0) throw InvalidArgument("OHM: the map has no occupancy layer");
  const ohm::MapLayer& layer = map.layout().layer(static_cast<size_t>(layer_index));
  if (layer.voxelByteSize() != sizeof(float))
    throw InvalidArgument("OHM: the occupancy layer does not hold one float per voxel");
  const glm::u8vec3 dim = layer.dimensions(map.regionVoxelDimensions());
  const double res = map.resolution();
  std::vector<const ohm::MapChunk*> chunks;
  map.enumerateRegions(chunks);
  out.writeCells([&](CellWriter& cells) {
    for (const ohm::MapChunk* chunk : chunks) {
      const ohm::VoxelBuffer<const ohm::VoxelBlock> buffer(chunk->voxel_blocks[layer_index]);
      const uint8_t* bytes = buffer.voxelMemory();
      for (unsigned z = 0; z < dim.z; ++z)
        for (unsigned y = 0; y < dim.y; ++y)
          for (unsigned x = 0; x < dim.x; ++x) {
            float value;
            std::memcpy(&value,
                        bytes + sizeof(float) * ohm::voxelIndex(x, y, z, dim.x, dim.y, dim.z),
                        sizeof(float));
            if (value == ohm::unobservedOccupancyValue()) continue;
            const ohm::Key key(chunk->region.coord, static_cast<uint8_t>(x),
                               static_cast<uint8_t>(y), static_cast<uint8_t>(z));
            // The centre lies half a cell inside, so floor() is exact.
            const glm::dvec3 c = map.voxelCentreGlobal(key);
            const VoxelKey k{static_cast<int32_t>(std::floor(c.x / res)),
                             static_cast<int32_t>(std::floor(c.y / res)),
                             static_cast<int32_t>(std::floor(c.z / res))};
            Cell cell;
            cell.log_odds_fx = fixedPointOf(value);
            cells.set(k, cell);
          }
    }
  });
  return out;
}

std::string OhmEngine::describeModel() const {
  const ohm::OccupancyMap& m = impl_->map;
  return fmt::format("hit {:.3g} miss {:.3g} clamp [{:.3g}, {:.3g}] occupied at p >= {:.3g}{}{}",
                     m.hitProbability(), m.missProbability(), m.minVoxelProbability(),
                     m.maxVoxelProbability(), m.occupancyThresholdProbability(),
                     impl_->options.matched_model ? " (matched to OctoMap's)" : " (OHM's defaults)",
                     impl_->gpu_map ? "" : ", CPU mapper");
}

}  // namespace fragg::bench
