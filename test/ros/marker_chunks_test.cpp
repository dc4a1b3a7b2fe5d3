// Incremental chunk markers (block_markers.h with chunk_blocks > 1, as the server sends them):
// after a sequence of insertions and edits (clear box, free box, cells set by hand, a block
// emptied), the updates applied in order show exactly what a full rebuild shows (the same
// cells in the same colours, one marker per chunk), chunks that empty are DELETEd, an update
// carries only the chunks that changed, and a late subscriber's snapshot (shownBlockMarkers)
// followed by the next increments shows the same. Also with hidden speckles and a height band.
// Paced (pacedBlockMarkersWire, the server's paced_outputs): the changes are taken in once a
// period and each call sends a share of their chunks; two periods after the last change the
// subscribers (and one that joined in between) see what a full rebuild shows; the taking-in
// only lists the changed blocks, which are drawn when their chunk is sent.
#include <gtest/gtest.h>

#include <algorithm>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <tuple>

#include "fragg_map/ros/block_markers.h"
#include "map_fixtures.h"

namespace {

using fragg::ros::MarkerLedger;
using fragg::ros::MarkerStyle;
using visualization_msgs::Marker;
using visualization_msgs::MarkerArray;

const ros::Time kStamp(12, 34);

// A drawn cell: voxel key and colour (to 1/1000).
using Drawn = std::tuple<int32_t, int32_t, int32_t, int, int, int, int>;
// What rviz shows after applying marker arrays in order: each marker id's cells.
using View = std::map<int32_t, std::vector<Drawn>>;

void apply(const fragg::Map& map, const MarkerArray& a, View* view) {
  for (const Marker& m : a.markers) {
    if (m.action == Marker::DELETEALL) {
      view->clear();
    } else if (m.action == Marker::DELETE) {
      EXPECT_EQ(view->erase(m.id), 1u) << "DELETE of a marker that is not shown";
    } else {
      ASSERT_EQ(m.action, Marker::ADD);
      ASSERT_EQ(m.type, Marker::CUBE_LIST);
      // Per-point colours, or none: the marker's colour draws every cube (flat markers).
      ASSERT_TRUE(m.colors.empty() || m.points.size() == m.colors.size());
      ASSERT_FALSE(m.points.empty()) << "an ADD of an empty chunk";
      std::vector<Drawn>& cells = (*view)[m.id];
      cells.clear();
      for (size_t i = 0; i < m.points.size(); ++i) {
        const auto& p = m.points[i];
        const fragg::VoxelKey v = map.keyOf(Eigen::Vector3d(p.x, p.y, p.z));
        const auto& c = m.colors.empty() ? m.color : m.colors[i];
        auto q = [](float x) { return static_cast<int>(std::lround(x * 1000.0f)); };
        cells.emplace_back(v.x, v.y, v.z, q(c.r), q(c.g), q(c.b), q(c.a));
      }
    }
  }
}

std::multiset<Drawn> allDrawn(const View& view) {
  std::multiset<Drawn> all;
  for (const auto& [id, cells] : view) all.insert(cells.begin(), cells.end());
  return all;
}

// The map after edit step `step` of the sequence (each step changes it).
void edit(fragg::Map& map, int step) {
  using fragg::ros::test::insertWall;
  using fragg::ros::test::setCell;
  switch (step) {
    case 0:
      insertWall(map, Eigen::Vector3d::Zero(), 3.0);
      break;
    case 1:
      insertWall(map, Eigen::Vector3d(0.0, 1.5, 0.3), 3.0);  // overlaps the first
      break;
    case 2:
      setCell(map, {40, -17, 5}, fragg::CellState::kOccupied);  // a lone cell, negative keys
      setCell(map, {41, -17, 5}, fragg::CellState::kOccupied);
      break;
    case 3:
      insertWall(map, Eigen::Vector3d(-2.0, 0.0, 0.0), 5.5);  // the wall from farther away
      break;
    case 4:
      map.clearBox(Eigen::Vector3d(2.5, -0.5, -0.5), Eigen::Vector3d(3.5, 0.5, 0.5));
      break;
    case 5:
      setCell(map, {40, -17, 5}, fragg::CellState::kFree);  // its chunk keeps the other
      break;
    case 6:
      setCell(map, {41, -17, 5}, fragg::CellState::kFree);  // ... now empties
      break;
    case 7:
      map.freeBox(Eigen::Vector3d(2.5, 1.0, -1.0), Eigen::Vector3d(3.5, 2.0, 1.0));
      break;
    default:
      insertWall(map, Eigen::Vector3d(0.0, -3.0, 0.0), 2.0 + 0.5 * step);
  }
}

/// `mirror`: the topic reads the map through a mask mirror (MarkerLedger::useMirror).
void expectIncrementsEqualRebuild(MarkerStyle style, bool mirror = false) {
  fragg::Map map(fragg::ros::test::cpuParams());
  MarkerLedger topic, late;
  if (mirror) topic.useMirror(std::make_shared<fragg::ros::MaskMirror>());
  View view, late_view;
  for (int step = 0; step < 10; ++step) {
    SCOPED_TRACE("after edit " + std::to_string(step));
    edit(map, step);
    const MarkerArray update = fragg::ros::changedBlockMarkers(map, style, kStamp, &topic);
    apply(map, update, &view);
    // No entry for a chunk twice, and fewer entries than chunks shown plus deleted.
    std::set<int32_t> ids;
    for (const Marker& m : update.markers) EXPECT_TRUE(ids.insert(m.id).second);
    MarkerLedger rebuilt;
    View full;
    apply(map, fragg::ros::allBlockMarkers(map, style, kStamp, &rebuilt), &full);
    {
      const auto a = allDrawn(view), b = allDrawn(full);
      std::vector<Drawn> only_inc, only_full;
      std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(only_inc));
      std::set_difference(b.begin(), b.end(), a.begin(), a.end(), std::back_inserter(only_full));
      EXPECT_TRUE(only_inc.empty() && only_full.empty())
          << only_inc.size() << " cells only in the increments, " << only_full.size()
          << " only in the rebuild"
          << (only_inc.empty() ? std::string()
                               : " e.g. " + std::to_string(std::get<0>(only_inc[0])) + "," +
                                     std::to_string(std::get<1>(only_inc[0])) + "," +
                                     std::to_string(std::get<2>(only_inc[0])));
    }
    EXPECT_EQ(view.size(), full.size()) << "one marker per chunk";
    EXPECT_EQ(topic.shownBlocks(), rebuilt.shownBlocks());
    EXPECT_EQ(topic.shownChunks(), rebuilt.shownChunks());
    if (step == 4) {
      // A subscriber joining now: the snapshot, then the topic's next increments.
      apply(map, fragg::ros::shownBlockMarkers(map, style, kStamp, topic), &late_view);
      EXPECT_EQ(allDrawn(late_view), allDrawn(full));
    } else if (step > 4) {
      apply(map, update, &late_view);
      EXPECT_EQ(allDrawn(late_view), allDrawn(full));
    }
  }
  EXPECT_FALSE(view.empty());
}

