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
#pragma once

#include <mutex>
#include <optional>
#include <shared_mutex>
#include <utility>

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
    ReadGuard(const State* state, std::shared_lock<std::shared_mutex> lock)
        : lock_(std::move(lock)), state_(state) {}
    std::shared_lock<std::shared_mutex> lock_;
    const State* state_;
  };

  /// Exclusive access: `State&` while the guard lives.
  class WriteGuard {
   public:
    State& operator*() const { return *state_; }
    State* operator->() const { return state_; }

   private:
    friend class Locked;
    WriteGuard(State* state, std::unique_lock<std::shared_mutex> lock)
        : lock_(std::move(lock)), state_(state) {}
    std::unique_lock<std::shared_mutex> lock_;
    State* state_;
  };

  explicit Locked(State state) : state_(std::move(state)) {}
  Locked(const Locked&) = delete;
  Locked& operator=(const Locked&) = delete;

  /// Waits while a writer holds the lock; shares it with other readers.
  ReadGuard read() const { return ReadGuard(&state_, std::shared_lock<std::shared_mutex>(mutex_)); }
  /// Never waits: empty while a writer holds the lock.
  std::optional<ReadGuard> tryRead() const {
    std::shared_lock<std::shared_mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return std::nullopt;
    return ReadGuard(&state_, std::move(lock));
  }
  /// Waits until no reader or writer holds the lock.
  WriteGuard write() { return WriteGuard(&state_, std::unique_lock<std::shared_mutex>(mutex_)); }
  /// Never waits: empty while anyone holds the lock.
  std::optional<WriteGuard> tryWrite() {
    std::unique_lock<std::shared_mutex> lock(mutex_, std::try_to_lock);
    if (!lock.owns_lock()) return std::nullopt;
    return WriteGuard(&state_, std::move(lock));
  }

 private:
  mutable std::shared_mutex mutex_;
  State state_;
};

/// The map alone behind the lock.
using LockedMap = Locked<Map>;

}  // namespace fragg
