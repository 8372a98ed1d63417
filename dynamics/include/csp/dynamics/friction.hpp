// Joint friction models (link side). Torques have the sign of the motion they oppose: the
// torque a motor must ADD to move the joint, as in tau = M ddq + c + g + tau_f.
#pragma once

#include "csp/dynamics/spatial.hpp"

namespace csp {

struct FrictionModel {
  enum class Type { kNone, kGazSigmoid, kLinear };
  Type type = Type::kNone;
  // kGazSigmoid (Gaz et al., RA-L 2019): phi1 [N m], phi2 [s/rad], phi3 [rad/s]
  Vector7 phi1 = Vector7::Zero(), phi2 = Vector7::Zero(), phi3 = Vector7::Zero();
  // kLinear: viscous [N m s/rad] * dq + coulomb [N m] * sign(dq) + offset [N m]
  Vector7 viscous = Vector7::Zero(), coulomb = Vector7::Zero(), offset = Vector7::Zero();
};

// tau_f(dq). Gaz sigmoid: phi1/(1+exp(-phi2 (dq+phi3))) - phi1/(1+exp(-phi2 phi3)), zero at rest.
Vector7 friction_torque(const FrictionModel& friction, const Vector7& dq);

}  // namespace csp
