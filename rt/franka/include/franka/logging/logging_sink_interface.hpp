// Where libfranka's log messages go: a sink registered with franka::logging::addLogger
// (libfranka 0.15's interface).
#pragma once

#include <string>

namespace franka {

class LoggingSinkInterface {
 public:
  virtual ~LoggingSinkInterface() = default;
  // The name removeLogger refers to.
  virtual auto getName() const -> std::string = 0;
  virtual auto logInfo(const std::string& message) -> void = 0;
  virtual auto logWarn(const std::string& message) -> void = 0;
  virtual auto logError(const std::string& message) -> void = 0;
};

}  // namespace franka
