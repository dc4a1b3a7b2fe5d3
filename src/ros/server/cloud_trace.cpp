// trace_csv rows.
#include "cloud_trace.h"

#include <cinttypes>
#include <cstdio>

#include "fragg_map/errors.h"

namespace fragg::ros {

CloudTraceCsv::CloudTraceCsv(const std::string& path) : out_(path, std::ios::trunc), path_(path) {
  if (!out_) throw fragg::IoError("trace_csv: cannot write " + path);
  out_ << header() << '\n';
  out_.flush();
}

const char* CloudTraceCsv::header() {
  return "stamp_s,points,outcome,queue_ms,tf_ms,insert_ms,publish_ms,total_ms,queue_depth,lock_"
         "wait_ms,"
         "publish_wait_ms,markers_ms,map_outputs_ms,stats_ms,between_ms,lock_holders";
}

void CloudTraceCsv::write(const CloudTrace& t) {
  char row[320];
  std::snprintf(row, sizeof(row),
                "%.6f,%" PRIu64 ",%s,%.3f,%.3f,%.3f,%.3f,%.3f,%zu,%.3f,%.3f,%.3f,%.3f,%.3f,%.3f,",
                t.stamp_s, t.points, t.outcome.c_str(), t.queue_ms, t.tf_ms, t.insert_ms,
                t.publish_ms, t.total_ms, t.queue_depth, t.lock_wait_ms, t.publish.wait_ms,
                t.publish.markers_ms, t.publish.map_outputs_ms, t.publish.stats_ms, t.between_ms);
  std::lock_guard<std::mutex> lock(mutex_);
  // The holders' names carry no commas (describeLockHolders): one field as it stands.
  out_ << row << t.lock_holders << '\n';
  out_.flush();
}

}  // namespace fragg::ros
