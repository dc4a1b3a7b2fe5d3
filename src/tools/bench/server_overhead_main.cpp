// fragg_map_server_overhead: what the map server spends per W1 cloud outside insertion, with
// one subscriber on every map output, before (main's path: occupied cloud and projected map
// rebuilt over the whole map after every cloud) and after (MapOutputCache: the pieces of the
// blocks whose cell states changed refreshed, messages assembled from them; "any": the same
// cache refreshing every changed block, as before BlockMeta::state_at). Per cloud: the PointCloud2
// conversion (cloudFromMsg), the incremental markers (changedBlockMarkers, as the server publishes
// them), the occupied cloud (occupied_cells and octomap_point_cloud_centers share one message), the
// projected map, and each message serialised once as roscpp does for a subscriber in another
// process (ros::serialization::serializeMessage; the markers as the server sends them, their
// changed chunks' kept wire bytes: marker_wire.h). As the server, glibc's thresholds are raised
// first so that message buffers are reused (publish_buffers.h; --fresh-buffers: not), and the
// page faults of the flush are counted. No ROS master: the builders are called directly. Markers
// are the same incremental update on both paths (timed once); the whole-map rebuilds of the old
// path run only after the scans whose rows are printed. Times are CPU milliseconds of the process
// (the machine is shared). With --marker-rate / --map-rate (the server's marker_rate and map_rate)
// the clouds arrive at
// --cloud-rate of sensor time and the after path runs the marker update, or the cache update +
// occupied cloud + projected map + their serialisation, only after the clouds where the
// server's RateThrottle lets one out (the skipped clouds' changes go out with the next); its
// rows then show 0 in the columns that were not due. Then it prints the after path's cost
// amortised over all clouds (sum / clouds), the median and max of one update of each kind
// (what a publication costs when it comes: that latency is not amortised), and what the
// server's timer would flush after the last cloud (not in the sum). Paced (the server's
// paced_outputs, the default; --unpaced: not), the markers send their share of the changed
// chunks and the cache recomputes its share of the changed blocks after every cloud (the
// whole-map messages when due); the per-cloud p50 / p99 is what the server's insertion thread
// spends outside insertion. The before and any paths stay unthrottled (any: the markers that
// the before rows borrow when the after path's were not due).
//   fragg_map_server_overhead --workloads DIR [--scans N] [--big-map FILE] [--big-scans K]
//                             [--cloud-rate HZ] [--marker-rate HZ] [--map-rate HZ]
//                             [--marker-chunk N] [--after-only] [--cells-always]
//                             [--fresh-buffers] [--unpaced] [--flat-markers] [--worst N]
//                             [--backend cpu|cuda] [--sync-stage] [--mirror auto|on|off]
// --mirror: the after path's cache and markers read a mask mirror (MaskMirror, as the server
// does on a CUDA map: auto) or the map's views.
// --sync-stage: before the outputs of a cloud where the markers take the changes in or a
// whole-map publication lists them (where the server's outputs read Map::blockView(), which on a
// CUDA map writes the device's changed blocks back first), that write-back is done and timed on
// its own (`sync`, `sync_flt` in --worst; a line of its own), so that the outputs' stages show
// what they cost apart from it. On a CPU map it costs nothing. With the mirror, the stage is
// the mirror's sync (the changed blocks' masks copied) instead.
#include <ros/serialization.h>
#include <sensor_msgs/PointCloud2.h>
#include <sensor_msgs/PointField.h>
#include <sys/resource.h>
#include <time.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "bench/velodyne_msg.h"
#include "bench/workloads.h"
#include "fragg_map/map.h"
#include "fragg_map/ros/block_markers.h"
#include "fragg_map/ros/cloud_from_msg.h"
#include "fragg_map/ros/mask_mirror.h"
#include "fragg_map/ros/occupied_cloud.h"
#include "fragg_map/ros/output_cache.h"
#include "fragg_map/ros/projected_map.h"
#include "fragg_map/ros/publish_buffers.h"
#include "fragg_map/ros/rate_throttle.h"
#include "percentile.h"

