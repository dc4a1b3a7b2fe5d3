// fragg::Locked / LockedMap: readers share the lock, a writer holds it alone, and a query is
// answered between two scans of a long insertion when the writer takes the lock per scan (the
// writer here is the test's own loop: the lock itself is under test; that the map server's
// insertion path takes it per scan is checked by test/ros/cloud_input_lock_test.cpp). Ordering is
// checked through counters and handshakes, never through wall-clock durations.
#include "fragg_map/map_lock.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "test_scenes.h"

namespace fragg {
namespace {

MapParams cpuParams() {
  MapParams p;
  p.backend = Backend::kCpu;
  p.threads = 1;
  p.resolution_m = 0.1;
  return p;
}

// Scan i: one hit 2.03 m from the origin at azimuth 7 i degrees: every scan occupies its own
// voxel and no ray (radial) crosses another scan's hit. Float, as the cloud holds it, so that
// the query looks in the voxel the map integrated.
Eigen::Vector3d hitOfScan(int i) {
  const double azimuth_rad = 7.0 * i * M_PI / 180.0;
  const Eigen::Vector3f p(2.03 * std::cos(azimuth_rad), 2.03 * std::sin(azimuth_rad), 0.05);
  return p.cast<double>();
}

PointCloud scanCloud(int i) { return test::cloudOf({hitOfScan(i).cast<float>()}); }

// Occupied voxels among the hits of scans 0..n-1.
int occupiedHits(const Map& map, int n) {
  int occupied = 0;
  for (int i = 0; i < n; ++i) occupied += map.query(hitOfScan(i)) == CellState::kOccupied;
  return occupied;
}

// A one-shot flag another thread can wait for; the wait gives up after 30 s so that a
// broken lock fails the test instead of hanging it (no result depends on the duration).
class Flag {
 public:
  void set() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      set_ = true;
    }
    cv_.notify_all();
  }
  bool wait() {
    std::unique_lock<std::mutex> lock(mutex_);
    return cv_.wait_for(lock, std::chrono::seconds(30), [this] { return set_; });
  }

 private:
  std::mutex mutex_;
  std::condition_variable cv_;
  bool set_ = false;
};

TEST(MapLock, TwoReadersHoldTheLockAtOnce) {
  LockedMap locked{Map(cpuParams())};
  const LockedMap::ReadGuard first = locked.read();
  bool second_got_it = false;
  std::thread other([&] { second_got_it = locked.tryRead().has_value(); });
  other.join();
  EXPECT_TRUE(second_got_it) << "a reader was refused while another reader held the lock";
  EXPECT_EQ(first->scanCount(), 0u);
}

TEST(MapLock, AWriterExcludesReadersAndWriters) {
  LockedMap locked{Map(cpuParams())};
  bool read_while_writing = true, wrote_while_writing = true, wrote_while_reading = true;
  bool read_after = false;
  {
    const LockedMap::WriteGuard writer = locked.write();
    writer->insert(scanCloud(0), Eigen::Isometry3d::Identity(), SensorModel::autoFromCloud());
    std::thread other([&] {
      read_while_writing = locked.tryRead().has_value();
      wrote_while_writing = locked.tryWrite().has_value();
    });
    other.join();
  }
  {
    const LockedMap::ReadGuard reader = locked.read();
    std::thread other([&] { wrote_while_reading = locked.tryWrite().has_value(); });
    other.join();
  }
  std::thread after([&] {
    const std::optional<LockedMap::ReadGuard> reader = locked.tryRead();
    read_after = reader && (*reader)->scanCount() == 1;
  });
  after.join();
  EXPECT_FALSE(read_while_writing) << "a reader got in while a writer held the lock";
  EXPECT_FALSE(wrote_while_writing) << "two writers held the lock at once";
  EXPECT_FALSE(wrote_while_reading) << "a writer got in while a reader held the lock";
  EXPECT_TRUE(read_after) << "the writer's scan is not there once it released the lock";
}

