// Contact force laws between the arm and its environment (docs/contact.md): a Hunt-Crossley
// normal force and a regularised Coulomb friction. Pure math, no allocation.
//
// Normal force (Hunt & Crossley 1975, "Coefficient of restitution interpreted as damping in
// vibroimpact", J. Appl. Mech. 42(2):440-445; in the form of Marhefka & Orin 1999, "A compliant
// contact model with nonlinear damping for simulation of robotic systems", IEEE Trans. SMC-A
// 29(6):566-572, eq. 5 with lambda = (3/2) alpha k):
//     F_n = k delta^n (1 + (3/2) alpha delta_dot),   clamped at F_n >= 0,
// delta >= 0 the penetration, delta_dot its rate (> 0 going in). The damping is proportional to
// delta^n, so the force is continuous at first touch and at separation; the clamp removes the
// sticky tension the law would otherwise pull with when a fast separation makes the bracket
// negative. For small alpha v_in the coefficient of restitution of an impact at speed v_in is
// e ~ 1 - alpha v_in (Hunt & Crossley's relation; hunt_crossley_rebound_speed gives it exactly).
//
// Friction (regularised Coulomb, as in Drake's stiction tolerance or the smooth Coulomb law of
// Brown & McPhee 2016): F_t = -mu F_n v_t / sqrt(|v_t|^2 + v_s^2). Sliding (|v_t| >> v_s): the
// Coulomb force mu F_n against the slip. A tangential load F below the cone mu F_n does not slide:
// the contact creeps at v_t = v_s F / sqrt((mu F_n)^2 - F^2), of the order of v_s.
#pragma once

#include <optional>
#include <string_view>

#include "csp/dynamics/spatial.hpp"

namespace csp {

struct Material {
  double stiffness = 0.0;   // k [N/m^n], > 0
  double exponent = 1.5;    // n [-], 1 (linear) to 3; 3/2 is Hertz's sphere on a half-space
  double damping = 0.0;     // alpha [s/m], >= 0 (Hunt-Crossley)
  double friction = 0.0;    // mu [-], >= 0 (Coulomb)
};

// What is wrong with a material: the field's name (stiffness, exponent, damping, friction) and
// what it must be; none when the material is valid (finite numbers in the ranges above).
struct MaterialProblem {
  std::string_view key;
  std::string_view expected;
};
std::optional<MaterialProblem> material_problem(const Material& material);

// Hunt-Crossley normal force [N] at penetration delta [m] (<= 0: none) and its rate [m/s].
double hunt_crossley_force(const Material& material, double penetration, double penetration_rate);

// d F_n / d delta at zero rate, n k delta^(n-1) [N/m]: the contact's stiffness for the
// integrator's step-size rule (docs/contact.md).
double hunt_crossley_stiffness(const Material& material, double penetration);

// Exact rebound speed (>= 0) of a mass hitting the material at v_in > 0 with no other force: the
// law has the first integral m/l^2 (l v - ln(1 + l v)) + k delta^(n+1)/(n+1) = const (l = (3/2)
// alpha; Marhefka & Orin 1999 sec. III), so the exit speed solves l v_out + ln(1 - l v_out) =
// -(l v_in - ln(1 + l v_in)), independent of mass, stiffness and exponent. Bisection to 1e-15
// relative. e = v_out / v_in ~ 1 - alpha v_in for small alpha v_in.
double hunt_crossley_rebound_speed(double damping, double impact_speed);

// Regularised Coulomb friction force (the slip's plane) on a contact sliding at v_t [m/s] under
// normal force F_n [N]; regularisation velocity v_s [m/s] > 0.
Vector3 regularized_friction(double friction, double normal_force, const Vector3& slip_velocity,
                             double regularization_velocity);

}  // namespace csp
