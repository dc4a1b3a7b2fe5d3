// fragg_map_sim: scenes, simulated LiDAR and depth-camera recordings (KITTI-style folders,
// depth-image folders, ROS bags), deterministic for a seed.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "command_error.h"
#include "fragg_map/errors.h"
#include "sim/commands.h"

int main(int argc, char** argv) {
  CLI::App app{"fragg_map_sim: simulated scenes and sensors (LiDAR, depth camera) for fragg_map"};
  app.require_subcommand(1);
  fragg::sim::tool::addSceneCommand(app);
  fragg::sim::tool::addRecordCommand(app);
  app.add_subcommand("info", "Print what this build can write (bag output needs ROS)")
      ->callback([] {
#ifdef FRAGG_HAVE_SIM_BAG
        std::printf("bag_output yes\n");
#else
        std::printf("bag_output no\n");
#endif
      });
  const std::string command_error = fragg::tools::commandError(app, argc, argv);
  if (!command_error.empty()) {
    std::fprintf(stderr, "fragg_map_sim: error: %s\n", command_error.c_str());
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    std::fprintf(stderr, "fragg_map_sim: error: %s (see --help)\n", e.what());
    return 2;
  } catch (const fragg::InvalidArgument& e) {
    std::fprintf(stderr, "fragg_map_sim: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map_sim: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
