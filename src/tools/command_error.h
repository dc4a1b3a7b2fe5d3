// The tools' answer to a missing or unknown command (CLI11 says only "A subcommand is
// required"): the word, and the commands there are.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

namespace fragg::tools {

/// The app's commands, comma-separated, in the order they were added.
inline std::string commandNames(const CLI::App& app) {
  std::string names;
  for (const CLI::App* c : app.get_subcommands([](const CLI::App*) { return true; }))
    names += (names.empty() ? "" : ", ") + c->get_name();
  return names;
}

/// The error for argv when its first word is no command of app (or there is none); empty when
/// the first argument is an option (--help) or a command, for CLI11 to parse.
inline std::string commandError(const CLI::App& app, int argc, char** argv) {
  if (argc < 2) return "give a command: " + commandNames(app) + " (see --help)";
  const std::string word = argv[1];
  if (word.empty() || word[0] == '-') return "";
  for (const CLI::App* c : app.get_subcommands([](const CLI::App*) { return true; }))
    if (c->check_name(word)) return "";
  return "unknown command '" + word + "'; the commands are: " + commandNames(app) + " (see --help)";
}

}  // namespace fragg::tools
