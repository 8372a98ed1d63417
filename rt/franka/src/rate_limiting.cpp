#include "franka/rate_limiting.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace franka {
namespace {

void require_finite(const std::array<double, 7>& values, const char* what) {
  for (double v : values)
    if (!std::isfinite(v)) throw std::invalid_argument(std::string("limitRate: ") + what + " is infinite or NaN");
}

}  // namespace

std::array<double, 7> limitRate(const std::array<double, 7>& max_derivatives,
                                const std::array<double, 7>& commanded_values,
                                const std::array<double, 7>& last_commanded_values) {
  require_finite(commanded_values, "commanded_values");
  std::array<double, 7> limited{};
  for (std::size_t i = 0; i < 7; ++i) {
    const double step = max_derivatives[i] * kDeltaT;
    limited[i] = last_commanded_values[i] + std::clamp(commanded_values[i] - last_commanded_values[i], -step, step);
  }
  return limited;
}

double limitRate(double upper_velocity, double lower_velocity, double max_acceleration, double max_jerk,
                 double commanded_velocity, double last_commanded_velocity, double last_commanded_acceleration) {
  if (!std::isfinite(commanded_velocity)) throw std::invalid_argument("limitRate: commanded_velocity is infinite or NaN");
  // Jerk first; then the acceleration, bounded so that the jerk limit can still bring it to zero
  // before the velocity reaches its bound (from a, the velocity still grows by a^2 / (2 j_max)).
  const double jerk = std::clamp(
      ((commanded_velocity - last_commanded_velocity) / kDeltaT - last_commanded_acceleration) / kDeltaT, -max_jerk,
      max_jerk);
  const double room_up = std::max(0.0, upper_velocity - last_commanded_velocity);
  const double room_down = std::max(0.0, last_commanded_velocity - lower_velocity);
  const double max_up = std::min(max_acceleration, std::sqrt(2.0 * max_jerk * room_up));
  const double max_down = std::min(max_acceleration, std::sqrt(2.0 * max_jerk * room_down));
  const double acceleration = std::clamp(last_commanded_acceleration + jerk * kDeltaT, -max_down, max_up);
  return std::clamp(last_commanded_velocity + acceleration * kDeltaT, lower_velocity, upper_velocity);
}

std::array<double, 7> limitRate(const std::array<double, 7>& upper_velocity,
                                const std::array<double, 7>& lower_velocity,
                                const std::array<double, 7>& max_acceleration,
                                const std::array<double, 7>& max_jerk,
                                const std::array<double, 7>& commanded_velocities,
                                const std::array<double, 7>& last_commanded_velocities,
                                const std::array<double, 7>& last_commanded_accelerations) {
  require_finite(commanded_velocities, "commanded_velocities");
  std::array<double, 7> limited{};
  for (std::size_t i = 0; i < 7; ++i)
    limited[i] = limitRate(upper_velocity[i], lower_velocity[i], max_acceleration[i], max_jerk[i],
                           commanded_velocities[i], last_commanded_velocities[i], last_commanded_accelerations[i]);
  return limited;
}

std::array<double, 7> limitRate(const std::array<double, 7>& upper_velocity,
                                const std::array<double, 7>& lower_velocity,
                                const std::array<double, 7>& max_acceleration,
                                const std::array<double, 7>& max_jerk,
                                const std::array<double, 7>& commanded_positions,
                                const std::array<double, 7>& last_commanded_positions,
                                const std::array<double, 7>& last_commanded_velocities,
                                const std::array<double, 7>& last_commanded_accelerations) {
  require_finite(commanded_positions, "commanded_positions");
  std::array<double, 7> velocities{};
  for (std::size_t i = 0; i < 7; ++i)
    velocities[i] = (commanded_positions[i] - last_commanded_positions[i]) / kDeltaT;
  velocities = limitRate(upper_velocity, lower_velocity, max_acceleration, max_jerk, velocities,
                         last_commanded_velocities, last_commanded_accelerations);
  std::array<double, 7> limited{};
  for (std::size_t i = 0; i < 7; ++i) limited[i] = last_commanded_positions[i] + velocities[i] * kDeltaT;
  return limited;
}

}  // namespace franka
