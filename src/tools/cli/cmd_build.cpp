// fragg_map build INPUT -o MAP.fgm: integrates every scan of a dataset into a map.
#include <fmt/format.h>
#include <sys/resource.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/paged_heap.h"
#include "cli/progress.h"
#include "fragg_map/atomic_file.h"
#include "fragg_map/errors.h"
#include "fragg_map/field_names.h"
#include "fragg_map/io/dataset.h"
#include "fragg_map/map.h"
#include "percentile.h"
#ifdef FRAGG_HAVE_ROSBAG
#include "fragg_map/io/rosbag_source.h"
#endif
#ifdef FRAGG_HAVE_PAGE_STORE
#include "fragg_map/store/page_stores.h"
#endif

namespace fragg::cli {

namespace {
using tools::percentile;

/// A line of /proc/self/status (`field`: "VmRSS", "RssAnon", "RssFile"...), MiB; 0 where
/// /proc or the field is missing.
double statusMib(const char* field) {
  std::FILE* f = std::fopen("/proc/self/status", "r");
  if (!f) return 0.0;
  const std::string format = std::string(field) + ": %lf kB";
  char line[256];
  double kib = 0.0;
  while (std::fgets(line, sizeof line, f))
    if (std::sscanf(line, format.c_str(), &kib) == 1) break;
  std::fclose(f);
  return kib / 1024.0;
}

/// The C heap as malloc holds it, MiB: `in_use` the bytes handed out, `free` the bytes its
/// arenas keep free (fragments, freed memory not yet returned), `mapped` the large blocks it
/// mapped apart (each returned when freed). Zeros without glibc.
struct HeapMib {
  double in_use = 0.0, free = 0.0, mapped = 0.0;
};
HeapMib heapMib() {
  HeapMib h;
#if defined(__GLIBC__) && (__GLIBC__ > 2 || (__GLIBC__ == 2 && __GLIBC_MINOR__ >= 33))
  const struct mallinfo2 m = mallinfo2();
  constexpr double kMib = 1024.0 * 1024.0;
  h.in_use = static_cast<double>(m.uordblks) / kMib;
  h.free = static_cast<double>(m.fordblks) / kMib;
  h.mapped = static_cast<double>(m.hblkhd) / kMib;
#endif
  return h;
}

/// The process's peak resident memory so far (getrusage's ru_maxrss), MiB.
double peakResidentMib() {
  struct rusage usage {};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return 0.0;
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // KiB on Linux
}

struct BuildOptions {
  std::string input, output;
  double resolution_m = MapParams().resolution_m;
  double max_range_m = -1.0, min_range_m = 0.0;
  double range_noise_m = 0.0, range_noise_quadratic_per_m = 0.0;
  std::string sensor = "auto", backend = "auto", raycast = "dda";
  double hfov_deg = 0.0, vfov_deg = 0.0;
  double elevation_min_deg = -90.0, elevation_max_deg = 90.0;
  // The LiDAR's beam table (nvblox's lidar_height / lidar_width), for --clear-no-return on
  // unorganised clouds.
  uint32_t lidar_rings = 0, lidar_columns = 0;
  std::vector<double> lidar_ring_elevations_deg;
  double lidar_azimuth_offset_deg = 0.0;
  std::string optical_axis = "z";
  std::string topic, frame = "map";
  OccupancyParams occupancy;
  bool clear_no_return = false;
  bool free_cut_cell = false;
  int threads = 0;
  size_t max_scans = 0;
  bool json = false;
  ScanStoreParams scans;
  double scan_budget_mib = 0.0;
  HeightFilterParams height_filter;
  DynamicParams dynamic;
  std::string dynamic_rule = "pass-through";  ///< DynamicParams::rule by name
  std::string page_store;                     ///< out-of-core paging: the store is the map
  bool heap_defaults = false;                 ///< paged: leave malloc's settings as they are
  PagingPolicy paging;
};

// The core's fields (as its validate() messages name them) -> the flags that set them.
const std::vector<FieldName>& flagNames() {
  static const std::vector<FieldName> names = {
      {"resolution_m", "--resolution"},
      {"occupancy.prob_hit", "--hit"},
      {"occupancy.prob_miss", "--miss"},
      {"occupancy.clamp_min", "--clamp-min"},
      {"occupancy.clamp_max", "--clamp-max"},
      {"occupancy.unknown_band", "--unknown-band"},
      {"backend", "--backend"},
      {"raycast", "--raycast"},
      {"threads", "--threads"},
      {"scans.point_step_m", "--scan-step"},
      {"height_filter.min_z_m", "--min-z"},
      {"height_filter.max_z_m", "--max-z"},
      {"dynamic.void_probability", "--void-probability"},
      {"dynamic.known_radius_cells", "--known-radius"},
      {"dynamic.rule", "--dynamic-rule"},
      {"dynamic.enabled", "--dynamic"},
      {"dynamic.decay_log_odds_per_scan", "--decay"},
      {"sensor.type", "--sensor"},
      {"sensor.hfov_rad", "--hfov"},
      {"sensor.vfov_rad", "--vfov"},
      {"sensor.elevation_min_rad", "--elevation-min"},
      {"sensor.elevation_max_rad", "--elevation-max"},
      {"sensor.min_range_m", "--min-range"},
      {"sensor.max_range_m", "--max-range"},
      {"sensor.range_noise_m", "--range-noise"},
      {"sensor.range_noise_quadratic_per_m", "--range-noise-quadratic"},
      {"sensor.lidar_rings", "--lidar-height"},
      {"sensor.lidar_columns", "--lidar-width"},
      {"sensor.lidar_ring_elevations_rad", "--lidar-ring-elevations"},
      {"sensor.lidar_azimuth_offset_rad", "--lidar-azimuth-offset"},
  };
  return names;
}

constexpr double kDeg = M_PI / 180.0;

SensorModel sensorShape(const BuildOptions& o) {
  switch (sensorTypeFromString(o.sensor)) {
    case SensorType::kPinhole:
      if (o.hfov_deg <= 0 || o.vfov_deg <= 0)
        throw InvalidArgument("--sensor pinhole needs --hfov and --vfov (degrees)");
      if (o.optical_axis != "z" && o.optical_axis != "x")
        throw InvalidArgument("--optical-axis must be z (camera optical frame) or x (body frame)");
      return SensorModel::pinhole(
          o.hfov_deg * kDeg, o.vfov_deg * kDeg, o.min_range_m, o.max_range_m,
          o.optical_axis == "x" ? OpticalAxis::kXForward : OpticalAxis::kZForward);
    case SensorType::kSpinningLidar:
      return SensorModel::spinningLidar(o.elevation_min_deg * kDeg, o.elevation_max_deg * kDeg,
                                        o.min_range_m, o.max_range_m);
    case SensorType::kAuto:
      break;
  }
  return SensorModel::autoFromCloud(o.min_range_m, o.max_range_m);
}

/// The beam table of --lidar-height/--lidar-width (rings evenly spaced over --sensor lidar's
/// --elevation-min..max) or --lidar-ring-elevations; empty when none is given.
LidarBeams beamsFrom(const BuildOptions& o) {
  LidarBeams b;
  if (!o.lidar_ring_elevations_deg.empty()) {
    if (o.lidar_rings != 0 && o.lidar_rings != o.lidar_ring_elevations_deg.size())
      throw InvalidArgument(
          "--lidar-height (" + std::to_string(o.lidar_rings) + ") disagrees with " +
          std::to_string(o.lidar_ring_elevations_deg.size()) + " --lidar-ring-elevations");
    for (double e : o.lidar_ring_elevations_deg) b.ring_elevations_rad.push_back(e * kDeg);
    b.columns = o.lidar_columns;
  } else if (o.lidar_rings != 0) {
    if (sensorTypeFromString(o.sensor) != SensorType::kSpinningLidar)
      throw InvalidArgument(
          "--lidar-height spaces its rings over --sensor lidar's --elevation-min..max: give "
          "--sensor lidar, or --lidar-ring-elevations");
    b = LidarBeams::evenlySpaced(o.lidar_rings, o.lidar_columns, o.elevation_min_deg * kDeg,
                                 o.elevation_max_deg * kDeg);
  } else {
    b.columns = o.lidar_columns;  // validate() refuses columns without rings
  }
  b.azimuth_offset_rad = o.lidar_azimuth_offset_deg * kDeg;
  return b;
}

SensorModel sensorFrom(const BuildOptions& o) {
  SensorModel m = sensorShape(o);
  m.range_noise_m = o.range_noise_m;
  m.range_noise_quadratic_per_m = o.range_noise_quadratic_per_m;
  m.lidar_beams = beamsFrom(o);
  m.validate();
  return m;
}

void runBuild(const BuildOptions& o) {
  // Before any thread or buffer: a paged build's heap in one arena, large buffers mapped apart.
  if (!o.page_store.empty() && !o.heap_defaults && !compactHeapForPaging())
    std::fprintf(stderr,
                 "fragg_map: note: malloc's settings for paging not applied (not glibc?)\n");
  MapParams params;
  SensorModel sensor;
  // The core checks the values; its messages come back naming the flags.
  withFieldNames(
      flagNames(),
      [&] {
        params.resolution_m = o.resolution_m;
        params.occupancy = o.occupancy;
        params.backend = backendFromString(o.backend);
        params.raycast = rayCastFromString(o.raycast);
        params.clear_no_return_rays = o.clear_no_return;
        params.free_cut_cell = o.free_cut_cell;
        params.threads = o.threads;
        params.scans = o.scans;
        params.height_filter = o.height_filter;
        params.dynamic = o.dynamic;
        params.dynamic.rule = voidSpaceRuleFromString(o.dynamic_rule);
        params.validate();
        sensor = sensorFrom(o);
      },
      "");
  if (!(o.scan_budget_mib >= 0.0)) throw InvalidArgument("--scan-budget must be >= 0 MiB");
  params.scans.max_bytes = static_cast<size_t>(o.scan_budget_mib * 1048576.0);
  if (!o.scans.keep && (o.scan_budget_mib > 0.0 || !o.scans.spill_dir.empty()))
    throw InvalidArgument("--scan-budget and --spill-dir need --keep-scans");
  if (o.output.empty() && o.page_store.empty())
    throw InvalidArgument("give an output map (-o MAP.fgm), a page store (--page-store), or both");
  if (!o.output.empty()) {
    if (o.output.size() < 5 || o.output.substr(o.output.size() - 4) != ".fgm")
      throw InvalidArgument("output must be a .fgm file, got '" + o.output + "'");
    AtomicFile probe(o.output);  // fail now, not after the build, if it cannot be written
  }
  if (o.page_store.empty() && (o.paging.budget_mb > 0 || o.paging.radius_m > 0))
    throw InvalidArgument("--page-budget-mb and --page-radius need --page-store");
  o.paging.validate();

#ifdef FRAGG_HAVE_ROSBAG
  registerRosbagReader();
#endif
  DatasetOptions dataset_options;
  dataset_options.topic = o.topic;
  dataset_options.frame = o.frame;
  auto source = openDataset(o.input, dataset_options);
  // With a page store that holds a map already, the build continues it: the store's scans are
  // the input's first scans, the rest are integrated.
  size_t resumed = 0;
  Map map = [&] {
    if (o.page_store.empty()) return Map(params);
#ifdef FRAGG_HAVE_PAGE_STORE
    if (params.scans.keep) throw InvalidArgument("--page-store cannot be used with --keep-scans");
    auto store = openPageStore(o.page_store, /*read_only=*/false);
    if (!store->readMeta().empty()) {
      Map m = Map::openPageStore(store, params, o.paging);
      if (m.resolution() != params.resolution_m)
        std::fprintf(stderr, "fragg_map: note: continuing %s at its resolution %g m\n",
                     o.page_store.c_str(), m.resolution());
      resumed = m.scanCount();
      return m;
    }
    Map m(params);
    m.attachPageStore(store, o.paging);
    return m;
#else
    throw InvalidArgument("--page-store: this fragg_map was built without SQLite (no page store)");
#endif
  }();

  // The process before its first scan (the backend started: the CUDA runtime's share).
  const double rss_open_mib = statusMib("VmRSS");
  Progress progress(source->size());
  InsertStats total;
  std::vector<double> ms_per_scan;
  std::vector<uint64_t> dynamic_per_scan;  // MapParams::dynamic: hits classified dynamic
  // Scans are read a batch at a time on another thread while the batch before is integrated
  // by one Map::insertSequence call (whose backend stages each next cloud during the scan
  // before). The reader skips empty messages (nothing to integrate) and the scans a resumed
  // page store holds already, and stops after --max-scans. A batch holds up to 16 scans and
  // 8 MiB of points, so that the two batches in memory stay small beside a paging budget
  // (W4: 1.9 MiB a scan, 63 MiB in two batches of 16 before the cap; heaptrack).
  constexpr size_t kBatchScans = 16;
  constexpr size_t kBatchBytes = size_t{8} << 20;
  size_t skipped_resumed = 0, taken = 0;  // the reader's
  bool input_left = true;                 // the reader's
  const auto readBatch = [&](std::vector<Scan>& batch) {
    batch.clear();
    size_t bytes = 0;
    while (input_left && batch.size() < kBatchScans && bytes < kBatchBytes &&
           (o.max_scans == 0 || taken < o.max_scans)) {
      Scan scan;
      if (!source->next(scan)) {
        input_left = false;
        break;
      }
      if (scan.cloud.empty()) continue;
      ++taken;
      if (skipped_resumed < resumed) {
        ++skipped_resumed;
        continue;
      }
      bytes += scan.cloud.points_S.size() * sizeof(Eigen::Vector3f) + scan.cloud.free_only.size();
      batch.push_back(std::move(scan));
    }
  };
  std::vector<Scan> batch, ahead;
  std::vector<ScanToInsert> to_insert;
  const auto t0 = std::chrono::steady_clock::now();
  std::future<void> ahead_read = std::async(std::launch::async, [&] { readBatch(ahead); });
  for (;;) {
    ahead_read.get();
    if (ahead.empty()) break;  // input read, or --max-scans reached
    std::swap(batch, ahead);
    ahead_read = std::async(std::launch::async, [&] { readBatch(ahead); });
    to_insert.clear();
    for (const Scan& scan : batch) {
      ScanToInsert s;
      s.cloud = &scan.cloud;
      s.T_map_sensor = scan.T_map_sensor;
      s.sensor = sensor;
      s.stamp_ns = scan.stamp_ns;
      to_insert.push_back(s);
    }
    for (const InsertStats& s : map.insertSequence(to_insert)) {
      total.add(s);
      ms_per_scan.push_back(s.seconds_total * 1e3);
      dynamic_per_scan.push_back(s.rays_dynamic);
    }
    progress.update(ms_per_scan.size());
  }
  progress.finish();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (ms_per_scan.empty() && resumed == 0) throw IoError(o.input + ": no scans with points found");
  if (resumed > skipped_resumed)
    throw IoError(fmt::format("{} holds {} scans but {} has only {}", o.page_store, resumed,
                              o.input, skipped_resumed));
  const double peak_rss_loop_mib = peakResidentMib();  // before the last commit and -o
  // What is resident at the loop's end: anonymous memory (the map, buffers, the runtime's heap),
  // mapped files (LMDB's map, libraries), shared memory.
  const double rss_anon_mib = statusMib("RssAnon"), rss_file_mib = statusMib("RssFile"),
               rss_shmem_mib = statusMib("RssShmem");
  const HeapMib heap = heapMib();  // how much of the anonymous memory is malloc's, and in use
  map.commitPages();
  if (!o.output.empty()) map.save(o.output);
  const PagingStats paging = map.pagingStats();
  const std::string where = o.output.empty() ? o.page_store : o.output;
  const size_t inserted = std::max<size_t>(1, ms_per_scan.size());

  const MemoryStats mem = map.memory();
  const double median = percentile(ms_per_scan, 0.5), p99 = percentile(ms_per_scan, 0.99);
  if (source->skipped() > 0)
    std::fprintf(stderr, "fragg_map: warning: %zu scans skipped (last: %s)\n", source->skipped(),
                 source->lastSkipReason().c_str());
  if (total.dropped_outside_frustum > 0)
    std::fprintf(stderr,
                 "fragg_map: warning: %llu points fell outside the %s sensor model's frustum "
                 "and were dropped (widen --hfov/--vfov or use --sensor auto)\n",
                 static_cast<unsigned long long>(total.dropped_outside_frustum), o.sensor.c_str());
  if (o.json) {
    nlohmann::json j = {
        {"output", where},
        {"input", source->describe()},
        {"backend", map.backendName()},
        {"backend_reason", map.backendReason()},
        {"device_bytes", mem.device_bytes},
        {"blocks_uploaded", total.blocks_uploaded},
        {"blocks_evicted", total.blocks_evicted},
        {"resolution_m", params.resolution_m},
        {"scans", ms_per_scan.size()},
        {"points", total.points_in},
        {"rays_hit", total.rays_hit},
        {"rays_free_only", total.rays_free_only},
        {"rays_no_return", total.rays_no_return},
        {"rays_dynamic", total.rays_dynamic},
        {"dropped_invalid", total.dropped_invalid},
        {"dropped_min_range", total.dropped_min_range},
        {"dropped_outside_frustum", total.dropped_outside_frustum},
        {"dropped_height", total.dropped_height},
        {"scans_skipped", source->skipped()},
        {"voxel_visits", total.voxel_visits},
        {"seconds", seconds},
        {"rss_mib",
         {{"before_first_scan", rss_open_mib},
          {"peak_build_loop", peak_rss_loop_mib},
          {"anon_loop_end", rss_anon_mib},
          {"file_loop_end", rss_file_mib},
          {"shmem_loop_end", rss_shmem_mib},
          {"heap_in_use_loop_end", heap.in_use},
          {"heap_free_loop_end", heap.free},
          {"heap_mapped_loop_end", heap.mapped}}},
        {"passes_redone", total.passes_redone},
        {"seconds_redone", total.seconds_redone},
        {"seconds_residency", total.seconds_residency},
        {"seconds_raycast", total.seconds_raycast},
        {"seconds_apply", total.seconds_apply},
        {"insert_seconds", total.seconds_total},
        {"ms_per_scan",
         {{"median", median}, {"p99", p99}, {"mean", total.seconds_total * 1e3 / inserted}}},
        {"known_voxels", mem.known_voxels},
        {"kept_scans", map.scanStore().size()},
        {"scan_store_bytes", mem.scan_store_bytes},
        {"blocks", mem.blocks},
        {"host_bytes", mem.host_block_bytes},
        {"culling",
         {{"blocks_tested", total.culling.blocks_tested},
          {"blocks_visible", total.culling.blocks_visible},
          {"tests_run", total.culling.tests_run},
          {"saved_by_plane_memory", total.culling.saved_by_plane_memory},
          {"saved_by_rotation", total.culling.saved_by_rotation},
          {"saved_by_translation", total.culling.saved_by_translation}}}};
    if (params.dynamic.decay_log_odds_per_scan > 0.0)
      j["decay_log_odds_per_scan"] = params.dynamic.decay_log_odds_per_scan;
    if (params.dynamic.enabled)
      j["dynamic"] = {{"rule", toString(params.dynamic.rule)},
                      {"void_probability", params.dynamic.void_probability},
                      {"known_radius_cells", params.dynamic.known_radius_cells},
                      {"rays_dynamic_per_scan", dynamic_per_scan}};
    if (paging.enabled)
      j["paging"] = {{"store", paging.store},
                     {"budget_mb", o.paging.budget_mb},
                     {"radius_m", o.paging.radius_m},
                     {"low_water", o.paging.low_water},
                     {"read_ahead_rays", o.paging.read_ahead_rays},
                     {"commit_every_scans", o.paging.commit_every_scans},
                     {"commit_every_s", o.paging.commit_every_s},
                     {"resumed_scans", resumed},
                     {"committed_scans", paging.committed_scans},
                     {"peak_resident_blocks", paging.peak_resident_blocks},
                     {"budget_blocks", paging.budget_blocks},
                     {"resident_blocks", paging.resident_blocks},
                     {"paged_blocks", paging.paged_blocks},
                     {"pages_written", paging.pages_written},
                     {"blocks_encoded", paging.blocks_encoded},
                     {"budget_bytes", paging.budget_bytes},
                     {"peak_counted_bytes", paging.peak_counted_bytes},
                     {"record_cache_bytes", paging.record_cache_bytes},
                     {"records_written", paging.records_written},
                     {"pages_read", paging.pages_read},
                     {"pages_read_pending", paging.pages_read_pending},
                     {"pages_evicted", paging.pages_evicted},
                     {"blocks_held", paging.blocks_held},
                     {"commits", paging.commits},
                     {"seconds_commit", paging.seconds_commit},
                     {"seconds_writer", paging.seconds_writer},
                     {"background_writer", o.paging.background_writer},
                     {"seconds_page_in", paging.seconds_page_in},
                     {"seconds_sync", paging.seconds_sync},
                     {"seconds_page_out", paging.seconds_page_out},
                     {"seconds_evict", paging.seconds_evict},
                     {"seconds_encode", paging.seconds_encode},
                     {"seconds_choose", paging.seconds_choose},
                     {"rounds_between_scans", paging.rounds_between_scans},
                     {"rounds_in_scan", paging.rounds_in_scan},
                     {"scans_read_ahead", paging.scans_read_ahead},
                     {"blocks_read_ahead", paging.blocks_read_ahead},
                     {"seconds_reach", paging.seconds_reach},
                     {"seconds_read_ahead", paging.seconds_read_ahead},
                     {"stops_in_scan", paging.stops_in_scan},
                     {"blocks_read_in_scan", paging.blocks_read_in_scan},
                     {"seconds_in_scan", paging.seconds_in_scan},
                     {"seconds_sync_in_scan", paging.seconds_sync_in_scan},
                     {"store_bytes", paging.store_bytes}};
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf(
        "%s\n",
        fmt::format("built {}: {} scans, {} points, {:.2f} s, {:.1f} ms/scan (median "
                    "{:.1f}, p99 {:.1f}), {} known voxels, {:.1f} MiB host memory, "
                    "backend {} ({})",
                    where, ms_per_scan.size(), total.points_in, seconds,
                    total.seconds_total * 1e3 / inserted, median, p99, mem.known_voxels,
                    mem.host_block_bytes / 1048576.0, map.backendName(), map.backendReason())
            .c_str());
    if (paging.enabled)
      std::printf("%s\n",
                  fmt::format("paging to {}: {} scans held ({} resumed), peak {} resident "
                              "blocks, {} now resident, {} paged out, {} pages written, {} read, "
                              "{} commits ({:.2f} s), store {:.1f} MiB",
                              paging.store, paging.committed_scans, resumed,
                              paging.peak_resident_blocks, paging.resident_blocks,
                              paging.paged_blocks, paging.pages_written, paging.pages_read,
                              paging.commits, paging.seconds_commit, paging.store_bytes / 1048576.0)
                      .c_str());
    if (map.scanStore().size() > 0)
      std::printf("%s\n",
                  fmt::format("kept {} scans for `fragg_map correct` ({:.1f} MiB of points "
                              "in memory, {} spilled, {} dropped)",
                              map.scanStore().size(), mem.scan_store_bytes / 1048576.0,
                              map.scanStore().spilledCount(), map.scanStore().droppedCount())
                      .c_str());
  }
}
}  // namespace

void addBuildCommand(CLI::App& app) {
  auto o = std::make_shared<BuildOptions>();
  CLI::App* c = app.add_subcommand("build",
                                   "Build a map from a dataset (bag, KITTI, graph, PCD "
                                   "folder + TUM poses, depth images, point file)");
  c->add_option("input", o->input, "Dataset to read")->required();
  c->add_option("-o,--output", o->output,
                "Map file to write (.fgm; optional with --page-store, which is the map)");
  c->add_option("--resolution", o->resolution_m, "Voxel edge in metres")->capture_default_str();
  c->add_option("--max-range", o->max_range_m,
                "Max range in metres; farther points clear free space up to it (<= 0: none)");
  c->add_option("--min-range", o->min_range_m, "Points closer than this are dropped (m)");
  c->add_option("--range-noise", o->range_noise_m,
                "Sensor range noise, one sigma (m): free space stops that far before each hit "
                "(LiDAR ~0.02; 0 = OctoMap's behaviour)")
      ->capture_default_str();
  c->add_option("--range-noise-quadratic", o->range_noise_quadratic_per_m,
                "Range noise growing with range^2 (1/m; depth cameras ~0.001-0.003): sigma(r) = "
                "--range-noise + this * r^2")
      ->capture_default_str();
  c->add_option("--sensor", o->sensor, "Sensor model: auto | lidar | pinhole")
      ->capture_default_str();
  c->add_option("--hfov", o->hfov_deg, "Pinhole horizontal field of view (degrees)");
  c->add_option("--vfov", o->vfov_deg, "Pinhole vertical field of view (degrees)");
  c->add_option("--optical-axis", o->optical_axis,
                "Pinhole forward axis: z (optical frame) or x (body frame)")
      ->capture_default_str();
  c->add_option("--elevation-min", o->elevation_min_deg, "LiDAR lowest beam (degrees)")
      ->capture_default_str();
  c->add_option("--elevation-max", o->elevation_max_deg, "LiDAR highest beam (degrees)")
      ->capture_default_str();
  c->add_option("--backend", o->backend, "auto | cpu | cuda")->capture_default_str();
  c->add_option("--raycast", o->raycast,
                "dda | bresenham | octomap (liboctomap's computeRayKeys arithmetic)")
      ->capture_default_str();
  c->add_option("--topic", o->topic, "Bag: PointCloud2 topic (default: the only one)");
  c->add_option("--frame", o->frame, "Bag: fixed frame of the map")->capture_default_str();
  c->add_option("--hit", o->occupancy.prob_hit, "Hit probability")->capture_default_str();
  c->add_option("--miss", o->occupancy.prob_miss, "Miss probability")->capture_default_str();
  c->add_option("--clamp-min", o->occupancy.clamp_min, "Lower clamping probability")
      ->capture_default_str();
  c->add_option("--clamp-max", o->occupancy.clamp_max, "Upper clamping probability")
      ->capture_default_str();
  c->add_option("--unknown-band", o->occupancy.unknown_band,
                "Cells with |p - 0.5| <= band are unknown")
      ->capture_default_str();
  c->add_option("--min-z", o->height_filter.min_z_m,
                "Points below this map-frame height are not inserted (m; octomap_server's "
                "pointcloud_min_z)");
  c->add_option("--max-z", o->height_filter.max_z_m,
                "Points above this map-frame height are not inserted (m; pointcloud_max_z)");
  c->add_flag("--clear-no-return", o->clear_no_return,
              "Clear free space to --max-range along rays without a return: an organised "
              "cloud's NaN pixels, or an unorganised cloud's empty beams of --lidar-height x "
              "--lidar-width");
  c->add_option("--lidar-height", o->lidar_rings,
                "LiDAR rings (nvblox's lidar_height), evenly spaced from --elevation-min to "
                "--elevation-max (--sensor lidar); with --lidar-width a beam table for "
                "--clear-no-return on unorganised clouds");
  c->add_option("--lidar-width", o->lidar_columns,
                "LiDAR columns a revolution (nvblox's lidar_width)");
  c->add_option("--lidar-ring-elevations", o->lidar_ring_elevations_deg,
                "LiDAR ring elevations, degrees ascending, comma-separated (rings not evenly "
                "spaced; instead of --lidar-height)")
      ->delimiter(',');
  c->add_option("--lidar-azimuth-offset", o->lidar_azimuth_offset_deg,
                "Azimuth of the LiDAR's column 0 (degrees counter-clockwise from +x)")
      ->capture_default_str();
  c->add_flag("--free-cut-cell", o->free_cut_cell,
              "A ray cut at --max-range also frees the cell at the cut point (octomap_server's "
              "rule; off: liboctomap's insertPointCloud leaves it)");
  c->add_flag("--dynamic", o->dynamic.enabled,
              "Dynamic scenes: hits in void space (observed free with confidence) are dynamic, "
              "not inserted; counted per scan in --json");
  c->add_option("--dynamic-rule", o->dynamic_rule,
                "With --dynamic: how space becomes void: pass-through (a ray through an occupied "
                "cell whose neighbourhood is observed voids it) | surround (DUFOMap's: a "
                "passed-through cell whose every neighbour is seen free)")
      ->capture_default_str();
  c->add_option("--void-probability", o->dynamic.void_probability,
                "With --dynamic: a cell is void at or below this probability")
      ->capture_default_str();
  c->add_option("--known-radius", o->dynamic.known_radius_cells,
                "With --dynamic: cells around a void hit that must have been observed "
                "(Chebyshev radius, 0-2)")
      ->capture_default_str();
  c->add_option("--decay", o->dynamic.decay_log_odds_per_scan,
                "Forgetting: after each scan every observed cell's log-odds moves this much "
                "toward 0 (0 = off, up to 4; CPU backend; with or without --dynamic)")
      ->capture_default_str();
  c->add_option("--threads", o->threads, "CPU threads (0 = every core)")->capture_default_str();
  c->add_option("--scans", o->max_scans, "Integrate only the first N scans (0 = all)")
      ->capture_default_str();
  c->add_flag("--keep-scans", o->scans.keep,
              "Keep every scan in the map file (points, pose, sensor model) so that "
              "`fragg_map correct` can move scans to corrected poses later");
  c->add_option("--scan-step", o->scans.point_step_m,
                "Kept points: 0 = float32 as received (12 bytes a point; the map is the same "
                "as without --keep-scans); > 0 = quantised to int16 at this step in metres "
                "(half the memory, but the map integrates the quantised points: at 0.001 and "
                "5 cm, 0.2-1.2 % of the cells differ on real scans)")
      ->capture_default_str();
  c->add_option("--scan-budget", o->scan_budget_mib,
                "Kept points held in memory at most, MiB (0 = no limit); older scans go to "
                "--spill-dir or are dropped");
  c->add_option("--spill-dir", o->scans.spill_dir, "Folder for kept points beyond --scan-budget");
  c->add_option("--page-store", o->page_store,
                "Out-of-core paging: the store that holds the map (.lmdb LMDB, .db SQLite; other "
                "names: LMDB where built, else SQLite); an "
                "existing store is continued (its scans are the input's first scans)");
  c->add_flag("--heap-defaults", o->heap_defaults,
              "Page store: leave malloc's settings as they are (by default a paged build keeps one "
              "arena and maps buffers of 1 MiB or more apart: a smaller peak RSS)");
  c->add_option("--page-budget-mb", o->paging.budget_mb,
                "Resident blocks' memory above which blocks are paged out (MB; 0 = never)")
      ->capture_default_str();
  c->add_option("--page-radius", o->paging.radius_m,
                "Blocks within this distance of the sensor are paged out last, only when the "
                "budget needs it (m)")
      ->capture_default_str();
  c->add_option("--page-low-water", o->paging.low_water,
                "Page store: a paging round brings the resident blocks down to this fraction of "
                "the budget (0-1]")
      ->capture_default_str();
  c->add_option("--read-ahead-rays", o->paging.read_ahead_rays,
                "Page store, CUDA backend: rays walked on the host before the ray pass to read "
                "back the paged-out regions it reaches (a sample of a denser scan; 0 = every ray)")
      ->capture_default_str();
  c->add_option("--commit-every", o->paging.commit_every_scans,
                "Page store: commit the changed blocks every N scans (0 = by time only)")
      ->capture_default_str();
  c->add_option("--commit-seconds", o->paging.commit_every_s,
                "Page store: commit at least this often (s; 0 = by scans only)")
      ->capture_default_str();
  c->add_flag_callback(
      "--sync-commits", [o] { o->paging.background_writer = false; },
      "Page store: write commits on the map's thread (default: a background writer)");
  c->add_flag("--json", o->json, "Print one JSON object on stdout");
  c->callback([o] { runBuild(*o); });
}

}  // namespace fragg::cli
