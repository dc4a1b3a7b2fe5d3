// A bounded FIFO between the cloud subscriber and the insertion thread: when clouds arrive
// faster than they are integrated, the oldest waiting one is dropped (and counted), so the
// map always works on the newest data. ROS-free.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <utility>

#include "fragg_map/errors.h"

namespace fragg::ros {

template <typename T>
class DropOldestQueue {
 public:
  explicit DropOldestQueue(size_t capacity) : capacity_(capacity) {
    if (capacity_ == 0) throw fragg::InvalidArgument("queue capacity must be >= 1");
  }

  /// Appends `item`; when the queue is full the oldest item is dropped first (moved into
  /// `*dropped_item` when given). Returns whether an item was dropped. Items pushed after
  /// close() are discarded (and not counted).
  bool push(T item, T* dropped_item = nullptr) {
    bool dropped = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (closed_) return false;
      if (items_.size() == capacity_) {
        if (dropped_item) *dropped_item = std::move(items_.front());
        items_.pop_front();
        ++dropped_;
        dropped = true;
      }
      items_.push_back(std::move(item));
    }
    ready_.notify_one();
    return dropped;
  }

  /// Waits for the oldest item and takes it; returns false once the queue is closed (items
  /// still waiting then are discarded).
  bool pop(T* out) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [this] { return closed_ || !items_.empty(); });
    if (closed_) return false;
    *out = std::move(items_.front());
    items_.pop_front();
    return true;
  }

  /// Wakes every waiting pop(), which then returns false.
  void close() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      closed_ = true;
      items_.clear();
    }
    ready_.notify_all();
  }

  size_t size() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return items_.size();
  }
  uint64_t dropped() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return dropped_;
  }
  size_t capacity() const { return capacity_; }

 private:
  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<T> items_;
  uint64_t dropped_ = 0;
  bool closed_ = false;
};

}  // namespace fragg::ros
