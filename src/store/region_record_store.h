// What both page stores share over their records by region (store format 2): reading blocks
// out of region records, encoding regions, a commit of single blocks (read, change and write
// back their regions), and the one-line refusal of a store of format 1. Each store gives two
// raw reads from one snapshot (withRecords, forEachRecord) and commitRecords.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "fragg_map/page_store.h"

namespace fragg {

class RegionRecordStore : public PageStore {
 public:
  std::vector<BlockKey> keys() override;
  bool read(const BlockKey& key, Block* out) override;
  std::vector<bool> readMany(
      const std::vector<BlockKey>& keys, const std::vector<Block*>& outs,
      std::vector<std::pair<BlockKey, BlockRecord>>* records = nullptr) override;
  std::vector<uint8_t> readAll(
      const std::function<void(const BlockKey&, const Block&)>& fn) override;
  std::vector<BlockRecord> encode(
      const std::vector<RegionBlocks>& regions,
      const std::vector<const BlockRecord*>& previous = {}) const override;
  bool decode(const BlockRecord& record, const BlockKey& key, Block* out) const override;
  void commit(const std::vector<std::pair<BlockKey, const Block*>>& puts,
              const std::vector<BlockKey>& erases, const std::vector<uint8_t>& meta) override;

  /// A store of format 1 (one record per block, keyed by block) read whole: fn(key, block) for
  /// each block, then its metadata. Only for a store opened as format 1 (convert-store).
  std::vector<uint8_t> readFormat1(const std::function<void(const BlockKey&, const Block&)>& fn);

  /// IoError: `path` is a store of format 1, with the command that converts it.
  [[noreturn]] static void refuseFormat1(const std::string& path);

 protected:
  /// Records as {data, size}, {nullptr, 0} for a region without one; valid during the call.
  using Records = std::vector<std::pair<const void*, size_t>>;
  /// The records of `regions` from one snapshot, handed to fn.
  virtual void withRecords(const std::vector<BlockKey>& regions,
                           const std::function<void(const Records&)>& fn) = 0;
  /// Every record (keyed by region; by block in a store of format 1) from one snapshot:
  /// fn(key, data, size); returns the snapshot's metadata.
  virtual std::vector<uint8_t> forEachRecord(
      const std::function<void(const BlockKey&, const void*, size_t)>& fn) = 0;
};

}  // namespace fragg
