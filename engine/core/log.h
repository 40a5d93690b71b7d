// The library's log: every message visbuf prints about its own work (validation layer messages, device choice,
// failures it returns as errors) goes through one sink, with a level. By default the sink writes to stderr
// (warnings and errors as "visbuf: LEVEL: message", info and debug as they are); a host routes it into its own
// log with setLogSink. Thread-safe: the sink may be
// replaced and called from any thread (calls are serialised: the sink needs no lock of its own).
#pragma once

#include <functional>
#include <string_view>

namespace visbuf {

enum class LogLevel { Debug, Info, Warning, Error };

const char* logLevelName(LogLevel level);

using LogSink = std::function<void(LogLevel level, std::string_view message)>;

// Replaces the sink (an empty function restores the default, stderr); returns the previous one.
LogSink setLogSink(LogSink sink);
void logMessage(LogLevel level, std::string_view message);

}  // namespace visbuf
