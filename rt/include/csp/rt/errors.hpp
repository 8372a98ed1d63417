// The robot's error flags with libfranka's names: the emulator latches them in an ErrorSet and
// publishes them as franka::Errors (RobotState::current_errors, last_motion_errors).
#pragma once

#include <array>
#include <ostream>
#include <string>

#include "franka/errors.h"

namespace csp::rt {

// One entry per flag of franka::Errors, in libfranka's order (the list lives in franka/errors.h).
enum class Error {
#define CSP_ENUM_ENTRY(name) name,
  CSP_FRANKA_ERRORS(CSP_ENUM_ENTRY)
#undef CSP_ENUM_ENTRY
};

inline constexpr int kNumErrors = 41;

// libfranka's name of an error, e.g. "joint_velocity_violation".
const char* error_name(Error error);

// A set of error flags that the emulator can set and merge (franka::Errors is read-only: its
// flags are references). Converts to and from franka::Errors flag for flag.
class ErrorSet {
 public:
  ErrorSet() = default;
  explicit ErrorSet(const std::array<bool, kNumErrors>& flags) : flags_(flags) {}
  explicit ErrorSet(const franka::Errors& errors);

  const std::array<bool, kNumErrors>& flags() const { return flags_; }
  bool has(Error error) const { return flags_[static_cast<int>(error)]; }
  void set(Error error) { flags_[static_cast<int>(error)] = true; }
  void merge(const ErrorSet& other) {
    for (int i = 0; i < kNumErrors; ++i) flags_[i] = flags_[i] || other.flags_[i];
  }
  franka::Errors errors() const { return franka::Errors(flags_); }

  explicit operator bool() const noexcept;
  // "[name_1, name_2]" as libfranka prints franka::Errors; "[]" without errors.
  explicit operator std::string() const;

  bool operator==(const ErrorSet&) const = default;

 private:
  std::array<bool, kNumErrors> flags_{};
};

// Whether franka::Errors has `error` set.
bool has(const franka::Errors& errors, Error error);

// Streams the set flags as a JSON array of names.
std::ostream& operator<<(std::ostream& out, const ErrorSet& errors);

}  // namespace csp::rt
