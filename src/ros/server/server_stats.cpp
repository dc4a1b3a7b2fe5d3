// Map server counters -> fragg_map/MapStats.
#include "server_stats.h"

namespace fragg::ros {

void ServerStats::settle() {
  if (in_flight_ > 0) --in_flight_;  // outcomes without addReceived (tests, a store's start)
}

void ServerStats::addReceived() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++received_;
  ++in_flight_;
}

void ServerStats::addLatency(double queue_ms, double tf_ms, double publish_ms, double total_ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  queue_ms_.add(queue_ms);
  tf_ms_.add(tf_ms);
  publish_ms_.add(publish_ms);
  latency_ms_.add(total_ms);
}

void ServerStats::addInsertion(uint64_t points, double ms, const fragg::InsertStats& inserted) {
  std::lock_guard<std::mutex> lock(mutex_);
  settle();
  ++inserted_;
  ++scans_;
  points_ += points;
  insertion_ms_.add(ms);
  points_invalid_ += inserted.dropped_invalid;
  points_beyond_range_ += inserted.rays_free_only;
  points_below_min_range_ += inserted.dropped_min_range;
  points_outside_height_ += inserted.dropped_height;
  points_outside_frustum_ += inserted.dropped_outside_frustum;
}

void ServerStats::addDroppedNoTf() {
  std::lock_guard<std::mutex> lock(mutex_);
  settle();
  ++dropped_no_tf_;
}

void ServerStats::addDroppedQueueFull() {
  std::lock_guard<std::mutex> lock(mutex_);
  settle();
  ++dropped_queue_full_;
}

void ServerStats::addEmptyCloud() {
  std::lock_guard<std::mutex> lock(mutex_);
  settle();
  ++empty_clouds_;
}

void ServerStats::addFault(CloudFault fault) {
  std::lock_guard<std::mutex> lock(mutex_);
  settle();
  ++faults_[static_cast<int>(fault)];
}

void ServerStats::addPointsInvalid(uint64_t points) {
  std::lock_guard<std::mutex> lock(mutex_);
  points_invalid_ += points;
}

void ServerStats::addBackendFallback() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++backend_fallbacks_;
}

uint64_t ServerStats::faults(CloudFault fault) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return faults_[static_cast<int>(fault)];
}

void ServerStats::addCorrection(uint64_t scans, double ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++corrections_;
  corrected_scans_ += scans;
  correction_ms_last_ = ms;
}

void ServerStats::addCollisionCheck(uint64_t poses, double ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  collision_ms_.add(ms);
  collision_poses_ += poses;
}

void ServerStats::addFrontierQuery() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++frontier_queries_;
}

void ServerStats::addFrontierUpdate(bool full, uint64_t blocks_examined, uint64_t cells,
                                    double ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++frontier_updates_;
  frontier_update_full_ = full;
  frontier_blocks_examined_ = blocks_examined;
  frontier_cells_ = cells;
  frontier_ms_last_ = ms;
}

void ServerStats::clearInsertions() {
  std::lock_guard<std::mutex> lock(mutex_);
  scans_ = 0;
  points_ = 0;
  insertion_ms_.clear();
  for (TimingStats* t : {&latency_ms_, &queue_ms_, &tf_ms_, &publish_ms_}) t->clear();
  corrections_ = 0;
  corrected_scans_ = 0;
  correction_ms_last_ = 0.0;
  collision_ms_.clear();
  collision_poses_ = 0;
}

void ServerStats::restart(uint64_t scans) {
  clearInsertions();
  std::lock_guard<std::mutex> lock(mutex_);
  scans_ = scans;
  received_ = in_flight_;  // the clouds still queued or being inserted come in the new count
  inserted_ = 0;
  dropped_no_tf_ = 0;
  dropped_queue_full_ = 0;
  empty_clouds_ = 0;
  for (uint64_t& n : faults_) n = 0;
  points_invalid_ = 0;
  points_beyond_range_ = 0;
  points_below_min_range_ = 0;
  points_outside_height_ = 0;
  points_outside_frustum_ = 0;
}

uint64_t ServerStats::droppedNoTf() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_no_tf_;
}