namespace {

/// CPU time of the whole process (all threads), so that figures taken on a shared, loaded
/// machine count this program's work and not the time it waited for a core.
struct Clock {
  using time_point = double;
  static double now() {
    timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
  }
};

double msSince(double start_ms) { return Clock::now() - start_ms; }

/// Minor page faults of the process so far (a fresh page costs ~15 us on the 2-core VM).
long minorFaults() {
  rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

/// One subscriber in another process: the message serialised once.
template <typename M>
size_t serialised(const M& msg) {
  return ros::serialization::serializeMessage(msg).num_bytes;
}

struct Times {
  double markers = 0, cloud = 0, grid = 0;
  double serialise = 0;  ///< all three messages
  size_t bytes = 0;
  // The markers' share (the same on both paths).
  double marker_serialise = 0;
  size_t marker_bytes = 0;
  long marker_faults = 0;        ///< minor page faults while the markers were built and serialised
  long marker_build_faults = 0;  ///< of those, while they were built
  long map_faults = 0;           ///< the same for the whole-map outputs
  size_t blocks_read = 0;        ///< blocks the output cache recomputed (after path)
  size_t cells_read = 0;         ///< of those, blocks whose cells it read (the others: masks)
  fragg::ros::OutputCacheUpdate stages;  ///< the cache update's own account (wall times)
  double cache_update = 0;               ///< of `cloud`: MapOutputCache::update alone (after path)
  /// --sync-stage: Map::blockView() alone (a CUDA map's write-back), or the mirror's sync
  double sync = 0;
  size_t sync_listed = 0;     ///< the mirror's sync: blocks the changed-block list named
  double sync_list_ms = 0;    ///< and the wall ms of Map::masksChangedSince in it
  double sync_update_ms = 0;  ///< of the held blocks' update
  double sync_add_ms = 0;     ///< of the new blocks' addition
  long sync_faults = 0;       ///< minor page faults in it
  bool synced = false;        ///< the stage ran before this cloud's outputs
  size_t pending_chunks = 0;  ///< marker chunks queued after the cloud (paced)
  size_t queued_blocks = 0;   ///< blocks the cache left queued after the cloud
  double total() const { return sync + markers + cloud + grid + serialise; }
  /// One marker update: built and serialised.
  double markerUpdate() const { return markers + marker_serialise; }
  /// One publication of the whole-map outputs: cache update, messages, serialised.
  double mapUpdate() const { return cloud + grid + serialise - marker_serialise; }
};

/// Blocks per side of a marker chunk (--marker-chunk; the server's markers/chunk_blocks).
int g_marker_chunk_blocks = 4;
/// --flat-markers: octomap_server's height_map false (one colour a marker, none per point).
bool g_flat_markers = false;
/// --cells-always: the after path's cache reads every refreshed block's cells (as before it
/// read the state masks where they suffice).
bool g_cells_always = false;
/// --sync-stage: the write-back before a take-in timed apart (the header's note).
bool g_sync_stage = false;
bool g_sync_between = false;
/// --mirror: the after path reads a mask mirror.
bool g_mirror = false;
/// --shares-between: the output cache's and the markers' shares run between clouds.
bool g_shares_between = false;

/// Which outputs of the after path go out after a cloud.
struct Due {
  bool markers = true;
  bool maps = true;
};

/// The server's paced_outputs (--unpaced: off): after every cloud the markers send their share
/// of the changed chunks and the output cache recomputes its share of the changed blocks, each
/// within a period of the rate of its change; the whole-map messages go out when due.
struct Pace {
  bool on = false;
  double now_s = 0.0;          ///< the cloud's sensor time
  double marker_period_s = 0;  ///< 1 / marker_rate (0: every cloud, not paced)
  double map_period_s = 0;     ///< 1 / map_rate
};

/// The outputs after one cloud, one way or the other. `before`: the whole-map rebuilds.
class Outputs {
 public:
  explicit Outputs(bool before, fragg::BlockChange refresh_on = fragg::BlockChange::kMasks)
      : before_(before), cache_(optionsWith(refresh_on)) {
    style_.chunk_blocks = g_marker_chunk_blocks;
    style_.height_colors = !g_flat_markers;
    if (!before && g_mirror) {
      mirror_ = std::make_shared<fragg::ros::MaskMirror>();
      cache_.useMirror(mirror_);
      ledger_.useMirror(mirror_);
    }
  }
  /// `due`: the after path's throttled outputs (the before path ignores it); `pace`: paced,
  /// the markers' share goes out and the cache takes its share after every cloud (the
  /// whole-map messages only when due).
  Times publish(const fragg::Map& map, Due due = Due(), const Pace& pace = Pace()) {
    Times t;
    const bool paced_markers = !before_ && pace.on && pace.marker_period_s > 0.0;
    const bool paced_maps = !before_ && pace.on && pace.map_period_s > 0.0;
    // The markers take the changes in at the first call, then a period after the last take-in
    // (every call unpaced); the cache lists at a publication.
    const bool takes_in =
        !paced_markers || !synced_once_ || pace.now_s - last_sync_s_ >= pace.marker_period_s - 1e-6;
    if (g_sync_stage && !before_ && (takes_in || due.maps)) {
      const auto ts = Clock::now();
      const long f = minorFaults();
      if (mirror_) {
        const fragg::ros::MaskMirror::SyncStats& m = mirror_->sync(map);  // changed blocks' masks
        t.sync_listed = m.listed;
        t.sync_list_ms = m.list_seconds * 1e3;
        t.sync_update_ms = m.update_seconds * 1e3;
        t.sync_add_ms = m.add_seconds * 1e3;
      } else {
        (void)map.blockView();  // a CUDA map's changed blocks written back
      }
      t.sync = msSince(ts);
      t.sync_faults = minorFaults() - f;
      t.synced = true;
    }
    if (takes_in) {
      synced_once_ = true;
      last_sync_s_ = pace.now_s;
    }
    auto t0 = Clock::now();
    long faults = minorFaults(), marker_faults = 0;
    fragg::ros::SerializedMarkerArray markers;  // as the server publishes them
    if (paced_markers) due.markers = true;      // something may be sent after every cloud
    if (!before_ && due.markers) {
      if (prepared_) {  // built between clouds (--shares-between): published as it is
        markers = std::move(*prepared_);
        prepared_.reset();
      } else {
        markers =
            fragg::ros::pacedBlockMarkersWire(map, style_, ros::Time(), pace.now_s,
                                              paced_markers ? pace.marker_period_s : 0.0, &ledger_);
      }
      t.markers = msSince(t0);
      markers_sent_ = true;
    }
    marker_faults = minorFaults() - faults;
    t.marker_build_faults = marker_faults;
    faults = minorFaults();
    t0 = Clock::now();
    sensor_msgs::PointCloud2 rebuilt;
    nav_msgs::OccupancyGrid grid;
    // The after path's messages as the server publishes them: in roscpp's wire layout already.
    fragg::ros::PreserializedCloud cloud_wire;
    fragg::ros::PreserializedGrid grid_wire;
    if (before_) {
      rebuilt = fragg::ros::occupiedCloud(map, "map", ros::Time());
      t.cloud = msSince(t0);
      t0 = Clock::now();
      grid = fragg::ros::projectedMap(map, kMinZ, kMaxZ, "map", ros::Time());
      t.grid = msSince(t0);
    } else if (paced_maps && !due.maps && sharesBetween()) {
      // The share runs between clouds (syncBetween): nothing on the path.
    } else if (paced_maps && !due.maps) {
      // This cloud's share of the changed blocks; no message.
      const fragg::ros::OutputCacheUpdate u =
          cache_.advance(map, pace.now_s, pace.map_period_s, false);
      t.blocks_read = u.blocks_read;
      t.cells_read = u.blocks_cells_read;
      t.stages = u;
      t.cache_update = msSince(t0);
      t.cloud = t.cache_update;
    } else if (due.maps) {
      const fragg::ros::OutputCacheUpdate u =
          paced_maps ? cache_.advance(map, pace.now_s, pace.map_period_s, true)
                     : cache_.update(map);
      t.blocks_read = u.blocks_read;
      t.cells_read = u.blocks_cells_read;
      t.stages = u;
      t.cache_update = msSince(t0);
      cloud_wire = cache_.occupiedCloudWire("map", ros::Time());
      t.cloud = msSince(t0);
      t0 = Clock::now();
      grid_wire = cache_.projectedMapWire("map", ros::Time());
      t.grid = msSince(t0);
    }
    t.map_faults = minorFaults() - faults;
    faults = minorFaults();
    t0 = Clock::now();
    t.marker_bytes = before_ || !due.markers ? 0 : serialised(markers);
    t.marker_serialise = msSince(t0);
    t.marker_faults = marker_faults + minorFaults() - faults;
    faults = minorFaults();
    t.bytes = t.marker_bytes;
    if (before_) t.bytes += serialised(rebuilt) + serialised(grid);
    if (!before_ && due.maps) t.bytes += serialised(cloud_wire) + serialised(grid_wire);
    t.serialise = msSince(t0);
    t.map_faults += minorFaults() - faults;
    t.pending_chunks = ledger_.pendingChunks();
    t.queued_blocks = cache_.queuedBlocks();
    return t;
  }
  /// --sync-between, the server's work between clouds (mirror_every_cloud): the mirror takes in
  /// the changes since its last sync, and the next cloud's take-ins read it as it stands, one
  /// cloud behind (MaskMirror::acceptLag). Returns the sync's CPU ms (0 without a mirror).
  /// With --shares-between (and paced whole-map outputs) the output cache's share follows the
  /// sync (the server's shares_between_clouds); its CPU ms go to `*share_ms`.
  /// With --shares-between the markers' next share is built there too (`*marker_ms`), and
  /// the next cloud publishes it.
  double syncBetween(const fragg::Map& map, const Pace& pace, double* share_ms, double* marker_ms) {
    *share_ms = *marker_ms = 0.0;
    double ms = 0.0;
    if (mirror_ && g_sync_between) {
      const auto t0 = Clock::now();
      mirror_->acceptLag(0);
      (void)mirror_->sync(map);
      ms = msSince(t0);
    }
    if (sharesBetween() && pace.on && pace.map_period_s > 0.0) {
      const auto t1 = Clock::now();
      (void)cache_.advance(map, pace.now_s, pace.map_period_s, false);
      *share_ms = msSince(t1);
    }
    if (sharesBetween() && pace.on && pace.marker_period_s > 0.0 && markers_sent_) {
      const auto t1 = Clock::now();
      prepared_ = fragg::ros::pacedBlockMarkersWire(map, style_, ros::Time(), pace.now_s,
                                                    pace.marker_period_s, &ledger_);
      *marker_ms = msSince(t1);
    }
    if (mirror_ && g_sync_between) mirror_->acceptLag(1);
    return ms;
  }
  /// Blocks and chunks queued by the paced path (what the server's timers send once the clouds
  /// stop).
  size_t queued() const { return cache_.queuedBlocks() + ledger_.pendingChunks(); }

 private:
  /// The after path's shares run between clouds (--shares-between; either map).
  bool sharesBetween() const { return !before_ && g_shares_between; }
  static fragg::ros::OutputCacheOptions optionsWith(fragg::BlockChange refresh_on) {
    fragg::ros::OutputCacheOptions o;
    o.refresh_on = refresh_on;
    o.masks_where_settled = !g_cells_always;
    return o;
  }
  static constexpr double kMinZ = -std::numeric_limits<double>::infinity();
  static constexpr double kMaxZ = std::numeric_limits<double>::infinity();
  bool before_;
  bool synced_once_ = false;  ///< --sync-stage: the markers' first take-in happened
  double last_sync_s_ = 0.0;  ///< and the time of the last
  fragg::ros::MarkerStyle style_;
  fragg::ros::MarkerLedger ledger_;
  fragg::ros::MapOutputCache cache_;
  std::shared_ptr<fragg::ros::MaskMirror> mirror_;  ///< --mirror (after path)
  /// --shares-between: the markers' share built between clouds, published by the next cloud.
  std::optional<fragg::ros::SerializedMarkerArray> prepared_;
  bool markers_sent_ = false;  ///< the first cloud's markers went out (the server's full set)
};

void printHeader() {
  std::printf("%-8s %-7s %9s %9s %9s %9s %9s %9s %10s %9s %11s\n", "scan", "path", "convert",
              "markers", "cloud", "grid", "serialise", "total", "MB out", "occupied",
              "blocks read");
}

void printRow(const std::string& scan, const char* path, double convert_ms, const Times& t,
              size_t occupied) {
  std::printf("%-8s %-7s %9.2f %9.2f %9.2f %9.2f %9.2f %9.2f %10.2f %9zu %11zu\n", scan.c_str(),
              path, convert_ms, t.markers, t.cloud, t.grid, t.serialise, convert_ms + t.total(),
              t.bytes / 1e6, occupied, t.blocks_read);
}

/// The server's marker_rate and map_rate on a cloud stream of `cloud_rate_hz` (sensor time).
struct Rates {
  double cloud_hz = 10.0;
  double marker_hz = 0.0;
  double map_hz = 0.0;
  bool limited() const { return marker_hz > 0.0 || map_hz > 0.0; }
};

/// The after path's cost over a run: per cloud (amortised) and per update of each kind.
void printAmortised(const Rates& rates, const std::vector<double>& convert_ms,
                    const std::vector<Times>& after, const std::vector<Due>& due,
                    const Times& flush) {
  using fragg::tools::percentile;
  double sum_convert = 0, sum_markers = 0, sum_maps = 0, sum_bytes = 0;
  std::vector<double> marker_updates, map_updates;
  for (size_t i = 0; i < after.size(); ++i) {
    sum_convert += convert_ms[i];
    sum_markers += after[i].markerUpdate();
    sum_maps += after[i].mapUpdate();
    sum_bytes += static_cast<double>(after[i].bytes);
    if (due[i].markers) marker_updates.push_back(after[i].markerUpdate());
    if (due[i].maps) map_updates.push_back(after[i].mapUpdate());
  }
  const size_t clouds = after.size();
  const double n = static_cast<double>(clouds);
  std::printf(
      "after, clouds at %.1f Hz, marker_rate %.2f Hz, map_rate %.2f Hz: amortised %.2f ms per "
      "cloud (sum / %zu clouds: convert %.2f + markers %.2f + whole-map outputs %.2f), %.2f MB "
      "out per cloud\n",
      rates.cloud_hz, rates.marker_hz, rates.map_hz, (sum_convert + sum_markers + sum_maps) / n,
      clouds, sum_convert / n, sum_markers / n, sum_maps / n, sum_bytes / n / 1e6);
  auto perUpdate = [](const char* what, const std::vector<double>& ms) {
    if (ms.empty()) {
      std::printf("  %s: none\n", what);
      return;
    }
    std::printf("  %s: %zu, ms per update median %.2f, max %.2f\n", what, ms.size(),
                percentile(ms, 0.5), percentile(ms, 1.0));
  };
  perUpdate("marker updates (build + serialise)", marker_updates);
  perUpdate("whole-map publications (cache update + cloud + grid + serialise)", map_updates);
  if (rates.limited())
    std::printf(
        "  pending after the last cloud, flushed by the server's timer (not in the sum): markers "
        "%.2f ms, whole-map outputs %.2f ms; with it, amortised %.2f ms per cloud (every "
        "cloud's changes published once)\n",
        flush.markerUpdate(), flush.mapUpdate(),
        (sum_convert + sum_markers + sum_maps + flush.markerUpdate() + flush.mapUpdate()) / n);
}

/// --worst N: the N costliest clouds of the after path (those that make its p99).
size_t g_worst = 0;

/// The `g_worst` costliest clouds of the after path, stage by stage: where a cloud's time goes.
void printWorst(const std::vector<double>& total_ms, const std::vector<double>& convert_ms,
                const std::vector<Times>& after) {
  if (g_worst == 0 || total_ms.empty()) return;
  std::vector<size_t> order(total_ms.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return total_ms[a] > total_ms[b]; });
  std::printf(
      "the %zu costliest clouds (CPU ms: total = convert + markers built + markers serialised + "
      "whole-map outputs (cache update + messages) + their serialisation; the cache update's "
      "stages in wall ms: list, pieces, columns and grid, gather; minor page faults of the markers "
      "and of the whole-map outputs; --sync-stage: the write-back before a take-in, its ms and "
      "faults)\n",
      std::min(g_worst, order.size()));
  std::printf(
      "%6s %8s %8s %8s %7s %8s %8s %6s %8s %8s %8s %8s | %7s %7s %7s %7s | %8s %8s %7s %9s %8s "
      "%8s %7s %7s\n",
      "cloud", "total", "convert", "sync", "sync_flt", "mk_build", "mk_ser", "mk_MB", "cache",
      "cloud_msg", "grid_msg", "map_ser", "list", "pieces", "grid", "gather", "blocks", "of_cells",
      "gathered", "MB_gath", "chunks_q", "blocks_q", "mk_flt", "map_flt");
  for (size_t k = 0; k < std::min(g_worst, order.size()); ++k) {
    const size_t i = order[k];
    const Times& t = after[i];
    std::printf(
        "%6zu %8.2f %8.2f %8.2f %7ld %8.2f %8.2f %6.2f %8.2f %8.2f %8.2f %8.2f | %7.2f %7.2f %7.2f "
        "%7.2f | %8zu %8zu %7zu %9.2f %8zu %8zu %7ld %7ld\n",
        i + 1, total_ms[i], convert_ms[i], t.sync, t.sync_faults, t.markers, t.marker_serialise,
        t.marker_bytes / 1e6, t.cache_update, t.cloud - t.cache_update, t.grid,
        t.serialise - t.marker_serialise, t.stages.list_ms, t.stages.pieces_ms, t.stages.grid_ms,
        t.stages.gather_ms, t.blocks_read, t.cells_read, t.stages.pieces_gathered,
        t.stages.bytes_gathered / 1e6, t.pending_chunks, t.queued_blocks, t.marker_faults,
        t.map_faults);
  }
  std::printf(
      "  their pieces' wall ms: made (in order) + recomputed (in parallel) + summed (in order)\n");
  for (size_t k = 0; k < std::min(g_worst, order.size()); ++k) {
    const Times& t = after[order[k]];
    std::printf("%6zu %8.2f = %7.2f + %7.2f + %7.2f\n", order[k] + 1, t.stages.pieces_ms,
                t.stages.pieces_made_ms, t.stages.pieces_computed_ms, t.stages.pieces_summed_ms);
  }
}

/// Occupied cells of the whole map (for the rows; untimed).
size_t occupiedCells(const fragg::Map& map) {
  size_t occupied = 0;
  map.forEachBlock([&](const fragg::BlockKey&, const fragg::Block& blk) {
    for (const fragg::Cell& c : blk.cells) occupied += map.state(c) == fragg::CellState::kOccupied;
  });
  return occupied;
}

/// Feeds `scans` into `map`, both output paths after each; prints the rows of `shown` scans
/// (1-based) and the medians.
void run(fragg::Map& map, const std::vector<fragg::Scan>& scans, double max_range_m,
         const std::vector<size_t>& shown, const std::string& label, const Rates& rates,
         bool after_only, bool paced) {
  // after: the cache refreshes the blocks whose cell states changed; any: every changed block
  // (as before BlockMeta::state_at), for the same-run comparison.
  Outputs before(true), after(false), any(false, fragg::BlockChange::kAny);
  std::printf("\n%s\n", label.c_str());
  if (rates.limited())
    std::printf(
        "after rows: 0 in markers, or in cloud and grid, = not due after that cloud "
        "(throttled)\n");
  printHeader();
  // The first call reads the whole map (a loaded map, or nothing yet): untimed.
  after.publish(map);
  if (!after_only) any.publish(map);
  std::vector<double> total_before, total_after, total_any, converts, between_ms, between_share_ms,
      between_marker_ms;
  std::vector<Times> after_times;
  std::vector<Due> dues;
  fragg::ros::RateThrottle marker_throttle(rates.marker_hz), map_throttle(rates.map_hz);
  fragg::PointCloud cloud;
  for (size_t i = 0; i < scans.size(); ++i) {
    const sensor_msgs::PointCloud2 msg = fragg::bench::velodyneLikeMsg(scans[i].cloud);
    auto t0 = Clock::now();
    fragg::ros::cloudFromMsg(msg, &cloud);  // into the last cloud's buffer, as the server
    const double convert_ms = msSince(t0);
    map.insert(cloud, scans[i].T_map_sensor, fragg::SensorModel::autoFromCloud(0.0, max_range_m));
    // As the server after this cloud: each throttled output goes out when due.
    const double now_s = static_cast<double>(i) / rates.cloud_hz;
    Due due;
    due.markers = marker_throttle.due(now_s);
    due.maps = map_throttle.due(now_s);
    if (due.markers) marker_throttle.published(now_s);
    if (due.maps) map_throttle.published(now_s);
    Pace pace;
    pace.on = paced;
    pace.now_s = now_s;
    pace.marker_period_s = rates.marker_hz > 0.0 ? 1.0 / rates.marker_hz : 0.0;
    pace.map_period_s = rates.map_hz > 0.0 ? 1.0 / rates.map_hz : 0.0;
    const Times a = after.publish(map, due, pace);
    if (g_sync_between || g_shares_between) {
      double share_ms = 0.0, marker_ms = 0.0;
      between_ms.push_back(after.syncBetween(map, pace, &share_ms, &marker_ms));
      between_share_ms.push_back(share_ms);
      between_marker_ms.push_back(marker_ms);
    }
    if (paced && pace.marker_period_s > 0.0) due.markers = true;  // a share after every cloud
    total_after.push_back(convert_ms + a.total());
    converts.push_back(convert_ms);
    after_times.push_back(a);
    dues.push_back(due);
    for (size_t s : shown)
      if (s == i + 1 && after_only)
        printRow(std::to_string(i + 1), "after", convert_ms, a, occupiedCells(map));
    if (after_only) continue;
    const Times y = any.publish(map);
    total_any.push_back(convert_ms + y.total());
    for (size_t s : shown) {
      if (s != i + 1) continue;
      Times b = before.publish(map);
      // The same incremental update (the any path's when the after path's was not due).
      const Times& m = due.markers ? a : y;
      b.markers = m.markers;
      b.serialise += m.marker_serialise;
      b.bytes += m.marker_bytes;
      total_before.push_back(convert_ms + b.total());
      const size_t occupied = occupiedCells(map);
      printRow(std::to_string(i + 1), "before", convert_ms, b, occupied);
      printRow(std::to_string(i + 1), "any", convert_ms, y, occupied);
      printRow(std::to_string(i + 1), "after", convert_ms, a, occupied);
    }
  }
  using fragg::tools::percentile;
  std::printf(
      "after%s: per cloud (convert + markers + whole-map outputs) p50 %.2f ms, p99 %.2f ms, max "
      "%.2f ms over %zu clouds\n",
      paced ? " (paced)" : "", percentile(total_after, 0.5), percentile(total_after, 0.99),
      percentile(total_after, 1.0), scans.size());
  if (g_sync_between && !between_ms.empty())
    std::printf(
        "  between clouds (--sync-between; not in the figures above): the mask mirror's sync p50 "
        "%.2f ms, p99 %.2f ms, max %.2f ms\n",
        percentile(between_ms, 0.5), percentile(between_ms, 0.99), percentile(between_ms, 1.0));
  if (g_shares_between && !between_share_ms.empty()) {
    std::vector<double> sum(between_ms.size());
    for (size_t i = 0; i < sum.size(); ++i)
      sum[i] = between_ms[i] + between_share_ms[i] + between_marker_ms[i];
    std::printf(
        "  between clouds (--shares-between): the output cache's share p50 %.2f ms, p99 %.2f ms, "
        "max %.2f ms; the markers' next share p50 %.2f, p99 %.2f, max %.2f; sync and shares p50 "
        "%.2f ms, p99 %.2f ms, max %.2f ms\n",
        percentile(between_share_ms, 0.5), percentile(between_share_ms, 0.99),
        percentile(between_share_ms, 1.0), percentile(between_marker_ms, 0.5),
        percentile(between_marker_ms, 0.99), percentile(between_marker_ms, 1.0),
        percentile(sum, 0.5), percentile(sum, 0.99), percentile(sum, 1.0));
  }
  if (!between_ms.empty() && between_ms.size() == total_after.size()) {
    // What issue 35's outputs goal counts: a cloud's outputs work wherever it runs.
    std::vector<double> work(total_after.size());
    for (size_t i = 0; i < work.size(); ++i)
      work[i] = total_after[i] + between_ms[i] + between_share_ms[i] + between_marker_ms[i];
    std::printf(
        "  outputs' work per cloud, its path and the work between clouds after it: p50 %.2f ms, "
        "p99 %.2f ms, max %.2f ms\n",
        percentile(work, 0.5), percentile(work, 0.99), percentile(work, 1.0));
  }
  if (g_sync_stage) {
    std::vector<double> sync_ms, list_ms, listed;
    long sync_faults = 0;
    for (const Times& t : after_times)
      if (t.synced) {
        sync_ms.push_back(t.sync);
        list_ms.push_back(t.sync_list_ms);
        listed.push_back(static_cast<double>(t.sync_listed));
        sync_faults += t.sync_faults;
      }
    if (!sync_ms.empty() && g_mirror)
      std::printf(
          "  of it, the mask mirror's sync before a take-in: %zu times, median %.2f ms, max %.2f "
          "ms, %ld page faults in all; blocks listed median %.0f, max %.0f; "
          "Map::masksChangedSince wall ms median %.2f, max %.2f\n",
          sync_ms.size(), percentile(sync_ms, 0.5), percentile(sync_ms, 1.0), sync_faults,
          percentile(listed, 0.5), percentile(listed, 1.0), percentile(list_ms, 0.5),
          percentile(list_ms, 1.0));
    if (!sync_ms.empty() && g_mirror)
      for (const Times& t : after_times)
        if (t.synced)
          std::printf(
              "    a sync: %zu blocks listed, %.2f ms = list %.2f + held blocks updated %.2f + "
              "new ones added %.2f (+ the rest), %ld page faults\n",
              t.sync_listed, t.sync, t.sync_list_ms, t.sync_update_ms, t.sync_add_ms,
              t.sync_faults);
    if (!sync_ms.empty() && !g_mirror)
      std::printf(
          "  of it, the write-back before a take-in (Map::blockView()): %zu times, median %.2f ms, "
          "max %.2f ms, %ld page faults in all\n",
          sync_ms.size(), percentile(sync_ms, 0.5), percentile(sync_ms, 1.0), sync_faults);
  }
  printWorst(total_after, converts, after_times);
  if (!after_only)
    std::printf("any:   median %.2f ms, max %.2f ms per cloud over %zu clouds\n",
                percentile(total_any, 0.5), percentile(total_any, 1.0), scans.size());
  // What the server's timers send once the clouds stop: the outputs not due at the last cloud.
  Times flush;
  if (!dues.empty()) {
    Due pending;  // the last cloud's changes (and those before it since the last update)
    pending.markers = !dues.back().markers || (paced && after.queued() > 0);
    pending.maps = !dues.back().maps || (paced && after.queued() > 0);
    if (pending.markers || pending.maps) flush = after.publish(map, pending);
    if (pending.maps)
      std::printf(
          "  the flush: markers %.2f (serialised %.2f; %.2f MB, %ld page faults, %ld in the "
          "build), cache update "
          "%.2f (%zu blocks read, %zu "
          "of them from their cells; wall ms: list %.2f, pieces %.2f, columns and grid %.2f), "
          "occupied cloud message %.2f, grid %.2f, whole-map messages serialised %.2f ms (%ld "
          "page faults)\n",
          flush.markers, flush.marker_serialise, flush.marker_bytes / 1e6, flush.marker_faults,
          flush.marker_build_faults, flush.cache_update, flush.blocks_read, flush.cells_read,
          flush.stages.list_ms, flush.stages.pieces_ms, flush.stages.grid_ms,
          flush.cloud - flush.cache_update, flush.grid, flush.serialise - flush.marker_serialise,
          flush.map_faults);
  }
  printAmortised(rates, converts, after_times, dues, flush);
}

}  // namespace

