// libfranka's logging: messages go to every registered sink (none by default). The library itself
// logs here, e.g. the warning when real-time scheduling is missing under RealtimeConfig::kIgnore.
// The formatting overloads (logInfo("{} of {}", a, b)) exist when {fmt} is available, as libfranka's
// need it; the plain-string functions always do. Self-contained, C++14.
#pragma once

#include <memory>
#include <string>
#include <utility>

#include "franka/logging/logging_sink_interface.hpp"

#if defined(__has_include)
#if __has_include(<fmt/format.h>)
#include <fmt/format.h>
#define CSP_FRANKA_HAS_FMT 1
#endif
#endif

namespace franka {
namespace logging {

// Registers a sink; a sink with the same name replaces the earlier one.
auto addLogger(const std::shared_ptr<LoggingSinkInterface>& logger) -> void;
auto removeLogger(const std::string& logger_name) -> void;
auto removeAllLoggers() -> void;

auto logInfo(const std::string& message) -> void;
auto logWarn(const std::string& message) -> void;
auto logError(const std::string& message) -> void;

#ifdef CSP_FRANKA_HAS_FMT
template <typename S, typename... Args>
auto logInfo(const S& format_str, Args&&... args) -> void {
  logInfo(std::string(fmt::format(fmt::runtime(format_str), std::forward<Args>(args)...)));
}
template <typename S, typename... Args>
auto logWarn(const S& format_str, Args&&... args) -> void {
  logWarn(std::string(fmt::format(fmt::runtime(format_str), std::forward<Args>(args)...)));
}
template <typename S, typename... Args>
auto logError(const S& format_str, Args&&... args) -> void {
  logError(std::string(fmt::format(fmt::runtime(format_str), std::forward<Args>(args)...)));
}
#endif

}  // namespace logging
}  // namespace franka
