// Map server counters -> fragg_map/MapStats.
#include "server_stats.h"

namespace fragg::ros {

void ServerStats::addInsertion(uint64_t points, double ms) {
  std::lock_guard<std::mutex> lock(mutex_);
  ++scans_;
  points_ += points;
  insertion_ms_.add(ms);
}

void ServerStats::addDroppedNoTf() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++dropped_no_tf_;
}

void ServerStats::addDroppedQueueFull() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++dropped_queue_full_;
}

void ServerStats::addRejected() {
  std::lock_guard<std::mutex> lock(mutex_);
  ++rejected_;
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
  dropped_no_tf_ = 0;
  dropped_queue_full_ = 0;
  rejected_ = 0;
}

uint64_t ServerStats::droppedNoTf() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return dropped_no_tf_;
}

fragg_map::MapStats ServerStats::toMsg(const fragg::Map& map, const std::string& frame_id,
                                       const ::ros::Time& stamp) const {
  fragg_map::MapStats msg;
  msg.header.frame_id = frame_id;
  msg.header.stamp = stamp;
  msg.backend = map.backendName();
  msg.resolution = map.resolution();
  const fragg::MemoryStats memory = map.memory();
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
  msg.rejected_clouds = rejected_;
  msg.dropped_clouds = dropped_no_tf_ + dropped_queue_full_ + rejected_;
  msg.insertion_ms_last = static_cast<float>(insertion_ms_.lastMs());
  msg.insertion_ms_mean = static_cast<float>(insertion_ms_.meanMs());
  msg.insertion_ms_p99 = static_cast<float>(insertion_ms_.percentileMs(0.99));
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
