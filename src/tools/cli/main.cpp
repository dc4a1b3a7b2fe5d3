// fragg_map: build, inspect, export, render and compare occupancy maps.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "cli/commands.h"
#include "command_error.h"
#include "fragg_map/errors.h"
#include "fragg_map/log.h"

int main(int argc, char** argv) {
  CLI::App app{
      "fragg_map: GPU-accelerated 3D occupancy maps (build, stats, export, render, "
      "compare, eval, octomap-build, truncate, merge, collide, convert-store)"};
  app.require_subcommand(1);
  // The backend choice is part of each command's summary line; warnings go to stderr.
  fragg::setLogSink([](fragg::LogLevel level, const std::string& message) {
    if (level == fragg::LogLevel::kWarning)
      std::fprintf(stderr, "fragg_map: warning: %s\n", message.c_str());
  });
  fragg::cli::addBuildCommand(app);
  fragg::cli::addCorrectCommand(app);
  fragg::cli::addTruncateCommand(app);
  fragg::cli::addMergeCommand(app);
  fragg::cli::addStatsCommand(app);
  fragg::cli::addExportCommand(app);
  fragg::cli::addRenderCommand(app);
  fragg::cli::addCompareCommand(app);
  fragg::cli::addEvalCommand(app);
  fragg::cli::addOctomapBuildCommand(app);
  fragg::cli::addCollideCommand(app);
  fragg::cli::addFrontiersCommand(app);
  fragg::cli::addConvertStoreCommand(app);
  const std::string command_error = fragg::tools::commandError(app, argc, argv);
  if (!command_error.empty()) {
    std::fprintf(stderr, "fragg_map: error: %s\n", command_error.c_str());
    return 2;
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help
    std::fprintf(stderr, "fragg_map: error: %s (see --help)\n", e.what());
    return 2;
  } catch (const fragg::InvalidArgument& e) {
    std::fprintf(stderr, "fragg_map: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fragg_map: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
