// Message payloads written in place, in roscpp's wire layout.
#include "fragg_map/ros/wire_payload.h"

#include <algorithm>
#include <cstring>
#include <utility>

namespace fragg::ros {
namespace {

// Bytes after the payload that a message may have (a PointCloud2's is_dense).
constexpr size_t kTailRoom = 16;

}  // namespace

uint8_t* WirePayload::reserve(size_t bytes, size_t kept) {
  const size_t need = kHeadroom + bytes + kTailRoom;
  if (current_.bytes && current_.capacity >= need) return current_.bytes.get() + kHeadroom;
  WireBuffer next = buffers_->take(need);
  if (current_.bytes && kept > 0)
    std::memcpy(next.bytes.get() + kHeadroom, current_.bytes.get() + kHeadroom, kept);
  current_ = std::move(next);
  return current_.bytes.get() + kHeadroom;
}

::ros::SerializedMessage WirePayload::finish(const ::ros::SerializedMessage& empty, size_t tail,
                                             size_t payload_bytes) {
  uint8_t* payload = reserve(payload_bytes, payload_bytes);
  // The empty message: [length][fields ...][payload length = 0][tail].
  const size_t head = empty.num_bytes - tail;
  const size_t total = head + payload_bytes + tail;
  const uint32_t length = static_cast<uint32_t>(total - 4);
  const uint32_t payload_length = static_cast<uint32_t>(payload_bytes);
  ::ros::SerializedMessage out;
  if (head <= kHeadroom) {
    uint8_t* start = payload - head;
    std::memcpy(start, empty.buf.get(), head);
    std::memcpy(start + head + payload_bytes, empty.buf.get() + head, tail);
    std::memcpy(start, &length, 4);
    std::memcpy(start + head - 4, &payload_length, 4);
    // The handed-out array shares the buffer's count: while roscpp holds it, it is not free.
    out.buf = boost::shared_array<uint8_t>(current_.bytes, start);
    out.num_bytes = total;
    out.message_start = start + 4;
    current_ = WireBuffer();  // the pool takes it again once roscpp lets go of `out`
    return out;
  }
  // Fields longer than the headroom (a very long frame_id): a buffer of the message's own.
  out.buf.reset(new uint8_t[total]);
  std::memcpy(out.buf.get(), empty.buf.get(), head);
  std::memcpy(out.buf.get() + head, payload, payload_bytes);
  std::memcpy(out.buf.get() + head + payload_bytes, empty.buf.get() + head, tail);
  std::memcpy(out.buf.get(), &length, 4);
  std::memcpy(out.buf.get() + head - 4, &payload_length, 4);
  out.num_bytes = total;
  out.message_start = out.buf.get() + 4;
  return out;
}

WireBuffer WireBufferPool::take(size_t bytes) {
  if (bytes > kLargest) return {boost::shared_array<uint8_t>(new uint8_t[bytes]), bytes};
  std::lock_guard<std::mutex> lock(mutex_);
  WireBuffer* fit = nullptr;   // the smallest free buffer that fits
  WireBuffer* grow = nullptr;  // else the largest free one, made anew larger
  for (WireBuffer& b : kept_) {
    if (b.bytes.use_count() != 1) continue;  // held: being written, queued or latched
    if (b.capacity >= bytes) {
      if (!fit || b.capacity < fit->capacity) fit = &b;
    } else if (!grow || b.capacity > grow->capacity) {
      grow = &b;
    }
  }
  if (!fit && (grow || kept_.size() < kKept)) {
    if (!grow) grow = &kept_.emplace_back();
    grow->capacity = std::max(2 * bytes, kMinCapacity);
    grow->bytes.reset(new uint8_t[grow->capacity]);
    fit = grow;
  }
  if (!fit) return {boost::shared_array<uint8_t>(new uint8_t[bytes]), bytes};  // all held
  return *fit;
}

size_t WireBufferPool::keptBytes() const {
  std::lock_guard<std::mutex> lock(mutex_);
  size_t total = 0;
  for (const WireBuffer& b : kept_) total += b.capacity;
  return total;
}

}  // namespace fragg::ros