TEST(MarkerChunks, IncrementsEqualAFullRebuildAfterInsertionsAndEdits) {
  MarkerStyle style;
  style.chunk_blocks = 4;
  expectIncrementsEqualRebuild(style);
}

TEST(MarkerChunks, PerBlockAndChunkOfTwoToo) {
  for (int chunk : {1, 2}) {
    MarkerStyle style;
    style.chunk_blocks = chunk;
    SCOPED_TRACE("chunk_blocks " + std::to_string(chunk));
    expectIncrementsEqualRebuild(style);
  }
}

TEST(MarkerChunks, HiddenSpecklesAndAHeightBandToo) {
  MarkerStyle style;
  style.chunk_blocks = 4;
  style.hide_speckles = true;
  style.heights = {-0.45, 0.65};
  expectIncrementsEqualRebuild(style);
}

TEST(MarkerChunks, FlatColoursWithoutPerPointColoursToo) {
  MarkerStyle style;
  style.chunk_blocks = 4;
  style.height_colors = false;  // octomap_server's height_map false
  style.flat_rgb[1] = 0.5f;
  expectIncrementsEqualRebuild(style);
}

TEST(MarkerChunks, FreeCellsToo) {
  MarkerStyle style;
  style.chunk_blocks = 4;
  style.state = fragg::CellState::kFree;
  style.ns = "free";
  expectIncrementsEqualRebuild(style);
}

