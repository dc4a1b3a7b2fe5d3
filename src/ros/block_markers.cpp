// One CUBE_LIST marker per chunk of blocks; incremental updates from the state masks and the
// changed-block lists.
#include "fragg_map/ros/block_markers.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <unordered_set>
#include <vector>

#include "fragg_map/ros/height_color.h"
#include "fragg_map/ros/layer_masks.h"
#include "fragg_map/ros/marker_wire.h"
#include "fragg_map/ros/speckles.h"
#include "fragg_map/state_masks.h"

namespace fragg::ros {
namespace {

visualization_msgs::Marker markerHeader(const MarkerStyle& style, const ::ros::Time& stamp,
                                        int32_t id, int32_t action) {
  visualization_msgs::Marker m;
  m.header.frame_id = style.frame_id;
  m.header.stamp = stamp;
  m.ns = style.ns;
  m.id = id;
  m.type = visualization_msgs::Marker::CUBE_LIST;
  m.action = action;
  m.pose.orientation.w = 1.0;
  return m;
}

}  // namespace

static int32_t floorDiv(int32_t a, int32_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

fragg::BlockKey chunkOf(const fragg::BlockKey& key, int32_t chunk_blocks) {
  if (chunk_blocks <= 1) return key;
  return {floorDiv(key.x, chunk_blocks), floorDiv(key.y, chunk_blocks),
          floorDiv(key.z, chunk_blocks)};
}

int32_t MarkerLedger::idOf(const fragg::BlockKey& key) const {
  const auto it = chunks_.find(chunkOf(key, chunk_blocks_));
  if (it == chunks_.end()) return -1;
  for (const ShownBlock& b : it->second.blocks)
    if (b.key == key) return it->second.id;
  return -1;
}

void MarkerLedger::clear(int32_t chunk_blocks) {
  chunks_.clear();
  pending_.clear();
  chunk_blocks_ = std::max(1, chunk_blocks);
  shown_blocks_ = 0;
  next_id_ = 0;
}

CellMask cellMask(const fragg::Map& map, const fragg::Block& block, fragg::CellState state) {
  // One 64-cell word at a time (the hot loop of an incremental update: every changed block is
  // scanned; layer_masks.h). Unobserved cells hold INT16_MIN, below every threshold.
  const fragg::OccupancyModel& model = map.model();
  const fragg::Cell* cells = block.cells;
  CellMask mask;
  for (int w = 0; w < fragg::kCellsPerBlock / 64; ++w) {
    const fragg::Cell* c = cells + 64 * w;
    uint64_t word = 0;
    switch (state) {
      case fragg::CellState::kOccupied:
        word = layerMasks(c, model.occupied_above_fx, model.free_below_fx).occupied;
        break;
      case fragg::CellState::kFree:
        word = layerMasks(c, model.occupied_above_fx, model.free_below_fx).free;
        break;
      default:
        for (int i = 0; i < 64; ++i)
          word |= uint64_t{model.state(c[i]) == fragg::CellState::kUnknown} << i;
    }
    if (word) mask |= CellMask(word) << (64 * w);
  }
  return mask;
}

namespace {

/// `cells` of block `key` within `style`'s heights, speckles left out when it hides them.
template <class View>
CellMask shownCells(const fragg::Map& map, const View& blocks, const fragg::BlockKey& key,
                    CellMask cells, const MarkerStyle& style) {
  if (!style.heights.unbounded()) {
    const uint8_t layers = style.heights.blockLayers(key.z, map.resolution());
    CellMask shown;
    for (int z = 0; z < fragg::kBlockSize; ++z)
      if (layers >> z & 1) shown |= CellMask(~uint64_t{0}) << (64 * z);
    cells &= shown;
  }
  if (style.hide_speckles && cells.any()) cells = withoutSpeckles(map, blocks, key, cells);
  return cells;
}

/// Whether the view holds block `key`.
bool holdsBlock(const fragg::BlockView& blocks, const fragg::BlockKey& key) {
  return blocks.findBlock(key) != nullptr;
}
bool holdsBlock(const MaskMirror& blocks, const fragg::BlockKey& key) {
  return blocks.contains(key);
}

/// drawnCells of block `key` (none when the view does not hold it).
CellMask drawnCellsOf(const fragg::Map& map, const fragg::BlockView& blocks,
                      const fragg::BlockKey& key, const MarkerStyle& style) {
  const fragg::Block* b = blocks.findBlock(key);
  return b ? drawnCells(map, blocks, key, *b, style) : CellMask();
}
/// The same from a mask mirror: every state from the block's masks (unknown: neither).
CellMask drawnCellsOf(const fragg::Map& map, const MaskMirror& blocks, const fragg::BlockKey& key,
                      const MarkerStyle& style) {
  const fragg::BlockStateMasks* masks = blocks.findMasks(key);
  CellMask cells;
  if (!masks) return cells;
  for (int w = 0; w < fragg::kStateMaskWords; ++w) {
    const uint64_t word = style.state == fragg::CellState::kOccupied ? masks->occupied[w]
                          : style.state == fragg::CellState::kFree
                              ? masks->free[w]
                              : ~(masks->occupied[w] | masks->free[w]);
    if (word) cells |= CellMask(word) << (64 * w);
  }
  return shownCells(map, blocks, key, cells, style);
}

}  // namespace

CellMask drawnCells(const fragg::Map& map, const fragg::BlockView& blocks,
                    const fragg::BlockKey& key, const fragg::Block& block,
                    const MarkerStyle& style) {
  // Occupied and free cells from the block's state masks (kept by every write): no cell read.
  CellMask cells;
  const fragg::BlockStateMasks* masks = nullptr;
  if (style.state == fragg::CellState::kOccupied || style.state == fragg::CellState::kFree)
    masks = blocks.findMasks(key);
  if (masks) {
    const uint64_t* words =
        style.state == fragg::CellState::kOccupied ? masks->occupied : masks->free;
    for (int w = 0; w < fragg::kStateMaskWords; ++w)
      if (words[w]) cells |= CellMask(words[w]) << (64 * w);
  } else {
    cells = cellMask(map, block, style.state);
  }
  return shownCells(map, blocks, key, cells, style);
}

namespace {

/// Appends the cells `cells` of block `key` to `m` (points and their colours).
void appendCells(const fragg::Map& map, const fragg::BlockKey& key, const CellMask& cells,
                 const MarkerStyle& style, visualization_msgs::Marker* m) {
  // The caller reserves the marker's points.
  const double res_m = map.resolution();
  // Colours depend on the height only: one per z layer of the block.
  std_msgs::ColorRGBA layer_color[fragg::kBlockSize];
  for (int z = 0; z < fragg::kBlockSize; ++z) {
    if (style.height_colors) {
      layer_color[z] = heightColor((key.z * fragg::kBlockSize + z + 0.5) * res_m,
                                   style.color_min_z_m, style.color_max_z_m, style.alpha);
    } else {
      layer_color[z].r = style.flat_rgb[0];
      layer_color[z].g = style.flat_rgb[1];
      layer_color[z].b = style.flat_rgb[2];
      layer_color[z].a = style.alpha;
    }
  }
  for (int c = 0; c < fragg::kCellsPerBlock; ++c) {
    if (!cells.test(c)) continue;
    const fragg::VoxelKey v = fragg::voxelKeyOf(key, c);
    geometry_msgs::Point p;
    p.x = (v.x + 0.5) * res_m;
    p.y = (v.y + 0.5) * res_m;
    p.z = (v.z + 0.5) * res_m;
    m->points.push_back(p);
    if (!perPointColors(style)) continue;  // the marker's colour
    m->colors.push_back(layer_color[c >> (2 * fragg::kBlockBits)]);
    if (style.colors) {
      if (const std::optional<Rgb8> rgb = style.colors->find(v)) {
        m->colors.back().r = rgb->r / 255.0f;
        m->colors.back().g = rgb->g / 255.0f;
        m->colors.back().b = rgb->b / 255.0f;
      }
    }
  }
}

visualization_msgs::Marker emptyCubeList(const fragg::Map& map, const MarkerStyle& style,
                                         const ::ros::Time& stamp, int32_t id) {
  visualization_msgs::Marker m = markerHeader(style, stamp, id, visualization_msgs::Marker::ADD);
  m.scale.x = m.scale.y = m.scale.z = map.resolution();
  if (perPointColors(style)) {
    m.color = heightColor(0.0, 0.0, 1.0, style.alpha);  // per-point colours win
  } else {
    m.color.r = style.flat_rgb[0];
    m.color.g = style.flat_rgb[1];
    m.color.b = style.flat_rgb[2];
    m.color.a = style.alpha;
  }
  return m;
}

bool byKey(const fragg::BlockKey& a, const fragg::BlockKey& b) {
  return a.x != b.x ? a.x < b.x : a.y != b.y ? a.y < b.y : a.z < b.z;
}

}  // namespace

visualization_msgs::Marker blockMarker(const fragg::Map& map, const fragg::BlockKey& key,
                                       const CellMask& cells, const MarkerStyle& style,
                                       const ::ros::Time& stamp, int32_t id) {
  visualization_msgs::Marker m = emptyCubeList(map, style, stamp, id);
  m.points.reserve(cells.count());
  if (perPointColors(style)) m.colors.reserve(cells.count());
  appendCells(map, key, cells, style, &m);
  return m;
}

namespace {

/// Writes the cells `cells` of block `key` as points first .. of `w` (as appendCells draws
/// them); returns the next point's index.
uint32_t writeCells(const fragg::Map& map, const fragg::BlockKey& key, const CellMask& cells,
                    const MarkerStyle& style, CubeListWriter* w, uint32_t first) {
  const double res_m = map.resolution();
  float layer_rgba[fragg::kBlockSize][4];
  for (int z = 0; z < fragg::kBlockSize; ++z) {
    if (style.height_colors) {
      const std_msgs::ColorRGBA c =
          heightColor((key.z * fragg::kBlockSize + z + 0.5) * res_m, style.color_min_z_m,
                      style.color_max_z_m, style.alpha);
      layer_rgba[z][0] = c.r, layer_rgba[z][1] = c.g, layer_rgba[z][2] = c.b,
      layer_rgba[z][3] = c.a;
    } else {
      for (int k = 0; k < 3; ++k) layer_rgba[z][k] = style.flat_rgb[k];
      layer_rgba[z][3] = style.alpha;
    }
  }
  uint32_t i = first;
  const bool per_point = perPointColors(style);
  for (size_t c = cells._Find_first(); c < cells.size(); c = cells._Find_next(c), ++i) {
    const fragg::VoxelKey v = fragg::voxelKeyOf(key, static_cast<int>(c));
    w->setPoint(i, (v.x + 0.5) * res_m, (v.y + 0.5) * res_m, (v.z + 0.5) * res_m);
    if (!per_point) continue;  // the marker's colour
    const float* rgba = layer_rgba[c >> (2 * fragg::kBlockBits)];
    if (style.colors) {
      if (const std::optional<Rgb8> rgb = style.colors->find(v)) {
        const float own[4] = {rgb->r / 255.0f, rgb->g / 255.0f, rgb->b / 255.0f, rgba[3]};
        w->setColor(i, own);
        continue;
      }
    }
    w->setColor(i, rgba);
  }
  return i;
}

/// The marker of a chunk (its blocks' cells, blocks in key order) in roscpp's wire layout,
/// points and colours written in place.
template <typename Blocks>
std::shared_ptr<WireMarker> chunkWire(const fragg::Map& map, const Blocks& blocks,
                                      const MarkerStyle& style, int32_t id,
                                      std::shared_ptr<WireMarker> reuse = nullptr) {
  std::vector<size_t> order(blocks.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return byKey(blocks[a].key, blocks[b].key); });
  size_t cells = 0;
  for (size_t i = 0; i < blocks.size(); ++i) cells += blocks[i].cells.count();
  CubeListWriter w(emptyCubeList(map, style, ::ros::Time(), id), static_cast<uint32_t>(cells),
                   std::move(reuse), perPointColors(style));
  uint32_t next = 0;
  for (size_t i : order) next = writeCells(map, blocks[i].key, blocks[i].cells, style, &w, next);
  return w.finish();
}

/// Encodes the kept wire of every chunk in `chunks` (in parallel where no colour table is read).
void encodeChunks(const fragg::Map& map, const MarkerStyle& style,
                  const std::vector<MarkerLedger::Chunk*>& chunks) {
  const int64_t n = static_cast<int64_t>(chunks.size());
#pragma omp parallel for schedule(dynamic, 8) if (n > 16 && !style.colors)
  for (int64_t j = 0; j < n; ++j)
    chunks[j]->wire =
        chunkWire(map, chunks[j]->blocks, style, chunks[j]->id, std::move(chunks[j]->wire));
}

}  // namespace

SerializedMarkerArray changedBlockMarkersWire(const fragg::Map& map, const MarkerStyle& style,
                                              const ::ros::Time& stamp, MarkerLedger* ledger) {
  return pacedBlockMarkersWire(map, style, stamp, 0.0, 0.0, ledger);
}

SerializedMarkerArray pacedBlockMarkersWire(const fragg::Map& map, const MarkerStyle& style,
                                            const ::ros::Time& stamp, double now_s, double period_s,
                                            MarkerLedger* ledger) {
  if (std::max(1, style.chunk_blocks) != ledger->chunk_blocks_ && !ledger->chunks_.empty())
    return allBlockMarkersWire(map, style, stamp, ledger);  // a new chunk size: redraw all
  ledger->chunk_blocks_ = std::max(1, style.chunk_blocks);
  const int32_t chunk_blocks = ledger->chunk_blocks_;
  SerializedMarkerArray out;
  out.stamp = stamp;
  out.buffers = ledger->buffers_;
  const uint64_t since = ledger->published_revision_;
  // Paced, the map's changes are taken in once a period (the first call, then a period after
  // the last time) and their chunks sent in even shares over the period's calls; unpaced, at
  // every call and all at once.
  const bool paced = period_s > 0.0;
  const bool note = !paced || !ledger->paced_ || now_s - ledger->last_note_s_ >= period_s - 1e-6;
  // The rest reads `blocks`: the map's view or the ledger's mask mirror (useMirror).
  const auto send = [&](const auto& blocks) -> SerializedMarkerArray {
    // A call that takes the changes in sends what is left of the last ones (nothing, when the
    // shares kept up); the others their share: what is left over the calls left until it is a
    // period old.
    size_t take = ledger->pending_.size();
    if (paced && !note && !ledger->pending_.empty()) {
      const double interval_s = std::clamp(now_s - ledger->last_paced_s_, 1e-6, period_s);
      const double left_s = ledger->pending_.front().since_s + period_s - now_s;
      const double calls_left = std::max(1.0, std::floor(left_s / interval_s + 1e-6));
      take =
          static_cast<size_t>(std::ceil(static_cast<double>(ledger->pending_.size()) / calls_left));
    }
    if (paced) {
      ledger->last_paced_s_ = now_s;
      ledger->paced_ = true;
    }
    // A chunk joins the queue once (a queued chunk is drawn when it is sent: its latest cells).
    const auto queue = [&](const fragg::BlockKey& chunk_key) -> MarkerLedger::Chunk& {
      MarkerLedger::Chunk& chunk = ledger->chunks_[chunk_key];
      if (!chunk.pending) {
        chunk.pending = true;
        ledger->pending_.push_back({chunk_key, now_s});
      }
      return chunk;
    };
    if (note) {
      // Shown blocks that were erased (clearBox, reset, paged out) are not listed as changed: look
      // them up, when the map's view changed since the last update (no erase without that).
      if (map.viewEpoch() != ledger->view_epoch_) {
        std::vector<fragg::BlockKey> emptied;
        for (auto& [chunk_key, chunk] : ledger->chunks_) {
          auto& list = chunk.blocks;
          const size_t before = list.size();
          list.erase(std::remove_if(list.begin(), list.end(),
                                    [&](const MarkerLedger::ShownBlock& b) {
                                      return !holdsBlock(blocks, b.key);
                                    }),
                     list.end());
          if (list.size() != before) {
            ledger->shown_blocks_ -= before - list.size();
            emptied.push_back(chunk_key);
          }
        }
        for (const fragg::BlockKey& chunk_key : emptied) queue(chunk_key).redraw = true;
      }
      // The blocks whose drawn state changed, with their 26 neighbours when speckles are hidden
      // (a cell's speckle state follows its neighbours' occupancy).
      // Occupied markers: the blocks where a cell crossed the occupied threshold (most blocks a
      // scan changes gain free cells only); other states: those whose masks changed, from the
      // change log. Listed by chunk only: their cells are drawn when the chunk is sent.
      std::vector<fragg::BlockKey> changed = blocks.changedSince(
          since, style.state == fragg::CellState::kOccupied ? fragg::BlockChange::kOccupied
                                                            : fragg::BlockChange::kMasks);
      if (style.hide_speckles && !changed.empty()) {
        std::unordered_set<fragg::BlockKey, fragg::BlockKeyHash> around;
        for (const fragg::BlockKey& k : changed)
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) around.insert({k.x + dx, k.y + dy, k.z + dz});
        changed.clear();
        for (const fragg::BlockKey& k : around)
          if (holdsBlock(blocks, k)) changed.push_back(k);
      }
      for (const fragg::BlockKey& k : changed) queue(chunkOf(k, chunk_blocks)).listed.push_back(k);
      // colored_map: blocks whose colours changed are redrawn even with the same cells.
      if (style.colors) {
        for (const fragg::BlockKey& k : style.colors->recoloredSince(ledger->colors_drawn_)) {
          if (!holdsBlock(blocks, k)) continue;
          MarkerLedger::Chunk& chunk = queue(chunkOf(k, chunk_blocks));
          chunk.listed.push_back(k);
          chunk.redraw = true;
        }
      }
      // What was listed: the map's changes up to the revision `blocks` is at (a mirror may be
      // left behind the map: MaskMirror::acceptLag).
      ledger->published_revision_ = revisionOf(map, blocks);
      ledger->view_epoch_ = map.viewEpoch();
      if (style.colors) ledger->colors_drawn_ = style.colors->sequence();
      if (paced) ledger->last_note_s_ = now_s;
    }
    if (!paced) take = ledger->pending_.size();
    // The chunks sent now, in key order.
    std::vector<fragg::BlockKey> order;
    order.reserve(take);
    for (size_t q = 0; q < take; ++q) {
      order.push_back(ledger->pending_.front().chunk);
      ledger->pending_.pop_front();
    }
    std::sort(order.begin(), order.end(), byKey);
    // Their listed blocks' drawn cells, in parallel (read-only; a block that left the map draws
    // nothing), then the ledger in order.
    struct Listed {
      MarkerLedger::Chunk* chunk;
      fragg::BlockKey key;
    };
    std::vector<MarkerLedger::Chunk*> sent;
    sent.reserve(order.size());
    std::vector<Listed> listed;
    for (const fragg::BlockKey& chunk_key : order) {
      MarkerLedger::Chunk& chunk = ledger->chunks_.at(chunk_key);
      sent.push_back(&chunk);
      std::sort(chunk.listed.begin(), chunk.listed.end(), byKey);
      chunk.listed.erase(std::unique(chunk.listed.begin(), chunk.listed.end()), chunk.listed.end());
      for (const fragg::BlockKey& k : chunk.listed) listed.push_back({&chunk, k});
    }
    std::vector<CellMask> masks(listed.size());
    const int64_t n = static_cast<int64_t>(listed.size());
#pragma omp parallel for schedule(static) if (n > 256)
    for (int64_t j = 0; j < n; ++j) {
      masks[j] = drawnCellsOf(map, blocks, listed[j].key, style);
    }
    for (size_t j = 0; j < listed.size(); ++j) {
      MarkerLedger::Chunk& chunk = *listed[j].chunk;
      const fragg::BlockKey& key = listed[j].key;
      const CellMask& cells = masks[j];
      auto& list = chunk.blocks;
      const auto shown =
          std::find_if(list.begin(), list.end(),
                       [&](const MarkerLedger::ShownBlock& b) { return b.key == key; });
      if (shown == list.end()) {
        if (cells.none()) continue;
        list.push_back({key, cells});
        ++ledger->shown_blocks_;
        chunk.redraw = true;
      } else if (cells.none()) {
        list.erase(shown);
        --ledger->shown_blocks_;
        chunk.redraw = true;
      } else if (cells != shown->cells) {
        shown->cells = cells;
        chunk.redraw = true;
      }
    }
    // One entry per chunk whose drawing changed: its whole marker (encoded again and kept), or
    // DELETE when it draws nothing now.
    std::vector<MarkerLedger::Chunk*> redrawn;
    redrawn.reserve(order.size());
    out.markers.reserve(order.size());
    for (size_t i = 0; i < order.size(); ++i) {
      MarkerLedger::Chunk& chunk = *sent[i];
      chunk.pending = false;
      chunk.listed.clear();
      const bool redraw = chunk.redraw;
      chunk.redraw = false;
      if (chunk.blocks.empty()) {
        if (chunk.id >= 0)
          out.markers.push_back(
              wireOf(markerHeader(style, stamp, chunk.id, visualization_msgs::Marker::DELETE)));
        ledger->chunks_.erase(order[i]);
        continue;
      }
      if (!redraw) continue;  // its blocks' drawn cells are as last sent
      if (chunk.id < 0) chunk.id = ledger->next_id_++;
      redrawn.push_back(&chunk);
      out.markers.emplace_back();  // its wire, once encoded
    }
    encodeChunks(map, style, redrawn);
    size_t next = 0;
    for (WireMarkerPtr& m : out.markers)
      if (!m) m = redrawn[next++]->wire;
    return out;
  };
  // A take-in reads the whole map (a CUDA map's changes written back first) or brings the mask
  // mirror up to date (the changed blocks' masks only); a share draws its chunks' listed blocks
  // from the host's copy or the mirror as they stand, so a CUDA map is written back (or its
  // masks read) once a period, not at every cloud (the same cells on a CPU map).
  if (ledger->mirror_) {
    // A mirror never synced (just handed to a ledger in use) holds nothing yet: a share drawn
    // from it would take every listed block for gone.
    if (note || !ledger->mirror_->valid()) ledger->mirror_->sync(map);
    return send(*ledger->mirror_);
  }
  return send(note ? map.blockView() : map.hostBlockView());
}
SerializedMarkerArray allBlockMarkersWire(const fragg::Map& map, const MarkerStyle& style,
                                          const ::ros::Time& stamp, MarkerLedger* ledger) {
  SerializedMarkerArray out;
  out.stamp = stamp;
  out.markers.push_back(
      wireOf(markerHeader(style, stamp, 0, visualization_msgs::Marker::DELETEALL)));
  ledger->clear(style.chunk_blocks);
  const fragg::BlockView blocks = map.blockView();
  const std::vector<fragg::BlockRef> all = blocks.all();
  std::vector<CellMask> masks(all.size());
  const int64_t n = static_cast<int64_t>(all.size());
#pragma omp parallel for schedule(static) if (n > 256)
  for (int64_t j = 0; j < n; ++j)
    masks[j] = drawnCells(map, blocks, all[j].key, *all[j].block, style);
  for (size_t j = 0; j < all.size(); ++j) {
    if (masks[j].none()) continue;
    ledger->chunks_[chunkOf(all[j].key, ledger->chunk_blocks_)].blocks.push_back(
        {all[j].key, masks[j]});
    ++ledger->shown_blocks_;
  }
  std::vector<fragg::BlockKey> order;
  order.reserve(ledger->chunks_.size());
  for (const auto& [chunk_key, chunk] : ledger->chunks_) order.push_back(chunk_key);
  std::sort(order.begin(), order.end(), byKey);
  std::vector<MarkerLedger::Chunk*> chunks;
  chunks.reserve(order.size());
  for (const fragg::BlockKey& chunk_key : order) {
    MarkerLedger::Chunk& chunk = ledger->chunks_[chunk_key];
    chunk.id = ledger->next_id_++;
    chunks.push_back(&chunk);
  }
  encodeChunks(map, style, chunks);
  for (const MarkerLedger::Chunk* chunk : chunks) out.markers.push_back(chunk->wire);
  ledger->published_revision_ = map.revision();
  ledger->started_ = true;
  ledger->view_epoch_ = map.viewEpoch();
  if (style.colors) ledger->colors_drawn_ = style.colors->sequence();
  return out;
}

