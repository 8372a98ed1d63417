// The specialised algorithms (issue 29) against their textbook forms, written out here as the
// library had them before: the Coriolis matrix in full 6x6 spatial algebra in base coordinates, the
// inertial regressor by its definition (differences of RNEA), and the two forward dynamics against
// the inverse dynamics they invert. Same quantity, other arithmetic.
// Seeded random states, the Panda (gaz2019 with the Hand) and the FR3, with and without armature.
// Tolerance 1e-12 relative to the largest entry of the reference: only rounding differs.
#include <algorithm>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "csp/dynamics/regressor.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

constexpr double kRelative = 1e-12;
constexpr int kStates = 200;

struct FastArm {
  std::string name;
  Model model;
};

Model with_armature(const Model& model, const Vector7& armature) {
  ModelParameters p = model.parameters();
  p.armature = armature;
  return Model(p);
}

std::vector<FastArm> fast_arms() {
  ModelOptions panda;
  panda.inertia = "gaz2019";
  panda.end_effector = "hand";
  const Model panda_model = make_model("panda", panda), fr3_model = make_model("fr3");
  Vector7 armature;
  armature << 0.195, 0.195, 0.195, 0.195, 0.074, 0.074, 0.074;   // order of the FR3's rotor inertias
  return {{"panda", panda_model},
          {"panda_armature", with_armature(panda_model, armature)},
          {"fr3", fr3_model},
          {"fr3_armature", with_armature(fr3_model, armature)}};
}

template <typename A, typename B>
::testing::AssertionResult relatively_near(const Eigen::MatrixBase<A>& actual, const Eigen::MatrixBase<B>& expected) {
  const double worst = (actual - expected).cwiseAbs().maxCoeff();
  const double bound = kRelative * expected.cwiseAbs().maxCoeff();
  if (worst <= bound) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "max |difference| " << worst << " > " << bound << "\nactual:\n"
                                       << actual << "\nexpected:\n" << expected;
}

// Base-frame spatial quantities of every body: pose from forward_kinematics, then the textbook forms.
struct BaseFrameBodies {
  std::array<Matrix6, kNumJoints> inertia;
  std::array<Vector6, kNumJoints> velocity, axis;
};

BaseFrameBodies base_frame_bodies(const Model& model, const Vector7& q, const Vector7& dq) {
  Data data;
  forward_kinematics(model, data, q);
  BaseFrameBodies bodies;
  Vector6 v = Vector6::Zero();
  for (int i = 0; i < kNumJoints; ++i) {
    bodies.inertia[i] = model.body(i).expressed_in(data.O_T_joint[i]).matrix();
    bodies.axis[i] = data.axis[i];
    v += data.axis[i] * dq[i];
    bodies.velocity[i] = v;
  }
  return bodies;
}

// Echeandia & Wensing 2021, Algorithm 1, with B_i as the 6x6 product of its definition.
Matrix7 reference_coriolis_matrix(const Model& model, const Vector7& q, const Vector7& dq) {
  const BaseFrameBodies b = base_frame_bodies(model, q, dq);
  std::array<Vector6, kNumJoints> axis_dot;
  for (int k = 0; k < kNumJoints; ++k) axis_dot[k] = cross_motion_matrix(b.velocity[k]) * b.axis[k];
  Matrix7 C;
  Matrix6 composite_inertia = Matrix6::Zero(), composite_B = Matrix6::Zero();
  for (int m = kNumJoints - 1; m >= 0; --m) {
    const Matrix6& I = b.inertia[m];
    const Vector6& v = b.velocity[m];
    composite_inertia += I;
    composite_B += 0.5 * (cross_force_matrix(v) * I + cross_force_bar_matrix(I * v) - I * cross_motion_matrix(v));
    const Vector6 F = composite_inertia * axis_dot[m] + composite_B * b.axis[m];
    for (int j = 0; j <= m; ++j) C(j, m) = b.axis[j].dot(F);
    for (int k = 0; k < m; ++k)
      C(m, k) = (composite_inertia * b.axis[m]).dot(axis_dot[k]) + (composite_B.transpose() * b.axis[m]).dot(b.axis[k]);
  }
  return C;
}

TEST(DynamicsFast, CoriolisMatrixMatchesTheSixBySixReference) {
  for (const FastArm& arm : fast_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(29);
    Data data;
    for (int k = 0; k < kStates; ++k) {
      const Vector7 q = random.q(arm.model.parameters().joint_limits), dq = random.uniform(2.5);
      coriolis_matrix(arm.model, data, q, dq);
      ASSERT_TRUE(relatively_near(data.coriolis_matrix, reference_coriolis_matrix(arm.model, q, dq)));
    }
  }
}

// The regressor by its definition: column k is rnea of the model with standard parameter k increased by
// one (the load lumped into link 7 first) minus rnea of the model.
InertialRegressorRows reference_regressor(const Model& model, const Vector7& q, const Vector7& dq, const Vector7& ddq) {
  Data data;
  Vector7 tau0, tau;
  rnea(model, data, q, dq, ddq, tau0);
  InertialRegressorRows Y;
  for (int k = 0; k < kInertialParameters; ++k) {
    ModelParameters p = model.parameters();
    p.end_effector = p.load = RigidBodyInertia{};
    for (int i = 0; i < kNumJoints; ++i) {
      LinkParameters value = link_parameters(model.body(i));
      if (i == k / kLinkParameters) value[k % kLinkParameters] += 1.0;
      p.links[i] = rigid_body(spatial_inertia(value));
    }
    rnea(Model(p), data, q, dq, ddq, tau);
    Y.col(k) = tau - tau0;
  }
  return Y;
}

