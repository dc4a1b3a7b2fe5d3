// PageStore's shared parts: a commit of blocks (encode, then commit the records) and the
// one-at-a-time readMany for stores without a batched read.
#include "fragg_map/page_store.h"

namespace fragg {

void PageStore::commit(const std::vector<std::pair<BlockKey, const Block*>>& puts,
                       const std::vector<BlockKey>& erases, const std::vector<uint8_t>& meta) {
  std::vector<const Block*> blocks;
  blocks.reserve(puts.size());
  for (const auto& p : puts) blocks.push_back(p.second);
  std::vector<BlockRecord> records = encode(blocks);
  std::vector<std::pair<BlockKey, BlockRecord>> encoded;
  encoded.reserve(puts.size());
  for (size_t j = 0; j < puts.size(); ++j)
    encoded.emplace_back(puts[j].first, std::move(records[j]));
  commitRecords(encoded, erases, meta);
}

std::vector<bool> PageStore::readMany(const std::vector<BlockKey>& keys,
                                      const std::vector<Block*>& outs) {
  std::vector<bool> found(keys.size());
  for (size_t j = 0; j < keys.size(); ++j) found[j] = read(keys[j], outs[j]);
  return found;
}

}  // namespace fragg
