// Who holds a reader/writer lock, and whom a writer waited for (fragg::Locked keeps one board
// per lock): each holder enters with a name (a string literal) and leaves with the time it held
// the lock; the last kKept departures are remembered, so that a writer that waited can list
// the holders it found and those that took the lock while it waited. A few hundred nanoseconds
// per guard (one small mutex, taken on entry and on leaving). Thread-safe.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <string>
#include <vector>

namespace fragg {

/// One holder of a lock: its name, its side, how long it held the lock (until it left, or
/// until asked while it still holds it).
struct LockHolder {
  const char* who = "";
  bool writes = false;
  double held_ms = 0.0;
};

class LockHolders;

/// A holder's place on the board: leaves it when destroyed (move-only).
class HolderTicket {
 public:
  HolderTicket() = default;
  HolderTicket(LockHolders* board, uint64_t id) : board_(board), id_(id) {}
  HolderTicket(HolderTicket&& other) noexcept : board_(other.board_), id_(other.id_) {
    other.board_ = nullptr;
  }
  HolderTicket& operator=(HolderTicket&& other) noexcept;
  HolderTicket(const HolderTicket&) = delete;
  HolderTicket& operator=(const HolderTicket&) = delete;
  ~HolderTicket();

 private:
  LockHolders* board_ = nullptr;
  uint64_t id_ = 0;
};

class LockHolders {
 public:
  using Clock = std::chrono::steady_clock;
  /// Departures remembered (a writer that waited longer than it took this many holders to
  /// leave sees the last kKept).
  static constexpr size_t kKept = 64;
  /// A point in the board's history, where a writer began to wait (startWaiting()).
  struct Mark {
    uint64_t departures = 0;
  };

  /// `who` takes the lock (a string literal: kept by pointer).
  [[nodiscard]] HolderTicket enter(const char* who, bool writes);
  /// The holder of ticket `id` left (HolderTicket's destructor).
  void leave(uint64_t id);
  /// A writer is about to wait for the lock: counted in writersWaiting() until doneWaiting().
  [[nodiscard]] Mark startWaiting();
  /// The writer that began to wait at `mark` has the lock: the holders that left since (the
  /// last kKept of them), oldest first.
  [[nodiscard]] std::vector<LockHolder> doneWaiting(const Mark& mark);
  /// Writers waiting for the lock now.
  [[nodiscard]] size_t writersWaiting() const;
  /// The holders now, each with how long it has held the lock so far.
  [[nodiscard]] std::vector<LockHolder> now() const;

 private:
  struct Entry {
    uint64_t id;
    const char* who;
    bool writes;
    Clock::time_point since;
  };
  mutable std::mutex mutex_;
  std::vector<Entry> holding_;
  std::array<LockHolder, kKept> left_{};  ///< ring of the last departures
  uint64_t departures_ = 0;
  uint64_t next_id_ = 1;
  size_t waiting_ = 0;
};

/// `holders` by name, the longest total first: "name 12.3 ms" (or "name x4 12.3 ms" for four
/// holdings), at most `most` names and "+N more", joined by "; " (no commas: a CSV field).
[[nodiscard]] std::string describeLockHolders(const std::vector<LockHolder>& holders,
                                              size_t most = 3);

}  // namespace fragg
