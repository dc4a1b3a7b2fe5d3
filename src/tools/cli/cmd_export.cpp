// fragg_map export MAP --format bt|ot|ply|pcd [--no-prune] -o FILE
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
  std::string format;     // "" = from the output's extension
  bool no_prune = false;  // ot: one leaf per cell (octomap_server's compress_map false)
};

std::string formatOf(const ExportArgs& args) {
  if (!args.format.empty()) return args.format;
  const std::string ext = extensionOf(args.output);
  if (ext == "bt" || ext == "ot" || ext == "ply" || ext == "pcd") return ext;
  throw InvalidArgument(fmt::format(
      "export: cannot tell the format from '{}'; pass --format bt|ot|ply|pcd", args.output));
}

void runExport(const ExportArgs& args) {
  const std::string format = formatOf(args);
#ifndef FRAGG_HAVE_OCTOMAP
  if (format == "bt" || format == "ot")
    throw InvalidArgument("export: this fragg_map was built without liboctomap: no ." + format +
                          " export");
#endif
  if (args.no_prune && format != "ot")
    throw InvalidArgument("export: --no-prune applies to the ot format only");
  checkOutputDirectory(args.output);
  const fragg::Map map = loadMapFile(args.input);
  if (format == "ply" || format == "pcd") {
    const size_t n =
        format == "ply" ? exportOccupiedPly(map, args.output) : exportOccupiedPcd(map, args.output);
    fmt::print("exported {} occupied voxel centres to {} ({})\n", n, args.output, format);
    return;
  }
#ifdef FRAGG_HAVE_OCTOMAP
  if (format == "ot") {
    exportOctomapFull(map, args.output, !args.no_prune);
    fmt::print("exported {} observed cells to {} (OctoMap full tree, {}, {} m)\n",
               map.knownVoxelCount(), args.output, args.no_prune ? "one leaf a cell" : "pruned",
               map.resolution());
    return;
  }
  exportOctomap(map, args.output);
  fmt::print("exported {} observed cells to {} (OctoMap binary tree, {} m)\n",
             map.knownVoxelCount(), args.output, map.resolution());
#endif
}

}  // namespace

void addExportCommand(CLI::App& app) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "export",
      "Export a map as an OctoMap .bt (free/occupied) or .ot (full log-odds) file, or its "
      "occupied voxel centres as PLY/PCD");
  cmd->add_option("map", args->input, "Map file (.fgm, or OctoMap .bt / .ot)")->required();
  cmd->add_option("-f,--format", args->format,
                  "bt | ot | ply | pcd (default: from the output file's extension)")
      ->check(CLI::IsMember({"bt", "ot", "ply", "pcd"}));
  cmd->add_flag("--no-prune", args->no_prune,
                "ot: one leaf per cell; by default eight equal sibling leaves are merged, as "
                "octomap_server's octomap_full with compress_map (lossless)");
  cmd->add_option("-o,--output", args->output, "Output file (written atomically)")->required();
  cmd->callback([args] { runExport(*args); });
}

}  // namespace fragg::cli