TEST(MarkerChunks, AnUpdateCarriesOnlyTheChunksThatChangedAndDeletesEmptiedOnes) {
  fragg::Map map(fragg::ros::test::cpuParams());
  MarkerStyle style;
  style.chunk_blocks = 4;
  MarkerLedger topic;
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  const MarkerArray first = fragg::ros::changedBlockMarkers(map, style, kStamp, &topic);
  const size_t wall_chunks = topic.shownChunks();
  ASSERT_GT(wall_chunks, 1u);
  EXPECT_EQ(first.markers.size(), wall_chunks);
  EXPECT_LT(wall_chunks, topic.shownBlocks()) << "chunks hold several blocks";
  // One lone cell far away: one new chunk, the wall's chunks not resent.
  const fragg::VoxelKey lone{200, 200, 3};
  fragg::ros::test::setCell(map, lone, fragg::CellState::kOccupied);
  const MarkerArray add = fragg::ros::changedBlockMarkers(map, style, kStamp, &topic);
  ASSERT_EQ(add.markers.size(), 1u);
  EXPECT_EQ(add.markers[0].action, Marker::ADD);
  EXPECT_EQ(add.markers[0].points.size(), 1u);
  const int32_t id = topic.idOf(fragg::blockKeyOf(lone));
  EXPECT_EQ(add.markers[0].id, id);
  // Nothing changed: nothing sent.
  EXPECT_TRUE(fragg::ros::changedBlockMarkers(map, style, kStamp, &topic).markers.empty());
  // The lone cell freed: its chunk is deleted.
  fragg::ros::test::setCell(map, lone, fragg::CellState::kFree);
  const MarkerArray del = fragg::ros::changedBlockMarkers(map, style, kStamp, &topic);
  ASSERT_EQ(del.markers.size(), 1u);
  EXPECT_EQ(del.markers[0].action, Marker::DELETE);
  EXPECT_EQ(del.markers[0].id, id);
  EXPECT_EQ(topic.idOf(fragg::blockKeyOf(lone)), -1);
  EXPECT_EQ(topic.shownChunks(), wall_chunks);
}

