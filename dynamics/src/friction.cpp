#include "csp/dynamics/friction.hpp"

#include <cmath>

namespace csp {

// Gaz et al. 2019, eq. (10) as in their code: a sigmoid in dq shifted so that tau_f(0) = 0.
double gaz_friction(double phi1, double phi2, double phi3, double dq) {
  return phi1 / (1.0 + std::exp(-phi2 * (dq + phi3))) - phi1 / (1.0 + std::exp(-phi2 * phi3));
}

// With s(x) = 1/(1+exp(-x)), s' = s (1 - s), s1 = s(phi2 (dq+phi3)) and s0 = s(phi2 phi3).
GazFrictionGradient gaz_friction_gradient(double phi1, double phi2, double phi3, double dq) {
  const double s1 = 1.0 / (1.0 + std::exp(-phi2 * (dq + phi3))), s0 = 1.0 / (1.0 + std::exp(-phi2 * phi3));
  const double ds1 = s1 * (1.0 - s1), ds0 = s0 * (1.0 - s0);
  return {s1 - s0, phi1 * (ds1 * (dq + phi3) - ds0 * phi3), phi1 * phi2 * (ds1 - ds0)};
}

Vector7 friction_torque(const FrictionModel& friction, const Vector7& dq) {
  Vector7 tau = Vector7::Zero();
  switch (friction.type) {
    case FrictionModel::Type::kNone:
      break;
    case FrictionModel::Type::kGazSigmoid:
      for (int i = 0; i < kNumJoints; ++i)
        tau[i] = gaz_friction(friction.phi1[i], friction.phi2[i], friction.phi3[i], dq[i]);
      break;
    case FrictionModel::Type::kLinear:
      for (int i = 0; i < kNumJoints; ++i) {
        const double sign = dq[i] > 0.0 ? 1.0 : (dq[i] < 0.0 ? -1.0 : 0.0);
        tau[i] = friction.viscous[i] * dq[i] + friction.coulomb[i] * sign + friction.offset[i];
      }
      break;
  }
  return tau;
}

}  // namespace csp
