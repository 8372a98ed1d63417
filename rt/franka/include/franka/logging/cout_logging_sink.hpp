// A sink that prints every message on std::cout (libfranka's CoutLoggingSink).
#pragma once

#include <string>

#include "franka/logging/logging_sink_interface.hpp"

namespace franka {

class CoutLoggingSink : public LoggingSinkInterface {
 public:
  ~CoutLoggingSink() override = default;
  auto getName() const -> std::string override;
  auto logInfo(const std::string& message) -> void override;
  auto logWarn(const std::string& message) -> void override;
  auto logError(const std::string& message) -> void override;
};

}  // namespace franka
