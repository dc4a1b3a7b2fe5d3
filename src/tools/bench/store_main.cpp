// fragg_map_store_bench: the page stores (SQLite, LMDB) on the blocks of a real map, tiled to
// the size asked for. Prints, per store: commit throughput (blocks/s and MB/s of cells), random
// single-block reads (what paging in does), one-snapshot reads of everything (what
// `fragg_map stats store.db` does), the store's size on disk.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/map.h"
#include "fragg_map/store/page_stores.h"

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct Options {
  std::string map, dir = ".";
  size_t blocks = 200000, batch = 5000, reads = 50000;
};

void benchStore(fragg::PageStoreKind kind, const Options& o,
                const std::vector<std::pair<fragg::BlockKey, fragg::Block>>& blocks) {
  const bool lmdb = kind == fragg::PageStoreKind::kLmdb;
  const std::string path = o.dir + (lmdb ? "/store_bench.lmdb" : "/store_bench.db");
  for (const char* suffix : {"", "-wal", "-shm", "-lock"}) std::filesystem::remove(path + suffix);
  auto store = fragg::openPageStore(path, false);
  const std::vector<uint8_t> meta = {1, 2, 3};
  auto t0 = Clock::now();
  for (size_t at = 0; at < blocks.size(); at += o.batch) {
    std::vector<std::pair<fragg::BlockKey, const fragg::Block*>> puts;
    for (size_t i = at; i < std::min(blocks.size(), at + o.batch); ++i)
      puts.emplace_back(blocks[i].first, &blocks[i].second);
    store->commit(puts, {}, meta);
  }
  const double write_s = since(t0);
  // Rewriting a tenth of the blocks (what the commits of a running map do).
  t0 = Clock::now();
  {
    std::vector<std::pair<fragg::BlockKey, const fragg::Block*>> puts;
    for (size_t i = 0; i < blocks.size(); i += 10) {
      puts.emplace_back(blocks[i].first, &blocks[i].second);
      if (puts.size() == o.batch) {
        store->commit(puts, {}, meta);
        puts.clear();
      }
    }
    if (!puts.empty()) store->commit(puts, {}, meta);
  }
  const double rewrite_s = since(t0);
  std::vector<size_t> order(std::min(o.reads, blocks.size()));
  std::mt19937_64 rng(7);
  for (size_t& i : order) i = rng() % blocks.size();
  fragg::Block b;
  t0 = Clock::now();
  for (size_t i : order)
    if (!store->read(blocks[i].first, &b)) throw fragg::IoError("missing block in " + path);
  const double read_s = since(t0);
  size_t all = 0;
  t0 = Clock::now();
  store->readAll([&](const fragg::BlockKey&, const fragg::Block&) { ++all; });
  const double scan_s = since(t0);
  if (all != blocks.size()) throw fragg::IoError("readAll saw " + std::to_string(all) + " blocks");
  const double mb = blocks.size() * sizeof(fragg::Block) / 1048576.0;
  std::printf(
      "%s\n",
      fmt::format("{:<7} {:>9} blocks  write {:>8.0f} blocks/s ({:>6.1f} MB/s)  rewrite 10% "
                  "{:>8.0f} blocks/s  random read {:>8.0f} blocks/s  read all {:>8.0f} "
                  "blocks/s  size {:>7.1f} MiB ({:.0f} B/block)",
                  store->kind(), blocks.size(), blocks.size() / write_s, mb / write_s,
                  (blocks.size() / 10.0) / rewrite_s, order.size() / read_s, all / scan_s,
                  store->diskBytes() / 1048576.0,
                  static_cast<double>(store->diskBytes()) / blocks.size())
          .c_str());
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("fragg_map_store_bench: SQLite vs LMDB page stores on a map's blocks");
  Options o;
  app.add_option("map", o.map, "A map (.fgm) whose blocks are tiled to --blocks")->required();
  app.add_option("--blocks", o.blocks, "Blocks to write")->capture_default_str();
  app.add_option("--batch", o.batch, "Blocks per commit")->capture_default_str();
  app.add_option("--reads", o.reads, "Random single-block reads")->capture_default_str();
  app.add_option("--dir", o.dir, "Where the stores are written")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const fragg::Map map = fragg::Map::load(o.map, fragg::Backend::kCpu);
    std::vector<std::pair<fragg::BlockKey, fragg::Block>> source;
    fragg::BlockKey lo{1 << 30, 1 << 30, 1 << 30}, hi{-(1 << 30), -(1 << 30), -(1 << 30)};
    map.forEachBlock([&](const fragg::BlockKey& k, const fragg::Block& b) {
      source.emplace_back(k, b);
      lo = {std::min(lo.x, k.x), std::min(lo.y, k.y), std::min(lo.z, k.z)};
      hi = {std::max(hi.x, k.x), std::max(hi.y, k.y), std::max(hi.z, k.z)};
    });
    if (source.empty()) throw fragg::InvalidArgument(o.map + " has no blocks");
    // Copies of the map side by side along x, then y: a map as large as asked.
    std::vector<std::pair<fragg::BlockKey, fragg::Block>> blocks;
    blocks.reserve(o.blocks);
    const int32_t dx = hi.x - lo.x + 1, dy = hi.y - lo.y + 1;
    for (int copy = 0; blocks.size() < o.blocks; ++copy)
      for (const auto& [k, b] : source) {
        if (blocks.size() == o.blocks) break;
        blocks.push_back({{k.x + (copy % 16) * dx, k.y + (copy / 16) * dy, k.z}, b});
      }
    std::printf("%zu blocks (%.0f MiB of cells) from %s, %zu per commit\n", blocks.size(),
                blocks.size() * sizeof(fragg::Block) / 1048576.0, o.map.c_str(), o.batch);
    benchStore(fragg::PageStoreKind::kSqlite, o, blocks);
    if (fragg::lmdbAvailable()) benchStore(fragg::PageStoreKind::kLmdb, o, blocks);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_store_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
