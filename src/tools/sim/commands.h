// Subcommands of `fragg_map_sim`. Errors are thrown (fragg::InvalidArgument -> exit 2,
// anything else -> exit 1) and printed as one line by main().
#pragma once

#include <CLI/CLI.hpp>

namespace fragg::sim::tool {

void addSceneCommand(CLI::App& app);
void addRecordCommand(CLI::App& app);

}  // namespace fragg::sim::tool
