#include "fragg_map/scan_store.h"

#include <filesystem>
#include <system_error>

#include "fragg_map/errors.h"
#include "fragg_map/internal/scan_codec.h"
#include "fragg_map/log.h"

namespace fragg {

void ScanStore::add(const ScanRecord& record, EncodedPoints points) {
  if (scans_.count(record.id))
    throw InvalidArgument("scan " + std::to_string(record.id) + " is already kept");
  Entry& e = scans_[record.id];
  e.record = record;
  e.record.points = points.count;
  memory_bytes_ += points.data.size();
  e.points = std::move(points);
  enforceBudget();
}

const ScanRecord& ScanStore::record(ScanId id) const {
  const auto it = scans_.find(id);
  if (it == scans_.end()) throw InvalidArgument("no kept scan with index " + std::to_string(id));
  return it->second.record;
}

bool ScanStore::hasPoints(ScanId id) const {
  const auto it = scans_.find(id);
  return it != scans_.end() && it->second.where != Where::kDropped;
}

bool ScanStore::canRemove(ScanId id) const {
  return hasPoints(id) && scans_.at(id).record.removable;
}

void ScanStore::markUnremovable(ScanId id) {
  const auto it = scans_.find(id);
  if (it != scans_.end()) it->second.record.removable = false;
}

EncodedPoints ScanStore::points(ScanId id) const {
  const auto it = scans_.find(id);
  if (it == scans_.end()) throw InvalidArgument("no kept scan with index " + std::to_string(id));
  switch (it->second.where) {
    case Where::kMemory:
      return it->second.points;
    case Where::kSpilled:
      return readSpillFile(spillPath(id), id);
    case Where::kDropped:
      break;
  }
  throw InvalidArgument("the points of scan " + std::to_string(id) +
                        " were dropped (scan store over its memory budget, no spill folder)");
}

const EncodedPoints* ScanStore::pointsInMemory(ScanId id) const {
  const auto it = scans_.find(id);
  return it != scans_.end() && it->second.where == Where::kMemory ? &it->second.points : nullptr;
}

void ScanStore::setPose(ScanId id, const Eigen::Isometry3d& T_map_sensor) {
  const auto it = scans_.find(id);
  if (it == scans_.end()) throw InvalidArgument("no kept scan with index " + std::to_string(id));
  it->second.record.T_map_sensor = T_map_sensor;
}

void ScanStore::erase(ScanId id) {
  const auto it = scans_.find(id);
  if (it == scans_.end()) return;
  if (it->second.where == Where::kSpilled) {
    std::error_code ec;
    std::filesystem::remove(spillPath(id), ec);
  }
  memory_bytes_ -= it->second.points.data.size();
  scans_.erase(it);
}

void ScanStore::clear() {
  while (!scans_.empty()) erase(scans_.begin()->first);
}

std::vector<ScanId> ScanStore::ids() const {
  std::vector<ScanId> out;
  out.reserve(scans_.size());
  for (const auto& [id, e] : scans_) out.push_back(id);
  return out;
}

size_t ScanStore::spilledCount() const {
  size_t n = 0;
  for (const auto& [id, e] : scans_) n += e.where == Where::kSpilled ? 1 : 0;
  return n;
}

size_t ScanStore::droppedCount() const {
  size_t n = 0;
  for (const auto& [id, e] : scans_) n += e.where == Where::kDropped ? 1 : 0;
  return n;
}

std::string ScanStore::spillPath(ScanId id) const {
  return (std::filesystem::path(params_.spill_dir) / ("scan_" + std::to_string(id) + ".fgs"))
      .string();
}

void ScanStore::enforceBudget() {
  if (params_.max_bytes == 0) return;
  // Oldest scans first (ids are insertion order); the newest one always stays in memory.
  for (auto it = scans_.begin(); memory_bytes_ > params_.max_bytes && it != scans_.end(); ++it) {
    Entry& e = it->second;
    if (e.where != Where::kMemory || std::next(it) == scans_.end()) continue;
    if (!params_.spill_dir.empty()) {
      // The scan is already in the map: a spill that fails keeps the points in memory.
      try {
        std::error_code ec;
        std::filesystem::create_directories(params_.spill_dir, ec);
        if (ec) throw IoError("cannot create " + params_.spill_dir + ": " + ec.message());
        writeSpillFile(spillPath(it->first), e.record, e.points);
      } catch (const IoError& err) {
        logMessage(LogLevel::kWarning,
                   std::string("scan store: cannot spill, points stay in memory: ") + err.what());
        return;
      }
      e.where = Where::kSpilled;
    } else {
      if (!warned_drop_) {
        logMessage(LogLevel::kWarning,
                   "scan store over its budget of " + std::to_string(params_.max_bytes) +
                       " bytes and no spill folder: the points of the oldest scans are dropped; "
                       "they can no longer be removed or corrected");
        warned_drop_ = true;
      }
      e.where = Where::kDropped;
    }
    memory_bytes_ -= e.points.data.size();
    e.points.data.clear();
    e.points.data.shrink_to_fit();
  }
}

}  // namespace fragg
