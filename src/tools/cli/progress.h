// A one-line progress bar on stderr (only when stderr is a terminal).
#pragma once

#include <chrono>
#include <cstddef>
#include <optional>

namespace fragg::cli {

class Progress {
 public:
  explicit Progress(std::optional<size_t> total);
  /// Redraws at most ~10 times a second.
  void update(size_t done);
  /// Clears the line.
  void finish();
  bool enabled() const { return enabled_; }

 private:
  std::optional<size_t> total_;
  bool enabled_;
  std::chrono::steady_clock::time_point start_, last_draw_;
};

}  // namespace fragg::cli
