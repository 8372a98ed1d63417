// A whole number of milliseconds, like franka::Duration: the emulator's clock and the period
// handed to control callbacks.
#pragma once

#include <chrono>
#include <cstdint>

namespace csp::rt {

class Duration {
 public:
  constexpr Duration() noexcept = default;
  constexpr explicit Duration(uint64_t milliseconds) noexcept : milliseconds_(milliseconds) {}
  constexpr Duration(std::chrono::duration<uint64_t, std::milli> duration) noexcept   // NOLINT: implicit as in libfranka
      : milliseconds_(duration.count()) {}

  constexpr operator std::chrono::duration<uint64_t, std::milli>() const noexcept {   // NOLINT
    return std::chrono::duration<uint64_t, std::milli>(milliseconds_);
  }
  constexpr double toSec() const noexcept { return static_cast<double>(milliseconds_) / 1000.0; }
  constexpr uint64_t toMSec() const noexcept { return milliseconds_; }

  constexpr Duration operator+(const Duration& rhs) const noexcept { return Duration(milliseconds_ + rhs.milliseconds_); }
  constexpr Duration& operator+=(const Duration& rhs) noexcept { milliseconds_ += rhs.milliseconds_; return *this; }
  constexpr Duration operator-(const Duration& rhs) const noexcept { return Duration(milliseconds_ - rhs.milliseconds_); }
  constexpr Duration& operator-=(const Duration& rhs) noexcept { milliseconds_ -= rhs.milliseconds_; return *this; }
  constexpr Duration operator*(uint64_t rhs) const noexcept { return Duration(milliseconds_ * rhs); }
  constexpr Duration operator/(uint64_t rhs) const noexcept { return Duration(milliseconds_ / rhs); }
  constexpr auto operator<=>(const Duration&) const noexcept = default;

 private:
  uint64_t milliseconds_ = 0;
};

}  // namespace csp::rt
