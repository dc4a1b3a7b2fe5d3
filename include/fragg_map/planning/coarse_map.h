// A coarser copy of a map's cell states, for frontiers that mean something on LiDAR maps
// (issue 34 item 5). A LiDAR at 5 cm leaves unobserved cells between its beams, so on the map
// itself most free space borders unknown cells and is frontier (60 M frontier cells for ten
// KITTI scans). On a grid at about the beam spacing those gaps vanish: a coarse cell of k x k x k
// map cells is
//   free      when any of its cells is free (space the sensor saw through),
//   unknown   when every one of its cells is unknown (never observed, or inside the unknown band),
//   occupied  otherwise (occupied cells, none free),
// so frontiers, clusters, viewpoints and gains computed on the coarse map (the paper's cell
// definition, unchanged: a free cell with an unknown cell among its 26 neighbours) are frontiers
// between space seen through and space not seen at all. This is the rule of planners that keep
// their frontier grid coarser than the map (FUEL's and ROG-Map's frontier grids); the map's own
// cell-level frontiers stay what findFrontierCells computes on the map.
//
// The coarse map has resolution k times the map's and keys floor(key / k): coarse cell c covers
// map cells [k c, k c + k - 1] on each axis. Its free cells hold the lower clamp's log-odds, its
// occupied cells the upper clamp's, so Map::state() says the rule above; it is a map of its own
// (CPU backend), built from the state masks (no cell is read).
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "fragg_map/map.h"
#include "fragg_map/planning/query_control.h"

namespace fragg::planning {

/// Coarse cell edges allowed, in map cells (divisors of the 8-cell block edge).
[[nodiscard]] bool validCoarseCells(int cells);

/// The coarse map of `map` at `cells` map cells a coarse cell (1, 2, 4 or 8; 1 copies the states
/// as they are). Throws InvalidArgument for another edge; QueryStopped when `control` fires.
/// Hold the map's read lock.
[[nodiscard]] Map coarseStateMap(const Map& map, int cells, const QueryControl* control = nullptr);

/// The coarse map of the part of `map` a query in the box [lo_m, hi_m] (map frame) can see:
/// the blocks within `margin_m` plus one coarse cell of the box, coarsened as coarseStateMap
/// does. Coarse cells inside the box hold the same states, with the same neighbours, as in
/// coarseStateMap(map, cells); `margin_m` is how far beyond the box the query looks (viewpoint
/// rings, clearance and gain rays). InvalidArgument for a non-finite or inverted box, a negative
/// margin or a bad edge; QueryStopped when `control` fires. Hold the map's read lock.
[[nodiscard]] Map coarseStateMapIn(const Map& map, int cells, const Eigen::Vector3d& lo_m,
                                   const Eigen::Vector3d& hi_m, double margin_m,
                                   const QueryControl* control = nullptr);

/// The coarse cell edge (map cells, a power of two <= 8) nearest below the spacing of a
/// sensor's beams at `range_m`: `angle_rad` between neighbouring beams (the larger of the
/// vertical and horizontal steps), at least 1.
[[nodiscard]] int coarseCellsForBeams(double resolution_m, double angle_rad, double range_m);

}  // namespace fragg::planning
