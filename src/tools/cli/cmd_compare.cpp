// fragg_map compare A B [--json] [--octomap-threshold]
#include <fmt/format.h>

#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/commands.h"
#include "cli/map_input.h"
#include "fragg_map/interop/compare.h"

namespace fragg::cli {
namespace {

struct CompareArgs {
  std::string a;
  std::string b;
  bool json = false;
  bool octomap_threshold = false;
};

constexpr CellState kStates[] = {CellState::kUnknown, CellState::kFree, CellState::kOccupied};

const char* nameOf(CellState s) {
  switch (s) {
    case CellState::kFree:
      return "free";
    case CellState::kOccupied:
      return "occupied";
    default:
      return "unknown";
  }
}

nlohmann::json fractionJson(double f) {
  return std::isnan(f) ? nlohmann::json(nullptr) : nlohmann::json(f);
}

std::string percent(double f) { return std::isnan(f) ? "n/a" : fmt::format("{:.3f} %", 100 * f); }

void printJson(const CompareArgs& args, double resolution, const MapComparison& c) {
  nlohmann::json confusion;
  for (CellState sa : kStates)
    for (CellState sb : kStates) confusion[nameOf(sa)][nameOf(sb)] = c.count(sa, sb);
  const nlohmann::json out = {
      {"a", args.a},
      {"b", args.b},
      {"resolution_m", resolution},
      {"threshold", c.octomap_threshold ? "octomap" : "band"},
      {"known_in_a", c.known_in_a},
      {"known_in_b", c.known_in_b},
      {"known_in_both", c.known_in_both},
      {"known_in_either", c.known_in_either},
      {"agreeing", c.agreeing},
      {"agreement_in_both", fractionJson(c.agreementInBoth())},
      {"agreement_in_either", fractionJson(c.agreementInEither())},
      {"confusion", confusion},
  };
  fmt::print("{}\n", out.dump());
}

void printText(const CompareArgs& args, double resolution, const MapComparison& c) {
  fmt::print("compare {} (a) with {} (b) at {} m; known = {}\n", args.a, args.b, resolution,
             c.octomap_threshold ? "observed, occupied iff p >= 0.5 (OctoMap)"
                                 : "free or occupied outside each map's unknown band");
  fmt::print("known in a: {}, known in b: {}\n", c.known_in_a, c.known_in_b);
  fmt::print("known in both:   {} cells, same state: {} ({})\n", c.known_in_both, c.agreeing,
             percent(c.agreementInBoth()));
  fmt::print("known in either: {} cells, same state: {} ({})\n", c.known_in_either, c.agreeing,
             percent(c.agreementInEither()));
  fmt::print("cells observed in a or b (rows: a, columns: b)\n");
  fmt::print("{:>10} {:>12} {:>12} {:>12}\n", "", "unknown", "free", "occupied");
  for (CellState sa : kStates)
    fmt::print("{:>10} {:>12} {:>12} {:>12}\n", nameOf(sa), c.count(sa, CellState::kUnknown),
               c.count(sa, CellState::kFree), c.count(sa, CellState::kOccupied));
}

void runCompare(const CompareArgs& args) {
  const fragg::Map a = loadMapFile(args.a);
  const fragg::Map b = loadMapFile(args.b);
  CompareOptions options;
  options.octomap_threshold = args.octomap_threshold;
  const MapComparison c = compareMaps(a, b, options);
  if (args.json) {
    printJson(args, a.resolution(), c);
  } else {
    printText(args, a.resolution(), c);
  }
}

}  // namespace

void addCompareCommand(CLI::App& app) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "compare", "Cell-by-cell agreement between two maps of the same resolution");
  cmd->add_option("a", args->a, "First map (.fgm, or OctoMap .bt / .ot)")->required();
  cmd->add_option("b", args->b, "Second map (.fgm, or OctoMap .bt / .ot)")->required();
  cmd->add_flag("--json", args->json, "Print one JSON object on stdout");
  cmd->add_flag("--octomap-threshold", args->octomap_threshold,
                "Every observed cell is known, occupied iff p >= 0.5 (OctoMap's rule) instead "
                "of each map's unknown band");
  cmd->callback([args] { runCompare(*args); });
}

}  // namespace fragg::cli
