// Where the core's few log lines go (backend selection, fallbacks). Default: stderr. The ROS
// server routes them to rosconsole.
#pragma once

#include <functional>
#include <string>

namespace fragg {

enum class LogLevel { kInfo, kWarning };
using LogSink = std::function<void(LogLevel, const std::string&)>;

/// Replaces the sink for every map in the process; an empty function restores stderr.
void setLogSink(LogSink sink);
void logMessage(LogLevel level, const std::string& message);

}  // namespace fragg
