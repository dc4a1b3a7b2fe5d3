// Small text helpers of the server: frame ids as tf2 wants them, file name suffixes.
#pragma once

#include <string>

namespace fragg::ros {

/// `frame` without a leading '/' (tf2 rejects ids that start with one).
[[nodiscard]] inline std::string withoutLeadingSlash(const std::string& frame) {
  return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame;
}

/// Whether `s` ends with `suffix`.
[[nodiscard]] inline bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() &&
         s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace fragg::ros
