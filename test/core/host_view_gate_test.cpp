// HostViewGate (Map::hostBlockView's pins against a reader's write-back): a write-back waits
// for the pins held, a pin waits for a write-back in progress, pins nest on one thread, and a
// thread that holds a pin and would write back gets an error instead of waiting for itself.
// Ordering is checked through the gate's waiting counters and handshakes, never through
// wall-clock durations.
#include "fragg_map/internal/host_view_gate.h"

#include <gtest/gtest.h>

#include <atomic>
#include <memory>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "fragg_map/map.h"
#include "test_scenes.h"

namespace fragg {
namespace {

/// Waits (yielding) until `ready()` holds; false when it did not within ~10 s of tries.
template <class Ready>
bool waitFor(Ready ready) {
  for (long i = 0; i < 20'000'000; ++i) {
    if (ready()) return true;
    std::this_thread::yield();
  }
  return ready();
}

TEST(HostViewGate, AWriteBackWaitsUntilThePinsAreGone) {
  auto gate = std::make_shared<HostViewGate>();
  HostViewGate::Pin pin = gate->pin();
  HostViewGate::Pin copy = pin;  // a copied view holds the same pin
  std::atomic<bool> written{false};
  std::thread writer([&] { gate->exclusive([&] { written = true; }); });
  // (EXPECT, not ASSERT: the threads are joined whatever happens.)
  EXPECT_TRUE(waitFor([&] { return gate->writersWaiting() == 1 || written; }));
  EXPECT_FALSE(written.load()) << "written back while a view was held";
  pin.reset();
  EXPECT_EQ(gate->pins(), 1u) << "the copy still pins";
  EXPECT_FALSE(written.load());
  copy.reset();
  writer.join();
  EXPECT_TRUE(written.load());
  EXPECT_EQ(gate->pins(), 0u);
}

TEST(HostViewGate, APinWaitsForAWriteBackInProgress) {
  auto gate = std::make_shared<HostViewGate>();
  std::atomic<bool> inside{false}, go_on{false}, written{false}, saw_written{false};
  std::thread writer([&] {
    gate->exclusive([&] {
      inside = true;
      while (!go_on) std::this_thread::yield();
      written = true;
    });
  });
  EXPECT_TRUE(waitFor([&] { return inside.load(); }));
  std::atomic<bool> pinned{false};
  std::thread reader([&] {
    HostViewGate::Pin pin = gate->pin();
    pinned = true;
    saw_written = written.load();
  });
  EXPECT_TRUE(waitFor([&] { return gate->pinsWaiting() == 1 || pinned; }));
  go_on = true;
  writer.join();
  reader.join();
  EXPECT_TRUE(saw_written.load()) << "a view was taken while the blocks were written";
}

TEST(HostViewGate, ANewPinWaitsBehindAWaitingWriteBack) {
  // Writers first: views taken over and over must not keep a write-back waiting for ever.
  auto gate = std::make_shared<HostViewGate>();
  HostViewGate::Pin held = gate->pin();
  std::atomic<bool> written{false}, pinned{false}, saw_written{false};
  std::thread writer([&] { gate->exclusive([&] { written = true; }); });
  EXPECT_TRUE(waitFor([&] { return gate->writersWaiting() == 1 || written; }));
  std::thread reader([&] {
    HostViewGate::Pin pin = gate->pin();
    pinned = true;
    saw_written = written.load();
  });
  EXPECT_TRUE(waitFor([&] { return gate->pinsWaiting() == 1 || pinned; }));
  EXPECT_FALSE(pinned.load()) << "a new view went ahead of the waiting write-back";
  held.reset();
  writer.join();
  reader.join();
  EXPECT_TRUE(saw_written.load());
}

TEST(HostViewGate, PinsNestOnAThreadAndItsOwnWriteBackIsAnError) {
  auto gate = std::make_shared<HostViewGate>();
  bool written = false;
  {
    HostViewGate::Pin outer = gate->pin();
    HostViewGate::Pin inner = gate->pin();  // no wait: this thread already reads
    EXPECT_EQ(gate->pins(), 2u);
    EXPECT_EQ(gate->pinsOfThisThread(), 2u);
    try {
      gate->exclusive([&] { written = true; });
      ADD_FAILURE() << "a write-back under this thread's own view did not throw";
    } catch (const std::logic_error& e) {
      EXPECT_NE(std::string(e.what()).find("hostBlockView"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(written);
  }
  EXPECT_EQ(gate->pins(), 0u);
  gate->exclusive([&] { written = true; });
  EXPECT_TRUE(written);
}

TEST(HostViewGate, APinReleasedOnAnotherThreadCountsForTheThreadThatTookIt) {
  auto gate = std::make_shared<HostViewGate>();
  HostViewGate::Pin pin = gate->pin();
  std::thread([p = std::move(pin)]() mutable { p.reset(); }).join();
  EXPECT_EQ(gate->pinsOfThisThread(), 0u);
  bool written = false;
  gate->exclusive([&] { written = true; });  // would throw if the pin were still counted here
  EXPECT_TRUE(written);
}

TEST(HostViewGate, AThrowingWriteBackOpensTheGateAgain) {
  auto gate = std::make_shared<HostViewGate>();
  EXPECT_THROW(gate->exclusive([] { throw std::runtime_error("write-back failed"); }),
               std::runtime_error);
  HostViewGate::Pin pin = gate->pin();  // would wait forever if the gate stayed shut
  EXPECT_EQ(gate->pins(), 1u);
}

TEST(HostViewGate, HostAndWholeViewsCoexistOnACpuMap) {
  // A CPU map has nothing to write back: blockView() while this thread holds a hostBlockView()
  // is no error there (the server's CPU paths take both), and both show the same blocks.
  MapParams params;
  params.backend = Backend::kCpu;
  params.threads = 1;
  params.resolution_m = 0.1;
  Map map(params);
  map.insert(test::roomScan(2.0, 1.0, 1.5, 8, 90), Eigen::Isometry3d::Identity(),
             SensorModel::autoFromCloud(0.0, 10.0));
  const BlockView host = map.hostBlockView();
  const BlockView all = map.blockView();
  const size_t blocks = all.size();
  EXPECT_GT(blocks, 0u);
  EXPECT_EQ(host.size(), blocks);
  // A map moved while a view pins its gate keeps working (the gate moves with it; the views
  // of the moved-from map are stale, as any view after a change).
  Map moved = std::move(map);
  EXPECT_EQ(moved.hostBlockView().size(), blocks);
  EXPECT_EQ(moved.blockView().size(), blocks);
}

}  // namespace
}  // namespace fragg
