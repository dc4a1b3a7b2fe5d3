// The map server's ROS-free parts: the drop-oldest cloud queue, the timing statistics and the
// rate throttle of marker_rate and map_rate.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

#include "fragg_map/errors.h"
#include "fragg_map/ros/drop_oldest_queue.h"
#include "fragg_map/ros/rate_throttle.h"
#include "fragg_map/ros/timing_stats.h"

namespace {

using fragg::ros::DropOldestQueue;

TEST(DropOldestQueue, KeepsTheNewestAndCountsTheDropped) {
  DropOldestQueue<int> q(3);
  EXPECT_FALSE(q.push(1));
  EXPECT_FALSE(q.push(2));
  EXPECT_FALSE(q.push(3));
  EXPECT_TRUE(q.push(4));  // drops 1
  EXPECT_TRUE(q.push(5));  // drops 2
  EXPECT_EQ(q.size(), 3u);
  EXPECT_EQ(q.dropped(), 2u);
  int v = 0;
  for (int want : {3, 4, 5}) {
    ASSERT_TRUE(q.pop(&v));
    EXPECT_EQ(v, want);
  }
  EXPECT_EQ(q.size(), 0u);
}

TEST(DropOldestQueue, CloseWakesAWaitingConsumer) {
  DropOldestQueue<int> q(2);
  std::atomic<bool> returned{false};
  bool result = true;
  std::thread consumer([&] {
    int v;
    result = q.pop(&v);
    returned = true;
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_FALSE(returned.load());
  q.close();
  consumer.join();
  EXPECT_FALSE(result);
  EXPECT_FALSE(q.push(7));  // discarded after close
  EXPECT_EQ(q.size(), 0u);
}

TEST(DropOldestQueue, ProducerConsumerLosesNothingButTheCountedDrops) {
  DropOldestQueue<int> q(4);
  std::vector<int> got;
  std::thread consumer([&] {
    int v;
    while (q.pop(&v)) {
      got.push_back(v);
      if (v == 999) return;
    }
  });
  for (int i = 0; i < 1000; ++i) q.push(i);
  consumer.join();
  q.close();
  EXPECT_EQ(got.size() + q.dropped(), 1000u);
  for (size_t i = 1; i < got.size(); ++i) EXPECT_LT(got[i - 1], got[i]);  // order kept
  EXPECT_EQ(got.back(), 999);  // the newest always survives
}

TEST(DropOldestQueue, ZeroCapacityIsRejected) {
  EXPECT_THROW(DropOldestQueue<int>(0), fragg::InvalidArgument);
}

TEST(TimingStats, LastMeanAndP99) {
  fragg::ros::TimingStats t(1000);
  EXPECT_EQ(t.percentileMs(0.99), 0.0);
  for (int i = 1; i <= 100; ++i) t.add(i);
  EXPECT_EQ(t.count(), 100u);
  EXPECT_EQ(t.lastMs(), 100.0);
  EXPECT_DOUBLE_EQ(t.meanMs(), 50.5);
  EXPECT_EQ(t.percentileMs(0.99), 99.0);
  EXPECT_EQ(t.percentileMs(0.5), 50.0);
  t.clear();
  EXPECT_EQ(t.count(), 0u);
  EXPECT_EQ(t.meanMs(), 0.0);
}

TEST(TimingStats, PercentileFollowsTheWindowMeanFollowsEverything) {
  fragg::ros::TimingStats t(10);
  for (int i = 0; i < 10; ++i) t.add(1000.0);
  for (int i = 0; i < 10; ++i) t.add(1.0);  // pushes every 1000 out of the window
  EXPECT_EQ(t.percentileMs(0.99), 1.0);
  EXPECT_DOUBLE_EQ(t.meanMs(), 500.5);
  EXPECT_THROW(fragg::ros::TimingStats(0), fragg::InvalidArgument);
}

TEST(RateThrottle, NoLimitIsAlwaysDue) {
  fragg::ros::RateThrottle t(0.0);
  EXPECT_FALSE(t.limited());
  EXPECT_TRUE(t.due(5.0));
  t.published(5.0);
  EXPECT_TRUE(t.due(5.0));
}

TEST(RateThrottle, AtMostOneUpdatePerPeriod) {
  fragg::ros::RateThrottle t(2.0);  // 2 Hz
  EXPECT_TRUE(t.limited());
  EXPECT_EQ(t.periodS(), 0.5);
  EXPECT_TRUE(t.due(100.0));  // the first update goes out at once
  t.published(100.0);
  EXPECT_FALSE(t.due(100.0));
  EXPECT_FALSE(t.due(100.49));
  EXPECT_TRUE(t.due(100.5));
  t.published(100.7);  // the period counts from the last update
  EXPECT_FALSE(t.due(101.1));
  EXPECT_TRUE(t.due(101.2));
  EXPECT_THROW(fragg::ros::RateThrottle(-1.0), fragg::InvalidArgument);
  EXPECT_THROW(fragg::ros::RateThrottle(std::nan("")), fragg::InvalidArgument);
}

// map_rate (as marker_rate) on a 10 Hz cloud stream: the clouds after which the whole-map
// outputs go out, the insertion thread asking after each cloud as MapPublishers does.
std::vector<int> dueClouds(double rate_hz, int clouds, double cloud_rate_hz) {
  fragg::ros::RateThrottle t(rate_hz);
  std::vector<int> out;
  for (int i = 0; i < clouds; ++i) {
    const double now_s = 50.0 + i / cloud_rate_hz;
    if (!t.due(now_s)) continue;
    t.published(now_s);
    out.push_back(i);
  }
  return out;
}

TEST(RateThrottle, MapRateOnACloudStream) {
  EXPECT_EQ(dueClouds(0.0, 5, 10.0), (std::vector<int>{0, 1, 2, 3, 4}));  // every cloud
  EXPECT_EQ(dueClouds(1.0, 31, 10.0), (std::vector<int>{0, 10, 20, 30}));
  EXPECT_EQ(dueClouds(0.2, 101, 10.0), (std::vector<int>{0, 50, 100}));
  EXPECT_EQ(dueClouds(4.0, 10, 10.0), (std::vector<int>{0, 3, 6, 9}));  // 0.3 s apart
  // Faster than the clouds: every cloud.
  EXPECT_EQ(dueClouds(20.0, 4, 10.0), (std::vector<int>{0, 1, 2, 3}));
}

TEST(HeldBackUpdate, HoldsTheLastStampUntilPublishedOrDropped) {
  fragg::ros::HeldBackUpdate<int> h(2.0);  // 2 Hz; stamps are cloud numbers here
  EXPECT_FALSE(h.flushDue(10.0));          // nothing held back yet
  EXPECT_TRUE(h.letThrough(10.0, 1));      // the first update goes out
  h.published(10.0);
  EXPECT_FALSE(h.letThrough(10.1, 2));  // held back ...
  EXPECT_FALSE(h.letThrough(10.2, 3));  // ... with the last cloud's stamp
  EXPECT_EQ(h.pendingStamp(), 3);
  EXPECT_FALSE(h.flushDue(10.4));  // not due before the period is over
  EXPECT_TRUE(h.flushDue(10.5));
  h.published(10.5);  // the timer sent it: nothing is held back
  EXPECT_FALSE(h.flushDue(20.0));
  EXPECT_FALSE(h.letThrough(10.6, 4));
  h.drop();  // no subscriber left: nothing to send later
  EXPECT_FALSE(h.flushDue(20.0));
  fragg::ros::HeldBackUpdate<int> unlimited(0.0);
  EXPECT_TRUE(unlimited.letThrough(1.0, 1));
  unlimited.published(1.0);
  EXPECT_TRUE(unlimited.letThrough(1.0, 2));
}

TEST(RateThrottle, FlushTickIsATenthOfASecondAtMost) {
  EXPECT_EQ(fragg::ros::RateThrottle(1.0).flushTickS(), 0.1);
  EXPECT_EQ(fragg::ros::RateThrottle(0.2).flushTickS(), 0.1);
  EXPECT_EQ(fragg::ros::RateThrottle(20.0).flushTickS(), 0.05);
}

}  // namespace
