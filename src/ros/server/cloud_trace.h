// Per-cloud latency trace of the map server (the trace_csv parameter): one CSV row per cloud
// received, with its outcome and where its time went, from receipt on cloud_in to its outputs
// published. ROS-free; safe to write from the subscriber and insertion threads.
#pragma once

#include <cstdint>
#include <fstream>
#include <mutex>
#include <string>

namespace fragg::ros {

/// Where the outputs' time after one insertion went (ms; MapPublishers::publishAfterInsert).
struct PublishTimes {
  double wait_ms = 0.0;         ///< for the publishers' mutex and the map's read lock
  double markers_ms = 0.0;      ///< both marker topics (the cloud's share, or an update when due)
  double map_outputs_ms = 0.0;  ///< occupied cloud, centers, projected map (share; sent when due)
  double stats_ms = 0.0;        ///< ~stats
};

/// One cloud's way through the server. Times in ms; a stage the cloud did not reach is 0.
struct CloudTrace {
  double stamp_s = 0.0;       ///< the cloud's header stamp
  uint64_t points = 0;        ///< width x height
  std::string outcome;        ///< inserted, queue_full, no_tf, tf_too_old, rejected, insert_failed
  double queue_ms = 0.0;      ///< receipt -> taken by the insertion thread
  double tf_ms = 0.0;         ///< conversion and the wait for the transform(s)
  double insert_ms = 0.0;     ///< the insertion, the wait for the write lock included
  double publish_ms = 0.0;    ///< the outputs after the insertion
  double total_ms = 0.0;      ///< receipt -> done (outputs published for an inserted cloud)
  size_t queue_depth = 0;     ///< clouds waiting behind it when it was taken
  double lock_wait_ms = 0.0;  ///< the part of insert_ms spent waiting for the map's write lock
  /// Whom that wait was for (fragg::describeLockHolders: "frontier topics 12.3 ms; ..."),
  /// empty when the lock was free.
  std::string lock_holders;
  PublishTimes publish;  ///< parts of publish_ms (the rest: dynamic points, octomaps, frustum)
  /// Work after the cloud's outputs, before the next cloud was taken (CloudPipeline::BetweenFn:
  /// the outputs' mask mirror taking the changes in); not part of total_ms.
  double between_ms = 0.0;
};

class CloudTraceCsv {
 public:
  /// Opens (truncates) `path` and writes the header; throws fragg::IoError when it cannot.
  explicit CloudTraceCsv(const std::string& path);
  /// Appends one row (flushed, so a killed node leaves its rows).
  void write(const CloudTrace& trace);
  /// The header row, for readers and tests.
  [[nodiscard]] static const char* header();

 private:
  std::mutex mutex_;
  std::ofstream out_;
  std::string path_;
};

}  // namespace fragg::ros
