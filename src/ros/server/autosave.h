// The map server's autosave (autosave/path, autosave/period_s; autosave_params.h): a thread
// that every period copies the map under the read lock (Map::image, a memory copy: insertion
// waits for that only) and writes the copy with the lock released (writeMapImage: temporary
// file, fsync, rename, so the previous autosave stays valid if the process dies mid-write),
// and a last save when the server stops. A period in which the map did not change writes
// nothing. Start-up (loadAutosave) reads an existing autosave back.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <tuple>

#include "fragg_map/map.h"
#include "fragg_map/ros/autosave_params.h"
#include "shared_map.h"

namespace fragg::ros {

/// The map in an existing autosave file with the server's runtime settings (map_file_loader.h),
/// or nothing when there is no file. Removes temporary files a killed process left beside it
/// ("<path>.tmp.<pid>"). Throws fragg::IoError for a file that cannot be read or is corrupt,
/// fragg::InvalidArgument for another resolution.
std::optional<fragg::Map> loadAutosave(const std::string& path, const fragg::MapParams& runtime);

class Autosaver {
 public:
  /// Creates the autosave's folder and, with period_s > 0, starts the saving thread.
  /// Throws fragg::IoError when the folder cannot be created.
  Autosaver(const AutosaveParams& params, SharedMap* shared);
  /// Stops the thread, then saves once more (the caller stops insertion first).
  ~Autosaver();
  Autosaver(const Autosaver&) = delete;
  Autosaver& operator=(const Autosaver&) = delete;

  /// Saves when the map changed since the last save (or `force`); true when it wrote the file.
  /// Failures are logged (throttled) and counted, never thrown.
  bool saveNow(bool force = false);
  uint64_t saves() const { return saves_; }
  uint64_t failures() const { return failures_; }

 private:
  void run();

  const AutosaveParams params_;
  SharedMap* shared_;
  std::mutex save_mutex_;  ///< one save at a time (the thread, the last save)
  /// What identifies the map's contents: view epoch (a new map), revision, scans, blocks.
  std::optional<std::tuple<uint64_t, uint64_t, size_t, size_t>> saved_version_;
  std::atomic<uint64_t> saves_{0}, failures_{0};
  std::chrono::steady_clock::time_point last_failure_log_;  ///< under save_mutex_
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  bool stop_ = false;
  std::thread thread_;
};

}  // namespace fragg::ros
