#include "csp/dynamics/limits.hpp"

#include <algorithm>
#include <cmath>

namespace csp {

Vector7 JointLimits::dq_upper(const Vector7& q) const {
  if (!position_based_velocity) return dq_max;
  Vector7 upper;
  for (int i = 0; i < kNumJoints; ++i) {
    const double braking = std::sqrt(std::max(0.0, 2.0 * ddq_dec[i] * (q_max[i] - q[i])));
    upper[i] = std::min(dq_max[i], std::max(0.0, -dq_offset[i] + braking));
  }
  return upper;
}

Vector7 JointLimits::dq_lower(const Vector7& q) const {
  if (!position_based_velocity) return -dq_max;
  Vector7 lower;
  for (int i = 0; i < kNumJoints; ++i) {
    const double braking = std::sqrt(std::max(0.0, 2.0 * ddq_dec[i] * (q[i] - q_min[i])));
    lower[i] = std::max(-dq_max[i], std::min(0.0, dq_offset[i] - braking));
  }
  return lower;
}

double joint_power(const Vector7& tau, const Vector7& dq) {
  double power = 0.0;
  for (int i = 0; i < kNumJoints; ++i) power += std::max(0.0, tau[i] * dq[i]);
  return power;
}

LimitViolations limit_violations(const JointLimits& limits, const Vector7& q, const Vector7& dq, const Vector7& tau,
                                 double power, double tolerance) {
  LimitViolations violated;
  const Vector7 upper = limits.dq_upper(q), lower = limits.dq_lower(q);
  for (int i = 0; i < kNumJoints; ++i) {
    violated.position[i] = q[i] > limits.q_max[i] + tolerance || q[i] < limits.q_min[i] - tolerance;
    violated.velocity[i] = dq[i] > upper[i] + tolerance || dq[i] < lower[i] - tolerance;
    violated.torque[i] = std::abs(tau[i]) > limits.tau_max[i] + tolerance;
  }
  violated.power = power > limits.power_max + tolerance;
  return violated;
}

}  // namespace csp