// Clouds every 1/8 s, markers at 1 Hz, paced: the changes taken in once a period go out in
// shares over the next period's calls (not all at once), none waits longer than two periods,
// and once the map stops changing the view (and a late subscriber's) equals a full rebuild.
/// `follows` (with `mirror`): as the server that brings the mirror up to date between clouds,
/// each call reads it one edit behind (MaskMirror::acceptLag) and a sync follows it.
/// `between` (with `follows`): as the server with shares_between_clouds, each call's share is
/// built between clouds (right after the sync) and sent by the next call.
void expectPacedReachesRebuild(MarkerStyle style, bool mirror = false, bool follows = false,
                               bool between = false) {
  fragg::Map map(fragg::ros::test::cpuParams());
  std::optional<fragg::ros::SerializedMarkerArray> prepared;
  MarkerLedger topic;
  const auto masks = std::make_shared<fragg::ros::MaskMirror>();
  if (mirror) topic.useMirror(masks);
  View view, late_view;
  constexpr double kPeriodS = 1.0, kIntervalS = 0.125;  // exact in binary
  size_t lagged = 0;  // calls that read the mirror one edit behind
  const auto paced = [&](double now_s) {
    if (follows) masks->acceptLag(1);
    MarkerArray out;
    if (prepared) {
      out = fragg::ros::toMarkerArray(*prepared);
      prepared.reset();
    } else {
      out = fragg::ros::toMarkerArray(
          fragg::ros::pacedBlockMarkersWire(map, style, kStamp, now_s, kPeriodS, &topic));
    }
    if (follows) {
      lagged += masks->valid() && masks->revision() + 1 == map.revision();
      masks->acceptLag(0);
      (void)masks->sync(map);  // between clouds
    }
    // The next call's share, from the mirror as just synced (a little later than this call).
    if (between)
      prepared = fragg::ros::pacedBlockMarkersWire(map, style, kStamp, now_s + kIntervalS / 4,
                                                   kPeriodS, &topic);
    return out;
  };
  bool shared = false;  // some call left chunks queued for later calls
  double now_s = 0.0;
  for (int step = 0; step < 10; ++step, now_s += kIntervalS) {
    SCOPED_TRACE("after edit " + std::to_string(step));
    edit(map, step);
    const MarkerArray update = paced(now_s);
    apply(map, update, &view);
    if (step > 0 && topic.pendingChunks() > 0) shared = true;
    if (step > 3) apply(map, update, &late_view);
    if (step == 3) {
      // A subscriber joining while chunks are queued: the chunks as last sent, then the
      // increments (the queued ones among them).
      apply(map, fragg::ros::shownBlockMarkers(map, style, kStamp, topic), &late_view);
      // (Between clouds the ledger holds the next call's share already, which the others
      // receive with that call.)
      if (!between) {
        EXPECT_EQ(allDrawn(late_view), allDrawn(view));
      }
    }
  }
  EXPECT_TRUE(shared) << "every call sent everything: not paced";
  // No more changes: two periods after the last one every chunk has gone out.
  const double last_change_s = now_s - kIntervalS;
  for (; now_s <= last_change_s + 2 * kPeriodS; now_s += kIntervalS) {
    const MarkerArray update = paced(now_s);
    apply(map, update, &view);
    apply(map, update, &late_view);
  }
  EXPECT_EQ(topic.pendingChunks(), 0u) << "a chunk waited longer than two periods";
  MarkerLedger rebuilt;
  View full;
  apply(map, fragg::ros::allBlockMarkers(map, style, kStamp, &rebuilt), &full);
  EXPECT_EQ(allDrawn(view), allDrawn(full));
  EXPECT_EQ(allDrawn(late_view), allDrawn(full));
  EXPECT_EQ(view.size(), full.size()) << "one marker per chunk";
  EXPECT_EQ(topic.shownChunks(), rebuilt.shownChunks());
  EXPECT_TRUE(paced(now_s).markers.empty()) << "nothing left to send";
  if (follows) {
    EXPECT_GE(lagged, 5u) << "the mirror was synced on the calls' path: not tested";
  }
}

TEST(MarkerChunks, PacedSharesEqualAFullRebuildTwoPeriodsAfterTheLastChange) {
  MarkerStyle style;
  style.chunk_blocks = 1;  // many markers an edit: shares of them
  expectPacedReachesRebuild(style);
  style.chunk_blocks = 2;
  style.hide_speckles = true;
  style.heights = {-0.45, 0.65};
  expectPacedReachesRebuild(style);
}

