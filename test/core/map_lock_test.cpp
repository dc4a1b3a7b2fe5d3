// fragg::Locked / LockedMap: readers share the lock, a writer holds it alone, and a query is
// answered between two scans of a long insertion when the writer takes the lock per scan (the
// writer here is the test's own loop: the lock itself is under test; that the map server's
// insertion path takes it per scan is checked by test/ros/cloud_input_lock_test.cpp). Ordering is
// checked through counters and handshakes, never through wall-clock durations.
#include "fragg_map/map_lock.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <mutex>
#include <thread>

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

}  // namespace
}  // namespace fragg
