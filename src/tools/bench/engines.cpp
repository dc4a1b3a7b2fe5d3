#include "bench/engines.h"

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "fragg_map/errors.h"

#ifdef FRAGG_HAVE_OCTOMAP
#include <octomap/octomap.h>

#include "fragg_map/interop/compare.h"
#include "fragg_map/interop/octomap_insert.h"
#include "fragg_map/interop/octomap_io.h"
#endif

namespace fragg::bench {

using Clock = std::chrono::steady_clock;

namespace {
constexpr const char* kSequenceOption = "sequence";

/// The '+'-joined tokens of an engine name: the backend, then its options.
std::vector<std::string> engineTokens(const std::string& engine) {
  std::vector<std::string> tokens;
  for (size_t begin = 0; begin <= engine.size();) {
    const size_t end = std::min(engine.find('+', begin), engine.size());
    tokens.push_back(engine.substr(begin, end - begin));
    begin = end + 1;
  }
  return tokens;
}

/// Whether the engine name carries `option` after its backend.
bool hasOption(const std::string& engine, const std::string& option) {
  const std::vector<std::string> tokens = engineTokens(engine);
  return std::find(tokens.begin() + 1, tokens.end(), option) != tokens.end();
}
}  // namespace

MapParams engineParams(const std::string& engine, const MapParams& base) {
  MapParams p = base;
  const std::vector<std::string> tokens = engineTokens(engine);
  p.backend = backendFromString(tokens.front());
  for (size_t i = 1; i < tokens.size(); ++i) {
    const std::string& token = tokens[i];
    if (token == "pageable") {
      p.cuda.pinned_host_blocks = false;
    } else if (token == "plain-loads") {
      p.cuda.readonly_ray_loads = false;
    } else if (token == "no-coherence") {
      p.culling.plane_memory = false;
      p.culling.rotation_coherence = false;
      p.culling.translation_coherence = false;
    } else if (token == "bresenham") {
      p.raycast = RayCast::kBresenham;
    } else if (token == "octomap-raycast") {
      p.raycast = RayCast::kOctomap;
    } else if (token == "no-skip") {
      p.skip_saturated_blocks = false;
    } else if (token == "no-coalesce") {
      p.cuda.coalesce_ray_marks = false;
    } else if (token == "host-auto") {
      p.cuda.device_auto_sensor = false;
    } else if (token == "block-apply") {
      p.cuda.warp_per_slot_apply = false;
    } else if (token == "all-host-threads") {
      p.cuda.host_threads = 0;
    } else if (token == "no-staging") {
      p.cuda.stage_next_cloud = false;
    } else if (token == "dynamic-surround" || token == "dynamic-pass-through") {
      p.dynamic.enabled = true;  // MapParams::dynamic under that rule (issue 37's cost)
      p.dynamic.rule = voidSpaceRuleFromString(token.substr(8));
    } else if (token.rfind("pieces=", 0) == 0) {
      try {
        p.cuda.ray_piece_steps = std::stoi(token.substr(7));
      } catch (const std::exception&) {
        throw InvalidArgument("engine option '" + token + "': N must be an integer");
      }
    } else if (token == kSequenceOption) {
      // runFragg's: the scans go through Map::insertSequence; the params are the same.
    } else {
      throw InvalidArgument(
          "unknown engine option '" + token + "' in '" + engine +
          "' (pageable, plain-loads, no-coherence, bresenham, octomap-raycast, no-skip, "
          "no-coalesce, host-auto, block-apply, all-host-threads, no-staging, dynamic-surround, "
          "dynamic-pass-through, pieces=N, sequence)");
    }
  }
  return p;
}

Figures runFragg(const Workload& w, const std::string& engine, size_t count, int repeats,
                 int threads, Map* keep) {
  Figures f;
  MapParams base;
  base.resolution_m = w.resolution_m;
  base.occupancy.unknown_band = 0.0;  // OctoMap's rule, for the agreement figures
  base.threads = threads;
  const MapParams p = engineParams(engine, base);
  const bool sequence = hasOption(engine, kSequenceOption);
  const SensorModel sensor = SensorModel::autoFromCloud(0.0, w.max_range_m);
  for (int r = 0; r < repeats; ++r) {
    Map map(p);
    const auto record = [&](const InsertStats& st, double ms) {
      f.ms.push_back(ms);
      f.scan_stats.push_back(st);
      f.visits += st.voxel_visits;
      if (r + 1 == repeats) f.totals.add(st);
    };
    if (sequence) {
      // One call over every scan; a scan's time is its own InsertStats::seconds_total (what
      // it waited for: the scan before's staging of it ran while the device was busy).
      std::vector<ScanToInsert> batch(count);
      for (size_t i = 0; i < count; ++i) {
        batch[i].cloud = &w.scans[i].cloud;
        batch[i].T_map_sensor = w.scans[i].T_map_sensor;
        batch[i].sensor = sensor;
      }
      const auto t0 = Clock::now();
      const std::vector<InsertStats> all = map.insertSequence(batch);
      f.seconds += std::chrono::duration<double>(Clock::now() - t0).count();
      for (const InsertStats& st : all) record(st, st.seconds_total * 1e3);
    } else {
      for (size_t i = 0; i < count; ++i) {
        const Scan& s = w.scans[i];
        const auto t0 = Clock::now();
        const InsertStats st = map.insert(s.cloud, s.T_map_sensor, sensor);
        const double sec = std::chrono::duration<double>(Clock::now() - t0).count();
        f.seconds += sec;
        record(st, sec * 1e3);
      }
    }
    if (r + 1 == repeats) {
      const MemoryStats m = map.memory();
      f.known = m.known_voxels;
      f.bytes = m.host_block_bytes;
      f.device_bytes = m.device_bytes;
      f.device_estimate_bytes = m.device_estimate_bytes;
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
