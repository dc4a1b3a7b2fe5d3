// A map (or a map with what must change with it) behind a reader/writer lock, so that every
// thread says whether it reads or writes:
//
//   fragg::LockedMap locked(fragg::Map(params));
//   { auto map = locked.write(); map->insert(cloud, T_map_sensor, sensor); }  // one scan
//   { auto map = locked.read(); state = map->query(p_map); }  // shares with other readers
//
// Readers (queries, markers, statistics, saving) share the lock; writers (insertion, clear box,
// reset, load, pose correction) hold it alone. A writer should hold it for one short edit (one
// scan, not a batch of them), so that a reader never waits for more than that edit. Map's const
// readers may run concurrently (the CUDA write-back behind Map::blockView() has its own guard).
// Each side names itself (`who`, a string literal): a writer that had to wait can ask whom it
// waited for (LockHolders), so that a long wait in a node's trace names its cause.
#pragma once

#include <mutex>
#include <optional>
#include <shared_mutex>
#include <string>
#include <utility>
#include <vector>

#include "fragg_map/lock_holders.h"
#include "fragg_map/map.h"

namespace fragg {

template <typename State>
class Locked {
 public:
  /// Shared access: `const State&` while the guard lives.
  class ReadGuard {
   public:
    const State& operator*() const { return *state_; }
    const State* operator->() const { return state_; }

   private:
    friend class Locked;
    ReadGuard(const State* state, std::shared_lock<std::shared_mutex> lock, HolderTicket ticket)
        : lock_(std::move(lock)), ticket_(std::move(ticket)), state_(state) {}
    std::shared_lock<std::shared_mutex> lock_;
    HolderTicket ticket_;  ///< destroyed first: the board forgets the holder, then it unlocks
    const State* state_;
  };

  /// Exclusive access: `State&` while the guard lives.
  class WriteGuard {
   public:
    State& operator*() const { return *state_; }
    State* operator->() const { return state_; }

   private:
    friend class Locked;
    WriteGuard(State* state, std::unique_lock<std::shared_mutex> lock, HolderTicket ticket)
        : lock_(std::move(lock)), ticket_(std::move(ticket)), state_(state) {}
    std::unique_lock<std::shared_mutex> lock_;
    HolderTicket ticket_;
    State* state_;
  };

  explicit Locked(State state) : state_(std::move(state)) {}
  Locked(const Locked&) = delete;
  Locked& operator=(const Locked&) = delete;

  /// Waits while a writer holds the lock; shares it with other readers. `who`: a string
  /// literal naming the reader (LockHolders reports it).
  ReadGuard read(const char* who = "a reader") const {
    std::shared_lock<std::shared_mutex> lock(mutex_);
    return ReadGuard(&state_, std::move(lock), holders_.enter(who, false));
  }
  /// Never waits: empty while a writer holds the lock.
  std::optional<ReadGuard> tryRead(const char* who = "a reader") const {
    std::shared_lock<std::shared_mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return std::nullopt;
    return ReadGuard(&state_, std::move(lock), holders_.enter(who, false));
  }
  /// Waits until no reader or writer holds the lock. `waited_for` (when given) gets whom it
  /// waited for: the holders when it came and those that took the lock while it waited, each
  /// with how long it held the lock (empty when it did not wait).
  WriteGuard write(const char* who = "a writer", std::vector<LockHolder>* waited_for = nullptr) {
    std::unique_lock<std::shared_mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) {
      const LockHolders::Mark came = holders_.startWaiting();
      lock.lock();
      std::vector<LockHolder> found = holders_.doneWaiting(came);
      if (waited_for) *waited_for = std::move(found);
    } else if (waited_for) {
      waited_for->clear();
    }
    return WriteGuard(&state_, std::move(lock), holders_.enter(who, true));
  }
  /// Never waits: empty while anyone holds the lock.
  std::optional<WriteGuard> tryWrite(const char* who = "a writer") {
    std::unique_lock<std::shared_mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return std::nullopt;
    return WriteGuard(&state_, std::move(lock), holders_.enter(who, true));
  }
  /// Who holds the lock now, and for how long.
  [[nodiscard]] std::vector<LockHolder> holders() const { return holders_.now(); }
  /// Writers waiting for the lock now (write() calls that found it held).
  [[nodiscard]] size_t writersWaiting() const { return holders_.writersWaiting(); }

 private:
  mutable std::shared_mutex mutex_;
  mutable LockHolders holders_;
  State state_;
};

/// The map alone behind the lock.
using LockedMap = Locked<Map>;

}  // namespace fragg
