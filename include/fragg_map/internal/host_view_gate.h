// Keeps the host's blocks still while readers of Map::hostBlockView() read them. On a CUDA map
// a reader that calls Map::blockView() (a service, the autosave, the outputs' listing) writes
// the device's changes back into the host's blocks under the map's *read* lock, and that
// write-back adds blocks (the storage's arrays and key table may move) and rewrites cells,
// while another reader (the paced outputs) reads the same blocks through hostBlockView(),
// which does not write back. The gate orders the two: a view taken from hostBlockView() holds
// a pin for its lifetime; a write-back waits until no pin is held, and a new pin waits for a
// write-back in progress or waiting. Pins nest on one thread (a reader may take several views); a
// thread that holds a pin and would write back gets a std::logic_error, not a deadlock.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <unordered_map>

namespace fragg {

class HostViewGate : public std::enable_shared_from_this<HostViewGate> {
 public:
  /// A pin: the host's blocks are not written back while any pin lives (release on
  /// destruction). Copyable through shared_ptr; released when the last copy goes.
  using Pin = std::shared_ptr<const void>;

  /// Takes a pin, waiting for a write-back in progress or waiting (not when this thread holds
  /// a pin already: it would wait for itself). The gate outlives its pins (they keep it alive).
  [[nodiscard]] Pin pin();
  /// Runs `write_back` once no pin is held (pins taken meanwhile wait for it). Throws
  /// std::logic_error when this thread holds a pin itself (the write-back would wait for it
  /// forever): a reader must not call Map::blockView() while it keeps a hostBlockView().
  void exclusive(const std::function<void()>& write_back);
  /// Pins held now, over every thread.
  [[nodiscard]] size_t pins() const;
  /// Pins this thread holds on this gate.
  [[nodiscard]] size_t pinsOfThisThread() const;
  /// Write-backs waiting for pins to go, and pins waiting for a write-back (what a test
  /// waits for before it lets the other side go on).
  [[nodiscard]] size_t writersWaiting() const;
  [[nodiscard]] size_t pinsWaiting() const;

 private:
  /// A pin's release (its thread: the one that took it, wherever the last copy goes).
  void release(std::thread::id owner);

  mutable std::mutex mutex_;
  std::condition_variable changed_;
  size_t pins_ = 0;
  size_t writers_waiting_ = 0, pins_waiting_ = 0;
  std::unordered_map<std::thread::id, size_t> pins_by_thread_;
  bool writing_ = false;
};

}  // namespace fragg
