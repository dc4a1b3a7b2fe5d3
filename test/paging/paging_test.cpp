// Out-of-core paging on the CPU backend: a map built with a small RAM budget pages blocks out
// to the store and back in, and ends byte-identical to the map built in memory; queries and
// edits page in what they reach; a store is a map on its own and a build continues it.
#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <condition_variable>
#include <cstring>
#include <fstream>
#include <memory>
#include <mutex>
#include <string>
#include <utility>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/planning/collision_check.h"
#include "fragg_map/store/page_stores.h"
#include "paging_scenes.h"

namespace fragg::test {
namespace {

constexpr int kScans = 80;

// ~4,800 blocks of the corridor map's 8,359; it holds one scan's reach (up to ~3,900 blocks):
// a budget that does not is refused at the scan (paging_budget_test.cpp).
PagingPolicy smallBudget() { return corridorBudget(10.0, 7); }

Map inMemory(int scans) {
  Map map(corridorParams());
  for (int i = 0; i < scans; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    map.insert(corridorScan(T), T, corridorSensor());
  }
  return map;
}

const Map& fullInMemory() {
  static const Map map = inMemory(kScans);
  return map;
}

void insertScans(Map& map, int from, int to) {
  for (int i = from; i < to; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    map.insert(corridorScan(T), T, corridorSensor());
  }
}

/// The centre of an occupied cell of `map` with x in [x0, x1) (a wall or the ground).
Eigen::Vector3d occupiedCellIn(const Map& map, double x0, double x1) {
  Eigen::Vector3d found = Eigen::Vector3d::Constant(NAN);
  map.forEachBlock([&](const BlockKey& k, const Block& b) {
    for (int c = 0; c < kCellsPerBlock && !found.allFinite(); ++c) {
      const Eigen::Vector3d p = map.centerOf(voxelKeyOf(k, c));
      if (p.x() >= x0 && p.x() < x1 && map.state(b.cells[c]) == CellState::kOccupied) found = p;
    }
  });
  EXPECT_TRUE(found.allFinite()) << "no occupied cell with x in [" << x0 << ", " << x1 << ")";
  return found;
}

class Paging : public ::testing::TestWithParam<PageStoreKind> {
 protected:
  std::string storePath(const std::string& dir) const {
    return dir + (GetParam() == PageStoreKind::kLmdb ? "/map.lmdb" : "/map.db");
  }
  void SetUp() override {
    if (GetParam() == PageStoreKind::kLmdb && !lmdbAvailable()) GTEST_SKIP() << "no LMDB";
  }
};

TEST_P(Paging, PagedBuildIsByteIdenticalToTheInMemoryBuild) {
  const std::string dir = testDir();
  const std::string path = storePath(dir);
  Map paged(corridorParams());
  paged.attachPageStore(openPageStore(path, false), smallBudget());
  insertScans(paged, 0, kScans);
  const PagingStats st = paged.pagingStats();
  // The budget was met by paging out, and the way back read blocks in again.
  EXPECT_GT(st.pages_evicted, 1000u);
  EXPECT_GT(st.pages_read, 100u);
  EXPECT_GT(st.paged_blocks, 0u);
  EXPECT_LT(st.peak_resident_blocks, fullInMemory().blockCount());
  EXPECT_LT(st.resident_blocks, fullInMemory().blockCount());

  // save() writes paged-out blocks too: the same bytes as the in-memory map's file.
  paged.save(dir + "/paged.fgm");
  fullInMemory().save(dir + "/memory.fgm");
  EXPECT_EQ(readBytes(dir + "/paged.fgm"), readBytes(dir + "/memory.fgm"));

  // The store alone (read whole, another handle) is the map.
  paged.commitPages();
  const Map from_store = Map::loadPageStore(*openPageStore(path, true));
  EXPECT_EQ(from_store.scanCount(), static_cast<size_t>(kScans));
  std::string why;
  EXPECT_TRUE(sameBlocks(from_store, fullInMemory(), &why)) << why;

  paged.ensureAllResident();
  EXPECT_EQ(paged.pagingStats().paged_blocks, 0u);
  EXPECT_TRUE(sameBlocks(paged, fullInMemory(), &why)) << why;
}

TEST_P(Paging, TheBudgetWinsOverTheRadiusAndUnchangedBlocksAreNotWrittenAgain) {
  const std::string dir = testDir();
  Map paged(corridorParams());
  PagingPolicy policy = smallBudget();
  policy.radius_m = 100.0;  // the whole corridor: the radius alone would keep every block
  policy.commit_every_scans = 0;
  paged.attachPageStore(openPageStore(storePath(dir), false), policy);
  const uint64_t budget = paged.pagingStats().budget_blocks;
  ASSERT_GT(budget, 0u);
  ASSERT_LT(budget, fullInMemory().blockCount());
  for (int i = 0; i < kScans; ++i) {
    insertScans(paged, i, i + 1);
    ASSERT_LE(paged.pagingStats().resident_blocks, budget) << "after scan " << i;
  }
  EXPECT_GT(paged.pagingStats().pages_evicted, 1000u);

  // Reading every block back changes none: the next commit writes nothing.
  paged.commitPages();
  const uint64_t written = paged.pagingStats().pages_written;
  paged.ensureAllResident();
  EXPECT_EQ(paged.pagingStats().paged_blocks, 0u);
  paged.commitPages();
  EXPECT_EQ(paged.pagingStats().pages_written, written);
  std::string why;
  EXPECT_TRUE(sameBlocks(paged, fullInMemory(), &why)) << why;
  const Map from_store = Map::loadPageStore(*openPageStore(storePath(dir), true));
  EXPECT_TRUE(sameBlocks(from_store, fullInMemory(), &why)) << why;
}

TEST_P(Paging, AScanReadsBackOnlyTheBlocksItsRaysReach) {
  // The CPU backend asks for the blocks its rays mark, not for every paged-out block of the
  // scan's box: a few rays across the corridor, diagonally up to the ceiling, leave the
  // paged-out blocks of their box that they do not cross where they are. Blocks come back by
  // region (a store record holds 4x4x4 blocks): at most the regions of the blocks touched.
  const std::string dir = testDir();
  Map paged(corridorParams());
  paged.attachPageStore(openPageStore(storePath(dir), false), smallBudget());
  // The way down the corridor only: it ends at x = 40, the start (x < 12) is paged out.
  insertScans(paged, 0, kScans / 2);
  Eigen::Isometry3d T = corridorPose(kScans / 2 - 1, kScans);
  T.translation().x() = 12.0;  // a scan from the middle, back to the start
  PointCloud rays;
  for (const Eigen::Vector3d& p_map :
       {Eigen::Vector3d(1.0, 3.0, 2.8), Eigen::Vector3d(1.0, 2.9, 2.7),
        Eigen::Vector3d(1.1, 3.0, 2.6)})
    rays.points_S.push_back((T.inverse() * p_map).cast<float>());
  rays.width = 3;
  rays.height = 1;
  const uint64_t read_before = paged.pagingStats().pages_read;
  const InsertStats st = paged.insert(rays, T, corridorSensor());
  const uint64_t read_by_scan = paged.pagingStats().pages_read - read_before;
  EXPECT_GT(read_by_scan, 0u);
  EXPECT_LE(read_by_scan, st.blocks_touched * kBlocksPerRegion);
  // The box of those rays (sensor to the farthest end, a cell's margin) still holds
  // paged-out blocks: bringing it in reads them.
  const uint64_t read_after_scan = paged.pagingStats().pages_read;
  paged.ensureResident(
      Eigen::Vector3d(0.8, 2.7, 2.4),
      T.translation().cwiseMax(Eigen::Vector3d(1.1, 3.0, 2.8)) + Eigen::Vector3d::Constant(0.2));
  EXPECT_GT(paged.pagingStats().pages_read - read_after_scan, 0u);

  // And the map is the one built in memory with the same scans.
  Map memory = inMemory(kScans / 2);
  memory.insert(rays, T, corridorSensor());
  paged.ensureAllResident();
  std::string why;
  EXPECT_TRUE(sameBlocks(paged, memory, &why)) << why;
}

TEST_P(Paging, QueriesAndEditsPageInWhatTheyReach) {
  const std::string dir = testDir();
  Map paged(corridorParams());
  PagingPolicy policy = smallBudget();
  policy.budget_mb = 10.0;
  paged.attachPageStore(openPageStore(storePath(dir), false), policy);
  insertScans(paged, 0, kScans / 2);  // the sensor ends at x = 40: the start is paged out
  ASSERT_GT(paged.pagingStats().paged_blocks, 0u);
  const Map reference = inMemory(kScans / 2);

  // A wall cell near the start: a const reader sees only resident blocks, the map pages it in.
  const Eigen::Vector3d wall = occupiedCellIn(reference, 0.0, 2.0);
  ASSERT_EQ(reference.query(wall), CellState::kOccupied);
  const Map& as_const = paged;
  EXPECT_EQ(as_const.query(wall), CellState::kUnknown);
  EXPECT_EQ(paged.query(wall), CellState::kOccupied);

  // extract over a paged-out box equals the in-memory extract.
  const Eigen::Vector3d lo(2, -5, -1), hi(9, 5, 4);
  std::string why;
  EXPECT_TRUE(sameBlocks(paged.extract(lo, hi), reference.extract(lo, hi), &why)) << why;

  // ensureResident brings a box back for const readers.
  const Eigen::Vector3d far_wall = occupiedCellIn(reference, 12.0, 13.0);
  paged.ensureResident(far_wall, far_wall);
  EXPECT_EQ(as_const.query(far_wall), reference.query(far_wall));
  EXPECT_THROW(paged.ensureResident(hi, lo), InvalidArgument);

  // Edits over paged-out blocks: clearBox, truncate, merge, then the store reopened.
  Map ref = inMemory(kScans / 2);
  for (Map* m : {&paged, &ref}) {
    m->clearBox({14, -5, -1}, {16, 5, 4});
    Map cut = m->truncate({20, -5, -1}, {24, 5, 4});
    Map sub = cut.extract({20, -5, -1}, {22, 5, 4});
    m->merge(sub, MergeMode::kOverwrite);
  }
  insertScans(paged, kScans / 2, kScans);
  insertScans(ref, kScans / 2, kScans);
  paged.commitPages();
  const Map from_store = Map::loadPageStore(*openPageStore(storePath(dir), true));
  EXPECT_TRUE(sameBlocks(from_store, ref, &why)) << why;
  paged.ensureAllResident();
  EXPECT_TRUE(sameBlocks(paged, ref, &why)) << why;
}

TEST_P(Paging, CollisionChecksPageInWhatThePosesReach) {
  const std::string dir = testDir();
  Map paged(corridorParams());
  PagingPolicy policy = smallBudget();
  policy.budget_mb = 10.0;
  paged.attachPageStore(openPageStore(storePath(dir), false), policy);
  insertScans(paged, 0, kScans / 2);  // the sensor ends at x = 40: the start is paged out
  const Map reference = inMemory(kScans / 2);
  // Spheres on wall cells all along the corridor, and the same poses shifted into free space.
  const auto sphere = planning::CollisionShape::sphere(0.12);
  std::vector<Eigen::Isometry3d> poses;
  for (double x = 0.0; x < 38.0; x += 2.0) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = occupiedCellIn(reference, x, x + 1.0);
    poses.push_back(T);
    T.translation().z() += 0.6;
    poses.push_back(T);
  }
  planning::CollisionOptions options;
  options.margin_m = 0.05;
  const auto expected = planning::checkPoses(reference, sphere, poses, options);
  const auto before = planning::checkPoses(static_cast<const Map&>(paged), sphere, poses, options);
  int expected_hits = 0, hits_before = 0;
  for (size_t i = 0; i < poses.size(); ++i) {
    expected_hits += expected[i].collides;
    hits_before += before[i].collides;
  }
  EXPECT_GE(expected_hits, 19);
  EXPECT_LT(hits_before, expected_hits) << "the paged-out walls are missing before paging in";
  planning::pageInForCollision(paged, sphere, poses, options);
  const auto after = planning::checkPoses(static_cast<const Map&>(paged), sphere, poses, options);
  for (size_t i = 0; i < poses.size(); ++i) {
    EXPECT_EQ(after[i].collides, expected[i].collides) << "pose " << i;
    if (expected[i].collides) {
      EXPECT_EQ(after[i].first_cell, expected[i].first_cell) << i;
    }
  }
  EXPECT_THROW(planning::pageInForCollision(paged, sphere, poses,
                                            [] {
                                              planning::CollisionOptions bad;
                                              bad.margin_m = -1.0;
                                              return bad;
                                            }()),
               InvalidArgument);
}

TEST_P(Paging, AStoreIsContinuedWhereItStopped) {
  const std::string dir = testDir();
  const std::string path = storePath(dir);
  {
    Map first(corridorParams());
    first.attachPageStore(openPageStore(path, false), smallBudget());
    insertScans(first, 0, 33);
  }  // closed: the last scans are committed
  Map again = Map::openPageStore(openPageStore(path, false), corridorParams(), smallBudget());
  EXPECT_EQ(again.scanCount(), 33u);
  insertScans(again, 33, kScans);
  again.ensureAllResident();
  std::string why;
  EXPECT_TRUE(sameBlocks(again, fullInMemory(), &why)) << why;
}

TEST_P(Paging, RefusesWhatItCannotPage) {
  const std::string dir = testDir();
  const std::string path = storePath(dir);
  Map first(corridorParams());
  first.attachPageStore(openPageStore(path, false), smallBudget());
  insertScans(first, 0, 3);
  first.commitPages();

  MapParams other = corridorParams();
  other.resolution_m = 0.2;
  Map wrong_resolution(other);
  EXPECT_THROW(wrong_resolution.attachPageStore(openPageStore(path, true), smallBudget()),
               InvalidArgument);
  Map not_empty = inMemory(1);
  EXPECT_THROW(not_empty.attachPageStore(openPageStore(path, true), smallBudget()),
               InvalidArgument);
  MapParams keep = corridorParams();
  keep.scans.keep = true;
  Map keeps(keep);
  EXPECT_THROW(keeps.attachPageStore(openPageStore(dir + "/other.db", false), smallBudget()),
               InvalidArgument);
  PagingPolicy bad = smallBudget();
  bad.budget_mb = -1;
  Map fresh(corridorParams());
  EXPECT_THROW(fresh.attachPageStore(openPageStore(dir + "/other2.db", false), bad),
               InvalidArgument);
  EXPECT_FALSE(fresh.paging());
  EXPECT_THROW(openPageStore(dir + "/missing.db", true), IoError);
  writeBytes(dir + "/garbage.db", std::string(4096, 'x'));
  EXPECT_THROW(openPageStore(dir + "/garbage.db", true), IoError);
}

/// The process's resident memory (/proc/self/statm), bytes.
size_t residentBytes() {
  std::ifstream statm("/proc/self/statm");
  size_t pages = 0, resident = 0;
  statm >> pages >> resident;
  return resident * static_cast<size_t>(sysconf(_SC_PAGESIZE));
}

// Free pages scattered one or two at a time stay (each release is a TLB shootdown on every
// core); a run of 64 KiB or more goes back.
TEST(BlockMap, ScatteredFreePagesStayAndLongRunsGoBack) {
  BlockMap blocks;
  constexpr int kBlocks = 4096;  // 8 MiB of cells, two blocks a 4 KiB page
  for (int i = 0; i < kBlocks; ++i) blocks.findOrCreate({i, 0, 0});
  // Every other page free: runs of one page.
  for (int i = 0; i < kBlocks; ++i)
    if ((i / 2) % 2 == 1) blocks.erase({i, 0, 0});
  EXPECT_EQ(blocks.releaseFreePages(), 0u);
  // Pages 0-99 free as well (blocks 0-199): one run of 100 pages, released whole, and only it.
  for (int i = 0; i < 200; ++i) blocks.erase({i, 0, 0});
  EXPECT_EQ(blocks.releaseFreePages(), size_t{100} * 4096);
  EXPECT_EQ(blocks.releaseFreePages(), 0u);
}

TEST(BlockMap, PagesOfFreeBlocksGoBackToTheSystemAndComeBackUsable) {
  BlockMap blocks;
  constexpr int kBlocks = 20000;  // 40 MiB of cells
  for (int i = 0; i < kBlocks; ++i) {
    Block& b = blocks.block(blocks.findOrCreate({i, 0, 0}));
    for (Cell& c : b.cells) c.log_odds_fx = 7;
  }
  EXPECT_EQ(blocks.releaseFreePages(), 0u);  // nothing free
  const size_t before = residentBytes();
  for (int i = 0; i < kBlocks; ++i)
    if (i % 1000 != 0) blocks.erase({i, 0, 0});  // 20 blocks stay
  const size_t released = blocks.releaseFreePages();
  EXPECT_GT(released, size_t{35} << 20);
  EXPECT_LT(residentBytes() + (size_t{30} << 20), before) << "the released pages stayed resident";
  EXPECT_EQ(blocks.releaseFreePages(), 0u);  // released already
  for (int i = 0; i < kBlocks; i += 1000) {  // the blocks that stayed are intact
    const Block* b = blocks.findBlock({i, 0, 0});
    ASSERT_NE(b, nullptr);
    for (const Cell& c : b->cells) ASSERT_EQ(c.log_odds_fx, 7);
  }
  for (int i = 0; i < kBlocks; ++i) {  // new blocks in released pages start unobserved
    if (i % 1000 == 0) continue;
    const Block& b = blocks.block(blocks.findOrCreate({i, 1, 0}));
    for (const Cell& c : b.cells) ASSERT_FALSE(c.observed());
  }
  EXPECT_EQ(blocks.size(), static_cast<size_t>(kBlocks));
}

TEST(PageStoreRecords, ARegionRecordHoldsItsBlocksUniformOnesShortAndEveryByteIsChecked) {
  const std::string dir = testDir();
  for (const std::string name : {"/r.db", "/r.lmdb"}) {
    if (name == "/r.lmdb" && !lmdbAvailable()) continue;
    auto store = openPageStore(dir + name, false);
    Block uniform, mixed;
    for (Cell& c : uniform.cells) c = Cell{0, -2000};
    for (int i = 0; i < kCellsPerBlock; ++i) mixed.cells[i] = Cell{int16_t(i % 3), int16_t(-i)};
    // Two blocks of region (-1, 0, 0) (negative keys too), one alone in region (0, 0, 0).
    const BlockKey ku{-4, 1, 3}, km{-1, 2, 0}, kalone{2, 0, 0};
    ASSERT_TRUE(regionOf(ku) == regionOf(km));
    const std::vector<BlockRecord> records =
        store->encode({{{km, &mixed}, {ku, &uniform}}, {{kalone, &uniform}}});
    ASSERT_EQ(records.size(), 2u);
    // Header 4 bytes, 6 a block, a uniform block 9 bytes (tag, cell, check).
    EXPECT_EQ(records[1].size(), 4u + 6u + 9u);
    EXPECT_GT(records[0].size(), 4u + 12u + 9u + 9u);
    Block back;
    ASSERT_TRUE(store->decode(records[0], ku, &back));
    EXPECT_EQ(std::memcmp(&back, &uniform, sizeof(Block)), 0) << name;
    ASSERT_TRUE(store->decode(records[0], km, &back));
    EXPECT_EQ(std::memcmp(&back, &mixed, sizeof(Block)), 0) << name;
    EXPECT_FALSE(store->decode(records[0], BlockKey{-2, 1, 3}, &back)) << "not in the record";
    // A byte changed anywhere in the record is refused, or (a bit zstd's frame header leaves
    // unused) reads as the same blocks: never as other blocks.
    size_t refused = 0;
    for (size_t at = 0; at < records[0].size(); ++at) {
      BlockRecord bad = records[0];
      bad[at] ^= 0x10;
      try {
        for (const auto& [k, b] : {std::pair{ku, &uniform}, std::pair{km, &mixed}}) {
          Block out;
          if (!store->decode(bad, k, &out)) throw IoError("block gone");
          EXPECT_EQ(std::memcmp(&out, b, sizeof(Block)), 0) << name << " byte " << at;
        }
      } catch (const IoError&) {
        ++refused;
      }
    }
    EXPECT_GE(refused, records[0].size() - 2);
    // Commits of single blocks merge into their regions' records; erasing the last block of a
    // region erases its record.
    const std::vector<uint8_t> meta = {7};
    store->commit({{ku, &uniform}, {km, &mixed}, {kalone, &mixed}}, {}, meta);
    store->commit({{kalone, &uniform}}, {km}, meta);
    std::vector<BlockKey> keys = store->keys();
    ASSERT_EQ(keys.size(), 2u);
    ASSERT_TRUE(store->read(kalone, &back));
    EXPECT_EQ(std::memcmp(&back, &uniform, sizeof(Block)), 0) << name;
    EXPECT_FALSE(store->read(km, &back));
    Block a, c;
    const std::vector<bool> found = store->readMany({ku, km, kalone}, {&a, &back, &c});
    EXPECT_EQ(found, (std::vector<bool>{true, false, true}));
    EXPECT_EQ(std::memcmp(&a, &uniform, sizeof(Block)), 0) << name;
    store->commit({}, {ku, kalone}, meta);
    EXPECT_TRUE(store->keys().empty()) << name;
  }
}

TEST(SqlitePageStore, ACorruptRecordIsRefusedWhenRead) {
  const std::string dir = testDir();
  const std::string path = dir + "/map.db";
  {
    Map map(corridorParams());
    map.attachPageStore(openPageStore(path, false), smallBudget());
    insertScans(map, 0, 2);
  }
  ASSERT_GT(Map::loadPageStore(*openPageStore(path, true)).blockCount(), 0u);
  // One record's value overwritten behind the store's back (as a disk error would): the
  // record of the region that holds the first scan's sensor, which every ray of a scan from
  // there crosses. The record key is z, y, x, each big-endian with the sign bit flipped.
  const Eigen::Isometry3d T = corridorPose(0, kScans);
  const BlockKey bad = regionOf(blockKeyOf(Map(corridorParams()).keyOf(T.translation())));
  std::string hex;
  for (int32_t v : {bad.z, bad.y, bad.x}) {
    char word[9];
    std::snprintf(word, sizeof(word), "%08X", static_cast<uint32_t>(v) ^ 0x80000000u);
    hex += word;
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  const std::string corrupt =
      "UPDATE blocks SET v = substr(v, 1, length(v) - 3) || x'000000' WHERE k = x'" + hex + "'";
  ASSERT_EQ(sqlite3_exec(db, corrupt.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
  ASSERT_EQ(sqlite3_changes(db), 1) << "no record of block " << hex;
  sqlite3_close(db);
  try {
    Map::loadPageStore(*openPageStore(path, true));
    FAIL() << "a corrupt record was read";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("block record"), std::string::npos) << e.what();
  }
  // Continuing the map reads that block when a scan reaches it: refused the same way.
  Map again = Map::openPageStore(openPageStore(path, false), corridorParams(), smallBudget());
  const size_t resident = again.pagingStats().resident_blocks;
  EXPECT_THROW(again.insert(corridorScan(T), T, corridorSensor()), IoError);
  EXPECT_EQ(again.scanCount(), 2u);
  // The blocks of that page-in stay paged out (the bad one among them), the map is as before.
  EXPECT_GE(again.pagingStats().paged_blocks, 1u);
  EXPECT_EQ(again.pagingStats().resident_blocks, resident);
}

/// A store whose commits wait at a gate until the test opens it: a commit stays in flight on
/// the map's background writer for as long as the test needs.
class GatedStore final : public PageStore {
 public:
  explicit GatedStore(std::shared_ptr<PageStore> inner) : inner_(std::move(inner)) {}
  void close() {
    std::lock_guard<std::mutex> lock(mutex_);
    open_ = false;
  }
  void open() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      open_ = true;
    }
    cv_.notify_all();
  }
  /// Waits until a commit is held at the closed gate.
  void waitForHeldCommit() {
    std::unique_lock<std::mutex> lock(mutex_);
    cv_.wait(lock, [&] { return held_ > 0; });
  }

  const char* kind() const override { return inner_->kind(); }
  const std::string& path() const override { return inner_->path(); }
  std::vector<BlockKey> keys() override { return inner_->keys(); }
  bool read(const BlockKey& key, Block* out) override { return inner_->read(key, out); }
  std::vector<bool> readMany(
      const std::vector<BlockKey>& keys, const std::vector<Block*>& outs,
      std::vector<std::pair<BlockKey, BlockRecord>>* records = nullptr) override {
    return inner_->readMany(keys, outs, records);
  }
  std::vector<uint8_t> readMeta() override { return inner_->readMeta(); }
  std::vector<uint8_t> readAll(
      const std::function<void(const BlockKey&, const Block&)>& fn) override {
    return inner_->readAll(fn);
  }
  std::vector<BlockRecord> encode(
      const std::vector<RegionBlocks>& regions,
      const std::vector<const BlockRecord*>& previous = {}) const override {
    return inner_->encode(regions, previous);
  }
  bool decode(const BlockRecord& record, const BlockKey& key, Block* out) const override {
    return inner_->decode(record, key, out);
  }
  void commit(const std::vector<std::pair<BlockKey, const Block*>>& puts,
              const std::vector<BlockKey>& erases, const std::vector<uint8_t>& meta) override {
    inner_->commit(puts, erases, meta);
  }
  void commitRecords(const std::vector<std::pair<BlockKey, BlockRecord>>& puts,
                     const std::vector<BlockKey>& erases,
                     const std::vector<uint8_t>& meta) override {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      ++held_;
      cv_.notify_all();
      cv_.wait(lock, [&] { return open_; });
      --held_;
    }
    inner_->commitRecords(puts, erases, meta);
  }
  uint64_t diskBytes() const override { return inner_->diskBytes(); }

