// Every parameter of a map, with its default. The one place defaults live.
#pragma once

#include <string>

#include "fragg_map/occupancy.h"

namespace fragg {

enum class Backend : uint8_t { kAuto = 0, kCpu = 1, kCuda = 2 };
const char* toString(Backend b);
Backend backendFromString(const std::string& s);  ///< "auto" | "cpu" | "cuda"

enum class RayCast : uint8_t { kDda = 0, kBresenham = 1 };
const char* toString(RayCast r);
RayCast rayCastFromString(const std::string& s);  ///< "dda" | "bresenham"

struct CullingParams {
  bool plane_memory = true;           ///< test the plane that rejected a block last time first
  bool rotation_coherence = true;     ///< skip re-testing blocks rejected within the TTL
  bool translation_coherence = true;  ///< skip re-testing near-plane rejects after moving ahead
  int coherence_ttl_scans = 8;        ///< how long a rejection may be reused
};

struct MapParams {
  double resolution_m = 0.05;
  OccupancyParams occupancy;
  Backend backend = Backend::kAuto;
  RayCast raycast = RayCast::kDda;
  /// Rays of organised clouds without a return clear free space up to the max range.
  bool clear_no_return_rays = false;
  CullingParams culling;
  /// Worker threads for the CPU backend; 0 = every core.
  int threads = 0;

  /// Throws InvalidArgument naming the bad field.
  void validate() const;
};

}  // namespace fragg
