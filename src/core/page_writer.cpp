#include "fragg_map/internal/page_writer.h"

#ifdef __linux__
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#endif

#include <algorithm>
#include <chrono>
#include <exception>
#include <unordered_set>

#include "fragg_map/errors.h"
#include "fragg_map/log.h"

namespace fragg {

namespace {
/// Nice value of the writer thread (Linux: per thread), above the map's threads' 0.
constexpr int kWriterNice = 10;
}  // namespace

PageWriter::PageWriter(std::shared_ptr<PageStore> store) : store_(std::move(store)) {
  thread_ = std::thread([this] { run(); });
}

PageWriter::~PageWriter() {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [&] { return !in_flight_; });
    if (failed_)
      logMessage(
          LogLevel::kWarning,
          "paging: the last commit failed (the store keeps its previous commit): " + failure_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

void PageWriter::run() {
#ifdef __linux__
  // A commit has until the next one to reach the store: the writer runs in the time the
  // map's threads leave (on a machine whose cores the insertion fills, a writer of equal
  // priority takes a core from a parallel ray cast, whose threads then wait for it). Should
  // it fail, the writer keeps the map's priority: slower there, nothing else changes.
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), kWriterNice);
#endif
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    cv_.wait(lock, [&] { return stop_ || in_flight_; });
    if (!in_flight_) return;  // stopping, nothing left
    const Batch& batch = *in_flight_;
    lock.unlock();
    // The batch is not changed while in flight: the map's thread only reads it (findPending).
    const auto t0 = std::chrono::steady_clock::now();
    std::string error;
    try {
      store_->commitRecords(batch.puts, batch.erases, batch.meta);
    } catch (const std::exception& e) {
      error = e.what();
      if (error.empty()) error = "unknown error";
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    lock.lock();
    seconds_writing_ += s;
    if (error.empty()) {
      ++batches_written_;
    } else {
      failure_ = error;
      failed_ = std::move(in_flight_);
    }
    in_flight_.reset();
    pending_bytes_ = failed_ ? bytesOf(*failed_) : 0;
    cv_.notify_all();
  }
}

void PageWriter::mergeOlder(Batch& newer, Batch older) {
  std::unordered_set<BlockKey, BlockKeyHash> newer_keys;
  for (const auto& p : newer.puts) newer_keys.insert(p.first);
  for (const BlockKey& k : newer.erases) newer_keys.insert(k);
  bool added = false;
  for (auto& p : older.puts)
    if (!newer_keys.count(p.first)) {
      newer.puts.push_back(std::move(p));
      added = true;
    }
  std::unordered_set<BlockKey, BlockKeyHash> put_keys;
  for (const auto& p : newer.puts) put_keys.insert(p.first);
  for (const BlockKey& k : older.erases)
    if (!put_keys.count(k)) newer.erases.push_back(k);
  if (added)
    std::sort(newer.puts.begin(), newer.puts.end(),
              [](const auto& a, const auto& b) { return storeOrder(a.first, b.first); });
}

void PageWriter::submit(Batch batch) {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [&] { return !in_flight_; });
  if (failed_) {
    logMessage(LogLevel::kWarning, "paging: a commit failed (" + failure_ +
                                       "): its blocks are written again with the next one");
    mergeOlder(batch, std::move(*failed_));
    failed_.reset();
    failure_.clear();
  }
  in_flight_ = std::make_unique<Batch>(std::move(batch));
  pending_bytes_ = bytesOf(*in_flight_);
  cv_.notify_all();
}

void PageWriter::wait() {
  std::unique_lock<std::mutex> lock(mutex_);
  cv_.wait(lock, [&] { return !in_flight_; });
  if (failed_) throw IoError("paging: commit failed: " + failure_);
}

size_t PageWriter::bytesOf(const Batch& batch) {
  size_t n = batch.puts.capacity() * sizeof(batch.puts[0]) +
             batch.erases.capacity() * sizeof(BlockKey) + batch.meta.capacity();
  for (const auto& p : batch.puts) n += p.second.capacity();
  return n;
}

const BlockRecord* PageWriter::findIn(const Batch& batch, const BlockKey& key) {
  auto it = std::lower_bound(batch.puts.begin(), batch.puts.end(), key,
                             [](const std::pair<BlockKey, BlockRecord>& p, const BlockKey& k) {
                               return storeOrder(p.first, k);
                             });
  if (it == batch.puts.end() || !(it->first == key)) return nullptr;
  return &it->second;
}

PageWriter::Pending PageWriter::findPending(const BlockKey& key, Block* out) {
  std::lock_guard<std::mutex> lock(mutex_);
  // At most one of the two exists: a failed batch is merged into the next one submitted.
  for (const Batch* b : {in_flight_.get(), failed_.get()}) {
    if (!b) continue;
    if (const BlockRecord* r = findIn(*b, regionOf(key)))
      return store_->decode(*r, key, out) ? Pending::kFound : Pending::kMissing;
  }
  return Pending::kNone;
}

double PageWriter::secondsWriting() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return seconds_writing_;
}

uint64_t PageWriter::batchesWritten() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return batches_written_;
}

}  // namespace fragg
