#include "csp/dynamics/contact.hpp"

#include <cmath>

namespace csp {

// Exponents above 3 are no contact law CSP knows a source for (Hertz 3/2, linear 1, soft tissue
// fits between); bounded so that a typo does not become a numerically absurd material.
constexpr double kMaxExponent = 3.0;

std::optional<MaterialProblem> material_problem(const Material& m) {
  if (!(std::isfinite(m.stiffness) && m.stiffness > 0.0)) return MaterialProblem{"stiffness", "a positive finite stiffness k [N/m^n]"};
  if (!(m.exponent >= 1.0 && m.exponent <= kMaxExponent)) return MaterialProblem{"exponent", "an exponent n from 1 to 3"};
  if (!(std::isfinite(m.damping) && m.damping >= 0.0)) return MaterialProblem{"damping", "a non-negative finite damping alpha [s/m]"};
  if (!(std::isfinite(m.friction) && m.friction >= 0.0)) return MaterialProblem{"friction", "a non-negative finite friction coefficient mu"};
  return std::nullopt;
}

double hunt_crossley_force(const Material& m, double penetration, double penetration_rate) {
  if (penetration <= 0.0) return 0.0;
  const double elastic = m.stiffness * std::pow(penetration, m.exponent);
  return std::max(0.0, elastic * (1.0 + 1.5 * m.damping * penetration_rate));
}

double hunt_crossley_stiffness(const Material& m, double penetration) {
  if (penetration <= 0.0) return m.exponent == 1.0 ? m.stiffness : 0.0;
  return m.exponent * m.stiffness * std::pow(penetration, m.exponent - 1.0);
}

double hunt_crossley_rebound_speed(double damping, double impact_speed) {
  const double l = 1.5 * damping;
  if (l == 0.0 || impact_speed <= 0.0) return impact_speed;
  // g(u) = u + ln(1 - u) for u = l v_out in [0, 1): 0 at 0, decreasing to -infinity at 1.
  const double target = -(l * impact_speed - std::log1p(l * impact_speed));
  double lo = 0.0, hi = 1.0;
  while (hi - lo > 1e-15 * hi) {
    const double mid = 0.5 * (lo + hi);
    if (mid + std::log1p(-mid) > target) lo = mid;
    else hi = mid;
  }
  return 0.5 * (lo + hi) / l;
}

Vector3 regularized_friction(double friction, double normal_force, const Vector3& slip_velocity,
                             double regularization_velocity) {
  const double scale = friction * normal_force /
                       std::sqrt(slip_velocity.squaredNorm() + regularization_velocity * regularization_velocity);
  return -scale * slip_velocity;
}

}  // namespace csp
