// Joint and Cartesian limits with libfranka's names, and the per-sample check of a joint state
// against them that the emulator's reflexes and the planner's trajectory check share.
#pragma once

#include <bitset>

#include "csp/dynamics/spatial.hpp"

namespace csp {

// Round-off allowance of the limit checks that judge computed values (a commanded trajectory, a
// planned one) rather than the robot's own state.
inline constexpr double kLimitTolerance = 1e-9;

// The bound on the power the joints deliver, sum_j max(0, tau_j dq_j) [W] (libfranka's
// power_limit_violation), unless a robot file's joint limit set gives its own (power_max). Franka
// publishes no value: 80 W is the dynamic-power bound of power and force limiting in
// ISO 10218-1:2011 5.10.5.
inline constexpr double kDefaultPowerMax = 80.0;

struct JointLimits {
  Vector7 q_min = Vector7::Zero(), q_max = Vector7::Zero();   // [rad]
  Vector7 dq_max = Vector7::Zero();                           // [rad/s]
  Vector7 ddq_max = Vector7::Zero();                          // [rad/s^2]
  Vector7 dddq_max = Vector7::Zero();                         // [rad/s^3]
  Vector7 tau_max = Vector7::Zero();                          // [N m]
  Vector7 dtau_max = Vector7::Zero();                         // [N m/s]
  // FR3: velocity limits that shrink near the position limits (Franka docs formula).
  bool position_based_velocity = false;
  Vector7 dq_offset = Vector7::Zero();                        // [rad/s]
  Vector7 ddq_dec = Vector7::Zero();                          // [rad/s^2]
  double power_max = kDefaultPowerMax;                        // [W], see kDefaultPowerMax

  // Velocity bounds at position q: constant +-dq_max, or the position-based formula
  //   upper = min(dq_max, max(0, -dq_offset + sqrt(max(0, 2 ddq_dec (q_max - q))))).
  Vector7 dq_upper(const Vector7& q) const;
  Vector7 dq_lower(const Vector7& q) const;
};

// The power the joints deliver to the arm, sum_j max(0, tau_j dq_j) [W]: joints that brake the
// arm (negative power) do not offset the others.
double joint_power(const Vector7& tau, const Vector7& dq);

// Which limits one joint state violates, joint by joint, each beyond `tolerance` (0: the exact
// comparison): the position, the velocity against dq_lower(q)..dq_upper(q), |tau| against tau_max,
// and `power` (joint_power of the caller's torque) against power_max. The torque and the power
// are the caller's to choose: the emulator judges the sensed torque's range and the true torque's power.
struct LimitViolations {
  std::bitset<kNumJoints> position, velocity, torque;
  bool power = false;
};
LimitViolations limit_violations(const JointLimits& limits, const Vector7& q, const Vector7& dq, const Vector7& tau,
                                 double power, double tolerance);

struct CartesianLimits {
  struct Axis {
    double v_max = 0.0, a_max = 0.0, j_max = 0.0;
  };
  Axis translation, rotation, elbow;
};

}  // namespace csp
