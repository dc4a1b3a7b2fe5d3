// The map server's paging parameters (paging/*) and its map: a new store is paged to, an
// existing store's map is continued, bad values are refused naming the parameter.
#include "fragg_map/ros/paging_params.h"

#include <gtest/gtest.h>

#include <string>

#include "../paging/paging_scenes.h"
#include "fragg_map/errors.h"

namespace {

using fragg::test::corridorParams;
using fragg::test::corridorPose;
using fragg::test::corridorScan;
using fragg::test::corridorSensor;
using XmlRpc::XmlRpcValue;

constexpr int kScans = 80;

void insertScans(fragg::Map& map, int from, int to) {
  for (int i = from; i < to; ++i) {
    const Eigen::Isometry3d T = corridorPose(i, kScans);
    map.insert(corridorScan(T), T, corridorSensor());
  }
}

void expectRejected(XmlRpcValue root, const std::string& name) {
  fragg::MapParams map;
  try {
    fragg::ros::parsePagingParameters(root, &map);
    FAIL() << name << ": accepted";
  } catch (const fragg::InvalidArgument& e) {
    EXPECT_NE(std::string(e.what()).find("'" + name + "'"), std::string::npos) << e.what();
  }
}

TEST(PagingParams, DefaultsPageNothingAndLeaveTheMapAsItWas) {
  fragg::MapParams map;
  map.scans.keep = true;
  const fragg::ros::PagingParams p = fragg::ros::parsePagingParameters(XmlRpcValue(), &map);
  EXPECT_TRUE(p.store.empty());
  EXPECT_TRUE(map.scans.keep);
  EXPECT_FALSE(fragg::ros::makeServerMap(corridorParams(), p).paging());
}

TEST(PagingParams, AStoreTurnsKeptScansOffAndTakesTheBudget) {
  XmlRpcValue root;
  root["paging"]["store"] = std::string("/tmp/x.lmdb");
  root["paging"]["budget_mb"] = 512;
  root["paging"]["radius_m"] = 30.5;
  root["paging"]["commit_every_scans"] = 20;
  root["paging"]["commit_every_s"] = 0;
  root["paging"]["low_water"] = 0.5;
  root["paging"]["read_ahead_rays"] = 0;
  fragg::MapParams map;
  map.scans.keep = true;  // the server's default
  const fragg::ros::PagingParams p = fragg::ros::parsePagingParameters(root, &map);
  EXPECT_EQ(p.store, "/tmp/x.lmdb");
  EXPECT_EQ(p.policy.budget_mb, 512.0);
  EXPECT_EQ(p.policy.radius_m, 30.5);
  EXPECT_EQ(p.policy.commit_every_scans, 20u);
  EXPECT_EQ(p.policy.commit_every_s, 0.0);
  EXPECT_EQ(p.policy.low_water, 0.5);
  EXPECT_EQ(p.policy.read_ahead_rays, 0u);  // every ray
  EXPECT_FALSE(map.scans.keep);
}

TEST(PagingParams, BadValuesAreRefusedNamingTheParameter) {
  XmlRpcValue with_store;
  with_store["paging"]["store"] = std::string("/tmp/x.db");
  {
    XmlRpcValue r = with_store;
    r["paging"]["budget_mb"] = -1.0;
    expectRejected(r, "paging/budget_mb");
  }
  {
    XmlRpcValue r = with_store;
    r["paging"]["radius_m"] = std::string("far");
    expectRejected(r, "paging/radius_m");
  }
  {
    XmlRpcValue r = with_store;
    r["paging"]["commit_every_scans"] = 2.5;
    expectRejected(r, "paging/commit_every_scans");
  }
  {
    XmlRpcValue r = with_store;
    r["paging"]["low_water"] = 1.5;  // a round cannot leave more than the budget
    expectRejected(r, "paging/low_water");
  }
  {
    XmlRpcValue r = with_store;
    r["paging"]["read_ahead_rays"] = 100.5;
    expectRejected(r, "paging/read_ahead_rays");
  }
  {
    XmlRpcValue r = with_store;
    r["keep_scans"] = true;  // the store holds no scans
    expectRejected(r, "paging/store");
  }
  {
    XmlRpcValue r;
    r["paging"]["store"] = 3;
    expectRejected(r, "paging/store");
  }
  {
    XmlRpcValue r;
    r["paging"]["budget_mb"] = 512;  // no store to page to
    expectRejected(r, "paging/budget_mb");
  }
}

TEST(PagingParams, TheServerMapPagesToANewStoreAndContinuesAnExistingOne) {
  const std::string dir = fragg::test::testDir();
  fragg::ros::PagingParams p;
  p.store = dir + "/server.db";
  // One corridor scan's reach: ~3,900 blocks, 8.7 MiB at 2,332 B a block (4,496 fit: the
  // map's arrays reserved for the budget, Pager::reservedBlockBytes).
  p.policy.budget_mb = 10.0;
  p.policy.radius_m = 4.0;
  p.policy.commit_every_scans = 7;
  p.policy.commit_every_s = 0;
  {
    fragg::Map first = fragg::ros::makeServerMap(corridorParams(), p);
    ASSERT_TRUE(first.paging());
    insertScans(first, 0, kScans / 2);
    EXPECT_GT(first.pagingStats().paged_blocks, 0u);
  }  // the node stops: its last scans are committed
  fragg::Map again = fragg::ros::makeServerMap(corridorParams(), p);
  EXPECT_EQ(again.scanCount(), static_cast<size_t>(kScans / 2));
  EXPECT_GT(again.pagingStats().paged_blocks, 0u);
  insertScans(again, kScans / 2, kScans);
  again.ensureAllResident();
  fragg::Map reference(corridorParams());
  insertScans(reference, 0, kScans);
  std::string why;
  EXPECT_TRUE(fragg::test::sameBlocks(again, reference, &why)) << why;

  // Another resolution than the store's map: refused.
  fragg::MapParams coarse = corridorParams();
  coarse.resolution_m *= 2;
  EXPECT_THROW(fragg::ros::makeServerMap(coarse, p), fragg::InvalidArgument);
}

}  // namespace