TEST(MapLock, AQueryIsAnsweredWhileALongInsertionRuns) {
  constexpr int kScans = 40;
  constexpr int kAskAfter = 10;  // the reader asks once this many scans are in
  LockedMap locked{Map(cpuParams())};
  std::atomic<int> inserted{0};  // scans integrated, counted under the write lock
  std::atomic<int> answered_at{-1};
  int occupied_seen = -1;
  size_t scans_seen = 0;
  Flag enough_inserted, answered;
  bool writer_waited = false;

  std::thread writer([&] {
    for (int i = 0; i < kScans; ++i) {
      {
        const LockedMap::WriteGuard map = locked.write();  // one scan per lock, not the batch
        map->insert(scanCloud(i), Eigen::Isometry3d::Identity(), SensorModel::autoFromCloud());
        inserted.store(i + 1);
      }
      if (i + 1 == kAskAfter) {
        enough_inserted.set();
        // Let the reader in before going on: it must get the lock between two scans.
        writer_waited = answered.wait();
      }
    }
  });
  std::thread reader([&] {
    if (!enough_inserted.wait()) return;
    {
      const LockedMap::ReadGuard map = locked.read();
      occupied_seen = occupiedHits(*map, kScans);
      scans_seen = map->scanCount();
      answered_at.store(inserted.load());
    }
    answered.set();
  });
  reader.join();
  writer.join();

  ASSERT_TRUE(writer_waited) << "the reader never got the lock between two scans";
  EXPECT_EQ(answered_at.load(), kAskAfter) << "the query was not answered mid-insertion";
  EXPECT_LT(answered_at.load(), inserted.load());
  // The reader saw a consistent map: exactly the scans inserted before it, each one whole.
  EXPECT_EQ(scans_seen, static_cast<size_t>(kAskAfter));
  EXPECT_EQ(occupied_seen, kAskAfter);
  EXPECT_EQ(inserted.load(), kScans);
  EXPECT_EQ(occupiedHits(*locked.read(), kScans), kScans);
}

TEST(MapLock, ReadersNeverSeeAHalfInsertedScan) {
  // Readers poll without waiting while a writer inserts: every answer they get must match a
  // whole number of scans (the count is bumped under the write lock, with the scan).
  constexpr int kScans = 30;
  LockedMap locked{Map(cpuParams())};
  std::atomic<int> inserted{0};
  std::atomic<bool> done{false};
  std::atomic<int> answers{0}, inconsistent{0};
  std::thread writer([&] {
    for (int i = 0; i < kScans; ++i) {
      const LockedMap::WriteGuard map = locked.write();
      map->insert(scanCloud(i), Eigen::Isometry3d::Identity(), SensorModel::autoFromCloud());
      inserted.store(i + 1);
    }
    done.store(true);
  });
  std::thread reader([&] {
    // One read per scan the writer completes (polling the counter, not the lock, so that the
    // writer is never starved by a reader that keeps taking the lock).
    for (int last = 0; !done.load();) {
      if (inserted.load() == last) {
        std::this_thread::yield();
        continue;
      }
      const std::optional<LockedMap::ReadGuard> map = locked.tryRead();
      if (!map) continue;
      const int n = inserted.load();
      last = n;
      if ((*map)->scanCount() != static_cast<size_t>(n) || occupiedHits(**map, kScans) != n)
        inconsistent.fetch_add(1);
      answers.fetch_add(1);
    }
  });
  writer.join();
  reader.join();
  EXPECT_EQ(inconsistent.load(), 0) << "of " << answers.load() << " answers";
  EXPECT_EQ(occupiedHits(*locked.read(), kScans), kScans);
}

