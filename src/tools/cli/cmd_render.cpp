// fragg_map render MAP -o FILE.png [--view top|slice] [--z M] [--scale N] [--frontiers ...]
//                                   [--highlight-ghosts STATIC_SCENE.obj]
#include <fmt/format.h>

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "cli/frontier_drawing.h"
#include "cli/frontier_options.h"
#include "cli/ghost_drawing.h"
#include "cli/map_input.h"
#include "fragg_map/errors.h"
#include "fragg_map/geometry/mesh_bvh.h"
#include "fragg_map/geometry/obj_file.h"
#include "fragg_map/interop/render.h"
#include "fragg_map/sim/scene.h"

namespace fragg::cli {
namespace {

struct RenderArgs {
  std::string input;
  std::string output;
  std::string view = "top";
  std::vector<double> z;  // zero or one value
  int scale = 1;
  std::vector<double> crop;  // zero or six values
  int max_size = RenderOptions().max_side_px;
  bool no_downscale = false;
  bool no_legend = false;
  bool frontiers = false;
  /// The static truth (OBJ or fragg_map_sim scene) whose ghost cells are drawn red.
  std::string ghosts_scene;
  /// The options of `fragg_map frontiers`, but the best viewpoint of each cluster by default.
  FrontierFlags frontier_flags = [] {
    FrontierFlags f;
    f.viewpoints = 1;
    return f;
  }();
};

RenderOptions optionsOf(const RenderArgs& args) {
  RenderOptions options;
  options.scale = args.scale;
  options.max_side_px = args.max_size;
  options.auto_downscale = !args.no_downscale;
  options.legend = !args.no_legend;
  if (!args.crop.empty()) {
    options.crop = Eigen::AlignedBox3d(Eigen::Vector3d(args.crop[0], args.crop[1], args.crop[2]),
                                       Eigen::Vector3d(args.crop[3], args.crop[4], args.crop[5]));
  }
  return options;
}

void runRender(const RenderArgs& args) {
  if (extensionOf(args.output) != "png")
    throw InvalidArgument(
        fmt::format("render: the output must be a .png file, got '{}'", args.output));
  const bool slice = args.view == "slice";
  if (slice && args.z.empty()) throw InvalidArgument("render: --view slice needs --z METRES");
  if (!slice && !args.z.empty()) throw InvalidArgument("render: --z applies to --view slice only");
  if (slice && args.frontiers)
    throw InvalidArgument("render: --frontiers draws over the top view, not --view slice");
  const bool ghosts = !args.ghosts_scene.empty();
  if (ghosts && slice)
    throw InvalidArgument("render: --highlight-ghosts draws over the top view, not --view slice");
  if (ghosts && args.frontiers)
    throw InvalidArgument(
        "render: --highlight-ghosts and --frontiers each draw over the map: "
        "give one");
  const std::string scene_ext = ghosts ? extensionOf(args.ghosts_scene) : "";
  if (ghosts && scene_ext != "obj" && scene_ext != "json")
    throw InvalidArgument(fmt::format(
        "render: --highlight-ghosts needs the static scene as an OBJ file or a fragg_map_sim "
        "scene (.json), got '{}'",
        args.ghosts_scene));
  const RenderOptions options = optionsOf(args);
  std::optional<FrontierSettings> frontier_settings;
  if (args.frontiers) frontier_settings = frontierSettings(args.frontier_flags);
  checkOutputDirectory(args.output);
  const fragg::Map map = loadMapFile(args.input);
  RenderInfo info;
  if (frontier_settings) {
    const FrontierResult frontiers = computeFrontiers(map, *frontier_settings);
    RenderImage image = renderTopDownImage(map, options);
    fadeForOverlay(image);
    const FrontierDrawStats drawn = drawFrontiers(image, map, frontiers, options.crop);
    if (options.legend) appendLegend(image, RenderView::kTop, options);
    writePng(image, args.output);
    info = image.info;
    fmt::print("frontiers: {} cells, {} clusters ({} cells drawn), {} viewpoints drawn\n",
               frontiers.cells.size(), frontiers.clusters.size(), drawn.cells_drawn,
               drawn.viewpoints_drawn);
  } else if (ghosts) {
    const geometry::MeshBvh scene(scene_ext == "obj" ? geometry::readObj(args.ghosts_scene)
                                                     : sim::loadScene(args.ghosts_scene).mesh);
    RenderImage image = renderTopDownImage(map, options);
    const GhostDrawStats drawn = drawGhosts(image, map, scene, options.crop);
    if (options.legend) appendLegend(image, RenderView::kTop, options);
    writePng(image, args.output);
    info = image.info;
    fmt::print("ghosts: {} cells occupied in the map and free in the static scene ({} drawn)\n",
               drawn.ghost_cells, drawn.cells_drawn);
  } else {
    info = slice ? renderSlice(map, args.z[0], args.output, options)
                 : renderTopDown(map, args.output, options);
  }
  std::string detail = fmt::format("{} px per voxel", info.scale);
  if (info.scale < args.scale)
    detail += fmt::format(", lowered from {} to fit --max-size {}", args.scale, args.max_size);
  if (info.voxels_per_pixel > 1)
    detail = fmt::format("downscaled to fit --max-size {}: {} x {} voxels per pixel", args.max_size,
                         info.voxels_per_pixel, info.voxels_per_pixel);
  if (info.legend_height_px > 0)
    detail += fmt::format("; with the legend below, the PNG is {} x {} px", info.width_px,
                          info.height_px);
  if (slice) {
    fmt::print("rendered the slice at z = {:.3f} m to {}: {} x {} px ({})\n", info.z_min_m,
               args.output, info.map_width_px, info.map_height_px, detail);
  } else {
    fmt::print("rendered the top view to {}: {} x {} px ({}), heights {:.2f} .. {:.2f} m\n",
               args.output, info.map_width_px, info.map_height_px, detail, info.z_min_m,
               info.z_max_m);
  }
}

}  // namespace

void addRenderCommand(CLI::App& app) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand(
      "render", "Render a map to PNG: top-down height image or a horizontal slice");
  cmd->add_option("map", args->input, "Map file (.fgm, or OctoMap .bt / .ot)")->required();
  cmd->add_option("-o,--output", args->output, "Output .png file (written atomically)")->required();
  cmd->add_option("--view", args->view, "top (height image, default) | slice")
      ->check(CLI::IsMember({"top", "slice"}));
  cmd->add_option("--z", args->z, "Slice height in metres (with --view slice)")->expected(1);
  cmd->add_option("--scale", args->scale, "Pixels per voxel (default 1)")->check(CLI::Range(1, 64));
  cmd->add_option("--crop", args->crop,
                  "Box to draw, metres: XMIN YMIN ZMIN XMAX YMAX ZMAX (default: the map)")
      ->expected(6);
  cmd->add_option("--max-size", args->max_size,
                  fmt::format("Longest image side in pixels (default {})", args->max_size))
      ->check(CLI::Range(1, 65536));
  cmd->add_flag("--no-downscale", args->no_downscale,
                "Fail when the image exceeds --max-size instead of drawing several voxels per "
                "pixel");
  cmd->add_flag("--no-legend", args->no_legend,
                "Leave out the legend strip below the map (colours, height ramp, pixel size)");
  CLI::Option* frontiers = cmd->add_flag(
      "--frontiers", args->frontiers,
      "Draw frontier clusters (cells coloured by cluster) and their best viewpoints (white "
      "discs with a heading line) over the top view (faded to half contrast); the options "
      "below are those of "
      "`fragg_map frontiers` (here --viewpoints defaults to 1)");
  addFrontierFlags(cmd, &args->frontier_flags, frontiers);
  cmd->add_option("--highlight-ghosts", args->ghosts_scene,
                  "Static truth (OBJ, or a fragg_map_sim scene .json): draw the map's ghost "
                  "cells -- occupied, but free in the static scene, as `fragg_map eval` counts "
                  "them -- in red over the top view (faded to half contrast)");
  cmd->callback([args] { runRender(*args); });
}

}  // namespace fragg::cli
