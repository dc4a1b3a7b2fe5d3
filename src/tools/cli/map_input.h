// Loading the map files the CLI accepts, chosen by extension.
#pragma once

#include <string>

#include "fragg_map/map.h"

namespace fragg::cli {

/// .fgm through fragg::Map::load; a page store (.db / .sqlite: SQLite, .lmdb: LMDB) through
/// fragg::Map::loadPageStore (read-only, one snapshot, when built with the page stores); .bt / .ot
/// through fragg::importOctomap when the tool was built with liboctomap. Throws IoError for a
/// missing or unreadable file (or a build without liboctomap), InvalidArgument for an extension it
/// does not know.
fragg::Map loadMapFile(const std::string& path);

/// Lower-case extension of `path` without the dot ("" when there is none).
std::string extensionOf(const std::string& path);

/// Throws IoError when the directory that would hold `path` does not exist, so commands fail
/// before doing their work rather than after it.
void checkOutputDirectory(const std::string& path);

}  // namespace fragg::cli
