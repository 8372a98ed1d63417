#include "csp/dynamics/friction.hpp"

#include <cmath>

namespace csp {

Vector7 friction_torque(const FrictionModel& friction, const Vector7& dq) {
  Vector7 tau = Vector7::Zero();
  switch (friction.type) {
    case FrictionModel::Type::kNone:
      break;
    case FrictionModel::Type::kGazSigmoid:
      // Gaz et al. 2019, eq. (10) as in their code: a sigmoid in dq shifted so that tau_f(0) = 0.
      for (int i = 0; i < kNumJoints; ++i) {
        const double p1 = friction.phi1[i], p2 = friction.phi2[i], p3 = friction.phi3[i];
        tau[i] = p1 / (1.0 + std::exp(-p2 * (dq[i] + p3))) - p1 / (1.0 + std::exp(-p2 * p3));
      }
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
