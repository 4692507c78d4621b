#include "rastercheck/core/Log.h"

#include <iostream>
#include <mutex>
#include <set>

namespace rastercheck
{
namespace
{
std::mutex &logMutex()
{
    static std::mutex mutex;
    return mutex;
}

LogHandler &handlerSlot()
{
    static LogHandler handler;
    return handler;
}

std::set<std::string> &loggedOnce()
{
    static std::set<std::string> messages;
    return messages;
}
}  // namespace

void setLogHandler(LogHandler handler)
{
    std::lock_guard<std::mutex> lock(logMutex());
    handlerSlot() = std::move(handler);
}

void logMessage(LogLevel level, const std::string &message)
{
    std::lock_guard<std::mutex> lock(logMutex());
    if (handlerSlot())
    {
        handlerSlot()(level, message);
        return;
    }
    std::cerr << "rastercheck: " << (level == LogLevel::Warning ? "warning: " : "") << message << '\n';
}

void logOnce(LogLevel level, const std::string &message)
{
    {
        std::lock_guard<std::mutex> lock(logMutex());
        if (!loggedOnce().insert(message).second)
            return;
    }
    logMessage(level, message);
}
}  // namespace rastercheck