// Read through a mask mirror (the server's way on a CUDA map: the changed blocks' masks, no
// write-back), the increments show the same: occupied and free cells, chunks of several sizes,
// hidden speckles (their neighbours from the mirror's masks) and a height band, paced or not.
TEST(MarkerChunks, ThroughAMaskMirrorToo) {
  for (int chunk : {1, 4}) {
    MarkerStyle style;
    style.chunk_blocks = chunk;
    SCOPED_TRACE("chunk_blocks " + std::to_string(chunk));
    expectIncrementsEqualRebuild(style, true);
  }
  MarkerStyle style;
  style.chunk_blocks = 4;
  style.hide_speckles = true;
  style.heights = {-0.45, 0.65};
  expectIncrementsEqualRebuild(style, true);
  MarkerStyle free_cells;
  free_cells.chunk_blocks = 4;
  free_cells.state = fragg::CellState::kFree;
  free_cells.ns = "free";
  expectIncrementsEqualRebuild(free_cells, true);
  style.chunk_blocks = 2;
  expectPacedReachesRebuild(style, true);
  expectPacedReachesRebuild(style, true, true);
  style.chunk_blocks = 1;
  style.hide_speckles = false;
  expectPacedReachesRebuild(style, true);
  expectPacedReachesRebuild(style, true, true);
  expectPacedReachesRebuild(style, true, true, true);
  style.chunk_blocks = 2;
  style.hide_speckles = true;
  expectPacedReachesRebuild(style, true, true, true);
}

// A full set of the empty map (a subscriber connected at start-up) starts the ledger at revision
// 0: the first clouds' changes then come as paced increments (taken in, sent in shares), which
// reach a full rebuild; a ledger no full set started is not started.
TEST(MarkerChunks, AFullSetOfTheEmptyMapStartsTheIncrements) {
  fragg::Map map(fragg::ros::test::cpuParams());
  MarkerStyle style;
  style.chunk_blocks = 1;
  MarkerLedger topic;
  EXPECT_FALSE(topic.started());
  View view;
  apply(map, fragg::ros::toMarkerArray(fragg::ros::allBlockMarkersWire(map, style, kStamp, &topic)),
        &view);
  EXPECT_TRUE(topic.started());
  EXPECT_EQ(topic.publishedRevision(), 0u);
  EXPECT_TRUE(view.empty());
  constexpr double kPeriodS = 1.0, kIntervalS = 0.125;  // exact in binary
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  double now_s = 0.0;
  const MarkerArray taken_in = fragg::ros::toMarkerArray(
      fragg::ros::pacedBlockMarkersWire(map, style, kStamp, now_s, kPeriodS, &topic));
  EXPECT_TRUE(taken_in.markers.empty()) << "the first cloud's markers all at once";
  EXPECT_GT(topic.pendingChunks(), 2u);
  for (now_s += kIntervalS; now_s < 2 * kPeriodS; now_s += kIntervalS)
    apply(map,
          fragg::ros::toMarkerArray(
              fragg::ros::pacedBlockMarkersWire(map, style, kStamp, now_s, kPeriodS, &topic)),
          &view);
  EXPECT_EQ(topic.pendingChunks(), 0u);
  MarkerLedger rebuilt;
  View full;
  apply(map, fragg::ros::allBlockMarkers(map, style, kStamp, &rebuilt), &full);
  EXPECT_FALSE(full.empty());
  EXPECT_EQ(allDrawn(view), allDrawn(full));
}

// A mirror handed to a ledger in the middle of a period (chunks listed from the map's view and
// still queued): the next share syncs it first, so no queued block is taken for gone.
TEST(MarkerChunks, AMirrorHandedOverMidPeriodLosesNoQueuedChunk) {
  fragg::Map map(fragg::ros::test::cpuParams());
  MarkerStyle style;
  style.chunk_blocks = 1;
  MarkerLedger topic;
  View view;
  constexpr double kPeriodS = 1.0, kIntervalS = 0.125;  // exact in binary
  const auto paced = [&](double now_s) {
    apply(map,
          fragg::ros::toMarkerArray(
              fragg::ros::pacedBlockMarkersWire(map, style, kStamp, now_s, kPeriodS, &topic)),
          &view);
  };
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  paced(0.0);  // the taking-in: every chunk queued
  paced(kIntervalS);
  ASSERT_GT(topic.pendingChunks(), 2u);
  topic.useMirror(std::make_shared<fragg::ros::MaskMirror>());
  for (double now_s = 2 * kIntervalS; now_s < 2 * kPeriodS; now_s += kIntervalS) paced(now_s);
  EXPECT_EQ(topic.pendingChunks(), 0u);
  MarkerLedger rebuilt;
  View full;
  apply(map, fragg::ros::allBlockMarkers(map, style, kStamp, &rebuilt), &full);
  EXPECT_EQ(allDrawn(view), allDrawn(full));
  EXPECT_EQ(topic.shownBlocks(), rebuilt.shownBlocks());
}

