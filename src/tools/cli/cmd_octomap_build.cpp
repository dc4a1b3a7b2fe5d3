// fragg_map octomap-build INPUT -o MAP.bt: OctoMap's map of a dataset (insertPointCloud with
// OctoMap's default sensor model), the reference `fragg_map eval --octomap` compares against.
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <string>

#include "cli/commands.h"
#include "cli/map_input.h"
#include "fragg_map/errors.h"
#include "fragg_map/io/dataset.h"
#ifdef FRAGG_HAVE_OCTOMAP
#include "fragg_map/interop/octomap_insert.h"
#endif
#ifdef FRAGG_HAVE_ROSBAG
#include "fragg_map/io/rosbag_source.h"
#endif

namespace fragg::cli {
namespace {

struct OctomapBuildOptions {
  std::string input, output, topic, frame = "map";
  double resolution_m = 0.05, max_range_m = -1.0;
  size_t max_scans = 0;
};

void runOctomapBuild(const OctomapBuildOptions& o) {
#ifndef FRAGG_HAVE_OCTOMAP
  throw InvalidArgument("octomap-build: this fragg_map was built without liboctomap");
#else
  if (!(o.resolution_m > 0)) throw InvalidArgument("--resolution must be > 0");
  if (extensionOf(o.output) != "bt") throw InvalidArgument("octomap-build writes a .bt file");
  checkOutputDirectory(o.output);
#ifdef FRAGG_HAVE_ROSBAG
  registerRosbagReader();
#endif
  DatasetOptions dataset_options;
  dataset_options.topic = o.topic;
  dataset_options.frame = o.frame;
  auto source = openDataset(o.input, dataset_options);
  octomap::OcTree tree(o.resolution_m);
  Scan scan;
  size_t scans = 0;
  double seconds = 0;
  while ((o.max_scans == 0 || scans < o.max_scans) && source->next(scan)) {
    if (scan.cloud.empty()) continue;
    seconds += insertIntoOcTree(tree, scan, o.max_range_m);
    ++scans;
  }
  const std::string tmp = o.output + ".tmp.bt";
  if (!tree.writeBinary(tmp) || std::rename(tmp.c_str(), o.output.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw IoError("cannot write " + o.output);
  }
  std::printf("%s", fmt::format("built {} with OctoMap: {} scans, {:.2f} s in insertPointCloud "
                                "({:.1f} ms/scan), {} leaves\n",
                                o.output, scans, seconds, scans ? 1e3 * seconds / scans : 0.0,
                                tree.getNumLeafNodes())
                        .c_str());
#endif
}

}  // namespace

void addOctomapBuildCommand(CLI::App& app) {
  auto o = std::make_shared<OctomapBuildOptions>();
  CLI::App* c = app.add_subcommand(
      "octomap-build",
      "Build OctoMap's map of a dataset (OcTree::insertPointCloud, OctoMap's default sensor "
      "model) and write it as .bt: the reference for `eval --octomap`");
  c->add_option("input", o->input, "Dataset to read (as for build)")->required();
  c->add_option("-o,--output", o->output, "OctoMap binary tree to write (.bt)")->required();
  c->add_option("--resolution", o->resolution_m, "Voxel edge in metres")->capture_default_str();
  c->add_option("--max-range", o->max_range_m, "insertPointCloud's max range (<= 0: none)")
      ->capture_default_str();
  c->add_option("--scans", o->max_scans, "Integrate only the first N scans (0 = all)")
      ->capture_default_str();
  c->add_option("--topic", o->topic, "Bag: PointCloud2 topic (default: the only one)");
  c->add_option("--frame", o->frame, "Bag: fixed frame of the map")->capture_default_str();
  c->callback([o] { runOctomapBuild(*o); });
}

}  // namespace fragg::cli
