// fragg_map convert-store OLD NEW [--json]: writes a page store of format 1 (one record per
// block, written before records by region) into a new store of this build's format (records
// by region), of the kind NEW's extension names (.lmdb/.mdb: LMDB, .db/.sqlite: SQLite).
#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "cli/commands.h"
#include "fragg_map/errors.h"
#ifdef FRAGG_HAVE_PAGE_STORE
#include "fragg_map/store/page_stores.h"
#endif

namespace fragg::cli {

namespace {
struct ConvertStoreOptions {
  std::string from, to;
  bool json = false;
};

void runConvertStore(const ConvertStoreOptions& o) {
#ifdef FRAGG_HAVE_PAGE_STORE
  if (!isPageStorePath(o.to))
    throw InvalidArgument("the new store must end in .lmdb, .mdb, .db or .sqlite, got '" + o.to +
                          "'");
  const auto t0 = std::chrono::steady_clock::now();
  const ConvertStats stats = convertPageStore(o.from, o.to);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (o.json) {
    const nlohmann::json j = {{"from", o.from},
                              {"to", o.to},
                              {"blocks", stats.blocks},
                              {"records", stats.records},
                              {"seconds", seconds}};
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("%s\n", fmt::format("converted {} -> {}: {} blocks in {} region records, {:.2f} s",
                                    o.from, o.to, stats.blocks, stats.records, seconds)
                            .c_str());
  }
#else
  throw InvalidArgument("this fragg_map was built without the page stores (" + o.from + ")");
#endif
}
}  // namespace

void addConvertStoreCommand(CLI::App& app) {
  auto o = std::make_shared<ConvertStoreOptions>();
  CLI::App* cmd = app.add_subcommand(
      "convert-store",
      "Convert a page store of format 1 (one record per block) to this build's format "
      "(records by region)");
  cmd->add_option("store", o->from, "Page store of format 1 (.lmdb/.mdb or .db/.sqlite)")
      ->required();
  cmd->add_option("new_store", o->to, "New page store to write (must not exist)")->required();
  cmd->add_flag("--json", o->json, "Print one JSON line");
  cmd->callback([o] { runConvertStore(*o); });
}

}  // namespace fragg::cli
