// The map server's own insertion path answers queries between two clouds (rostest
// cloud_input_lock.test: needs a master). Clouds are published on cloud_in to a CloudInput
// (subscriber -> drop-oldest queue -> insertion thread -> CloudInserter, as the nodelet runs
// it), not inserted by a loop of the test. After each cloud the insertion thread calls the
// server's `on_inserted` hook; there another thread asks the shared map for its read lock
// without waiting (tryRead) and counts the scans. Asserts, for every cloud k of the stream:
// the read lock was free (the server holds the write lock for one scan, never across the
// clouds waiting in its queue), the query saw exactly k whole scans, every cloud was inserted
// and none dropped. No result depends on a duration: tryRead never waits, and the waits for
// the stream (subscriber connected, all clouds inserted) only give up after 60 s.
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <sensor_msgs/PointCloud2.h>
#include <tf2_ros/buffer.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

#include "../../src/ros/server/cloud_input.h"
#include "cloud_msg_builder.h"
#include "fragg_map/map.h"

namespace {

using fragg::ros::CloudInput;
using fragg::ros::ServerParams;
using fragg::ros::ServerStats;
using fragg::ros::SharedMap;
using fragg::ros::test::makeCloud;
using fragg::ros::test::packedXyz;

constexpr int kClouds = 12;

// Cloud i: a wall 3 m ahead, shifted 0.5 m up per cloud, in the map frame (no tf needed).
sensor_msgs::PointCloud2 cloudMsg(int i) {
  std::vector<Eigen::Vector3f> pts;
  for (int a = -10; a <= 10; ++a)
    for (int b = -5; b <= 5; ++b) pts.emplace_back(3.0f, 0.1f * a, 0.5f * i + 0.04f * b);
  sensor_msgs::PointCloud2 msg =
      makeCloud(pts, static_cast<uint32_t>(pts.size()), 1, packedXyz(), 12);
  msg.header.frame_id = "map";
  msg.header.stamp = ::ros::Time::now();
  return msg;
}

// Waits up to 60 s for `done` (checked every 10 ms); false when it never came.
template <class Done>
bool waitFor(Done done) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (!done()) {
    if (std::chrono::steady_clock::now() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return true;
}

TEST(CloudInputLock, AQueryIsAnsweredBetweenEveryTwoCloudsOfTheServersInsertion) {
  ServerParams params;
  params.map.backend = fragg::Backend::kCpu;
  params.map.threads = 1;
  params.map.resolution_m = 0.1;
  params.queue_size = kClouds;  // every cloud waits in the queue, none dropped
  params.frame_id = "map";
  SharedMap shared{fragg::ros::MapState(fragg::Map(params.map))};
  ServerStats stats;
  tf2_ros::Buffer tf;

  std::mutex mutex;
  std::vector<int> free_at, scans_seen;  // per cloud: the lock was free, the scans it saw
  std::atomic<int> inserted{0};
  auto on_inserted = [&](const sensor_msgs::PointCloud2&, const fragg::SensorModel&,
                         const Eigen::Isometry3d&, fragg::ros::PublishTimes*) {
    // A query from another thread while the insertion thread is between two clouds.
    bool got = false;
    int scans = -1;
    std::thread query([&] {
      const std::optional<SharedMap::ReadGuard> state = shared.tryRead();
      got = state.has_value();
      if (got) scans = static_cast<int>((*state)->map.scanCount());
    });
    query.join();
    {
      std::lock_guard<std::mutex> lock(mutex);
      free_at.push_back(got ? 1 : 0);
      scans_seen.push_back(scans);
    }
    inserted.fetch_add(1);
  };

  ::ros::NodeHandle nh("~");
  CloudInput input(nh, params, tf, &shared, &stats, on_inserted);
  ::ros::Publisher pub = nh.advertise<sensor_msgs::PointCloud2>("cloud_in", kClouds);
  ASSERT_TRUE(waitFor([&] { return pub.getNumSubscribers() > 0; })) << "cloud_in never connected";
  for (int i = 0; i < kClouds; ++i) pub.publish(cloudMsg(i));
  ASSERT_TRUE(waitFor([&] { return inserted.load() == kClouds; }))
      << inserted.load() << " of " << kClouds << " clouds inserted";

  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_EQ(free_at.size(), static_cast<size_t>(kClouds));
  for (int k = 0; k < kClouds; ++k) {
    EXPECT_EQ(free_at[k], 1) << "the map was still locked after cloud " << k + 1
                             << ": the server held its write lock past one scan";
    EXPECT_EQ(scans_seen[k], k + 1)
        << "the query after cloud " << k + 1 << " saw " << scans_seen[k] << " scans";
  }
  EXPECT_EQ(stats.droppedNoTf(), 0u);
  EXPECT_EQ(shared.read()->map.scanCount(), static_cast<size_t>(kClouds));
}

}  // namespace

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ::ros::init(argc, argv, "cloud_input_lock_test");
  return RUN_ALL_TESTS();
}
