#include "fragg_map/log.h"

#include <cstdio>
#include <mutex>

namespace fragg {

namespace {
std::mutex& sinkMutex() {
  static std::mutex m;
  return m;
}
LogSink& sink() {
  static LogSink s;
  return s;
}
}  // namespace

void setLogSink(LogSink s) {
  std::lock_guard<std::mutex> lock(sinkMutex());
  sink() = std::move(s);
}

void logMessage(LogLevel level, const std::string& message) {
  std::lock_guard<std::mutex> lock(sinkMutex());
  if (sink()) {
    sink()(level, message);
    return;
  }
  std::fprintf(stderr, "[fragg_map] %s%s\n", level == LogLevel::kWarning ? "warning: " : "",
               message.c_str());
}

}  // namespace fragg
