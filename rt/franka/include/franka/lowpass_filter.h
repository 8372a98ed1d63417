// First-order low-pass filter of commanded values, as libfranka applies it in Robot::control.
// Self-contained, C++14.
#pragma once

#include <array>

namespace franka {

// At or above this cutoff the filter is off.
constexpr double kMaxCutoffFrequency = 1000.0;      // [Hz]
constexpr double kDefaultCutoffFrequency = 100.0;   // [Hz]

// The filtered value of sample y given the previous output y_last: a discretised RC filter,
// y_last + a (y - y_last) with a = T / (T + 1 / (2 pi f_c)). std::invalid_argument for a
// non-positive or non-finite sample time or cutoff, or non-finite values.
double lowpassFilter(double sample_time, double y, double y_last, double cutoff_frequency);

// The same for a pose (column-major 4x4): the translation filtered as above, the rotation moved
// from y_last's towards y's by the same fraction along the shortest rotation (slerp).
std::array<double, 16> cartesianLowpassFilter(double sample_time, std::array<double, 16> y,
                                              std::array<double, 16> y_last, double cutoff_frequency);

}  // namespace franka