// Paced, the taking-in lists the changed blocks by chunk and draws none of them: each chunk's
// blocks are drawn when it is sent (the work comes in the shares, not on one cloud), and a
// chunk whose drawn cells did not change (a cell above the height band turned occupied) is not
// sent at all.
TEST(MarkerChunks, PacedTakingInListsAndTheSharesDraw) {
  fragg::Map map(fragg::ros::test::cpuParams());
  MarkerStyle style;
  style.chunk_blocks = 1;
  style.heights = {-0.45, 0.65};
  MarkerLedger topic;
  constexpr double kPeriodS = 1.0, kIntervalS = 0.125;  // exact in binary
  const auto paced = [&](double now_s) {
    return fragg::ros::toMarkerArray(
        fragg::ros::pacedBlockMarkersWire(map, style, kStamp, now_s, kPeriodS, &topic));
  };
  fragg::ros::test::insertWall(map, Eigen::Vector3d::Zero(), 3.0);
  fragg::ros::test::setCell(map, {200, 200, 0}, fragg::CellState::kOccupied);
  EXPECT_TRUE(paced(0.0).markers.empty()) << "the taking-in sent chunks";
  ASSERT_GT(topic.pendingChunks(), 1u);
  EXPECT_EQ(topic.shownBlocks(), 0u) << "the taking-in drew blocks";
  View view;
  size_t sends = 0;
  double now_s = kIntervalS;
  for (; now_s < kPeriodS; now_s += kIntervalS) {
    const MarkerArray share = paced(now_s);
    sends += !share.markers.empty();
    apply(map, share, &view);
  }
  EXPECT_EQ(topic.pendingChunks(), 0u);
  EXPECT_GE(sends, 2u) << "not sent in shares";
  MarkerLedger rebuilt;
  View full;
  apply(map, fragg::ros::allBlockMarkers(map, style, kStamp, &rebuilt), &full);
  EXPECT_EQ(allDrawn(view), allDrawn(full));
  EXPECT_EQ(topic.shownBlocks(), rebuilt.shownBlocks());
  // Above the band, in the lone cell's block: the block is listed, draws the same, goes nowhere.
  fragg::ros::test::setCell(map, {200, 200, 7}, fragg::CellState::kOccupied);
  EXPECT_TRUE(paced(now_s).markers.empty());
  EXPECT_EQ(topic.pendingChunks(), 1u);
  for (now_s += kIntervalS; now_s < 2 * kPeriodS; now_s += kIntervalS)
    EXPECT_TRUE(paced(now_s).markers.empty()) << "an unchanged chunk was sent";
  EXPECT_EQ(topic.pendingChunks(), 0u);
}

TEST(MarkerChunks, ChunkKeysFloorNegativeBlocks) {
  EXPECT_EQ(fragg::ros::chunkOf({-1, -4, -5}, 4), (fragg::BlockKey{-1, -1, -2}));
  EXPECT_EQ(fragg::ros::chunkOf({3, 4, 0}, 4), (fragg::BlockKey{0, 1, 0}));
  EXPECT_EQ(fragg::ros::chunkOf({-7, 7, 9}, 1), (fragg::BlockKey{-7, 7, 9}));
}

}  // namespace
