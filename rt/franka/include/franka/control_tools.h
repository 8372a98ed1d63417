// Helpers around control: real-time scheduling and the checks libfranka makes on commands
// (libfranka's control_tools.h, the same functions). Self-contained, C++14.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>

namespace franka {

// Whether the elbow's joint-4 sign is +1 or -1.
inline bool isValidElbow(const std::array<double, 2>& elbow) noexcept { return elbow[1] == -1.0 || elbow[1] == 1.0; }

// Whether a column-major 4x4 matrix is a homogeneous transform: last row (0 0 0 1) and rotation
// rows and columns of unit length within 1e-5.
inline bool isHomogeneousTransformation(const std::array<double, 16>& transform) noexcept {
  constexpr double kOrthonormalThreshold = 1e-5;
  if (transform[3] != 0.0 || transform[7] != 0.0 || transform[11] != 0.0 || transform[15] != 1.0) return false;
  for (std::size_t j = 0; j < 3; ++j) {
    const double column = std::sqrt(transform[j * 4] * transform[j * 4] + transform[j * 4 + 1] * transform[j * 4 + 1] +
                                    transform[j * 4 + 2] * transform[j * 4 + 2]);
    const double row = std::sqrt(transform[j] * transform[j] + transform[4 + j] * transform[4 + j] +
                                 transform[8 + j] * transform[8 + j]);
    if (std::abs(column - 1.0) > kOrthonormalThreshold || std::abs(row - 1.0) > kOrthonormalThreshold) return false;
  }
  return true;
}

// Whether the running kernel is PREEMPT_RT (/sys/kernel/realtime reads 1).
bool hasRealtimeKernel();

// SCHED_FIFO at the highest priority for the calling thread; false (with the reason in
// *error_message) when the process may not.
bool setCurrentThreadToHighestSchedulerPriority(std::string* error_message);

// std::invalid_argument("Commanding value is infinite or NaN.") unless every value is finite.
template <std::size_t N>
inline void checkFinite(const std::array<double, N>& array) {
  if (!std::all_of(array.begin(), array.end(), [](double value) { return std::isfinite(value); }))
    throw std::invalid_argument("Commanding value is infinite or NaN.");
}

inline void checkMatrix(const std::array<double, 16>& transform) {
  checkFinite(transform);
  if (!isHomogeneousTransformation(transform))
    throw std::invalid_argument(
        "libfranka: Attempt to set invalid transformation in motion generator. Has to be column major!");
}

inline void checkElbow(const std::array<double, 2>& elbow) {
  checkFinite(elbow);
  if (!isValidElbow(elbow))
    throw std::invalid_argument(
        "Invalid elbow configuration given! Only +1 or -1 are allowed for the sign of the 4th joint.");
}

}  // namespace franka
