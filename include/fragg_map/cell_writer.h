// Direct cell writes, handed out by Map::writeCells (importers, test fixtures): the map
// stamps the blocks, invalidates the backend's cache and marks kept scans unremovable.
#pragma once

#include <cstdint>

#include "fragg_map/block_map.h"
#include "fragg_map/key.h"
#include "fragg_map/occupancy.h"

namespace fragg {

class CellWriter {
 public:
  /// Sets one cell (Cell() makes it unknown). Values are written as given (an importer keeps
  /// a file's exact log-odds, even beyond the clamping range). Throws InvalidArgument for a
  /// negative hit count (nothing written).
  void set(const VoxelKey& key, const Cell& cell);
  /// Sets every cell of block `key` to `block`'s (copies of another map's blocks: the
  /// server's mirror of its map). Only the cells that differ are written (and stamped); a block
  /// the map lacks is made only when `block` has an observed cell. Throws InvalidArgument for a
  /// negative hit count (nothing written).
  void setBlock(const BlockKey& key, const Block& block);
  /// Sets the fixed-point log-odds of every cell of the cube [lo, lo + edge_vox - 1], keeping
  /// their hit counts.
  void fillCube(const VoxelKey& lo, int32_t edge_vox, int16_t log_odds_fx);
  const OccupancyModel& model() const { return model_; }
  uint64_t cellsWritten() const { return written_; }

 private:
  friend class Map;
  CellWriter(BlockMap& blocks, const OccupancyModel& model, uint64_t revision)
      : blocks_(blocks), model_(model), revision_(revision) {}
  void setInBlock(BlockIndex i, int cell, const Cell& value);

  BlockMap& blocks_;
  const OccupancyModel& model_;
  uint64_t revision_;
  uint64_t written_ = 0;
};

}  // namespace fragg
