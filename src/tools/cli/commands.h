// Subcommands of the `fragg_map` tool. Each add*Command registers its options and a callback
// that runs the command; errors are thrown (fragg::InvalidArgument -> exit 2, anything else
// -> exit 1) and printed as one line by main().
#pragma once

#include <CLI/CLI.hpp>

namespace fragg::cli {

void addBuildCommand(CLI::App& app);
void addCorrectCommand(CLI::App& app);
void addTruncateCommand(CLI::App& app);
void addMergeCommand(CLI::App& app);
void addStatsCommand(CLI::App& app);
void addExportCommand(CLI::App& app);
void addRenderCommand(CLI::App& app);
void addCompareCommand(CLI::App& app);
void addEvalCommand(CLI::App& app);
void addOctomapBuildCommand(CLI::App& app);
void addCollideCommand(CLI::App& app);
void addFrontiersCommand(CLI::App& app);
void addConvertStoreCommand(CLI::App& app);

}  // namespace fragg::cli
