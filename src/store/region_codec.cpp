#include "region_codec.h"

#include <algorithm>
#include <cstring>
#include <exception>
#include <memory>

#include "fragg_map/errors.h"

namespace fragg {

namespace {
constexpr uint8_t kRegionTag = 'R';
constexpr size_t kHeaderBytes = 4;
constexpr size_t kEntryBytes = 6;

template <class T>
T load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}
}  // namespace

RegionRecordView::RegionRecordView(const void* data, size_t size, const BlockKey& region,
                                   const std::string& where)
    : data_(static_cast<const uint8_t*>(data)), region_(region) {
  auto fail = [&](const std::string& why) {
    throw IoError(where + ": region record of region (" + std::to_string(region.x) + ", " +
                  std::to_string(region.y) + ", " + std::to_string(region.z) + ") " + why);
  };
  if (size < kHeaderBytes || data_[0] != kRegionTag) fail("is not a region record");
  if (data_[1] != kRegionBits) fail("has another region size");
  const size_t count = load<uint16_t>(data_ + 2);
  if (count == 0 || count > static_cast<size_t>(kBlocksPerRegion)) fail("has a bad block count");
  if (size < kHeaderBytes + count * kEntryBytes) fail("is cut short");
  entries_.resize(count);
  size_t offset = kHeaderBytes + count * kEntryBytes;
  for (size_t i = 0; i < count; ++i) {
    const uint8_t* e = data_ + kHeaderBytes + i * kEntryBytes;
    Entry& entry = entries_[i];
    entry.local = load<uint16_t>(e);
    entry.size = load<uint32_t>(e + 2);
    entry.offset = offset;
    if (entry.local >= kBlocksPerRegion || (i > 0 && entry.local <= entries_[i - 1].local))
      fail("has bad block indices");
    if (entry.size > size - offset) fail("is cut short");
    offset += entry.size;
  }
  if (offset != size) fail("has trailing bytes");
}

BlockKey RegionRecordView::key(size_t i) const {
  const BlockKey first = firstBlockOf(region_);
  const int l = entries_[i].local;
  return {first.x | (l & kRegionMask), first.y | ((l >> kRegionBits) & kRegionMask),
          first.z | ((l >> (2 * kRegionBits)) & kRegionMask)};
}

bool RegionRecordView::find(const BlockKey& key, size_t* i) const {
  if (!(regionOf(key) == region_)) return false;
  const uint16_t local = localIndexOf(key);
  auto it = std::lower_bound(entries_.begin(), entries_.end(), local,
                             [](const Entry& e, uint16_t l) { return e.local < l; });
  if (it == entries_.end() || it->local != local) return false;
  *i = static_cast<size_t>(it - entries_.begin());
  return true;
}

size_t encodeRegion(BlockCodec& codec, const BlockKey& region, RegionBlocks blocks,
                    const BlockRecord* previous, const std::string& where, BlockRecord* out) {
  if (blocks.empty() || blocks.size() > static_cast<size_t>(kBlocksPerRegion))
    throw IoError("paging: a region record holds 1 to 64 blocks (internal error)");
  std::sort(blocks.begin(), blocks.end(), [](const auto& a, const auto& b) {
    return localIndexOf(a.first) < localIndexOf(b.first);
  });
  std::unique_ptr<RegionRecordView> before;
  if (previous)
    before = std::make_unique<RegionRecordView>(previous->data(), previous->size(), region, where);
  out->assign(kHeaderBytes + blocks.size() * kEntryBytes, 0);
  (*out)[0] = kRegionTag;
  (*out)[1] = static_cast<uint8_t>(kRegionBits);
  const auto count = static_cast<uint16_t>(blocks.size());
  std::memcpy(out->data() + 2, &count, sizeof(count));
  size_t compressed = 0;
  for (size_t i = 0; i < blocks.size(); ++i) {
    const BlockKey& k = blocks[i].first;
    if (!(regionOf(k) == region) || (i > 0 && localIndexOf(k) == localIndexOf(blocks[i - 1].first)))
      throw IoError("paging: a block outside its region record, or twice (internal error)");
    const uint8_t* bytes = nullptr;
    size_t size = 0;
    if (blocks[i].second) {
      const std::vector<uint8_t>& enc = codec.encode(*blocks[i].second);
      bytes = enc.data();
      size = enc.size();
      ++compressed;
    } else {
      size_t at = 0;
      if (!before || !before->find(k, &at))
        throw IoError(where +
                      ": a block kept from its region's earlier record is not in it "
                      "(internal error)");
      const auto [data, n] = before->encoding(at);
      bytes = static_cast<const uint8_t*>(data);
      size = n;
    }
    const uint16_t local = localIndexOf(k);
    const auto size32 = static_cast<uint32_t>(size);
    uint8_t* e = out->data() + kHeaderBytes + i * kEntryBytes;
    std::memcpy(e, &local, sizeof(local));
    std::memcpy(e + 2, &size32, sizeof(size32));
    out->insert(out->end(), bytes, bytes + size);
  }
  return compressed;
}

std::vector<BlockRecord> encodeRegions(const std::vector<RegionBlocks>& regions,
                                       const std::vector<const BlockRecord*>& previous,
                                       const std::string& where) {
  if (!previous.empty() && previous.size() != regions.size())
    throw IoError("paging: one earlier record (or none) per region (internal error)");
  std::vector<BlockRecord> out(regions.size());
  const long n = static_cast<long>(regions.size());
  bool failed = false;
  std::string why;
#pragma omp parallel if (n > 8)
  {
    // A context per thread, made once per call (cheap against the blocks it compresses).
    std::unique_ptr<BlockCodec> codec;
    try {
      codec = std::make_unique<BlockCodec>();
    } catch (const std::exception& e) {
#pragma omp critical(fragg_encode_regions)
      {
        failed = true;
        why = e.what();
      }
    }
#pragma omp for schedule(dynamic, 4)
    for (long j = 0; j < n; ++j) {
      if (!codec) continue;
      try {
        const RegionBlocks& r = regions[j];
        encodeRegion(*codec, r.empty() ? BlockKey{} : regionOf(r.front().first), r,
                     previous.empty() ? nullptr : previous[j], where, &out[j]);
      } catch (const std::exception& e) {
#pragma omp critical(fragg_encode_regions)
        {
          failed = true;
          why = e.what();
        }
      }
    }
  }
  if (failed) throw IoError(why);
  return out;
}

}  // namespace fragg
