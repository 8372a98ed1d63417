// First-order low-pass filter of commanded values, as libfranka applies it in Robot::control.
#pragma once

namespace franka {

// At or above this cutoff the filter is off.
constexpr double kMaxCutoffFrequency = 1000.0;   // [Hz]
constexpr double kDefaultCutoffFrequency = 100.0;   // [Hz]

// The filtered value of sample y given the previous output y_last: a discretised RC filter,
// y_last + a (y - y_last) with a = T / (T + 1 / (2 pi f_c)).
double lowpassFilter(double sample_time, double y, double y_last, double cutoff_frequency);

}  // namespace franka
