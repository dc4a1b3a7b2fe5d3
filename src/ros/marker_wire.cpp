// Markers in roscpp's wire layout: serialised once, points and colours written in place.
#include "fragg_map/ros/marker_wire.h"

#include <utility>

#include "fragg_map/errors.h"

namespace fragg::ros {
namespace {

std::shared_ptr<WireMarker> allocate(uint32_t size, std::shared_ptr<WireMarker> reuse = nullptr) {
  if (reuse && reuse.use_count() == 1 && reuse->capacity >= size) {
    reuse->size = size;
    return reuse;
  }
  auto out = std::make_shared<WireMarker>();
  // Room to grow by an eighth (a chunk's cells change a little from update to update).
  const uint32_t capacity = size + size / 8;
  out->bytes.reset(new uint8_t[capacity]);  // every byte is written before it is read
  out->size = size;
  out->capacity = capacity;
  return out;
}

}  // namespace

WireMarkerPtr wireOf(const visualization_msgs::Marker& marker) {
  const uint32_t size = ::ros::serialization::serializationLength(marker);
  std::shared_ptr<WireMarker> out = allocate(size);
  ::ros::serialization::OStream stream(out->bytes.get(), size);
  ::ros::serialization::serialize(stream, marker);
  return out;
}

CubeListWriter::CubeListWriter(const visualization_msgs::Marker& head, uint32_t points,
                               std::shared_ptr<WireMarker> reuse, bool with_colors) {
  if (!head.points.empty() || !head.colors.empty())
    throw fragg::InvalidArgument("CubeListWriter: the head marker must have no points or colours");
  // Marker's fields after colors: text and mesh_resource (strings: a uint32 length and the
  // bytes), mesh_use_embedded_materials (uint8). Before them, points and colors serialise
  // as a uint32 count each (0 here): the head's bytes are prefix | 0 | 0 | tail.
  const uint32_t head_size = ::ros::serialization::serializationLength(head);
  const uint32_t tail =
      static_cast<uint32_t>(4 + head.text.size() + 4 + head.mesh_resource.size() + 1);
  const uint32_t prefix = head_size - 8 - tail;
  const uint32_t colors = with_colors ? points : 0;
  const uint32_t size = head_size + points * 24 + colors * 16;
  out_ = allocate(size, std::move(reuse));
  uint8_t* bytes = out_->bytes.get();
  ::ros::serialization::OStream stream(bytes, head_size);
  ::ros::serialization::serialize(stream, head);
  std::memmove(bytes + size - tail, bytes + head_size - tail, tail);
  std::memcpy(bytes + prefix, &points, 4);
  points_ = bytes + prefix + 4;
  std::memcpy(points_ + 24 * size_t{points}, &colors, 4);
  colors_ = with_colors ? points_ + 24 * size_t{points} + 4 : nullptr;
}

std::shared_ptr<WireMarker> CubeListWriter::finish() { return std::move(out_); }

::ros::SerializedMessage serializeMarkerArray(const SerializedMarkerArray& array) {
  ::ros::SerializedMessage m;
  const uint32_t length = ::ros::serialization::serializationLength(array);
  m.num_bytes = size_t{length} + 4;
  m.buf = array.buffers ? array.buffers->take(m.num_bytes).bytes
                        : boost::shared_array<uint8_t>(new uint8_t[m.num_bytes]);
  ::ros::serialization::OStream stream(m.buf.get(), static_cast<uint32_t>(m.num_bytes));
  ::ros::serialization::serialize(stream, length);
  m.message_start = stream.getData();
  ::ros::serialization::serialize(stream, array);
  return m;
}

visualization_msgs::MarkerArray toMarkerArray(const SerializedMarkerArray& wire) {
  const uint32_t size = ::ros::serialization::serializationLength(wire);
  std::vector<uint8_t> bytes(size);
  ::ros::serialization::OStream out(bytes.data(), size);
  ::ros::serialization::serialize(out, wire);
  visualization_msgs::MarkerArray array;
  ::ros::serialization::IStream in(bytes.data(), size);
  ::ros::serialization::deserialize(in, array);
  return array;
}

}  // namespace fragg::ros