fragg_map::MapStats ServerStats::toMsg(const fragg::Map& map, const std::string& frame_id,
                                       const ::ros::Time& stamp, MapFigures figures,
                                       const MaskMirror* mirror) const {
  fragg_map::MapStats msg;
  msg.header.frame_id = frame_id;
  msg.header.stamp = stamp;
  msg.backend = map.backendName();
  msg.resolution = map.resolution();
  fragg::MemoryStats memory;
  if (figures == MapFigures::kRecent && mirror && mirror->valid()) {
    memory = map.memoryAsHeld();
    memory.blocks = mirror->size();
    memory.known_voxels = mirror->knownCells();
  } else {
    // Map::memory() walks every cell (11 ms at W1 5 cm after 40 clouds on 2 cores): ~stats,
    // published after every cloud, takes it at most every kMapFiguresPeriodSeconds.
    std::lock_guard<std::mutex> lock(memory_mutex_);
    const auto now = std::chrono::steady_clock::now();
    const bool stale = !memory_valid_ || (map.revision() != memory_revision_ &&
                                          std::chrono::duration<double>(now - memory_at_).count() >=
                                              kMapFiguresPeriodSeconds);
    if (figures == MapFigures::kExact || stale) {
      memory_ = map.memory();
      memory_valid_ = true;
      memory_revision_ = map.revision();
      memory_at_ = now;
    }
    memory = memory_;
  }
  msg.known_voxels = memory.known_voxels;
  msg.blocks = memory.blocks;
  const fragg::PagingStats paging = map.pagingStats();
  msg.resident_blocks = paging.enabled ? paging.resident_blocks : memory.blocks;
  msg.paged_blocks = paging.paged_blocks;
  msg.host_bytes = memory.host_block_bytes;
  msg.gpu_bytes = memory.device_bytes;
  msg.scans_kept = map.scanStore().size();
  std::lock_guard<std::mutex> lock(mutex_);
  msg.scans = scans_;
  msg.points = points_;
  msg.dropped_no_tf = dropped_no_tf_;
  msg.dropped_queue_full = dropped_queue_full_;
  msg.empty_clouds = empty_clouds_;
  auto fault = [this](CloudFault f) { return faults_[static_cast<int>(f)]; };
  msg.rejected_malformed = fault(CloudFault::kMalformed);
  msg.rejected_no_finite_point = fault(CloudFault::kNoFinitePoint);
  msg.rejected_bad_transform = fault(CloudFault::kBadTransform);
  msg.insertion_failures = fault(CloudFault::kInsertFailed);
  msg.dropped_tf_too_old = fault(CloudFault::kTfTooOld);
  msg.rejected_clouds = msg.rejected_malformed + msg.rejected_no_finite_point +
                        msg.rejected_bad_transform + msg.insertion_failures;
  msg.dropped_clouds =
      dropped_no_tf_ + msg.dropped_tf_too_old + dropped_queue_full_ + msg.rejected_clouds;
  msg.clouds_received = received_;
  msg.clouds_inserted = inserted_;
  msg.clouds_in_flight = in_flight_;
  msg.backend_fallbacks = backend_fallbacks_;
  msg.points_invalid = points_invalid_;
  msg.points_beyond_range = points_beyond_range_;
  msg.points_below_min_range = points_below_min_range_;
  msg.points_outside_height = points_outside_height_;
  msg.points_outside_frustum = points_outside_frustum_;
  msg.insertion_ms_last = static_cast<float>(insertion_ms_.lastMs());
  msg.insertion_ms_mean = static_cast<float>(insertion_ms_.meanMs());
  msg.insertion_ms_p99 = static_cast<float>(insertion_ms_.percentileMs(0.99));
  msg.insertion_ms_p50 = static_cast<float>(insertion_ms_.percentileMs(0.5));
  msg.latency_ms_p50 = static_cast<float>(latency_ms_.percentileMs(0.5));
  msg.latency_ms_p99 = static_cast<float>(latency_ms_.percentileMs(0.99));
  msg.queue_ms_p50 = static_cast<float>(queue_ms_.percentileMs(0.5));
  msg.queue_ms_p99 = static_cast<float>(queue_ms_.percentileMs(0.99));
  msg.tf_ms_p50 = static_cast<float>(tf_ms_.percentileMs(0.5));
  msg.tf_ms_p99 = static_cast<float>(tf_ms_.percentileMs(0.99));
  msg.publish_ms_p50 = static_cast<float>(publish_ms_.percentileMs(0.5));
  msg.publish_ms_p99 = static_cast<float>(publish_ms_.percentileMs(0.99));
  msg.corrections = corrections_;
  msg.corrected_scans = corrected_scans_;
  msg.correction_ms_last = static_cast<float>(correction_ms_last_);
  msg.collision_checks = collision_ms_.count();
  msg.collision_poses = collision_poses_;
  msg.collision_ms_last = static_cast<float>(collision_ms_.lastMs());
  msg.collision_ms_mean = static_cast<float>(collision_ms_.meanMs());
  msg.frontier_queries = frontier_queries_;
  msg.frontier_updates = frontier_updates_;
  msg.frontier_update_full = frontier_update_full_;
  msg.frontier_blocks_examined = frontier_blocks_examined_;
  msg.frontier_cells = frontier_cells_;
  msg.frontier_ms_last = static_cast<float>(frontier_ms_last_);
  return msg;
}

}  // namespace fragg::ros
