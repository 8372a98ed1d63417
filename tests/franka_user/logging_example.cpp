// A custom sink for libfranka's log messages: everything the library logs (and what the program
// logs through franka::logging) goes to standard output with its level.
#include <iostream>
#include <memory>
#include <string>

#include <franka/logging/logger.hpp>
#include <franka/logging/logging_sink_interface.hpp>

class StdoutLogger : public franka::LoggingSinkInterface {
 public:
  auto getName() const -> std::string override { return "StdoutLogger"; }
  auto logInfo(const std::string& message) -> void override { print("INFO", message); }
  auto logWarn(const std::string& message) -> void override { print("WARNING", message); }
  auto logError(const std::string& message) -> void override { print("ERROR", message); }

 private:
  static void print(const char* level, const std::string& message) {
    std::cout << level << ": " << message << std::endl;
  }
};

int main() {
  franka::logging::addLogger(std::make_shared<StdoutLogger>());

  franka::logging::logInfo("This is an info message.");
  franka::logging::logWarn("This is a warning message.");
  franka::logging::logError("This is an error message.");
  return 0;
}
