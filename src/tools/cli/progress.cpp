#include "cli/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <string>

namespace fragg::cli {

Progress::Progress(std::optional<size_t> total)
    : total_(total),
      enabled_(::isatty(STDERR_FILENO) == 1),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_ - std::chrono::seconds(1)) {}

void Progress::update(size_t done) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double rate = elapsed > 0 ? done / elapsed : 0.0;
  if (total_ && *total_ > 0) {
    const int width = 30;
    const int filled = static_cast<int>(width * std::min<size_t>(done, *total_) / *total_);
    const double eta = rate > 0 ? (*total_ - std::min<size_t>(done, *total_)) / rate : 0.0;
    std::fprintf(stderr, "\r[%s%s] %zu/%zu scans  %.1f scans/s  ETA %.0f s ",
                 std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(), done,
                 *total_, rate, eta);
  } else {
    std::fprintf(stderr, "\r%zu scans  %.1f scans/s ", done, rate);
  }
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_) return;
  std::fprintf(stderr, "\r%80s\r", "");
  std::fflush(stderr);
}

}  // namespace fragg::cli
