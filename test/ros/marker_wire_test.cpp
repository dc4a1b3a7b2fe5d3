// Markers in roscpp's wire layout (marker_wire.h): the bytes a marker topic sends are exactly
// roscpp's serialisation of the markers built field by field (blockMarker), for height and
// flat colours; kept chunk buffers are written over in place only when nobody else holds them;
// a late subscriber's snapshot from the kept bytes equals one drawn afresh.
#include "fragg_map/ros/marker_wire.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/ros/block_markers.h"
#include "map_fixtures.h"

namespace {

using fragg::ros::MarkerLedger;
using fragg::ros::MarkerStyle;
using fragg::ros::SerializedMarkerArray;
using visualization_msgs::Marker;
using visualization_msgs::MarkerArray;

const ros::Time kStamp(12, 34);

template <typename M>
std::vector<uint8_t> bytesOf(const M& msg) {
  const ros::SerializedMessage m = ros::serialization::serializeMessage(msg);
  return std::vector<uint8_t>(m.buf.get(), m.buf.get() + m.num_bytes);
}

bool byKey(const fragg::BlockKey& a, const fragg::BlockKey& b) {
  return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
}

// What a full set of one-block markers is, built field by field: DELETEALL, then each block
// with drawn cells in key order (ids from 0).
MarkerArray fieldByField(const fragg::Map& map, const MarkerStyle& style) {
  MarkerArray expected;
  Marker all;
  all.header.frame_id = style.frame_id;
  all.header.stamp = kStamp;
  all.ns = style.ns;
  all.id = 0;
  all.type = Marker::CUBE_LIST;
  all.action = Marker::DELETEALL;
  all.pose.orientation.w = 1.0;
  expected.markers.push_back(all);
  const fragg::BlockView blocks = map.blockView();
  std::vector<fragg::BlockRef> refs = blocks.all();
  std::sort(refs.begin(), refs.end(),
            [](const fragg::BlockRef& a, const fragg::BlockRef& b) { return byKey(a.key, b.key); });
  int32_t id = 0;
  for (const fragg::BlockRef& r : refs) {
    const fragg::ros::CellMask cells = fragg::ros::drawnCells(map, blocks, r.key, *r.block, style);
    if (cells.none()) continue;
    expected.markers.push_back(fragg::ros::blockMarker(map, r.key, cells, style, kStamp, id++));
  }
  return expected;
}

void expectSameBytesAsFieldByField(const MarkerStyle& style) {
  fragg::Map map(fragg::ros::test::cpuParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  fragg::ros::test::insertWall(map, Eigen::Vector3d(0.0, 0.7, 0.4), 2.2);
  MarkerLedger ledger;
  const SerializedMarkerArray wire = fragg::ros::allBlockMarkersWire(map, style, kStamp, &ledger);
  const MarkerArray expected = fieldByField(map, style);
  ASSERT_GT(expected.markers.size(), 2u);
  ASSERT_EQ(wire.markers.size(), expected.markers.size());
  EXPECT_EQ(bytesOf(wire), bytesOf(expected));
}

TEST(MarkerWire, BytesEqualRoscppsSerialisationOfTheMarkersHeightColours) {
  MarkerStyle style;
  style.chunk_blocks = 1;
  expectSameBytesAsFieldByField(style);
}

TEST(MarkerWire, BytesEqualRoscppsSerialisationOfTheMarkersFlatColoursFreeCells) {
  MarkerStyle style;
  style.chunk_blocks = 1;
  style.height_colors = false;
  style.flat_rgb[0] = 0.25f;
  style.alpha = 0.5f;
  style.state = fragg::CellState::kFree;
  style.ns = "free";
  style.frame_id = "odom";
  expectSameBytesAsFieldByField(style);
  // Flat: the marker's colour, no per-point colours (24 bytes a cell, not 40).
  fragg::Map map(fragg::ros::test::cpuParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  MarkerLedger flat, coloured;
  const MarkerArray a = fragg::ros::allBlockMarkers(map, style, kStamp, &flat);
  ASSERT_GT(a.markers.size(), 1u);
  size_t cells = 0;
  for (const Marker& m : a.markers) {
    if (m.action != Marker::ADD) continue;
    EXPECT_TRUE(m.colors.empty());
    EXPECT_FLOAT_EQ(m.color.r, 0.25f);
    EXPECT_FLOAT_EQ(m.color.a, 0.5f);
    cells += m.points.size();
  }
  style.height_colors = true;
  const SerializedMarkerArray with_colours =
      fragg::ros::allBlockMarkersWire(map, style, kStamp, &coloured);
  style.height_colors = false;
  const SerializedMarkerArray without = fragg::ros::allBlockMarkersWire(map, style, kStamp, &flat);
  EXPECT_EQ(bytesOf(with_colours).size() - bytesOf(without).size(), 16 * cells);
}

TEST(MarkerWire, CubeListWriterRefusesAHeadWithPoints) {
  Marker head;
  head.points.resize(1);
  EXPECT_THROW(fragg::ros::CubeListWriter(head, 3), fragg::InvalidArgument);
}

TEST(MarkerWire, KeptBufferWrittenOverOnlyWhenNobodyElseHoldsIt) {
  Marker head;
  head.type = Marker::CUBE_LIST;
  const float red[4] = {1.f, 0.f, 0.f, 1.f};
  fragg::ros::CubeListWriter first(head, 4);
  for (uint32_t i = 0; i < 4; ++i) {
    first.setPoint(i, i, 0.0, 0.0);
    first.setColor(i, red);
  }
  std::shared_ptr<fragg::ros::WireMarker> kept = first.finish();
  const uint8_t* buffer = kept->bytes.get();
  // Held by a message being sent: a new buffer, the held bytes untouched.
  fragg::ros::WireMarkerPtr held = kept;
  const std::vector<uint8_t> held_bytes(held->bytes.get(), held->bytes.get() + held->size);
  fragg::ros::CubeListWriter second(head, 3, kept);
  for (uint32_t i = 0; i < 3; ++i) {
    second.setPoint(i, 9.0, 9.0, 9.0);
    second.setColor(i, red);
  }
  std::shared_ptr<fragg::ros::WireMarker> other = second.finish();
  EXPECT_NE(other->bytes.get(), buffer);
  EXPECT_EQ(std::vector<uint8_t>(held->bytes.get(), held->bytes.get() + held->size), held_bytes);
  // Sent and let go: nobody else holds it, so it is written over in place and decodes to the
  // new points.
  held.reset();
  fragg::ros::CubeListWriter third(head, 2, std::move(kept));
  third.setPoint(0, 5.0, 6.0, 7.0);
  third.setColor(0, red);
  third.setPoint(1, -1.0, -2.0, -3.0);
  third.setColor(1, red);
  SerializedMarkerArray array;
  array.stamp = kStamp;
  array.markers.push_back(third.finish());
  EXPECT_EQ(array.markers[0]->bytes.get(), buffer);
  const MarkerArray decoded = fragg::ros::toMarkerArray(array);
  ASSERT_EQ(decoded.markers.size(), 1u);
  ASSERT_EQ(decoded.markers[0].points.size(), 2u);
  ASSERT_EQ(decoded.markers[0].colors.size(), 2u);
  EXPECT_EQ(decoded.markers[0].points[1].z, -3.0);
  EXPECT_EQ(decoded.markers[0].colors[1].r, 1.f);
  EXPECT_EQ(decoded.markers[0].header.stamp, kStamp);
}

TEST(MarkerWire, SnapshotFromKeptBytesEqualsOneDrawnAfresh) {
  // After increments, the late subscriber's snapshot (kept chunk bytes) equals a full rebuild's
  // markers by chunk (same ids are not required of a rebuild: compare as id-free sets).
  fragg::Map map(fragg::ros::test::cpuParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  MarkerStyle style;
  style.chunk_blocks = 2;
  MarkerLedger topic;
  (void)fragg::ros::changedBlockMarkersWire(map, style, kStamp, &topic);
  fragg::ros::test::insertWall(map, Eigen::Vector3d(0.3, -0.5, 0.2), 2.4);
  (void)fragg::ros::changedBlockMarkersWire(map, style, kStamp, &topic);
  const MarkerArray snapshot = fragg::ros::shownBlockMarkers(map, style, kStamp, topic);
  MarkerLedger fresh;
  const MarkerArray rebuilt = fragg::ros::allBlockMarkers(map, style, kStamp, &fresh);
  auto withoutIds = [](MarkerArray a) {
    std::vector<std::vector<uint8_t>> out;
    for (Marker& m : a.markers) {
      m.id = 0;
      out.push_back(bytesOf(m));
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  ASSERT_GT(snapshot.markers.size(), 2u);
  EXPECT_EQ(withoutIds(snapshot), withoutIds(rebuilt));
}

}  // namespace

// A marker topic's updates are serialised into its kept buffers: the bytes are roscpp's
// serialisation of the markers, a buffer roscpp still holds is never written again, and one it
// let go of serves the next update (its pages are resident).
TEST(MarkerWire, UpdatesSerialiseIntoKeptBuffersNobodyElseHolds) {
  fragg::Map map(fragg::ros::test::cpuParams());
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  MarkerStyle style;
  MarkerLedger ledger;
  const SerializedMarkerArray update =
      fragg::ros::changedBlockMarkersWire(map, style, kStamp, &ledger);
  ASSERT_GT(update.markers.size(), 1u);
  ASSERT_NE(update.buffers, nullptr);
  const MarkerArray decoded = fragg::ros::toMarkerArray(update);
  const std::vector<uint8_t> expected = bytesOf(decoded);
  const ros::SerializedMessage held = ros::serialization::serializeMessage(update);
  ASSERT_EQ(held.num_bytes, expected.size());
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(), held.buf.get()));
  EXPECT_EQ(held.message_start, held.buf.get() + 4);
  const uint8_t* let_go = nullptr;
  {
    const ros::SerializedMessage next = ros::serialization::serializeMessage(update);
    EXPECT_NE(next.buf.get(), held.buf.get()) << "a held buffer was handed out again";
    let_go = next.buf.get();
  }
  const ros::SerializedMessage again = ros::serialization::serializeMessage(update);
  EXPECT_EQ(again.buf.get(), let_go) << "a buffer nobody holds was not reused";
  EXPECT_TRUE(std::equal(expected.begin(), expected.end(), held.buf.get()))
      << "a held message was written over";
  // Without buffers (a full set): a buffer of its own, the same bytes.
  SerializedMarkerArray own = update;
  own.buffers = nullptr;
  EXPECT_EQ(bytesOf(own), expected);
}

TEST(WireBufferPool, TakesTheSmallestFreeBufferGrowsOneOrMakesItsOwn) {
  fragg::ros::WireBufferPool pool;
  fragg::ros::WireBuffer a = pool.take(1000);
  EXPECT_GE(a.capacity, 1000u);
  fragg::ros::WireBuffer b = pool.take(100);  // a is held
  EXPECT_NE(b.bytes.get(), a.bytes.get());
  const uint8_t* small = b.bytes.get();
  b = fragg::ros::WireBuffer();
  EXPECT_EQ(pool.take(50).bytes.get(), small) << "the smallest free buffer that fits";
  // Larger than any free one: the free one is made anew, larger.
  const size_t kept = pool.keptBytes();
  const size_t larger = fragg::ros::WireBufferPool::kMinCapacity + 1;  // address space only
  fragg::ros::WireBuffer big = pool.take(larger);
  EXPECT_GE(big.capacity, larger);
  EXPECT_GT(pool.keptBytes(), kept);
  // Every kept buffer held: a buffer of its own, not kept.
  std::vector<fragg::ros::WireBuffer> held = {std::move(a), std::move(big)};
  while (held.size() < fragg::ros::WireBufferPool::kKept) held.push_back(pool.take(10));
  const size_t all_kept = pool.keptBytes();
  const fragg::ros::WireBuffer extra = pool.take(10);
  for (const fragg::ros::WireBuffer& h : held) EXPECT_NE(extra.bytes.get(), h.bytes.get());
  EXPECT_EQ(pool.keptBytes(), all_kept);
}
