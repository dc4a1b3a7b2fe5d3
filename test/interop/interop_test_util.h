// Hand-made maps and temporary files for the interop tests (no ray casting involved).
#pragma once

#include <dirent.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "fragg_map/map.h"
#include "test_dir.h"

namespace fragg::test {

inline MapParams paramsAt(double resolution_m) {
  MapParams p;
  p.resolution_m = resolution_m;
  p.backend = Backend::kCpu;
  p.threads = 1;
  return p;
}

/// Sets one cell's fixed-point log-odds, creating its block when needed.
inline void setCell(Map& map, const VoxelKey& k, int16_t log_odds_fx) {
  map.writeCells([&](CellWriter& cells) {
    Cell c;
    c.log_odds_fx = log_odds_fx;
    cells.set(k, c);
  });
}

/// log_odds_fx of a cell, or kUnobservedLogOdds when it has no block.
inline int16_t cellFx(const Map& map, const VoxelKey& k) {
  const Cell* c = map.findCell(k);
  return c ? c->log_odds_fx : kUnobservedLogOdds;
}

inline CellState stateAt(const Map& map, const VoxelKey& k) {
  const Cell* c = map.findCell(k);
  return c ? map.state(*c) : CellState::kUnknown;
}

inline bool fileExists(const std::string& path) { return std::ifstream(path).good(); }

inline std::string readBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

inline void writeBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// Names in a directory (without "." and ".."), to check that nothing was left behind.
inline std::vector<std::string> listDir(const std::string& dir) {
  std::vector<std::string> names;
  if (DIR* d = opendir(dir.c_str())) {
    while (dirent* e = readdir(d)) {
      const std::string n = e->d_name;
      if (n != "." && n != "..") names.push_back(n);
    }
    closedir(d);
  }
  return names;
}

#ifdef FRAGG_CLI_PATH
inline const char* cliPath() { return FRAGG_CLI_PATH; }

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

/// Runs the fragg_map binary with `args` (shell words), capturing its output in `dir`.
inline RunResult runCli(const std::string& dir, const std::string& args) {
  const std::string out = dir + "/stdout.txt", err = dir + "/stderr.txt";
  const std::string cmd =
      std::string("'") + cliPath() + "' " + args + " > '" + out + "' 2> '" + err + "'";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  r.out = readBytes(out);
  r.err = readBytes(err);
  std::remove(out.c_str());
  std::remove(err.c_str());
  return r;
}

#endif

}  // namespace fragg::test
