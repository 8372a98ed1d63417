// The exceptions of libfranka, with its names and hierarchy.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "franka/log.h"

namespace franka {

// Base of every exception this API throws itself.
struct Exception : public std::runtime_error {
  using std::runtime_error::runtime_error;
};

// The robot's model could not be built.
struct ModelException : public Exception {
  using Exception::Exception;
};

// The robot cannot be reached (in CSP: never thrown, kept so that handlers compile).
struct NetworkException : public Exception {
  using Exception::Exception;
};

// A motion ended in a reflex, or could not start. `log` holds the last cycles before it.
struct ControlException : public Exception {
  explicit ControlException(const std::string& what, std::vector<Record> log = {})
      : Exception(what), log(std::move(log)) {}
  const std::vector<Record> log;
};

// A command was invalid (in CSP: a non-finite control value).
struct CommandException : public Exception {
  using Exception::Exception;
};

// Real-time scheduling was required (RealtimeConfig::kEnforce) but is not available.
struct RealtimeException : public Exception {
  using Exception::Exception;
};

// The call is not allowed now, e.g. setLoad while a motion runs.
struct InvalidOperationException : public Exception {
  using Exception::Exception;
};

}  // namespace franka
