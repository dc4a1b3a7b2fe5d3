// Insertion itself: a scan (points, sensor pose, resolution, max range, sensor model and ray
// caster from the input bytes, insert_input.h) through Map::insert on the CPU backend, then,
// with the scan kept, a second insertion, a pose correction and a removal. The errors a caller
// catches (InvalidArgument for bad arguments) are fine; a crash, a sanitizer report or a broken
// invariant is a finding: the statistics must account for every point, and no block may lie
// beyond the max range (plus a block) from the sensor after the first insertion.
#include <cmath>
#include <cstdlib>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fuzz_targets.h"
#include "insert_input.h"

namespace fragg::fuzz {

namespace {

/// A broken invariant: abort, so that libFuzzer (and the corpus replay) reports the input.
void check(bool ok) {
  if (!ok) std::abort();
}

/// Every point of `s` counted once: a ray (hit, dynamic hit, free-only, no return) or a drop.
void checkPointsAccountedFor(const InsertStats& s, size_t points) {
  const uint64_t counted = s.rays_hit + s.rays_dynamic + s.rays_free_only + s.rays_no_return +
                           s.dropped_invalid + s.dropped_min_range + s.dropped_outside_frustum +
                           s.dropped_height;
  check(s.points_in == points && counted == points);
}

/// No block farther than the max range (and two blocks' diagonals) from the sensor.
void checkBlocksWithinRange(const Map& map, const Eigen::Vector3d& sensor_m, double max_range_m) {
  if (!(max_range_m > 0.0)) return;
  const double block_m = map.resolution() * kBlockSize;
  const double reach_m = max_range_m + 2.0 * std::sqrt(3.0) * block_m;
  map.forEachBlock([&](const BlockKey& key, const Block&) {
    const Eigen::Vector3d centre_m =
        (Eigen::Vector3d(key.x, key.y, key.z).array() + 0.5).matrix() * block_m;
    check((centre_m - sensor_m).norm() <= reach_m);
  });
}

}  // namespace

bool insertScan(const uint8_t* data, size_t size) {
  const InsertInput in = decodeInsertInput(data, size);
  try {
    Map map(in.params);
    const InsertStats first = map.insert(in.cloud, in.T_map_sensor, in.sensor);
    checkPointsAccountedFor(first, in.cloud.size());
    checkBlocksWithinRange(map, in.T_map_sensor.translation(), first.sensor.max_range_m);
    correctAndRemove(in, first.scan_id, map);
  } catch (const InvalidArgument&) {
    return false;
  }
  return true;
}

}  // namespace fragg::fuzz
