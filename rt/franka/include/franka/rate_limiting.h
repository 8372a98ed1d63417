// Rate limiting of commanded values, as libfranka applies it in Robot::control when limit_rate is
// true: each command is changed just enough to respect the robot's derivative limits. The limits
// and the limitRate overloads of two libfranka API versions (docs/franka_api.md):
//   CSP_FRANKA_API_VERSION 1500 (default): libfranka 0.15 (FR3 limits; joint velocity limits that
//     depend on the position, computeUpperLimitsJointVelocity; limitRate with upper and lower
//     velocity limits);
//   CSP_FRANKA_API_VERSION 900: libfranka 0.9 (Panda limits; kMaxJointVelocity; limitRate with a
//     symmetric max_velocity).
// The library holds both sets of functions (0.9's in the inline namespace api_0_9), so one build
// serves programs of either version. Self-contained, C++14.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "franka/api_version.h"

namespace franka {

constexpr double kDeltaT = 1e-3;     // FCI cycle [s]
constexpr double kLimitEps = 1e-3;   // margin kept below every limit
constexpr double kNormEps = std::numeric_limits<double>::epsilon();
constexpr double kFactorCartesianRotationPoseInterface = 0.99;   // rotation limits of the pose interface, scaled

#if CSP_FRANKA_API_VERSION >= 1000
// libfranka 0.15 (FR3).
constexpr double kTolNumberPacketsLost = 0.0;
constexpr std::array<double, 7> kMaxTorqueRate{{1000 - kLimitEps, 1000 - kLimitEps, 1000 - kLimitEps, 1000 - kLimitEps,
                                                1000 - kLimitEps, 1000 - kLimitEps, 1000 - kLimitEps}};
constexpr std::array<double, 7> kMaxJointJerk{{5000.0 - kLimitEps, 5000.0 - kLimitEps, 5000.0 - kLimitEps,
                                               5000.0 - kLimitEps, 5000.0 - kLimitEps, 5000.0 - kLimitEps,
                                               5000.0 - kLimitEps}};
constexpr std::array<double, 7> kMaxJointAcceleration{{10.0 - kLimitEps, 10.0 - kLimitEps, 10.0 - kLimitEps,
                                                       10.0 - kLimitEps, 10.0 - kLimitEps, 10.0 - kLimitEps,
                                                       10.0 - kLimitEps}};
constexpr std::array<double, 7> kJointVelocityLimitsTolerance{
    {kLimitEps + kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[0],
     kLimitEps + kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[1],
     kLimitEps + kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[2],
     kLimitEps + kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[3],
     kLimitEps + kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[4],
     kLimitEps + kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[5],
     kLimitEps + kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[6]}};
constexpr double kMaxTranslationalJerk = 4500.0 - kLimitEps;
constexpr double kMaxTranslationalAcceleration = 9.0 - kLimitEps;
constexpr double kMaxTranslationalVelocity = 3.0 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxTranslationalAcceleration;
constexpr double kMaxRotationalJerk = 8500.0 - kLimitEps;
constexpr double kMaxRotationalAcceleration = 17.0 - kLimitEps;
constexpr double kMaxRotationalVelocity = 2.5 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxRotationalAcceleration;
constexpr double kMaxElbowJerk = 5000 - kLimitEps;
constexpr double kMaxElbowAcceleration = 10.0 - kLimitEps;
constexpr double kMaxElbowVelocity = 1.5 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxElbowAcceleration;

namespace detail {
// FR3's velocity bound of one joint at position q: min(v_max, max(0, -a + sqrt(b (q_limit - q)))),
// the speed from which the joint can still stop before its position limit (FR3 datasheet).
inline double fr3_velocity_bound(double v_max, double a, double b, double distance_to_limit) {
  return std::min(v_max, std::max(0.0, -a + std::sqrt(std::max(0.0, b * distance_to_limit))));
}
}  // namespace detail

// FR3's upper and lower joint velocity limits at joint positions q [rad/s], kept
// kJointVelocityLimitsTolerance inside.
inline std::array<double, 7> computeUpperLimitsJointVelocity(const std::array<double, 7>& q) {
  using detail::fr3_velocity_bound;
  return {{fr3_velocity_bound(2.62, 0.30, 12.0, 2.75010 - q[0]) - kJointVelocityLimitsTolerance[0],
           fr3_velocity_bound(2.62, 0.20, 5.17, 1.79180 - q[1]) - kJointVelocityLimitsTolerance[1],
           fr3_velocity_bound(2.62, 0.20, 7.00, 2.90650 - q[2]) - kJointVelocityLimitsTolerance[2],
           fr3_velocity_bound(2.62, 0.30, 8.00, -0.1458 - q[3]) - kJointVelocityLimitsTolerance[3],
           fr3_velocity_bound(5.26, 0.35, 34.0, 2.81010 - q[4]) - kJointVelocityLimitsTolerance[4],
           fr3_velocity_bound(4.18, 0.35, 11.0, 4.52050 - q[5]) - kJointVelocityLimitsTolerance[5],
           fr3_velocity_bound(5.26, 0.35, 34.0, 3.01960 - q[6]) - kJointVelocityLimitsTolerance[6]}};
}
inline std::array<double, 7> computeLowerLimitsJointVelocity(const std::array<double, 7>& q) {
  using detail::fr3_velocity_bound;
  return {{-fr3_velocity_bound(2.62, 0.30, 12.0, 2.750100 + q[0]) + kJointVelocityLimitsTolerance[0],
           -fr3_velocity_bound(2.62, 0.20, 5.17, 1.791800 + q[1]) + kJointVelocityLimitsTolerance[1],
           -fr3_velocity_bound(2.62, 0.20, 7.00, 2.906500 + q[2]) + kJointVelocityLimitsTolerance[2],
           -fr3_velocity_bound(2.62, 0.30, 8.00, 3.048100 + q[3]) + kJointVelocityLimitsTolerance[3],
           -fr3_velocity_bound(5.26, 0.35, 34.0, 2.810100 + q[4]) + kJointVelocityLimitsTolerance[4],
           -fr3_velocity_bound(4.18, 0.35, 11.0, -0.54092 + q[5]) + kJointVelocityLimitsTolerance[5],
           -fr3_velocity_bound(5.26, 0.35, 34.0, 3.019600 + q[6]) + kJointVelocityLimitsTolerance[6]}};
}
#else
// libfranka 0.9 (Panda).
constexpr double kTolNumberPacketsLost = 3.0;
constexpr std::array<double, 7> kMaxTorqueRate{{1000 - kLimitEps, 1000 - kLimitEps, 1000 - kLimitEps, 1000 - kLimitEps,
                                                1000 - kLimitEps, 1000 - kLimitEps, 1000 - kLimitEps}};
constexpr std::array<double, 7> kMaxJointJerk{{7500.0 - kLimitEps, 3750.0 - kLimitEps, 5000.0 - kLimitEps,
                                               6250.0 - kLimitEps, 7500.0 - kLimitEps, 10000.0 - kLimitEps,
                                               10000.0 - kLimitEps}};
constexpr std::array<double, 7> kMaxJointAcceleration{{15.0 - kLimitEps, 7.5 - kLimitEps, 10.0 - kLimitEps,
                                                       12.5 - kLimitEps, 15.0 - kLimitEps, 20.0 - kLimitEps,
                                                       20.0 - kLimitEps}};
constexpr std::array<double, 7> kMaxJointVelocity{
    {2.1750 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[0],
     2.1750 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[1],
     2.1750 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[2],
     2.1750 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[3],
     2.6100 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[4],
     2.6100 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[5],
     2.6100 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxJointAcceleration[6]}};
constexpr double kMaxTranslationalJerk = 6500.0 - kLimitEps;
constexpr double kMaxTranslationalAcceleration = 13.0 - kLimitEps;
constexpr double kMaxTranslationalVelocity = 2.0 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxTranslationalAcceleration;
constexpr double kMaxRotationalJerk = 12500.0 - kLimitEps;
constexpr double kMaxRotationalAcceleration = 25.0 - kLimitEps;
constexpr double kMaxRotationalVelocity = 2.5 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxRotationalAcceleration;
constexpr double kMaxElbowJerk = 5000 - kLimitEps;
constexpr double kMaxElbowAcceleration = 10.0 - kLimitEps;
constexpr double kMaxElbowVelocity = 2.1750 - kLimitEps - kTolNumberPacketsLost * kDeltaT * kMaxElbowAcceleration;
#endif

// Both versions. Each value moves from `last_commanded_values` by at most max_derivatives * kDeltaT
// (torques: kMaxTorqueRate). std::invalid_argument if a commanded value is not finite.
std::array<double, 7> limitRate(const std::array<double, 7>& max_derivatives,
                                const std::array<double, 7>& commanded_values,
                                const std::array<double, 7>& last_commanded_values);

// Cartesian velocity O_dP_EE_c [m/s x3, rad/s x3]: the translational and the rotational part are
// each limited in the norm of their velocity, acceleration and jerk.
std::array<double, 6> limitRate(double max_translational_velocity, double max_translational_acceleration,
                                double max_translational_jerk, double max_rotational_velocity,
                                double max_rotational_acceleration, double max_rotational_jerk,
                                const std::array<double, 6>& O_dP_EE_c,         // NOLINT(readability-identifier-naming)
                                const std::array<double, 6>& last_O_dP_EE_c,    // NOLINT(readability-identifier-naming)
                                const std::array<double, 6>& last_O_ddP_EE_c);  // NOLINT(readability-identifier-naming)

// Cartesian pose O_T_EE_c (column-major 4x4): the twist from the last pose is limited as above
// (rotation limits scaled by kFactorCartesianRotationPoseInterface) and integrated once.
// std::invalid_argument for a pose that is not finite or not a homogeneous transform.
std::array<double, 16> limitRate(double max_translational_velocity, double max_translational_acceleration,
                                 double max_translational_jerk, double max_rotational_velocity,
                                 double max_rotational_acceleration, double max_rotational_jerk,
                                 const std::array<double, 16>& O_T_EE_c,         // NOLINT(readability-identifier-naming)
                                 const std::array<double, 16>& last_O_T_EE_c,    // NOLINT(readability-identifier-naming)
                                 const std::array<double, 6>& last_O_dP_EE_c,    // NOLINT(readability-identifier-naming)
                                 const std::array<double, 6>& last_O_ddP_EE_c);  // NOLINT(readability-identifier-naming)

#if CSP_FRANKA_API_VERSION >= 1000
// libfranka 0.15: velocity limits [lower, upper] (position-dependent on the FR3: use
// computeLower/UpperLimitsJointVelocity). One joint velocity, limited in velocity, acceleration
// and jerk; one joint position, whose implied velocity is limited so and integrated once; and the
// same for seven joints.
double limitRate(double upper_limits_velocity, double lower_limits_velocity, double max_acceleration, double max_jerk,
                 double commanded_velocity, double last_commanded_velocity, double last_commanded_acceleration);
double limitRate(double upper_limits_velocity, double lower_limits_velocity, double max_acceleration, double max_jerk,
                 double commanded_position, double last_commanded_position, double last_commanded_velocity,
                 double last_commanded_acceleration);
std::array<double, 7> limitRate(const std::array<double, 7>& upper_limits_velocity,
                                const std::array<double, 7>& lower_limits_velocity,
                                const std::array<double, 7>& max_acceleration, const std::array<double, 7>& max_jerk,
                                const std::array<double, 7>& commanded_velocities,
                                const std::array<double, 7>& last_commanded_velocities,
                                const std::array<double, 7>& last_commanded_accelerations);
std::array<double, 7> limitRate(const std::array<double, 7>& upper_limits_velocity,
                                const std::array<double, 7>& lower_limits_velocity,
                                const std::array<double, 7>& max_acceleration, const std::array<double, 7>& max_jerk,
                                const std::array<double, 7>& commanded_positions,
                                const std::array<double, 7>& last_commanded_positions,
                                const std::array<double, 7>& last_commanded_velocities,
                                const std::array<double, 7>& last_commanded_accelerations);
#else
// libfranka 0.9: a symmetric velocity limit [-max_velocity, max_velocity]. Their own symbols (the
// inline namespace api_0_9), because some of their parameter lists equal 0.15's.
inline namespace api_0_9 {
double limitRate(double max_velocity, double max_acceleration, double max_jerk, double commanded_velocity,
                 double last_commanded_velocity, double last_commanded_acceleration);
double limitRate(double max_velocity, double max_acceleration, double max_jerk, double commanded_position,
                 double last_commanded_position, double last_commanded_velocity, double last_commanded_acceleration);
std::array<double, 7> limitRate(const std::array<double, 7>& max_velocity,
                                const std::array<double, 7>& max_acceleration, const std::array<double, 7>& max_jerk,
                                const std::array<double, 7>& commanded_velocities,
                                const std::array<double, 7>& last_commanded_velocities,
                                const std::array<double, 7>& last_commanded_accelerations);
std::array<double, 7> limitRate(const std::array<double, 7>& max_velocity,
                                const std::array<double, 7>& max_acceleration, const std::array<double, 7>& max_jerk,
                                const std::array<double, 7>& commanded_positions,
                                const std::array<double, 7>& last_commanded_positions,
                                const std::array<double, 7>& last_commanded_velocities,
                                const std::array<double, 7>& last_commanded_accelerations);
}  // namespace api_0_9
#endif

}  // namespace franka
