#include "autosave.h"

#include <ros/console.h>

#include <chrono>
#include <filesystem>
#include <system_error>
#include <utility>

#include "fragg_map/errors.h"
#include "fragg_map/map_image.h"
#include "map_file_loader.h"

namespace fragg::ros {
namespace fs = std::filesystem;

namespace {

constexpr const char* kMoveAway = " (move the file away to start without it)";

/// Temporary files of AtomicFile ("<name>.tmp.<pid>") that a killed process left beside `path`.
void removeStaleTemporaries(const fs::path& path) {
  std::error_code ec;
  const std::string prefix = path.filename().string() + ".tmp.";
  for (const fs::directory_entry& e : fs::directory_iterator(path.parent_path(), ec)) {
    const std::string name = e.path().filename().string();
    if (name.compare(0, prefix.size(), prefix) == 0) {
      fs::remove(e.path(), ec);
      ROS_INFO("fragg_map: autosave: removed %s (an interrupted save)", e.path().c_str());
    }
  }
}

}  // namespace

std::optional<fragg::Map> loadAutosave(const std::string& path, const fragg::MapParams& runtime) {
  removeStaleTemporaries(path);
  std::error_code ec;
  if (!fs::exists(path, ec)) return std::nullopt;
  try {
    return loadMapFile(path, runtime);
  } catch (const fragg::IoError& e) {
    throw fragg::IoError(std::string("autosave ") + e.what() + kMoveAway);
  } catch (const fragg::InvalidArgument& e) {
    throw fragg::InvalidArgument(std::string("autosave ") + e.what() + kMoveAway);
  }
}

Autosaver::Autosaver(const AutosaveParams& params, SharedMap* shared)
    : params_(params), shared_(shared) {
  std::error_code ec;
  fs::create_directories(fs::path(params_.path).parent_path(), ec);
  if (ec)
    throw fragg::IoError("autosave: cannot create the folder of " + params_.path + ": " +
                         ec.message());
  if (params_.period_s > 0) thread_ = std::thread([this] { run(); });
}

Autosaver::~Autosaver() {
  {
    std::lock_guard<std::mutex> lock(wake_mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (saveNow())
    ROS_INFO("fragg_map: autosave: saved the map on shutdown to %s", params_.path.c_str());
}

void Autosaver::run() {
  using Clock = std::chrono::steady_clock;
  const auto period =
      std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(params_.period_s));
  Clock::time_point next = Clock::now() + period;
  std::unique_lock<std::mutex> lock(wake_mutex_);
  while (!wake_.wait_until(lock, next, [this] { return stop_; })) {
    lock.unlock();
    next = Clock::now() + period;  // from the start of this save: a save per period
    saveNow();
    lock.lock();
  }
}

bool Autosaver::saveNow(bool force) {
  std::lock_guard<std::mutex> saving(save_mutex_);
  try {
    fragg::MapImage image;
    std::tuple<uint64_t, uint64_t, size_t, size_t> version;
    {
      const SharedMap::ReadGuard state = shared_->read("autosave");  // the copy only, not the write
      const fragg::Map& map = state->map;
      version = {map.viewEpoch(), map.revision(), map.scanCount(), map.blockCount()};
      if (!force && saved_version_ == version) return false;
      image = map.image();
    }
    fragg::writeMapImage(image, params_.path);
    saved_version_ = version;
    if (saves_++ == 0)
      ROS_INFO("fragg_map: autosave: first save to %s (%zu blocks, %zu scans)",
               params_.path.c_str(), image.blocks.size(), std::get<2>(version));
    return true;
  } catch (const std::exception& e) {
    ++failures_;
    // Throttled on the steady clock (ROS_*_THROTTLE needs ROS time, absent in tests).
    const auto now = std::chrono::steady_clock::now();
    if (failures_ == 1 || now - last_failure_log_ >= std::chrono::seconds(10)) {
      last_failure_log_ = now;
      ROS_ERROR("fragg_map: autosave to %s failed (%lu failures; the previous file stays): %s",
                params_.path.c_str(), static_cast<unsigned long>(failures_.load()), e.what());
    }
    return false;
  }
}

}  // namespace fragg::ros
