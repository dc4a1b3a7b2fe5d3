// The page store's background writer (Pager): a commit's records, encoded on the map's thread
// (a snapshot of the dirty blocks), are written to the store on this thread while the map goes
// on. Double-buffered: one batch is written while the map builds the next; submitting waits for
// the one in flight. A block paged out while its region's record is in a batch not yet written
// is read from that batch (findPending), so the map never reads an older record from the store.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <tuple>
#include <utility>
#include <vector>

#include "fragg_map/page_store.h"

namespace fragg {

/// The page stores' order of block and region keys: by z, then y, then x.
[[nodiscard]] inline bool storeOrder(const BlockKey& a, const BlockKey& b) {
  return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
}

class PageWriter {
 public:
  struct Batch {
    /// Region records, sorted by region key in the stores' order (z, y, x), one per region.
    std::vector<std::pair<BlockKey, BlockRecord>> puts;
    /// Regions whose records go.
    std::vector<BlockKey> erases;
    std::vector<uint8_t> meta;
  };

  explicit PageWriter(std::shared_ptr<PageStore> store);
  /// Waits for the batch in flight (a failure is logged: the store keeps its previous commit).
  ~PageWriter();
  PageWriter(const PageWriter&) = delete;
  PageWriter& operator=(const PageWriter&) = delete;

  /// Waits for the batch in flight, then hands `batch` to the thread. A batch whose write failed
  /// is written again with this one (its records where this one has none for the key): its
  /// blocks may be paged out, held nowhere else.
  void submit(Batch batch);
  /// Waits until nothing is in flight; IoError when the last batch failed (it stays pending
  /// and goes with the next submit).
  void wait();
  enum class Pending {
    kNone,     ///< no batch not yet written holds a record of the block's region
    kFound,    ///< decoded into *out
    kMissing,  ///< such a batch holds the region's record, without the block
  };
  /// Block `key` from the record of its region in a batch not yet written.
  Pending findPending(const BlockKey& key, Block* out);
  /// RAM of the batches not yet in the store (the one in flight and a failed one): their
  /// records' bytes and entries. Lock-free (the budget reads it often).
  [[nodiscard]] size_t pendingBytes() const {
    return pending_bytes_.load(std::memory_order_relaxed);
  }
  /// The same for one batch.
  [[nodiscard]] static size_t bytesOf(const Batch& batch);
  /// Seconds the thread spent writing, and batches written.
  double secondsWriting() const;
  uint64_t batchesWritten() const;

 private:
  void run();
  static const BlockRecord* findIn(const Batch& batch, const BlockKey& key);
  static void mergeOlder(Batch& newer, Batch older);

  std::shared_ptr<PageStore> store_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  /// The batch being written (or waiting for the thread); null when none.
  std::unique_ptr<Batch> in_flight_;
  /// The last batch whose write failed, with why; null when none.
  std::unique_ptr<Batch> failed_;
  std::string failure_;
  bool stop_ = false;
  /// bytesOf(in_flight_) + bytesOf(failed_), changed under mutex_.
  std::atomic<size_t> pending_bytes_{0};
  double seconds_writing_ = 0;
  uint64_t batches_written_ = 0;
  std::thread thread_;
};

}  // namespace fragg
