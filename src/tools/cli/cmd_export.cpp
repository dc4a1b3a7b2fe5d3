// fragg_map export MAP --format bt|ply|pcd -o FILE
#include <fmt/format.h>

#include <memory>
#include <string>

#include "cli/commands.h"
#include "cli/map_input.h"
#include "fragg_map/errors.h"
#include "fragg_map/interop/export.h"
#ifdef FRAGG_HAVE_OCTOMAP
#include "fragg_map/interop/octomap_io.h"
#endif

namespace fragg::cli {
namespace {

struct ExportArgs {
  std::string input;
  std::string output;
  std::string format;  // "" = from the output's extension
};

std::string formatOf(const ExportArgs& args) {
  if (!args.format.empty()) return args.format;
  const std::string ext = extensionOf(args.output);
  if (ext == "bt" || ext == "ply" || ext == "pcd") return ext;
  throw InvalidArgument(fmt::format(
      "export: cannot tell the format from '{}'; pass --format bt|ply|pcd", args.output));
}

void runExport(const ExportArgs& args) {
  const std::string format = formatOf(args);
#ifndef FRAGG_HAVE_OCTOMAP
  if (format == "bt")
    throw InvalidArgument("export: this fragg_map was built without liboctomap: no .bt export");
#endif
  checkOutputDirectory(args.output);
  const fragg::Map map = loadMapFile(args.input);
  if (format == "ply" || format == "pcd") {
    const size_t n =
        format == "ply" ? exportOccupiedPly(map, args.output) : exportOccupiedPcd(map, args.output);
    fmt::print("exported {} occupied voxel centres to {} ({})\n", n, args.output, format);
    return;
  }
#ifdef FRAGG_HAVE_OCTOMAP
  exportOctomap(map, args.output);
  fmt::print("exported {} observed cells to {} (OctoMap binary tree, {} m)\n",
             map.knownVoxelCount(), args.output, map.resolution());
#endif
}

}  // namespace

void addExportCommand(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "export", "Export a map as an OctoMap .bt file, or its occupied voxel centres as PLY/PCD");
  cmd->add_option("map", args->input, "Map file (.fgm, or OctoMap .bt / .ot)")->required();
  cmd->add_option("-f,--format", args->format,
                  "bt | ply | pcd (default: from the output file's extension)")
      ->check(CLI::IsMember({"bt", "ply", "pcd"}));
  cmd->add_option("-o,--output", args->output, "Output file (written atomically)")->required();
  cmd->callback([args] { runExport(*args); });
}

}  // namespace fragg::cli
