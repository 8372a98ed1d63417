// franka::Duration: a whole number of milliseconds, the robot's clock and the period handed to
// control callbacks (libfranka's class, interface for interface). Header-only and C++14.
#pragma once

#include <chrono>
#include <cstdint>
#include <ratio>

namespace franka {

class Duration {
 public:
  Duration() noexcept : duration_(0) {}
  explicit Duration(uint64_t milliseconds) noexcept : duration_(milliseconds) {}
  Duration(std::chrono::duration<uint64_t, std::milli> duration) noexcept   // NOLINT: implicit as in libfranka
      : duration_(duration) {}
  Duration(const Duration&) = default;
  Duration& operator=(const Duration&) = default;

  operator std::chrono::duration<uint64_t, std::milli>() const noexcept { return duration_; }   // NOLINT
  double toSec() const noexcept { return static_cast<double>(duration_.count()) / 1000.0; }
  uint64_t toMSec() const noexcept { return duration_.count(); }

  Duration operator+(const Duration& rhs) const noexcept { return Duration(duration_ + rhs.duration_); }
  Duration& operator+=(const Duration& rhs) noexcept { duration_ += rhs.duration_; return *this; }
  Duration operator-(const Duration& rhs) const noexcept { return Duration(duration_ - rhs.duration_); }
  Duration& operator-=(const Duration& rhs) noexcept { duration_ -= rhs.duration_; return *this; }
  Duration operator*(uint64_t rhs) const noexcept { return Duration(duration_ * rhs); }
  Duration& operator*=(uint64_t rhs) noexcept { duration_ *= rhs; return *this; }
  uint64_t operator/(const Duration& rhs) const noexcept { return duration_ / rhs.duration_; }
  Duration operator/(uint64_t rhs) const noexcept { return Duration(duration_ / rhs); }
  Duration& operator/=(uint64_t rhs) noexcept { duration_ /= rhs; return *this; }
  Duration operator%(const Duration& rhs) const noexcept { return Duration(duration_ % rhs.duration_); }
  Duration operator%(uint64_t rhs) const noexcept { return Duration(duration_ % rhs); }
  Duration& operator%=(const Duration& rhs) noexcept { duration_ %= rhs.duration_; return *this; }
  Duration& operator%=(uint64_t rhs) noexcept { duration_ %= rhs; return *this; }

  bool operator==(const Duration& rhs) const noexcept { return duration_ == rhs.duration_; }
  bool operator!=(const Duration& rhs) const noexcept { return duration_ != rhs.duration_; }
  bool operator<(const Duration& rhs) const noexcept { return duration_ < rhs.duration_; }
  bool operator<=(const Duration& rhs) const noexcept { return duration_ <= rhs.duration_; }
  bool operator>(const Duration& rhs) const noexcept { return duration_ > rhs.duration_; }
  bool operator>=(const Duration& rhs) const noexcept { return duration_ >= rhs.duration_; }

 private:
  std::chrono::duration<uint64_t, std::milli> duration_;
};

inline Duration operator*(uint64_t lhs, const Duration& rhs) noexcept { return rhs * lhs; }

}  // namespace franka
