#include "csp/dynamics/friction.hpp"

#include <Eigen/Cholesky>
#include <array>
#include <cmath>

namespace csp {
namespace {

// Gauss-Seidel sweeps before static_friction_velocity gives up on an exact answer (a safety net:
// the arm's cases settle in a few sweeps).
constexpr int kMaxSweeps = 100;

// The minimiser of 1/2 m v^2 - r v + bound |v| times m: r shrunk towards 0 by bound.
double shrink(double r, double bound) { return r > bound ? r - bound : (r < -bound ? r + bound : 0.0); }

// Which case each joint is in: 0 sticks, +-1 slides that way, 2 has no static friction.
using Case = std::array<int, kNumJoints>;
Case case_of(const Vector7& v, const Vector7& bound) {
  Case c;
  for (int i = 0; i < kNumJoints; ++i) c[i] = bound[i] > 0.0 ? (v[i] > 0.0) - (v[i] < 0.0) : 2;
  return c;
}

// The exact solution of one case: sticking joints at v_i = 0, sliding ones with p_i = bound_i
// sgn(v_i), i.e. M_FF v_F = (M v_free)_F - bound_F sgn(v_F). True if it is the solution: the
// sliders keep their direction and every sticking joint needs at most its bound. Otherwise the
// case is updated (primal-dual active set): a sticking joint that needs more starts to slide, a
// slider that would reverse sticks.
bool solve_case(const Matrix7& M, const Vector7& M_v_free, const Vector7& bound, Case& c, Vector7& v) {
  Matrix7 A = M;
  Vector7 rhs = M_v_free;
  for (int i = 0; i < kNumJoints; ++i) {
    if (c[i] == 0) {
      A.row(i).setZero();
      A.col(i).setZero();
      A(i, i) = 1.0;
      rhs[i] = 0.0;
    } else if (c[i] != 2) {
      rhs[i] -= bound[i] * c[i];
    }
  }
  v = Eigen::LLT<Matrix7>(A).solve(rhs);
  const Vector7 impulse = M_v_free - M * v;
  bool solution = true;
  for (int i = 0; i < kNumJoints; ++i) {
    if (c[i] == 0 && std::abs(impulse[i]) > bound[i] * (1.0 + 1e-9)) {
      c[i] = impulse[i] > 0.0 ? 1 : -1;
      solution = false;
    } else if ((c[i] == 1 || c[i] == -1) && v[i] * c[i] <= 0.0) {
      c[i] = 0;
      solution = false;
    }
  }
  return solution;
}

}  // namespace

// Gaz et al. 2019, eq. (10) as in their code: a sigmoid in dq shifted so that tau_f(0) = 0.
double gaz_friction(double phi1, double phi2, double phi3, double dq) { return GazFriction(phi1, phi2, phi3)(dq); }

// rest_ as phi1 / (1 + e), not phi1 s0: the arithmetic of the law's first form, bit for bit.
GazFriction::GazFriction(double phi1, double phi2, double phi3) : phi1_(phi1), phi2_(phi2), phi3_(phi3) {
  const double e = std::exp(-phi2 * phi3);
  s0_ = 1.0 / (1.0 + e);
  rest_ = phi1 / (1.0 + e);
}

// With s(x) = 1/(1+exp(-x)), s' = s (1 - s), s1 = s(phi2 (dq+phi3)) and s0 = s(phi2 phi3).
GazFrictionGradient GazFriction::gradient(double dq) const {
  const double s1 = logistic(phi2_ * (dq + phi3_));
  const double ds1 = s1 * (1.0 - s1), ds0 = s0_ * (1.0 - s0_);
  return {s1 - s0_, phi1_ * (ds1 * (dq + phi3_) - ds0 * phi3_), phi1_ * phi2_ * (ds1 - ds0)};
}

double stribeck_level(double breakaway, double stribeck_velocity, double dq) {
  const double x = dq / stribeck_velocity;
  return breakaway * std::exp(-x * x);
}

// Coordinate descent on the strictly convex problem (each joint's exact minimiser with the others
// fixed, a Gauss-Seidel sweep) finds which joints stick and which way the others slide; from that
// case a few active-set updates reach the exact solution, where a sticking joint's velocity is
// exactly zero.
Vector7 static_friction_velocity(const Matrix7& M, const Vector7& v_free, const Vector7& bound) {
  if (!(bound.array() > 0.0).any()) return v_free;
  const Vector7 M_v_free = M * v_free;
  Vector7 v = v_free, exact;
  Case previous = case_of(v, bound);
  for (int sweep = 0; sweep < kMaxSweeps; ++sweep) {
    for (int i = 0; i < kNumJoints; ++i) {
      const double r = M_v_free[i] - M.row(i).dot(v) + M(i, i) * v[i];
      v[i] = shrink(r, bound[i]) / M(i, i);
    }
    const Case current = case_of(v, bound);
    if (current == previous) {
      Case guess = current;
      for (int update = 0; update < kNumJoints; ++update)
        if (solve_case(M, M_v_free, bound, guess, exact)) return exact;
    }
    previous = current;
  }
  return v;   // the sweeps' approximation: sticking joints are still exactly at rest
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
