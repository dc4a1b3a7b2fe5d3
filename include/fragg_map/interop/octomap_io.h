// OctoMap interop (liboctomap): export a map as a .bt file and import .bt / .ot files.
//
// Keys line up exactly: fragg's voxel key k is OctoMap's key k + 32768 on every axis, so a
// cell keeps its place and centre. OctoMap keys are 16-bit: only cells with voxel keys in
// [-32768, 32767] per axis (about +-1.6 km at 5 cm) can be represented; the export refuses
// anything beyond that instead of wrapping around.
#pragma once

#include <octomap/OcTree.h>

#include <cstdint>
#include <memory>
#include <string>

#include "fragg_map/map.h"

namespace fragg {

/// Voxel keys OctoMap can represent, per axis (inclusive).
constexpr int32_t kOctomapMinKey = -32768;
constexpr int32_t kOctomapMaxKey = 32767;

/// An OcTree with the map's resolution and occupancy parameters (hit, miss, clamping; the
/// occupancy threshold stays OctoMap's 0.5) holding one leaf per observed cell with the
/// cell's exact log-odds (log_odds_fx / 1024). Not pruned. Throws IoError naming the first
/// cell outside OctoMap's key range.
std::unique_ptr<octomap::OcTree> toOcTree(const Map& map);

/// Writes the map as an OctoMap binary tree (.bt) at `path_bt`, atomically (temporary file
/// and rename). As with any .bt, only free/occupied survives: OctoMap's rule is
/// occupied iff log-odds >= 0 (p >= 0.5), and the tree is pruned. Throws IoError when a cell
/// is outside OctoMap's key range or the file cannot be written (nothing is left behind).
void exportOctomap(const Map& map, const std::string& path_bt);

/// Writes the map as a full OctoMap tree (.ot, id OcTree) at `path_ot`, atomically: every
/// observed cell with its exact log-odds, as octomap_server's `octomap_full` carries it. With
/// `prune` (octomap_server's `compress_map`, the default there) eight sibling leaves of equal
/// value become one (lossless: reading the file back gives the same cells); without it, one
/// leaf per cell. Throws IoError as exportOctomap does.
void exportOctomapFull(const Map& map, const std::string& path_ot, bool prune);

/// The data section of a full OctoMap tree of the map (OcTree::writeData of toOcTree(map),
/// pruned first with `prune`): what octomap_msgs/Octomap's `data` holds for `octomap_full`.
std::string octomapFullData(const Map& map, bool prune);

/// A map with the tree's resolution and occupancy parameters (the unknown band keeps
/// MapParams' default) holding every leaf of the tree; leaves at a coarser depth are
/// expanded into voxels at the tree's resolution. Log-odds are rounded to fixed point and
/// clamped to the int16 range. Throws IoError for a tree whose leaves would expand to more
/// than kMaxImportVoxels voxels or hold a non-finite value.
Map fromOcTree(const octomap::OcTree& tree, Backend backend = Backend::kAuto);

/// Reads an OctoMap file: binary (.bt, "# Octomap OcTree binary file") or full (.ot,
/// "# Octomap OcTree file" with id OcTree, ColorOcTree or OcTreeStamped); the kind is taken
/// from the file's first line, not its name. The data is checked for structure before
/// liboctomap parses it. Throws IoError for a missing, truncated or corrupt file.
Map importOctomap(const std::string& path, Backend backend = Backend::kAuto);

/// Upper bound on the voxels an import may create (2^28 voxels: 1 GiB of cells).
constexpr uint64_t kMaxImportVoxels = uint64_t{1} << 28;

}  // namespace fragg
