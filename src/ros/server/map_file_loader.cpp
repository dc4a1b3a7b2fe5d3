// .fgm through Map::load, .bt / .ot through the OctoMap import merged into a map with the
// server's settings.
#include "map_file_loader.h"

#include <cmath>
#include <filesystem>
#include <system_error>

#include "fragg_map/errors.h"
#include "frame_text.h"
#if FRAGG_HAVE_OCTOMAP
#include "fragg_map/interop/octomap_io.h"
#include "fragg_map/submap.h"
#endif

namespace fragg::ros {
namespace {

void requireResolution(const fragg::Map& loaded, const fragg::MapParams& runtime,
                       const std::string& path) {
  if (std::abs(loaded.resolution() - runtime.resolution_m) > 1e-12)
    throw fragg::InvalidArgument(path + ": the file's resolution " +
                                 std::to_string(loaded.resolution()) + " m differs from the " +
                                 "server's " + std::to_string(runtime.resolution_m) + " m");
}

}  // namespace

fragg::Map loadMapFile(const std::string& path, const fragg::MapParams& runtime) {
  // (A folder would open as a stream of undefined size: the readers are given files only.)
  std::error_code ec;
  if (std::filesystem::exists(path, ec) && !std::filesystem::is_regular_file(path, ec))
    throw fragg::IoError(path + ": not a regular file");
  if (endsWith(path, ".fgm")) {
    fragg::Map loaded = fragg::Map::load(path, runtime);
    requireResolution(loaded, runtime, path);
    return loaded;
  }
  if (endsWith(path, ".bt") || endsWith(path, ".ot")) {
#if FRAGG_HAVE_OCTOMAP
    const fragg::Map imported = fragg::importOctomap(path, fragg::Backend::kCpu);
    requireResolution(imported, runtime, path);
    // The tree's occupancy model (hit, miss, clamps), the server's other settings.
    fragg::MapParams params = runtime;
    params.occupancy.prob_hit = imported.params().occupancy.prob_hit;
    params.occupancy.prob_miss = imported.params().occupancy.prob_miss;
    params.occupancy.clamp_min = imported.params().occupancy.clamp_min;
    params.occupancy.clamp_max = imported.params().occupancy.clamp_max;
    fragg::Map map(params);
    map.merge(imported, fragg::MergeMode::kOverwrite);
    return map;
#else
    throw fragg::InvalidArgument(path + ": this build has no liboctomap: .bt/.ot are not readable");
#endif
  }
  throw fragg::InvalidArgument("unknown extension of '" + path + "': use .fgm, .bt or .ot");
}

}  // namespace fragg::ros
