// Integrating a scan into an OctoMap OcTree the way octomap_server does (the reference the
// benchmark and `fragg_map octomap-build` compare against).
#pragma once

#include <octomap/OcTree.h>

#include "fragg_map/io/dataset.h"

namespace fragg {

/// Transforms the scan's finite, non-zero points into the map frame and calls
/// OcTree::insertPointCloud(points, sensor origin, max_range_m) (max_range_m <= 0: no limit).
/// Returns the seconds spent in insertPointCloud alone.
double insertIntoOcTree(octomap::OcTree& tree, const Scan& scan, double max_range_m);

}  // namespace fragg
