// visualization_msgs/MarkerArray kept as roscpp's wire bytes, one buffer per Marker: a marker
// topic keeps each chunk's serialised marker and sends, per update, an array of only the chunks
// that changed, its latched full set gathered from the kept ones. roscpp serialises a
// geometry_msgs/Point or std_msgs/ColorRGBA element by element (gencpp emits no IsSimple trait:
// a vector of them is a loop over each element's fields); the CUBE_LIST's points and colours are
// written here straight into the wire layout instead, once per changed chunk.
// SerializedMarkerArray carries MarkerArray's md5sum, datatype and definition, so a Publisher of
// visualization_msgs::MarkerArray publishes it and every subscriber receives a MarkerArray.
#pragma once

#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <ros/time.h>
#include <visualization_msgs/Marker.h>
#include <visualization_msgs/MarkerArray.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <vector>

#include "fragg_map/ros/wire_payload.h"

namespace fragg::ros {

/// One visualization_msgs/Marker in roscpp's wire layout (no length prefix): `size` bytes of
/// a buffer of `capacity`.
struct WireMarker {
  std::unique_ptr<uint8_t[]> bytes;
  uint32_t size = 0;
  uint32_t capacity = 0;
};
using WireMarkerPtr = std::shared_ptr<const WireMarker>;

/// A MarkerArray as its markers' wire bytes (shared with the ledger that keeps them). Every
/// marker's header stamp is written as `stamp` when serialised (kept chunks were encoded at
/// earlier updates).
struct SerializedMarkerArray {
  ::ros::Time stamp;
  std::vector<WireMarkerPtr> markers;
  /// Where the serialised array is written (a topic's kept buffers); nullptr: a new buffer.
  std::shared_ptr<WireBufferPool> buffers;
};

/// `array` serialised as roscpp does (length prefix, then MarkerArray's layout), into a buffer
/// of array.buffers when it has them.
[[nodiscard]] ::ros::SerializedMessage serializeMarkerArray(const SerializedMarkerArray& array);

/// `marker` serialised by roscpp (any type and action).
[[nodiscard]] WireMarkerPtr wireOf(const visualization_msgs::Marker& marker);

/// Writes a CUBE_LIST's points and colours straight into the wire layout: the marker `head`
/// (every field but points and colors as sent; those two empty) serialised by roscpp around
/// `points` points, whose 24 point bytes and 16 colour bytes (when it has colours) the caller
/// writes through setPoint / setColor before handing the buffer on.
class CubeListWriter {
 public:
  /// Throws fragg::InvalidArgument when `head` has points or colours already. `reuse`: a
  /// marker's buffer that nobody else holds any more (use_count 1), written over in place
  /// when large enough (its pages are resident: a fresh buffer of a chunk's size costs a page
  /// fault per 4 KiB, ~15 us each on the 2-core VM); otherwise a new one.
  /// `with_colors` false: no per-point colours (the marker's own colour draws every cube, as
  /// octomap_server's flat markers): 24 bytes a cell instead of 40, setColor not called.
  CubeListWriter(const visualization_msgs::Marker& head, uint32_t points,
                 std::shared_ptr<WireMarker> reuse = nullptr, bool with_colors = true);
  /// Point `i` (x, y, z as float64).
  void setPoint(uint32_t i, double x_m, double y_m, double z_m) {
    const double xyz[3] = {x_m, y_m, z_m};
    std::memcpy(points_ + 24 * size_t{i}, xyz, sizeof xyz);
  }
  /// Colour `i` (r, g, b, a as float32).
  void setColor(uint32_t i, const float rgba[4]) {
    std::memcpy(colors_ + 16 * size_t{i}, rgba, 16);
  }
  /// The bytes (the writer is spent).
  [[nodiscard]] std::shared_ptr<WireMarker> finish();

 private:
  std::shared_ptr<WireMarker> out_;
  uint8_t* points_ = nullptr;
  uint8_t* colors_ = nullptr;
};

/// The MarkerArray roscpp would deliver for `wire` (tests, tools: decodes every marker).
[[nodiscard]] visualization_msgs::MarkerArray toMarkerArray(const SerializedMarkerArray& wire);

}  // namespace fragg::ros

namespace ros {
namespace message_traits {

template <>
struct IsMessage<fragg::ros::SerializedMarkerArray> : TrueType {};
template <>
struct MD5Sum<fragg::ros::SerializedMarkerArray> {
  static const char* value() { return MD5Sum<visualization_msgs::MarkerArray>::value(); }
  static const char* value(const fragg::ros::SerializedMarkerArray&) { return value(); }
};
template <>
struct DataType<fragg::ros::SerializedMarkerArray> {
  static const char* value() { return DataType<visualization_msgs::MarkerArray>::value(); }
  static const char* value(const fragg::ros::SerializedMarkerArray&) { return value(); }
};
template <>
struct Definition<fragg::ros::SerializedMarkerArray> {
  static const char* value() { return Definition<visualization_msgs::MarkerArray>::value(); }
  static const char* value(const fragg::ros::SerializedMarkerArray&) { return value(); }
};

}  // namespace message_traits

namespace serialization {

/// MarkerArray's layout: the marker count, then each marker's bytes (its stamp rewritten).
template <>
struct Serializer<fragg::ros::SerializedMarkerArray> {
  /// Header: seq (uint32), then the stamp's sec and nsec (uint32 each).
  static constexpr uint32_t kStampOffset = 4;
  template <typename Stream>
  static void write(Stream& stream, const fragg::ros::SerializedMarkerArray& m) {
    stream.next(static_cast<uint32_t>(m.markers.size()));
    const uint32_t stamp[2] = {m.stamp.sec, m.stamp.nsec};
    for (const fragg::ros::WireMarkerPtr& marker : m.markers) {
      uint8_t* dst = stream.advance(marker->size);
      std::memcpy(dst, marker->bytes.get(), marker->size);
      std::memcpy(dst + kStampOffset, stamp, sizeof stamp);
    }
  }
  static uint32_t serializedLength(const fragg::ros::SerializedMarkerArray& m) {
    uint32_t bytes = 4;
    for (const fragg::ros::WireMarkerPtr& marker : m.markers) bytes += marker->size;
    return bytes;
  }
};

/// Publisher::publish serialises through this: into the topic's kept buffers.
template <>
inline SerializedMessage serializeMessage<fragg::ros::SerializedMarkerArray>(
    const fragg::ros::SerializedMarkerArray& message) {
  return fragg::ros::serializeMarkerArray(message);
}

}  // namespace serialization
}  // namespace ros
