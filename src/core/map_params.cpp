#include "fragg_map/map_params.h"

#include <cmath>
#include <string>

#include "fragg_map/errors.h"

namespace fragg {

const char* toString(Backend b) {
  switch (b) {
    case Backend::kCpu:
      return "cpu";
    case Backend::kCuda:
      return "cuda";
    case Backend::kAuto:
      break;
  }
  return "auto";
}

Backend backendFromString(const std::string& s) {
  if (s == "auto") return Backend::kAuto;
  if (s == "cpu") return Backend::kCpu;
  if (s == "cuda") return Backend::kCuda;
  throw InvalidArgument("backend must be auto, cpu or cuda, got '" + s + "'");
}

const char* toString(RayCast r) {
  return r == RayCast::kBresenham ? "bresenham" : r == RayCast::kOctomap ? "octomap" : "dda";
}

RayCast rayCastFromString(const std::string& s) {
  if (s == "dda") return RayCast::kDda;
  if (s == "bresenham") return RayCast::kBresenham;
  if (s == "octomap") return RayCast::kOctomap;
  throw InvalidArgument("raycast must be dda, bresenham or octomap, got '" + s + "'");
}

void MapParams::validate() const {
  // Messages name the field by its path in MapParams (front ends rename it: field_names.h).
  if (!std::isfinite(resolution_m) || resolution_m < 1e-3 || resolution_m > 100.0)
    throw InvalidArgument("resolution_m must be in [0.001, 100] m, got " +
                          std::to_string(resolution_m));
  occupancy.validate();
  if (culling.coherence_ttl_scans < 1 || culling.coherence_ttl_scans > 32)
    throw InvalidArgument("culling.coherence_ttl_scans must be in [1, 32] scans, got " +
                          std::to_string(culling.coherence_ttl_scans));
  if (threads < 0)
    throw InvalidArgument("threads must be >= 0 (0 = every core), got " + std::to_string(threads));
  if (!std::isfinite(cuda.pool_margin) || cuda.pool_margin <= 0.0 || cuda.pool_margin > 100.0)
    throw InvalidArgument("cuda.pool_margin must be in (0, 100], got " +
                          std::to_string(cuda.pool_margin));
  if (cuda.device < 0) throw InvalidArgument("cuda.device must be >= 0");
  if (cuda.host_threads < 0)
    throw InvalidArgument("cuda.host_threads must be >= 0 (0 = every core), got " +
                          std::to_string(cuda.host_threads));
  if (cuda.ray_piece_steps < 0 || cuda.ray_piece_steps > 4096)
    throw InvalidArgument(
        "cuda.ray_piece_steps must be in [0, 4096] cells (0 = one thread a ray), got " +
        std::to_string(cuda.ray_piece_steps));
  if (!std::isfinite(scans.point_step_m) || scans.point_step_m < 0.0 || scans.point_step_m > 0.1)
    throw InvalidArgument("scans.point_step_m must be in [0, 0.1] m (0 = float32), got " +
                          std::to_string(scans.point_step_m));
  if (std::isnan(height_filter.min_z_m) || std::isnan(height_filter.max_z_m))
    throw InvalidArgument(std::string(std::isnan(height_filter.min_z_m) ? "height_filter.min_z_m"
                                                                        : "height_filter.max_z_m") +
                          " must be a height in m (or +-infinity), got NaN");
  if (height_filter.min_z_m > height_filter.max_z_m)
    throw InvalidArgument("height_filter.min_z_m (" + std::to_string(height_filter.min_z_m) +
                          " m) must not exceed height_filter.max_z_m (" +
                          std::to_string(height_filter.max_z_m) + " m)");
  if (dynamic.enabled) {
    const double v = dynamic.void_probability;
    if (!std::isfinite(v) || v <= 0.0 || v >= 0.5 - occupancy.unknown_band)
      throw InvalidArgument("dynamic.void_probability must be in (0, 0.5 - unknown_band = " +
                            std::to_string(0.5 - occupancy.unknown_band) + "), got " +
                            std::to_string(v));
    if (v < occupancy.clamp_min)
      throw InvalidArgument("dynamic.void_probability (" + std::to_string(v) +
                            ") is below occupancy.clamp_min (" +
                            std::to_string(occupancy.clamp_min) + "): no cell could be void");
    if (dynamic.rule != VoidSpaceRule::kPassThrough && dynamic.rule != VoidSpaceRule::kSurround)
      throw InvalidArgument("dynamic.rule must be pass-through or surround, got value " +
                            std::to_string(static_cast<int>(dynamic.rule)));
    if (dynamic.known_radius_cells < 0 || dynamic.known_radius_cells > 2)
      throw InvalidArgument("dynamic.known_radius_cells must be in [0, 2] cells, got " +
                            std::to_string(dynamic.known_radius_cells));
    if (scans.keep)
      throw InvalidArgument(
          "dynamic.enabled cannot be combined with scans.keep: removing a scan would not know "
          "which of its hits were dynamic");
  }
  const double decay = dynamic.decay_log_odds_per_scan;
  if (!std::isfinite(decay) || decay < 0.0 || decay > 4.0)
    throw InvalidArgument(
        "dynamic.decay_log_odds_per_scan must be in [0, 4] (log-odds per scan, "
        "0 = off), got " +
        std::to_string(decay));
  if (decay > 0.0 && scans.keep)
    throw InvalidArgument(
        "dynamic.decay_log_odds_per_scan cannot be combined with scans.keep: removing a scan "
        "after cells decayed would not give back the map without it");
}

const char* toString(VoidSpaceRule rule) {
  switch (rule) {
    case VoidSpaceRule::kPassThrough:
      return "pass-through";
    case VoidSpaceRule::kSurround:
      return "surround";
  }
  return "invalid";
}

VoidSpaceRule voidSpaceRuleFromString(const std::string& name) {
  if (name == "pass-through") return VoidSpaceRule::kPassThrough;
  if (name == "surround") return VoidSpaceRule::kSurround;
  throw InvalidArgument("dynamic.rule must be pass-through or surround, got '" + name + "'");
}

}  // namespace fragg
