// Joint friction models (link side). Torques have the sign of the motion they oppose: the
// torque a motor must ADD to move the joint, as in tau = M ddq + c + g + tau_f.
#pragma once

#include <cmath>

#include "csp/dynamics/spatial.hpp"

namespace csp {

struct FrictionModel {
  enum class Type { kNone, kGazSigmoid, kLinear };
  Type type = Type::kNone;
  // kGazSigmoid (Gaz et al., RA-L 2019): phi1 [N m], phi2 [s/rad], phi3 [rad/s]
  Vector7 phi1 = Vector7::Zero(), phi2 = Vector7::Zero(), phi3 = Vector7::Zero();
  // kLinear: viscous [N m s/rad] * dq + coulomb [N m] * sign(dq) + offset [N m]
  Vector7 viscous = Vector7::Zero(), coulomb = Vector7::Zero(), offset = Vector7::Zero();
  // Static friction (stiction) on top of either law: at rest a joint holds any net torque up to
  // `breakaway` [N m]; sliding, this part decays with the Stribeck velocity [rad/s]
  // (stribeck_level). Zero breakaway: no static friction.
  Vector7 breakaway = Vector7::Zero();
  Vector7 stribeck_velocity = Vector7::Constant(0.05);
};

// The Gaz et al. (2019) law of one joint, zero at rest (docs/seed-errata.md):
//   tau_f = phi1/(1+exp(-phi2 (dq+phi3))) - phi1/(1+exp(-phi2 phi3)).
double gaz_friction(double phi1, double phi2, double phi3, double dq);

// Partial derivatives of the law with respect to its parameters (for fitting them).
struct GazFrictionGradient {
  double phi1 = 0.0, phi2 = 0.0, phi3 = 0.0;
};

// The same law for one set of parameters: its rest term phi1 s(phi2 phi3) is computed once, since a fit
// evaluates the law and its gradient at every sample of a log for each trial of the parameters.
class GazFriction {
 public:
  GazFriction(double phi1, double phi2, double phi3);
  double operator()(double dq) const { return phi1_ / (1.0 + std::exp(-phi2_ * (dq + phi3_))) - rest_; }
  GazFrictionGradient gradient(double dq) const;

 private:
  static double logistic(double x) { return 1.0 / (1.0 + std::exp(-x)); }
  double phi1_, phi2_, phi3_, s0_, rest_;  // rest_ = phi1 s0
};

// Static friction at sliding speed dq (Stribeck): breakaway exp(-(dq / stribeck_velocity)^2), the
// Gaussian decay of Armstrong-Helouvry et al. (1994). Its magnitude only: the sign is the motion's,
// and at rest it is whatever holds the joint, up to `breakaway`. gap's static_friction effect fits
// the same law.
double stribeck_level(double breakaway, double stribeck_velocity, double dq);

// One implicit step of static friction for the whole arm (velocity-level time stepping, as Moreau
// and Jean's, and MuJoCo's `frictionloss`). v_free is the joint velocity the arm reaches at the end
// of a step of length h under every other torque, M its mass matrix (with armature), bound_i =
// h * stribeck_level(...) the largest friction impulse joint i can take. Returns the velocity v that
// minimises 1/2 (v - v_free)^T M (v - v_free) + sum_i bound_i |v_i|, i.e. M (v - v_free) = -p with
// p_i = bound_i sgn(v_i) on a sliding joint and |p_i| <= bound_i on a sticking one (v_i = 0 exactly).
// Unconditionally stable, never adds energy (p^T v >= 0, v^T M v <= v_free^T M v_free), and holds
// a joint without creep below its breakaway torque.
Vector7 static_friction_velocity(const Matrix7& mass_matrix, const Vector7& v_free, const Vector7& bound);

// tau_f(dq) of every joint: zero (kNone), gaz_friction per joint (kGazSigmoid), or
// viscous dq + coulomb sign(dq) + offset (kLinear). Static friction is not in it: it is set-valued
// at rest and is applied implicitly (static_friction_velocity).
Vector7 friction_torque(const FrictionModel& friction, const Vector7& dq);

}  // namespace csp
