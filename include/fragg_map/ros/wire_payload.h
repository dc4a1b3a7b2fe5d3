// Messages built in roscpp's wire layout where they are kept, so that publishing them copies and
// serialises nothing: a whole-map message (the occupied cloud, the projected map) is mostly one
// byte array, its payload, which the output cache writes straight into a buffer at a fixed
// offset (the cloud in shares over the clouds of a period); at publication the message's other
// fields are serialised in front of it and roscpp is handed the buffer as it is
// (Preserialized<M>: ros::serialization::serializeMessage is specialised for it). A buffer
// roscpp still holds (queued for a subscriber, latched) is never written again: the next message
// takes another one.
#pragma once

#include <nav_msgs/OccupancyGrid.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <ros/serialized_message.h>
#include <sensor_msgs/PointCloud2.h>

#include <boost/shared_array.hpp>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <mutex>
#include <vector>

namespace fragg::ros {

/// A message of type M already in roscpp's wire layout (length prefix included): a Publisher of
/// M publishes it as an M, handing `wire` to roscpp without a copy.
template <typename M>
struct Preserialized {
  ::ros::SerializedMessage wire;
};
using PreserializedCloud = Preserialized<sensor_msgs::PointCloud2>;
using PreserializedGrid = Preserialized<nav_msgs::OccupancyGrid>;

/// A buffer of a serialised message and its size.
struct WireBuffer {
  boost::shared_array<uint8_t> bytes;
  size_t capacity = 0;
};

/// Buffers for serialised messages, taken again once nobody else holds them (roscpp lets go of
/// a message once sent and no longer latched), so that a topic publishing every cloud writes
/// into pages it already has: a fresh buffer's pages fault in when first written (on the 2-core
/// VM ~3.7 ms for each 2 MiB huge page). A buffer is made with twice the room asked for and at
/// least kMinCapacity (untouched room costs address space only, never a page), so that a growing
/// message rarely needs a new one: it faults in only the pages it grows into.
/// Thread-safe: a late subscriber's snapshot may be serialised beside the updates.
class WireBufferPool {
 public:
  /// Buffers kept (those held elsewhere included); beyond, a message gets a buffer of its own.
  static constexpr size_t kKept = 4;
  /// Messages above this many bytes get a buffer of their own.
  static constexpr size_t kLargest = size_t{1} << 30;
  /// The least room of a kept buffer.
  static constexpr size_t kMinCapacity = size_t{32} << 20;
  /// A buffer of at least `bytes` that nobody else holds: the smallest kept one that fits,
  /// else a kept one nobody holds made anew larger, else a new one (kept while fewer than
  /// kKept are).
  [[nodiscard]] WireBuffer take(size_t bytes);
  /// Bytes of the kept buffers (address space; their pages come in when written).
  [[nodiscard]] size_t keptBytes() const;

 private:
  mutable std::mutex mutex_;
  std::vector<WireBuffer> kept_;
};

/// The payload (last byte array) of one message at a time, written in place, and the buffers
/// it was written into. Not thread-safe: one owner.
class WirePayload {
 public:
  /// Room in front of the payload for the message's other fields (a longer frame_id than fits
  /// costs a copy of the payload: finish()).
  static constexpr size_t kHeadroom = 1024;

  /// Makes room for a payload of `bytes`, keeping the first `kept` bytes written so far (moved
  /// when another buffer is taken); returns where the payload starts.
  uint8_t* reserve(size_t bytes, size_t kept);
  /// The message: `empty` is the message serialised by roscpp (serializeMessage) with an empty
  /// payload, whose last `tail` bytes follow the payload (a PointCloud2's is_dense; 0 for an
  /// OccupancyGrid), and `payload_bytes` of payload written since reserve(). The buffer goes to
  /// the caller (and roscpp): the next reserve() writes into another one.
  ::ros::SerializedMessage finish(const ::ros::SerializedMessage& empty, size_t tail,
                                  size_t payload_bytes);

 private:
  WireBuffer current_;  ///< the one being written
  /// Where current_ comes from: a buffer handed out is taken again once roscpp lets go of it.
  std::shared_ptr<WireBufferPool> buffers_ = std::make_shared<WireBufferPool>();
};

}  // namespace fragg::ros

namespace ros {
namespace message_traits {

template <typename M>
struct IsMessage<fragg::ros::Preserialized<M>> : TrueType {};
template <typename M>
struct MD5Sum<fragg::ros::Preserialized<M>> {
  static const char* value() { return MD5Sum<M>::value(); }
  static const char* value(const fragg::ros::Preserialized<M>&) { return value(); }
};
template <typename M>
struct DataType<fragg::ros::Preserialized<M>> {
  static const char* value() { return DataType<M>::value(); }
  static const char* value(const fragg::ros::Preserialized<M>&) { return value(); }
};
template <typename M>
struct Definition<fragg::ros::Preserialized<M>> {
  static const char* value() { return Definition<M>::value(); }
  static const char* value(const fragg::ros::Preserialized<M>&) { return value(); }
};

}  // namespace message_traits

namespace serialization {

/// Publisher::publish and SingleSubscriberPublisher::publish serialise through this: the kept
/// bytes, shared (no copy).
template <>
inline SerializedMessage serializeMessage<fragg::ros::PreserializedCloud>(
    const fragg::ros::PreserializedCloud& message) {
  return message.wire;
}
template <>
inline SerializedMessage serializeMessage<fragg::ros::PreserializedGrid>(
    const fragg::ros::PreserializedGrid& message) {
  return message.wire;
}

}  // namespace serialization
}  // namespace ros
