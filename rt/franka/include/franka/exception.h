// The exceptions of libfranka, with its names and hierarchy. Self-contained, C++14.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "franka/logging/robot_state_log.hpp"

namespace franka {

// Base of every exception this API throws itself.
struct Exception : public std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The robot's model could not be built.
struct ModelException : public Exception {
  using Exception::Exception;
};

// The robot cannot be reached. In CSP: the robot's address names no scenario that can be loaded
// (docs/franka_api.md, "The robot's address").
struct NetworkException : public Exception {
  using Exception::Exception;
};

// The robot answered something unexpected (kept so that handlers compile; CSP does not throw it).
struct ProtocolException : public Exception {
  using Exception::Exception;
};

// The robot's server version is not the one this library speaks (kept so that handlers compile).
struct IncompatibleVersionException : public Exception {
  IncompatibleVersionException(uint16_t server_version, uint16_t library_version) noexcept;
  const uint16_t server_version;
  const uint16_t library_version;
};

// A motion ended in a reflex, was preempted (Robot::stop), or could not start. `log` holds the
// last cycles before it.
struct ControlException : public Exception {
  explicit ControlException(const std::string& what, std::vector<franka::Record> log = {}) noexcept;
  const std::vector<franka::Record> log;
};

// The robot refused a command (e.g. a setting out of its range, or a call in the wrong mode).
struct CommandException : public Exception {
  using Exception::Exception;
};

// Real-time scheduling was required (RealtimeConfig::kEnforce) but is not available.
struct RealtimeException : public Exception {
  using Exception::Exception;
};

// The call is not allowed now, e.g. a second motion while one runs.
struct InvalidOperationException : public Exception {
  using Exception::Exception;
};

}  // namespace franka