TEST(DynamicsFast, RegressorMatchesDifferencesOfRnea) {
  for (const FastArm& arm : fast_arms()) {
    SCOPED_TRACE(arm.name);
    const InertialRegressor regressor(arm.model);
    RandomStates random(3);
    Data data;
    for (int k = 0; k < fewer_when_sanitized(50, 5); ++k) {
      const Vector7 q = random.q(arm.model.parameters().joint_limits), dq = random.uniform(2.5), ddq = random.uniform(10.0);
      const InertialRegressorRows Y = regressor(data, q, dq, ddq);
      // The differences of two RNEAs of ~100 N m lose ~1e-13 absolute: compare to that, relative to
      // the largest torque, not to each column's own size.
      Vector7 tau;
      rnea(arm.model, data, q, dq, ddq, tau);
      const InertialRegressorRows expected = reference_regressor(arm.model, q, dq, ddq);
      ASSERT_LE((Y - expected).cwiseAbs().maxCoeff(), kRelative * tau.cwiseAbs().maxCoeff()) << Y - expected;
      // The standard parameters reproduce the inverse dynamics.
      Eigen::Matrix<double, kInertialParameters, 1> pi;
      for (int i = 0; i < kNumJoints; ++i) pi.segment<kLinkParameters>(kLinkParameters * i) = link_parameters(arm.model.body(i));
      ASSERT_TRUE(relatively_near(Vector7(Y * pi + arm.model.armature().cwiseProduct(ddq)), tau));
    }
  }
}

// Both forward dynamics (aba; crba + rnea bias + LDL^T) are inverted by RNEA: at their ddq, with the
// same link wrenches, rnea gives back tau (RNEA shares neither one's recursion nor its solve). A
// solve's residual scales with the terms it balances, |M| |ddq| (the FR3's light wrist without
// armature reaches thousands of rad/s^2), so the tolerance is relative to those or to tau.
::testing::AssertionResult inverts_rnea(const Model& model, const Vector7& q, const Vector7& dq, const Vector7& tau,
                                        const LinkWrenches& f, const Vector7& ddq) {
  Data data;
  Vector7 tau_back;
  rnea(model, data, q, dq, ddq, f, tau_back);
  crba(model, data, q);
  const double scale = std::max(tau.cwiseAbs().maxCoeff(), (data.mass_matrix.cwiseAbs() * ddq.cwiseAbs()).maxCoeff());
  const double worst = (tau_back - tau).cwiseAbs().maxCoeff();
  if (worst <= kRelative * scale) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "max |rnea(ddq) - tau| " << worst << " > " << kRelative * scale;
}

TEST(DynamicsFast, ForwardDynamicsAreInvertedByRnea) {
  for (const FastArm& arm : fast_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(31);
    Data data;
    for (int k = 0; k < kStates; ++k) {
      const Vector7 q = random.q(arm.model.parameters().joint_limits), dq = random.uniform(2.5);
      const Vector7 tau = random.uniform(50.0);
      const bool with_wrenches = k % 2 == 1;
      LinkWrenches f = kNoLinkWrenches;
      if (with_wrenches)
        for (Vector6& wrench : f) wrench << random.uniform(20.0).head<6>();
      if (with_wrenches)
        aba(arm.model, data, q, dq, tau, f);
      else
        aba(arm.model, data, q, dq, tau);   // the overload without wrenches has its own path
      ASSERT_TRUE(inverts_rnea(arm.model, q, dq, tau, f, data.ddq)) << "aba, wrenches " << with_wrenches;
      forward_dynamics_cholesky(arm.model, data, q, dq, tau, f);
      ASSERT_TRUE(inverts_rnea(arm.model, q, dq, tau, f, data.ddq)) << "cholesky, wrenches " << with_wrenches;
    }
  }
}

// crba's link-frame recursion against the definition of M: column j is the inverse dynamics at
// ddq = e_j less that at ddq = 0 (q at rest; RNEA is linear in ddq, so only rounding differs).
TEST(DynamicsFast, MassMatrixColumnsAreRneaDifferences) {
  for (const FastArm& arm : fast_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(37);
    Data data;
    for (int k = 0; k < kStates; ++k) {
      const Vector7 q = random.q(arm.model.parameters().joint_limits);
      Vector7 at_rest;
      rnea(arm.model, data, q, Vector7::Zero(), Vector7::Zero(), kNoLinkWrenches, at_rest);
      Matrix7 reference;
      for (int j = 0; j < kNumJoints; ++j) {
        Vector7 column;
        rnea(arm.model, data, q, Vector7::Zero(), Vector7::Unit(j), kNoLinkWrenches, column);
        reference.col(j) = column - at_rest;
      }
      crba(arm.model, data, q);
      ASSERT_TRUE(relatively_near(data.mass_matrix, reference)) << "state " << k;
    }
  }
}

}  // namespace
}  // namespace csp::test
