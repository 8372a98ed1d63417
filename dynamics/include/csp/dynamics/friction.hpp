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
  // Static friction on top of either law [N m]: at rest a joint holds any net torque up to
  // `breakaway`; sliding, the excess decays with the Stribeck velocity [rad/s] (stribeck_excess).
  Vector7 breakaway = Vector7::Zero();
  Vector7 stribeck_velocity = Vector7::Constant(0.01);
};

// The Gaz et al. (2019) law of one joint, zero at rest (docs/seed-errata.md):
//   tau_f = phi1/(1+exp(-phi2 (dq+phi3))) - phi1/(1+exp(-phi2 phi3)).
double gaz_friction(double phi1, double phi2, double phi3, double dq);

// Partial derivatives of gaz_friction with respect to its parameters (for fitting them).
struct GazFrictionGradient {
  double phi1 = 0.0, phi2 = 0.0, phi3 = 0.0;
};
GazFrictionGradient gaz_friction_gradient(double phi1, double phi2, double phi3, double dq);

// tau_f(dq) of every joint: zero (kNone), gaz_friction per joint (kGazSigmoid), or
// viscous dq + coulomb sign(dq) + offset (kLinear).
Vector7 friction_torque(const FrictionModel& friction, const Vector7& dq);

}  // namespace csp