// A writer that finds the lock held names whom it waited for: the reader that held it when it
// came and the one that took it while it waited (glibc's rwlock lets readers in ahead of a
// waiting writer), each once, with the time it held the lock; the holders' board is empty after.
TEST(MapLock, AWriterThatWaitedNamesTheReadersItWaitedFor) {
  LockedMap locked{Map(cpuParams())};
  Flag first_holds, second_holds;
  std::thread first([&] {
    const LockedMap::ReadGuard map = locked.read("first reader");
    first_holds.set();
    // Until the writer waits (a counter, no sleep), then until the second reader holds it too.
    while (locked.writersWaiting() == 0) std::this_thread::yield();
    ASSERT_TRUE(second_holds.wait());
  });
  ASSERT_TRUE(first_holds.wait());
  std::thread second([&] {
    while (locked.writersWaiting() == 0) std::this_thread::yield();
    // Taken while the writer waits: shared with the first reader.
    std::optional<LockedMap::ReadGuard> map;
    while (!(map = locked.tryRead("second reader"))) std::this_thread::yield();
    second_holds.set();
  });
  const std::vector<LockHolder> now = locked.holders();
  ASSERT_EQ(now.size(), 1u);
  EXPECT_STREQ(now[0].who, "first reader");
  EXPECT_FALSE(now[0].writes);
  std::vector<LockHolder> waited_for;
  {
    const LockedMap::WriteGuard map = locked.write("writer", &waited_for);
    const std::vector<LockHolder> holding = locked.holders();
    ASSERT_EQ(holding.size(), 1u);
    EXPECT_STREQ(holding[0].who, "writer");
    EXPECT_TRUE(holding[0].writes);
    EXPECT_EQ(locked.writersWaiting(), 0u);
  }
  first.join();
  second.join();
  ASSERT_EQ(waited_for.size(), 2u);
  std::vector<std::string> names{waited_for[0].who, waited_for[1].who};
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"first reader", "second reader"}));
  for (const LockHolder& h : waited_for) {
    EXPECT_FALSE(h.writes);
    EXPECT_GE(h.held_ms, 0.0);
  }
  EXPECT_TRUE(locked.holders().empty());
  // A writer that found the lock free waited for nobody.
  { const LockedMap::WriteGuard map = locked.write("writer", &waited_for); }
  EXPECT_TRUE(waited_for.empty());
}

// A guard moved out of an optional leaves the board once, when the last owner goes.
TEST(MapLock, AMovedGuardLeavesTheBoardOnce) {
  LockedMap locked{Map(cpuParams())};
  {
    std::optional<LockedMap::ReadGuard> a = locked.tryRead("moved");
    ASSERT_TRUE(a.has_value());
    const LockedMap::ReadGuard b = std::move(*a);
    a.reset();
    ASSERT_EQ(locked.holders().size(), 1u);
    EXPECT_STREQ(locked.holders()[0].who, "moved");
  }
  EXPECT_TRUE(locked.holders().empty());
  EXPECT_TRUE(locked.tryWrite().has_value()) << "the lock was left held";
}

// Holders by name, the longest total first, at most `most` names, no commas (a CSV field).
TEST(LockHolders, DescribedByNameLongestFirst) {
  const std::vector<LockHolder> holders = {{"mirror piece", false, 2.0},
                                           {"stats", false, 1.0},
                                           {"mirror piece", false, 3.5},
                                           {"a, b", true, 0.25},
                                           {"frontiers", false, 40.0}};
  EXPECT_EQ(describeLockHolders(holders),
            "frontiers 40.0 ms; mirror piece x2 5.5 ms; stats 1.0 ms; +1 more");
  EXPECT_EQ(describeLockHolders(holders, 10),
            "frontiers 40.0 ms; mirror piece x2 5.5 ms; stats 1.0 ms; a  b 0.2 ms");
  EXPECT_EQ(describeLockHolders({}), "");
}

// The board remembers the last kKept departures: a writer that waited through more sees the
// most recent ones, oldest first.
TEST(LockHolders, KeepsTheLastDepartures) {
  LockHolders board;
  const LockHolders::Mark mark = board.startWaiting();
  EXPECT_EQ(board.writersWaiting(), 1u);
  static const char* const kNames[] = {"even", "odd"};
  for (size_t i = 0; i < LockHolders::kKept + 5; ++i) {
    HolderTicket t = board.enter(kNames[i % 2], false);
  }
  const std::vector<LockHolder> left = board.doneWaiting(mark);
  EXPECT_EQ(board.writersWaiting(), 0u);
  ASSERT_EQ(left.size(), LockHolders::kKept);
  EXPECT_STREQ(left.front().who, kNames[5 % 2]);  // departures 5 .. kKept + 4
  EXPECT_STREQ(left.back().who, kNames[(LockHolders::kKept + 4) % 2]);
}

}  // namespace
}  // namespace fragg
