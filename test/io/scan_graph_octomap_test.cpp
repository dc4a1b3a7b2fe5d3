// Cross-check of the ROS- and OctoMap-free ScanGraph parser against liboctomap itself: the real
// sample file, and a multi-node graph with rotations and edges written by liboctomap.
#include <gtest/gtest.h>
#include <octomap/ScanGraph.h>
#include <octomap/octomap.h>

#include <random>
#include <string>
#include <vector>

#include "fragg_map/io/dataset.h"
#include "io_test_util.h"

namespace fragg {
namespace {

// Compares every scan of `path` read by openDataset with liboctomap's ScanGraph::readBinary:
// same points in the sensor frame, and the same map-frame points after the node pose.
void expectSameAsOctomap(const std::string& path, size_t expected_nodes) {
  octomap::ScanGraph graph;
  ASSERT_TRUE(graph.readBinary(path));
  ASSERT_EQ(graph.size(), expected_nodes);

  auto source = openDataset(path);
  ASSERT_EQ(source->size(), std::optional<size_t>(expected_nodes));
  Scan scan;
  for (octomap::ScanGraph::iterator it = graph.begin(); it != graph.end(); ++it) {
    ASSERT_TRUE(source->next(scan));
    const octomap::ScanNode& node = **it;
    ASSERT_EQ(scan.cloud.size(), node.scan->size());
    EXPECT_NE(scan.source.find("node " + std::to_string(node.id)), std::string::npos);
    for (size_t i = 0; i < node.scan->size(); ++i) {
      const octomap::point3d& p = (*node.scan)[i];
      ASSERT_EQ(scan.cloud.points_S[i], Eigen::Vector3f(p.x(), p.y(), p.z())) << "point " << i;
      const octomap::point3d p_map = node.pose.transform(p);
      const Eigen::Vector3d ours = scan.T_map_sensor * scan.cloud.points_S[i].cast<double>();
      ASSERT_NEAR(ours.x(), p_map.x(), 1e-4) << "point " << i;
      ASSERT_NEAR(ours.y(), p_map.y(), 1e-4) << "point " << i;
      ASSERT_NEAR(ours.z(), p_map.z(), 1e-4) << "point " << i;
    }
  }
  EXPECT_FALSE(source->next(scan));
}

TEST(ScanGraphVsOctomap, RealSample) {
  expectSameAsOctomap(test::realData("octomap/spherical_scan.graph"), 1);
}

TEST(ScanGraphVsOctomap, GraphWrittenByLiboctomap) {
  const std::string path = test::scratchDir() + "/three.graph";
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> coord(-20.0f, 20.0f);
  std::uniform_real_distribution<double> angle(-3.0, 3.0);
  {
    octomap::ScanGraph graph;
    for (int n = 0; n < 3; ++n) {
      auto* cloud = new octomap::Pointcloud();  // owned by the graph
      for (int i = 0; i < 500 + 100 * n; ++i) cloud->push_back(coord(rng), coord(rng), coord(rng));
      graph.addNode(cloud, octomap::pose6d(coord(rng), coord(rng), coord(rng), angle(rng),
                                           angle(rng) / 2, angle(rng)));
      graph.connectPrevious();
    }
    ASSERT_TRUE(graph.writeBinary(path));
  }
  expectSameAsOctomap(path, 3);
  EXPECT_NE(openDataset(path)->describe().find("2 edges"), std::string::npos);
}

}  // namespace
}  // namespace fragg
