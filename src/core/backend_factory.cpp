#include "fragg_map/internal/backend_factory.h"

#include <atomic>

#include "fragg_map/device_scratch.h"
#include "fragg_map/errors.h"
#include "fragg_map/internal/cpu_backend.h"
#include "fragg_map/log.h"
#if FRAGG_HAVE_CUDA
#include "fragg_map/internal/cuda_backend_factory.h"
#endif

namespace fragg {

bool builtWithCuda() { return FRAGG_HAVE_CUDA != 0; }

#if !FRAGG_HAVE_CUDA
std::string cudaDeviceName(int, std::string* why_not) {
  if (why_not) *why_not = "built without CUDA";
  return "";
}

std::unique_ptr<DeviceScratch> makeDeviceScratch(int) {
  throw InvalidArgument("device scratch memory: built without CUDA");
}
#endif

namespace {
/// `auto` says what it chose once per process, not once per map.
void logAutoChoiceOnce(LogLevel level, const std::string& line) {
  static std::atomic<bool> said{false};
  if (!said.exchange(true)) logMessage(level, line);
}
}  // namespace

BackendChoice makeBackend(const MapParams& p) {
  BackendChoice c;
  if (p.backend == Backend::kCpu) {
    c.backend = std::make_unique<CpuBackend>(p.threads);
    c.reason = "cpu: requested";
    return c;
  }
  if (p.dynamic.decay_log_odds_per_scan > 0.0) {  // a map-wide pass over the host map
    if (p.backend == Backend::kCuda)
      throw InvalidArgument(
          "dynamic.decay_log_odds_per_scan: the CUDA backend does not decay cells; use backend "
          "cpu or auto");
    c.backend = std::make_unique<CpuBackend>(p.threads);
    c.reason = "auto: CPU backend (dynamic.decay_log_odds_per_scan runs on the CPU backend)";
    logAutoChoiceOnce(LogLevel::kInfo, "backend " + c.reason);
    return c;
  }
#if FRAGG_HAVE_CUDA
  std::string why_not;
  const std::string name = cudaDeviceName(p.cuda.device, &why_not);
  if (!name.empty()) {
    try {
      c.backend = makeCudaBackend(p);
      c.reason = std::string(p.backend == Backend::kAuto ? "auto" : "requested") +
                 ": CUDA device " + std::to_string(p.cuda.device) + " (" + name + ")";
    } catch (const CudaError& e) {
      why_not = e.what();
    }
  }
  if (!c.backend && p.backend == Backend::kCuda)
    throw InvalidArgument("backend cuda requested, but " + why_not);
  if (!c.backend) {
    c.backend = std::make_unique<CpuBackend>(p.threads);
    c.reason = "auto: CPU backend (" + why_not + ")";
  }
#else
  if (p.backend == Backend::kCuda)
    throw InvalidArgument("backend cuda requested, but this build has no CUDA backend");
  c.backend = std::make_unique<CpuBackend>(p.threads);
  c.reason = "auto: CPU backend (built without CUDA)";
#endif
  if (p.backend == Backend::kAuto) logAutoChoiceOnce(LogLevel::kInfo, "backend " + c.reason);
  return c;
}

}  // namespace fragg
