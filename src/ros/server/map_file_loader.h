// Reading a map file into the server's map: .fgm (fragg_map) or .bt / .ot (OctoMap, through
// liboctomap when the build has it). Used by ~load_map and the start-up map (map_file).
#pragma once

#include <string>

#include "fragg_map/map.h"

namespace fragg::ros {

/// The map in `path` with the server's runtime settings (`runtime`: backend, threads, scan
/// store...). The file gives the cells, the occupancy model and the resolution, which must be
/// `runtime.resolution_m`. Throws fragg::InvalidArgument for an unknown extension or another
/// resolution, fragg::IoError for a missing or corrupt file.
fragg::Map loadMapFile(const std::string& path, const fragg::MapParams& runtime);

}  // namespace fragg::ros