 private:
  std::shared_ptr<PageStore> inner_;
  std::mutex mutex_;
  std::condition_variable cv_;
  bool open_ = true;
  int held_ = 0;
};

TEST_P(Paging, ABlockPagedOutBeforeItsCommitIsWrittenIsReadFromThatCommit) {
  const std::string dir = testDir();
  const std::string path = storePath(dir);
  auto gated = std::make_shared<GatedStore>(openPageStore(path, false));
  PagingPolicy policy = smallBudget();
  policy.radius_m = 0;  // every block may leave, those the last scan changed too
  policy.commit_every_scans = 1;
  ASSERT_TRUE(policy.background_writer);
  Map paged(corridorParams());
  paged.attachPageStore(gated, policy);
  constexpr int kBefore = 20;
  insertScans(paged, 0, kBefore);
  paged.commitPages();  // every commit so far is in the store

  // A scan's commit is held in flight while blocks leave RAM whose only record is that commit's
  // (blocks the scan changed or made, paged out after the commit or held for it): the first
  // scan from kBefore on with such a paging round (rounds do not run after every scan, and
  // some page out only blocks whose records the store has).
  int scan = kBefore;
  for (; scan < kScans; ++scan) {
    gated->close();
    const PagingStats before = paged.pagingStats();
    insertScans(paged, scan, scan + 1);
    gated->waitForHeldCommit();
    if (paged.pagingStats().pages_evicted > before.pages_evicted) {
      // The store (another handle) still holds the map before that scan.
      EXPECT_EQ(Map::loadPageStore(*openPageStore(path, true)).scanCount(),
                static_cast<size_t>(scan));
      // Reading every block back: those of the commit in flight come from it, not the store.
      paged.ensureAllResident();
      if (paged.pagingStats().pages_read_pending > before.pages_read_pending) break;
    }
    gated->open();
    paged.commitPages();
  }
  ASSERT_LT(scan, kScans) << "no block was paged out while its only record was in flight";
  std::string why;
  EXPECT_TRUE(sameBlocks(paged, inMemory(scan + 1), &why)) << why;

  gated->open();
  paged.commitPages();
  const Map from_store = Map::loadPageStore(*openPageStore(path, true));
  EXPECT_EQ(from_store.scanCount(), static_cast<size_t>(scan + 1));
  EXPECT_TRUE(sameBlocks(from_store, inMemory(scan + 1), &why)) << why;
  insertScans(paged, scan + 1, kScans);
  paged.ensureAllResident();
  EXPECT_TRUE(sameBlocks(paged, fullInMemory(), &why)) << why;
}

TEST_P(Paging, CommitsOnTheMapsThreadGiveTheSameMap) {
  const std::string dir = testDir();
  PagingPolicy policy = smallBudget();
  policy.background_writer = false;
  Map paged(corridorParams());
  paged.attachPageStore(openPageStore(storePath(dir), false), policy);
  insertScans(paged, 0, kScans);
  EXPECT_GT(paged.pagingStats().pages_evicted, 1000u);
  EXPECT_EQ(paged.pagingStats().seconds_writer, 0.0);
  paged.ensureAllResident();
  std::string why;
  EXPECT_TRUE(sameBlocks(paged, fullInMemory(), &why)) << why;
}

INSTANTIATE_TEST_SUITE_P(Stores, Paging,
                         ::testing::Values(PageStoreKind::kSqlite, PageStoreKind::kLmdb),
                         [](const auto& info) {
                           return info.param == PageStoreKind::kLmdb ? "Lmdb" : "Sqlite";
                         });

}  // namespace
}  // namespace fragg::test
