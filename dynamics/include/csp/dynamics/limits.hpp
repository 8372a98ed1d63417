// Joint and Cartesian limits with libfranka's names.
#pragma once

#include "csp/dynamics/spatial.hpp"

namespace csp {

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

  // Velocity bounds at position q: constant +-dq_max, or the position-based formula
  //   upper = min(dq_max, max(0, -dq_offset + sqrt(max(0, 2 ddq_dec (q_max - q))))).
  Vector7 dq_upper(const Vector7& q) const;
  Vector7 dq_lower(const Vector7& q) const;
};

struct CartesianLimits {
  struct Axis {
    double v_max = 0.0, a_max = 0.0, j_max = 0.0;
  };
  Axis translation, rotation, elbow;
};

}  // namespace csp
