// Rate limiting of commanded values, as libfranka applies it in Robot::control when limit_rate
// is true: the command is changed just enough to respect the robot's derivative limits.
#pragma once

#include <array>

namespace franka {

constexpr double kDeltaT = 1e-3;     // FCI cycle [s]
constexpr double kLimitEps = 1e-3;   // margin kept below every limit

// Each value moves from `last_commanded_values` by at most max_derivatives * kDeltaT
// (torques: max_derivatives = dtau_max). Throws std::invalid_argument if a value is not finite.
std::array<double, 7> limitRate(const std::array<double, 7>& max_derivatives,
                                const std::array<double, 7>& commanded_values,
                                const std::array<double, 7>& last_commanded_values);

// One joint velocity, limited in velocity [lower, upper], acceleration and jerk.
double limitRate(double upper_velocity, double lower_velocity, double max_acceleration, double max_jerk,
                 double commanded_velocity, double last_commanded_velocity, double last_commanded_acceleration);

// Joint velocities, each limited as above.
std::array<double, 7> limitRate(const std::array<double, 7>& upper_velocity,
                                const std::array<double, 7>& lower_velocity,
                                const std::array<double, 7>& max_acceleration,
                                const std::array<double, 7>& max_jerk,
                                const std::array<double, 7>& commanded_velocities,
                                const std::array<double, 7>& last_commanded_velocities,
                                const std::array<double, 7>& last_commanded_accelerations);

// Joint positions: the implied velocity is limited as above and integrated once.
std::array<double, 7> limitRate(const std::array<double, 7>& upper_velocity,
                                const std::array<double, 7>& lower_velocity,
                                const std::array<double, 7>& max_acceleration,
                                const std::array<double, 7>& max_jerk,
                                const std::array<double, 7>& commanded_positions,
                                const std::array<double, 7>& last_commanded_positions,
                                const std::array<double, 7>& last_commanded_velocities,
                                const std::array<double, 7>& last_commanded_accelerations);

}  // namespace franka
