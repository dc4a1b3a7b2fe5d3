// Per-cloud latency trace of the map server (the trace_csv parameter): one CSV row per cloud
// received, with its outcome and where its time went, from receipt on cloud_in to its outputs
// published. ROS-free; safe to write from the subscriber and insertion threads.
#pragma once

#include <cstdint>
#include <fstream>
#include <mutex>
#include <string>

namespace fragg::ros {

/// One cloud's way through the server. Times in ms; a stage the cloud did not reach is 0.
struct CloudTrace {
  double stamp_s = 0.0;     ///< the cloud's header stamp
  uint64_t points = 0;      ///< width x height
  std::string outcome;      ///< inserted, queue_full, no_tf, tf_too_old, rejected, insert_failed
  double queue_ms = 0.0;    ///< receipt -> taken by the insertion thread
  double tf_ms = 0.0;       ///< conversion and the wait for the transform(s)
  double insert_ms = 0.0;   ///< the insertion, the wait for the write lock included
  double publish_ms = 0.0;  ///< the outputs after the insertion
  double total_ms = 0.0;    ///< receipt -> done (outputs published for an inserted cloud)
  size_t queue_depth = 0;   ///< clouds waiting behind it when it was taken
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
