// Message payloads written in place, in roscpp's wire layout.
#include "fragg_map/ros/wire_payload.h"

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
  Buffer next;
  if (sent_.free() && sent_.capacity >= need) {
    next = std::move(sent_);  // the last message's buffer: roscpp has let go of it
    sent_ = Buffer();
  } else {
    // Room for the payload to grow by half before the next buffer: a fresh buffer's pages
    // fault in when first written (~15 us each on the 2-core VM).
    next.capacity = need + bytes / 2;
    next.bytes.reset(new uint8_t[next.capacity]);
  }
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
    sent_ = std::move(current_);
    current_ = Buffer();
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

}  // namespace fragg::ros
