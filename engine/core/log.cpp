#include "visbuf/core/log.h"

#include <cstdio>
#include <mutex>

namespace visbuf {

namespace {
std::mutex& sinkMutex() {
  static std::mutex m;
  return m;
}
LogSink& currentSink() {
  static LogSink sink;
  return sink;
}
}  // namespace

const char* logLevelName(LogLevel level) {
  switch (level) {
    case LogLevel::Debug: return "debug";
    case LogLevel::Info: return "info";
    case LogLevel::Warning: return "warning";
    case LogLevel::Error: return "error";
  }
  return "?";
}

LogSink setLogSink(LogSink sink) {
  std::lock_guard lock(sinkMutex());
  LogSink previous = std::move(currentSink());
  currentSink() = std::move(sink);
  return previous;
}

void logMessage(LogLevel level, std::string_view message) {
  std::lock_guard lock(sinkMutex());
  if (currentSink()) {
    currentSink()(level, message);
    return;
  }
  const int n = static_cast<int>(message.size());
  if (level == LogLevel::Info || level == LogLevel::Debug)
    std::fprintf(stderr, "%.*s\n", n, message.data());
  else
    std::fprintf(stderr, "visbuf: %s: %.*s\n", logLevelName(level), n, message.data());
}

}  // namespace visbuf