int runMain(int argc, char** argv) {
  CLI::App app("per-cloud map server overhead outside insertion, before and after");
  std::string workloads, big_map;
  size_t scans = 100, big_scans = 5;
  std::vector<size_t> shown = {1, 10, 50, 100};
  app.add_option("--workloads", workloads, "scripts/make_workloads.sh output (has w1_lidar360)")
      ->required();
  app.add_option("--scans", scans, "W1 scans fed into a new map")->check(CLI::PositiveNumber);
  app.add_option("--show", shown, "scans (1-based) whose rows are printed");
  app.add_option("--big-map", big_map, ".fgm to load and feed W1 scans into (e.g. W1's final map)");
  app.add_option("--big-scans", big_scans, "W1 scans fed into the big map");
  Rates rates;
  app.add_option("--cloud-rate", rates.cloud_hz, "clouds per second of sensor time")
      ->check(CLI::PositiveNumber);
  app.add_option("--marker-rate", rates.marker_hz,
                 "most marker updates per second, as the server's marker_rate (0: every cloud)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--map-rate", rates.map_hz,
                 "most whole-map publications per second, as the server's map_rate (0: every "
                 "cloud)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--marker-chunk", g_marker_chunk_blocks,
                 "blocks per side of one marker, as the server's markers/chunk_blocks (1: one "
                 "marker per block)")
      ->check(CLI::Range(1, 64));
  app.add_flag("--cells-always", g_cells_always,
               "the output cache reads every refreshed block's cells, none from its state masks "
               "alone (the behaviour before, for same-run comparisons)");
  bool after_only = false;
  app.add_flag("--after-only", after_only,
               "only the server's path (no whole-map rebuild, no cache refreshing every changed "
               "block): for profiles and long runs");
  std::string backend = "cpu";
  app.add_option("--backend", backend,
                 "cpu | cuda: the map's backend (the outputs read its masks and change log; "
                 "cuda needs a CUDA build)")
      ->check(CLI::IsMember({"cpu", "cuda"}));
  app.add_flag("--flat-markers", g_flat_markers,
               "markers in one colour without per-point colours (the server's height_map "
               "false: 24 bytes a cell instead of 40)");
  app.add_option("--worst", g_worst,
                 "print the N costliest clouds of the after path stage by stage (what makes its "
                 "p99)");
  std::string mirror = "auto";
  app.add_option("--mirror", mirror,
                 "auto | on | off: the after path reads a mask mirror (the server's way on a "
                 "CUDA map: auto) or the map's views")
      ->check(CLI::IsMember({"auto", "on", "off"}));
  app.add_flag("--sync-stage", g_sync_stage,
               "time the write-back before each take-in of the changes apart (Map::blockView(): a "
               "CUDA map's changed blocks copied back) and print it");
  app.add_flag("--sync-between", g_sync_between,
               "as the server with mirror_every_cloud: the mask mirror takes each cloud's changes "
               "in after its outputs (timed apart, printed), and the take-ins read it one cloud "
               "behind (with a mirror only)");
  app.add_flag("--shares-between", g_shares_between,
               "as the server with shares_between_clouds: the output cache's shares and the "
               "markers' next share are worked out between clouds (after the sync with "
               "--sync-between; timed apart, printed), the markers' published by the next "
               "cloud; only a publication's call stays on the cloud's path");
  bool unpaced = false;
  app.add_flag("--unpaced", unpaced,
               "as the server with paced_outputs false: the throttled updates whole when due "
               "(default: paced, their work spread over the clouds of a period)");
  bool fresh_buffers = false;
  app.add_flag("--fresh-buffers", fresh_buffers,
               "leave glibc's mmap and trim thresholds as they are (the server raises them: "
               "keepPublicationBuffers), so that each serialised message maps fresh pages");
  CLI11_PARSE(app, argc, argv);
  const bool paced = !unpaced && rates.limited();
  if (!fresh_buffers && !fragg::ros::keepPublicationBuffers(fragg::ros::kKeptPublicationBytes))
    std::printf("keepPublicationBuffers: refused (not glibc?): fresh pages per message\n");
  std::setvbuf(stdout, nullptr, _IOLBF, 0);  // rows as they come (long runs)

  const auto want = [](const std::string& name) { return name == "W1 lidar360 30 m"; };
  const std::vector<fragg::bench::Workload> w =
      fragg::bench::simWorkloads(workloads, std::max(scans, big_scans), want);
  const fragg::bench::Workload& w1 = w.at(0);
  fragg::MapParams params;
  params.resolution_m = w1.resolution_m;
  params.backend = fragg::backendFromString(backend);
  std::printf(
      "%s, %.2f m, %s backend; ms per cloud, MB out = bytes serialised for one "
      "subscriber per topic\n",
      w1.name.c_str(), w1.resolution_m, backend.c_str());
  {
    fragg::Map map(params);
    g_mirror = mirror == "on" || (mirror == "auto" && std::strcmp(map.backendName(), "cpu") != 0);
    std::printf("outputs read %s\n", g_mirror ? "a mask mirror" : "the map's views");
    std::vector<fragg::Scan> first(w1.scans.begin(),
                                   w1.scans.begin() + std::min(scans, w1.scans.size()));
    run(map, first, w1.max_range_m, shown, "new map, W1 scans 1.." + std::to_string(first.size()),
        rates, after_only, paced);
  }
  if (!big_map.empty()) {
    fragg::Map map = fragg::Map::load(big_map, params);
    std::vector<fragg::Scan> first(w1.scans.begin(),
                                   w1.scans.begin() + std::min(big_scans, w1.scans.size()));
    std::vector<size_t> all;
    for (size_t i = 1; i <= first.size(); ++i) all.push_back(i);
    run(map, first, w1.max_range_m, all,
        big_map + " (" + std::to_string(map.blockCount()) + " blocks) + W1 scans 1.." +
            std::to_string(first.size()),
        rates, after_only, paced);
  }
  return 0;
}

int main(int argc, char** argv) {
  try {
    return runMain(argc, argv);
  } catch (const std::exception& e) {  // a CUDA backend asked of a CPU build, a bad map file
    std::fprintf(stderr, "fragg_map_server_overhead: %s\n", e.what());
    return 1;
  }
}
