#include "bench/engines.h"

#include <chrono>

#ifdef FRAGG_HAVE_OCTOMAP
#include <octomap/octomap.h>

#include "fragg_map/interop/compare.h"
#include "fragg_map/interop/octomap_insert.h"
#include "fragg_map/interop/octomap_io.h"
#endif

namespace fragg::bench {

using Clock = std::chrono::steady_clock;

Figures runFragg(const Workload& w, Backend backend, size_t count, int repeats, int threads,
                 Map* keep) {
  Figures f;
  MapParams p;
  p.resolution_m = w.resolution_m;
  p.occupancy.unknown_band = 0.0;  // OctoMap's rule, for the agreement figures
  p.threads = threads;
  p.backend = backend;
  for (int r = 0; r < repeats; ++r) {
    Map map(p);
    for (size_t i = 0; i < count; ++i) {
      const Scan& s = w.scans[i];
      const auto t0 = Clock::now();
      const InsertStats st =
          map.insert(s.cloud, s.T_map_sensor, SensorModel::autoFromCloud(0.0, w.max_range_m));
      const double sec = std::chrono::duration<double>(Clock::now() - t0).count();
      f.ms.push_back(sec * 1e3);
      f.seconds += sec;
      f.visits += st.voxel_visits;
    }
    if (r + 1 == repeats) {
      const MemoryStats m = map.memory();
      f.known = m.known_voxels;
      f.bytes = m.host_block_bytes;
      if (keep) *keep = std::move(map);
    }
  }
  return f;
}

#ifdef FRAGG_HAVE_OCTOMAP
OctomapRun runOctomap(const Workload& w, size_t count) {
  OctomapRun out;
  octomap::OcTree tree(w.resolution_m);  // OctoMap's defaults = fragg's defaults
  for (size_t i = 0; i < count; ++i) {
    const double sec = insertIntoOcTree(tree, w.scans[i], w.max_range_m);
    out.figures.ms.push_back(sec * 1e3);
    out.figures.seconds += sec;
  }
  out.figures.bytes = tree.memoryUsage();
  out.map = fromOcTree(tree);
  out.figures.known = out.map.knownVoxelCount();
  return out;
}

std::pair<double, double> agreementWithOctomap(const Map& fragg_map, const Map& octomap_map) {
  CompareOptions rule;
  rule.octomap_threshold = true;
  const MapComparison c = compareMaps(fragg_map, octomap_map, rule);
  return {c.agreementInBoth(), c.agreementInEither()};
}
#endif

}  // namespace fragg::bench
