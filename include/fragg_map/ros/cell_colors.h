// octomap_server's colored_map: cell colours from the points' RGB. The core map stores no
// colour, so the server keeps this side table: per block, the colour of each cell that a
// coloured point ended in, averaged as octomap's ColorOcTree::averageNodeColor does (a cell's
// first point sets its colour, every later point halves the way to its own: c = (c + p) / 2,
// per channel in integers). Only occupied cells are drawn in colour (markers); a cell with no
// colour keeps the height (or flat) colour. Each block remembers the table's sequence number
// (one more per integrated cloud) of its last recolouring, so incremental markers (whose ledger
// keeps the sequence they drew) redraw blocks whose colours changed even when their occupied
// cells did not. Not thread-safe: one owner (the server's publishers).
#pragma once

#include <sensor_msgs/PointCloud2.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <unordered_map>
#include <utility>
#include <vector>

#include "fragg_map/key.h"
#include "fragg_map/map.h"

namespace fragg::ros {

struct Rgb8 {
  uint8_t r = 0, g = 0, b = 0;
  bool operator==(const Rgb8& o) const { return r == o.r && g == o.g && b == o.b; }
};

/// Whether `msg` has an `rgb` or `rgba` field (PCL's packing: FLOAT32 or UINT32/INT32 holding
/// 0x00RRGGBB / 0xAARRGGBB in the low 24 bits).
bool hasRgbField(const sensor_msgs::PointCloud2& msg);

class CellColors {
 public:
  /// Averages the colour of every point of `msg` (sensor frame, placed by `T_map_sensor`)
  /// into the cell it ends in, for points with finite x, y, z within `max_range_m` of the
  /// sensor (<= 0: no limit) and inside the map's height filter, as those are the cells the
  /// insertion marked occupied. Blocks recoloured are stamped with the next sequence(). Returns
  /// the points used; 0 when the message has no rgb/rgba field. Throws
  /// fragg::InvalidArgument for a malformed rgb field (past point_step, 1- or 2-byte type).
  size_t integrate(const sensor_msgs::PointCloud2& msg, const Eigen::Isometry3d& T_map_sensor,
                   double max_range_m, const fragg::Map& map);

  /// The colour of cell `v`, if a point gave it one.
  std::optional<Rgb8> find(const fragg::VoxelKey& v) const;
  /// Clouds integrated so far (that gave a colour).
  uint64_t sequence() const { return sequence_; }
  /// Blocks recoloured after sequence number `sequence`.
  std::vector<fragg::BlockKey> recoloredSince(uint64_t sequence) const;
  /// Drops the colours of cells that are no longer observed (after clear_bbx, truncate,
  /// reset, load); keeps those of observed cells.
  void prune(const fragg::Map& map);
  void clear() { blocks_.clear(); }  ///< (the sequence goes on)
  size_t cells() const;

 private:
  struct BlockColors {
    uint64_t recolored_at = 0;
    std::vector<std::pair<uint16_t, Rgb8>> cells;  ///< cell index -> colour, unsorted
  };
  std::unordered_map<fragg::BlockKey, BlockColors, fragg::BlockKeyHash> blocks_;
  uint64_t sequence_ = 0;
};

}  // namespace fragg::ros
