#pragma once

#include <functional>
#include <string>

namespace rastercheck
{
/** \brief Severity of a message the library emits while loading (never on the hot path). */
enum class LogLevel
{
    Info,
    Warning
};

/** \brief Receives every warning and notice (documented fallbacks, backend choice). The default
    handler prints "rastercheck: warning: ..." to stderr. Set once at start-up; not thread-safe to
    change while other threads load models. */
using LogHandler = std::function<void(LogLevel, const std::string &)>;
void setLogHandler(LogHandler handler);
void logMessage(LogLevel level, const std::string &message);
/** \brief As logMessage, but a message already logged by this process is not logged again: what
    loading a file reports (an open mesh) is read once, not at every load of the same file. */
void logOnce(LogLevel level, const std::string &message);
inline void logWarning(const std::string &message) { logMessage(LogLevel::Warning, message); }
inline void logInfo(const std::string &message) { logMessage(LogLevel::Info, message); }
}  // namespace rastercheck
