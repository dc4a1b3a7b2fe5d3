#include "fragg_map/internal/host_view_gate.h"

#include <stdexcept>

namespace fragg {

HostViewGate::Pin HostViewGate::pin() {
  const std::thread::id me = std::this_thread::get_id();
  {
    std::unique_lock<std::mutex> lock(mutex_);
    const auto mine = pins_by_thread_.find(me);
    const bool nested = mine != pins_by_thread_.end() && mine->second > 0;
    // Writers first: a write-back waiting for the pins held is not kept waiting by new ones
    // (a nested pin does not wait: its thread's first pin holds the writer back anyway).
    if (!nested && (writing_ || writers_waiting_ > 0)) {
      ++pins_waiting_;
      changed_.wait(lock, [&] { return !writing_ && writers_waiting_ == 0; });
      --pins_waiting_;
    }
    ++pins_;
    ++pins_by_thread_[me];
  }
  // The pin keeps the gate alive: a view may outlive the map's member that made it.
  std::shared_ptr<HostViewGate> self = shared_from_this();
  return Pin(static_cast<const void*>(self.get()), [self, me](const void*) { self->release(me); });
}

void HostViewGate::release(std::thread::id owner) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    --pins_;
    const auto it = pins_by_thread_.find(owner);
    if (it != pins_by_thread_.end() && --it->second == 0) pins_by_thread_.erase(it);
  }
  changed_.notify_all();
}

void HostViewGate::exclusive(const std::function<void()>& write_back) {
  {
    std::unique_lock<std::mutex> lock(mutex_);
    if (pins_by_thread_.count(std::this_thread::get_id()) != 0)
      throw std::logic_error(
          "the map's device changes cannot be written back while this thread holds a "
          "Map::hostBlockView() (its blocks would move under it): take blockView() first");
    ++writers_waiting_;
    changed_.wait(lock, [&] { return !writing_ && pins_ == 0; });
    --writers_waiting_;
    writing_ = true;
  }
  // The gate opens again however the write-back ends.
  struct Reopen {
    HostViewGate* gate;
    ~Reopen() {
      {
        std::lock_guard<std::mutex> lock(gate->mutex_);
        gate->writing_ = false;
      }
      gate->changed_.notify_all();
    }
  } reopen{this};
  write_back();
}

size_t HostViewGate::pins() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pins_;
}

size_t HostViewGate::writersWaiting() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return writers_waiting_;
}

size_t HostViewGate::pinsWaiting() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return pins_waiting_;
}

size_t HostViewGate::pinsOfThisThread() const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = pins_by_thread_.find(std::this_thread::get_id());
  return it == pins_by_thread_.end() ? 0 : it->second;
}

}  // namespace fragg
