// The bridge between fragg_map's datasets and DUFOMap's input and output for
// scripts/dufomap_side_by_side.sh (built there against a plain CMake build of fragg_map, in a
// git-ignored folder):
//   kth_io convert DATASET OUT_DIR     OUT_DIR/pcd/NNNNNN.pcd, one a scan as fragg::openDataset
//                                      reads it: its finite points in the map frame (float32,
//                                      binary PCD, the order of the labels/*.dyn files) and
//                                      VIEWPOINT = T_map_sensor (the KTH DynamicMap benchmark's
//                                      format, which DUFOMap reads)
//   kth_io tobt KEPT.xyz RES_M OUT.bt  the cell of every kept point (float32 x y z triples, as
//                                      dufomap_eval writes them) occupied at OctoMap's upper
//                                      clamp, nothing else known: DUFOMap's static map as a map
//                                      fragg_map eval reads
//   kth_io intersect A.bt B.bt OUT.bt  the cells occupied in both, with A's log-odds (ghost
//                                      cells the two maps share: fragg_map eval OUT.bt counts
//                                      them, A's cells occupied under fragg's rule)
#include <octomap/OcTree.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <string>
#include <vector>

#include "fragg_map/io/dataset.h"

namespace {

int convert(const std::string& dataset, const std::filesystem::path& out_dir) {
  std::unique_ptr<fragg::ScanSource> source = fragg::openDataset(dataset);
  std::filesystem::create_directories(out_dir / "pcd");
  fragg::Scan scan;
  size_t index = 0, total = 0;
  while (source->next(scan)) {
    std::vector<float> xyz_map;
    for (const Eigen::Vector3f& p_S : scan.cloud.points_S) {
      if (!p_S.allFinite()) continue;
      const Eigen::Vector3d p_map = scan.T_map_sensor * p_S.cast<double>();
      xyz_map.insert(xyz_map.end(), {float(p_map.x()), float(p_map.y()), float(p_map.z())});
    }
    const size_t n = xyz_map.size() / 3;
    total += n;
    const Eigen::Vector3d t = scan.T_map_sensor.translation();
    const Eigen::Quaterniond q(scan.T_map_sensor.rotation());
    char name[32];
    std::snprintf(name, sizeof name, "%06zu.pcd", index++);
    std::ofstream f(out_dir / "pcd" / name, std::ios::binary);
    f.precision(17);
    f << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH " << n
      << "\nHEIGHT 1\nVIEWPOINT " << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.w() << ' '
      << q.x() << ' ' << q.y() << ' ' << q.z() << "\nPOINTS " << n << "\nDATA binary\n";
    f.write(reinterpret_cast<const char*>(xyz_map.data()),
            static_cast<std::streamsize>(xyz_map.size() * sizeof(float)));
    if (!f) throw std::runtime_error("cannot write " + (out_dir / "pcd" / name).string());
  }
  std::cout << "converted " << index << " scans, " << total << " finite points\n";
  return 0;
}

int toBt(const std::string& kept_path, double res_m, const std::string& out_bt) {
  std::ifstream in(kept_path, std::ios::binary);
  if (!in) throw std::runtime_error("cannot open " + kept_path);
  const std::vector<char> raw{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (raw.size() % (3 * sizeof(float)) != 0)
    throw std::runtime_error(kept_path + ": not float32 x y z triples");
  std::vector<float> xyz(raw.size() / sizeof(float));
  std::copy(raw.begin(), raw.end(), reinterpret_cast<char*>(xyz.data()));
  octomap::OcTree tree(res_m);
  for (size_t i = 0; i < xyz.size(); i += 3)
    tree.setNodeValue(octomap::point3d(xyz[i], xyz[i + 1], xyz[i + 2]),
                      tree.getClampingThresMaxLog());
  if (!tree.writeBinary(out_bt)) throw std::runtime_error("cannot write " + out_bt);
  std::cout << "kept points " << xyz.size() / 3 << ", occupied cells " << tree.getNumLeafNodes()
            << "\n";
  return 0;
}

std::unique_ptr<octomap::OcTree> readBt(const std::string& path) {
  auto tree = std::make_unique<octomap::OcTree>(0.1);
  if (!tree->readBinary(path)) throw std::runtime_error("cannot read " + path);
  return tree;
}

int intersect(const std::string& a_bt, const std::string& b_bt, const std::string& out_bt) {
  const std::unique_ptr<octomap::OcTree> a = readBt(a_bt), b = readBt(b_bt);
  if (a->getResolution() != b->getResolution())
    throw std::runtime_error("the two maps' resolutions differ");
  octomap::OcTree both(a->getResolution());
  size_t cells = 0;
  a->expand();
  for (auto it = a->begin_leafs(); it != a->end_leafs(); ++it) {
    if (!a->isNodeOccupied(*it)) continue;
    const octomap::OcTreeNode* n = b->search(it.getKey());
    if (n == nullptr || !b->isNodeOccupied(n)) continue;
    both.setNodeValue(it.getKey(), it->getLogOdds());  // A's state: eval applies A's rule
    ++cells;
  }
  if (!both.writeBinary(out_bt)) throw std::runtime_error("cannot write " + out_bt);
  std::cout << "occupied in both: " << cells << " cells\n";
  return 0;
}

}  // namespace

int main(int argc, char** argv) try {
  const std::string cmd = argc > 1 ? argv[1] : "";
  if (cmd == "convert" && argc == 4) return convert(argv[2], argv[3]);
  if (cmd == "tobt" && argc == 5) return toBt(argv[2], std::stod(argv[3]), argv[4]);
  if (cmd == "intersect" && argc == 5) return intersect(argv[2], argv[3], argv[4]);
  std::cerr << "usage: kth_io convert DATASET OUT_DIR | tobt KEPT.xyz RES_M OUT.bt | "
               "intersect A.bt B.bt OUT.bt\n";
  return 2;
} catch (const std::exception& e) {
  std::cerr << "kth_io: " << e.what() << "\n";
  return 1;
}