SerializedMarkerArray shownBlockMarkersWire(const fragg::Map& map, const MarkerStyle& style,
                                            const ::ros::Time& stamp, const MarkerLedger& ledger) {
  SerializedMarkerArray out;
  out.stamp = stamp;
  out.markers.push_back(
      wireOf(markerHeader(style, stamp, 0, visualization_msgs::Marker::DELETEALL)));
  const fragg::BlockView blocks = map.blockView();
  std::vector<fragg::BlockKey> order;
  order.reserve(ledger.chunks_.size());
  for (const auto& [chunk_key, chunk] : ledger.chunks_) order.push_back(chunk_key);
  std::sort(order.begin(), order.end(), byKey);
  // The kept wire is what the subscribers were sent, unless blocks may have left the map since
  // (the view moved) or colours may have changed (colored_map): then the chunk is drawn again.
  const bool kept = map.viewEpoch() == ledger.view_epoch_ && !style.colors;
  for (const fragg::BlockKey& chunk_key : order) {
    const MarkerLedger::Chunk& chunk = ledger.chunks_.at(chunk_key);
    if (chunk.id < 0) continue;  // queued, never sent: it comes with the increments
    if (kept && chunk.wire) {
      out.markers.push_back(chunk.wire);
      continue;
    }
    // An erased block is still shown until the next increment redraws its chunk: its cells
    // stand nowhere else, so it is left out (a chunk left empty is not sent).
    std::vector<MarkerLedger::ShownBlock> present;
    for (const MarkerLedger::ShownBlock& b : chunk.blocks)
      if (blocks.findBlock(b.key)) present.push_back(b);
    if (!present.empty()) out.markers.push_back(chunkWire(map, present, style, chunk.id));
  }
  return out;
}

visualization_msgs::MarkerArray changedBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                    const ::ros::Time& stamp,
                                                    MarkerLedger* ledger) {
  return toMarkerArray(changedBlockMarkersWire(map, style, stamp, ledger));
}

visualization_msgs::MarkerArray allBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                const ::ros::Time& stamp, MarkerLedger* ledger) {
  return toMarkerArray(allBlockMarkersWire(map, style, stamp, ledger));
}

visualization_msgs::MarkerArray shownBlockMarkers(const fragg::Map& map, const MarkerStyle& style,
                                                  const ::ros::Time& stamp,
                                                  const MarkerLedger& ledger) {
  return toMarkerArray(shownBlockMarkersWire(map, style, stamp, ledger));
}

}  // namespace fragg::ros
