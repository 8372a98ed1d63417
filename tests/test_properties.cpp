// Property tests: physical laws and mathematical identities the dynamics must satisfy, checked on
// seeded random states (csp::test::RandomStates) for the physical inertial sets: Panda gaz2019
// without and with the Franka Hand, and FR3 franka_description.
//
// Tolerances are relative to the size of the compared quantities: |a - b| <= tol * (1 + max|b|).
// Identities that are exact in exact arithmetic get 1e-10 (observed ~1e-14). Comparisons with
// central finite differences get a tolerance from the step h: truncation O(h^2) plus round-off
// O(eps/h); each test states its h and bound.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "csp/dynamics/regressor.hpp"
#include "kdl_peer.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

constexpr int kNumStates = 200;
constexpr double kExact = 1e-10;          // identities that hold exactly in exact arithmetic
constexpr double kMaxVelocity = 2.0;      // rad/s
constexpr double kMaxAcceleration = 5.0;  // rad/s^2

struct Arm {
  std::string name;
  Model model;
};

std::vector<Arm> physical_arms() {
  ModelOptions panda;
  panda.inertia = "gaz2019";
  ModelOptions panda_hand = panda;
  panda_hand.end_effector = "hand";
  return {{"panda_gaz2019", make_model("panda", panda)},
          {"panda_gaz2019_hand", make_model("panda", panda_hand)},
          {"fr3_franka_description", make_model("fr3")}};
}

template <typename A, typename B>
::testing::AssertionResult near_rel(const Eigen::MatrixBase<A>& actual, const Eigen::MatrixBase<B>& expected,
                                    double tolerance) {
  Eigen::Index r = 0, c = 0;
  const double worst = (actual - expected).cwiseAbs().maxCoeff(&r, &c);
  const double bound = tolerance * (1.0 + expected.cwiseAbs().maxCoeff());
  if (worst <= bound) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "max |difference| " << worst << " > " << bound << " at (" << r << ", " << c
                                       << "): actual " << actual(r, c) << ", expected " << expected(r, c)
                                       << "\nactual:\n" << actual << "\nexpected:\n" << expected;
}

// kNumStates random states within the joint limits of `model`, the same for every call.
std::vector<State> random_states(const Model& model, unsigned seed = 42) {
  RandomStates random(seed);
  std::vector<State> states;
  for (int k = 0; k < kNumStates; ++k) {
    State s;
    s.q = random.q(model.parameters().joint_limits);
    s.dq = random.uniform(kMaxVelocity);
    s.ddq = random.uniform(kMaxAcceleration);
    states.push_back(s);
  }
  return states;
}

// Random contact wrenches on every link: forces up to 20 N, moments up to 5 N m.
LinkWrenches random_wrenches(RandomStates& random) {
  LinkWrenches w;
  for (auto& wrench : w) {
    const Vector7 r = random.uniform(1.0);
    wrench << 20.0 * r.head<3>(), 5.0 * r.segment<3>(3);
  }
  return w;
}

Transform pose_of(const Model& model, const Vector7& q, Frame frame) {
  Data data;
  forward_kinematics(model, data, q);
  return frame_pose(data, frame);
}

Matrix6x7 zero_jacobian_of(const Model& model, const Vector7& q, Frame frame) {
  Data data;
  forward_kinematics(model, data, q);
  Matrix6x7 J;
  zero_jacobian(data, frame, J);
  return J;
}

double kinetic_energy(const Model& model, const Vector7& q, const Vector7& dq) {
  return 0.5 * dq.dot(mass_of(model, q) * dq);
}

// sum_i J_i^T f_i for wrenches given in link frame i about its origin. With the body Jacobian of
// joint frame i (rows: origin velocity and angular velocity, both in frame i) the power of f_i is
// f_i . (J_i dq), so the generalized force is J_i^T f_i directly.
Vector7 generalized_wrench_force(const Data& data_after_fk, const LinkWrenches& f) {
  Vector7 tau = Vector7::Zero();
  Matrix6x7 J;
  for (int i = 0; i < kNumJoints; ++i) {
    body_jacobian(data_after_fk, static_cast<Frame>(i), J);
    tau += J.transpose() * f[i];
  }
  return tau;
}

const std::vector<Frame> kAllFrames = {Frame::kJoint1, Frame::kJoint2, Frame::kJoint3, Frame::kJoint4,
                                       Frame::kJoint5, Frame::kJoint6, Frame::kJoint7, Frame::kFlange,
                                       Frame::kEndEffector, Frame::kStiffness};

// ---------------------------------------------------------------------------------------------
// Mass matrix

// Kinetic energy 0.5 dq^T M dq > 0 for every dq != 0 with physical link inertias.
TEST(PropertiesMassMatrix, SymmetricPositiveDefinite) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    ASSERT_TRUE(arm.model.parameters().physically_consistent);
    for (const State& s : random_states(arm.model)) {
      const Matrix7 M = mass_of(arm.model, s.q);
      ASSERT_TRUE(near_rel(M, Matrix7(M.transpose()), 1e-14));
      // Cholesky succeeds exactly for symmetric positive definite matrices; its pivots are the
      // positive ratios of leading principal minors.
      const Eigen::LLT<Matrix7> llt(M);
      ASSERT_EQ(llt.info(), Eigen::Success) << "q = " << s.q.transpose();
      const Vector7 pivots = Matrix7(llt.matrixL()).diagonal();
      ASSERT_GT(pivots.minCoeff(), 0.0) << "q = " << s.q.transpose();
    }
  }
}

// CRBA against inverse dynamics: column j of M is the torque that produces ddq = e_j at rest,
// without gravity (two different algorithms for the same quantity).
TEST(PropertiesMassMatrix, ColumnsEqualInverseDynamicsOfUnitAccelerations) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    const Model weightless = with_gravity(arm.model, Vector3::Zero());
    Data data;
    for (const State& s : random_states(arm.model)) {
      Matrix7 columns;
      for (int j = 0; j < kNumJoints; ++j) {
        Vector7 tau;
        rnea(weightless, data, s.q, Vector7::Zero(), Vector7::Unit(j), tau);
        columns.col(j) = tau;
      }
      ASSERT_TRUE(near_rel(mass_of(arm.model, s.q), columns, kExact));
    }
  }
}

// tau = M(q) ddq + C(q,dq) dq + g(q): the inverse dynamics splits into its three terms.
TEST(PropertiesInverseDynamics, SplitsIntoInertialCoriolisAndGravityTerms) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    Data data;
    for (const State& s : random_states(arm.model)) {
      Vector7 tau, c;
      rnea(arm.model, data, s.q, s.dq, s.ddq, tau);
      coriolis_torque(arm.model, data, s.q, s.dq, c);
      const Vector7 sum = mass_of(arm.model, s.q) * s.ddq + c + gravity_of(arm.model, s.q);
      ASSERT_TRUE(near_rel(tau, sum, kExact));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Coriolis matrix

// Passivity: dM/dt - 2C is skew-symmetric, i.e. dM/dt = C + C^T. dM/dt = sum_k dM/dq_k dq_k is
// taken by a central difference of CRBA along dq: M(q + h dq) - M(q - h dq) over 2h, h = 1e-6 s.
// Truncation ~h^2 |d3M| ~ 1e-11, round-off ~eps |M| / h ~ 1e-9 (observed 1.2e-9); bound 1e-7
// relative to 1 + |dM|.
TEST(PropertiesCoriolis, MassDerivativeMinusTwoCIsSkewSymmetric) {
  constexpr double h = 1e-6;
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    Data data;
    double worst = 0.0;
    for (const State& s : random_states(arm.model)) {
      const Matrix7 dM = (mass_of(arm.model, s.q + h * s.dq) - mass_of(arm.model, s.q - h * s.dq)) / (2.0 * h);
      coriolis_matrix(arm.model, data, s.q, s.dq);
      const Matrix7 N = dM - 2.0 * data.coriolis_matrix;
      ASSERT_TRUE(near_rel(Matrix7(N + N.transpose()), Matrix7::Zero(), 1e-7 * (1.0 + dM.cwiseAbs().maxCoeff())))
          << "q = " << s.q.transpose() << "\ndq = " << s.dq.transpose();
      worst = std::max(worst, (N + N.transpose()).cwiseAbs().maxCoeff());
    }
    RecordProperty(arm.name + "_worst_skew_residual", std::to_string(worst));
  }
}

// C(q,dq) dq from the Coriolis matrix equals the RNEA velocity-product torque.
TEST(PropertiesCoriolis, MatrixTimesVelocityEqualsCoriolisTorque) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    Data data;
    for (const State& s : random_states(arm.model)) {
      Vector7 c;
      coriolis_torque(arm.model, data, s.q, s.dq, c);
      coriolis_matrix(arm.model, data, s.q, s.dq);
      ASSERT_TRUE(near_rel(Vector7(data.coriolis_matrix * s.dq), c, kExact));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Forward dynamics

// Two independent forward dynamics (articulated-body recursion vs. CRBA + Cholesky) agree.
// Torques: gravity compensation plus up to +-20 N m, so accelerations reach tens of rad/s^2.
TEST(PropertiesForwardDynamics, AbaEqualsCholeskySolve) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(7);
    Data data;
    for (const State& s : random_states(arm.model)) {
      const Vector7 tau = gravity_of(arm.model, s.q) + random.uniform(20.0);
      aba(arm.model, data, s.q, s.dq, tau);
      const Vector7 ddq_aba = data.ddq;
      forward_dynamics_cholesky(arm.model, data, s.q, s.dq, tau);
      ASSERT_TRUE(near_rel(ddq_aba, data.ddq, 1e-9));
    }
  }
}

// With contact wrenches: ddq = M^-1 (tau - c - g + sum J_i^T f_i), so ABA with wrenches equals the
// Cholesky solve with the wrenches mapped to joint torques by the link Jacobians.
TEST(PropertiesForwardDynamics, AbaWithLinkWrenchesEqualsCholeskyWithJacobianTranspose) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(8);
    Data data;
    for (const State& s : random_states(arm.model)) {
      const Vector7 tau = gravity_of(arm.model, s.q) + random.uniform(20.0);
      const LinkWrenches f = random_wrenches(random);
      aba(arm.model, data, s.q, s.dq, tau, f);
      const Vector7 ddq_aba = data.ddq;
      forward_kinematics(arm.model, data, s.q);
      const Vector7 tau_contact = generalized_wrench_force(data, f);
      forward_dynamics_cholesky(arm.model, data, s.q, s.dq, tau + tau_contact);
      ASSERT_TRUE(near_rel(ddq_aba, data.ddq, 1e-9));
    }
  }
}

// Inverse dynamics undoes forward dynamics, with and without contact wrenches.
TEST(PropertiesForwardDynamics, RneaInvertsAba) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(9);
    Data data;
    for (const State& s : random_states(arm.model)) {
      const Vector7 tau = gravity_of(arm.model, s.q) + random.uniform(20.0);
      Vector7 back;
      aba(arm.model, data, s.q, s.dq, tau);
      const Vector7 ddq = data.ddq;
      rnea(arm.model, data, s.q, s.dq, ddq, back);
      ASSERT_TRUE(near_rel(back, tau, kExact));

      const LinkWrenches f = random_wrenches(random);
      aba(arm.model, data, s.q, s.dq, tau, f);
      const Vector7 ddq_contact = data.ddq;
      rnea(arm.model, data, s.q, s.dq, ddq_contact, f, back);
      ASSERT_TRUE(near_rel(back, tau, kExact));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Armature: the rotor inertia reflected to the link, I_a,i on joint axis i (Featherstone sec. 7.3,
// Pinocchio model.armature). M becomes M + diag(I_a), RNEA adds I_a,i ddq_i, ABA adds I_a,i to D_i.

// The physical arms with rotor inertias of the order of a geared motor's reflected inertia [kg m^2].
std::vector<Arm> arms_with_armature() {
  std::vector<Arm> arms;
  for (const Arm& arm : physical_arms()) {
    ModelParameters p = arm.model.parameters();
    p.armature << 0.4, 0.4, 0.3, 0.3, 0.1, 0.1, 0.05;
    arms.push_back({arm.name + "_armature", Model(p)});
  }
  return arms;
}

// The two forward dynamics agree with armature and contact wrenches: ABA's D_i = I_a,i + S_i^T U_i
// and the Cholesky solve of (M + diag(I_a)) ddq = tau - c - g + sum J^T f.
TEST(PropertiesArmature, AbaEqualsCholeskyWithLinkWrenches) {
  for (const Arm& arm : arms_with_armature()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(13);
    Data data;
    for (const State& s : random_states(arm.model)) {
      const Vector7 tau = gravity_of(arm.model, s.q) + random.uniform(20.0);
      const LinkWrenches f = random_wrenches(random);
      aba(arm.model, data, s.q, s.dq, tau, f);
      const Vector7 ddq_aba = data.ddq;
      forward_dynamics_cholesky(arm.model, data, s.q, s.dq, tau, f);
      ASSERT_TRUE(near_rel(ddq_aba, data.ddq, 1e-9));
    }
  }
}

// Inverse dynamics undoes forward dynamics with armature and contact wrenches.
TEST(PropertiesArmature, RneaInvertsAbaWithLinkWrenches) {
  for (const Arm& arm : arms_with_armature()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(14);
    Data data;
    for (const State& s : random_states(arm.model)) {
      const Vector7 tau = gravity_of(arm.model, s.q) + random.uniform(20.0);
      const LinkWrenches f = random_wrenches(random);
      aba(arm.model, data, s.q, s.dq, tau, f);
      const Vector7 ddq = data.ddq;
      Vector7 back;
      rnea(arm.model, data, s.q, s.dq, ddq, f, back);
      ASSERT_TRUE(near_rel(back, tau, kExact));
    }
  }
}

// M = d tau / d ddq: column j of CRBA's M is the central difference of RNEA along ddq = e_j, with
// contact wrenches (which do not depend on ddq). RNEA is linear in ddq, so the difference is exact
// but for round-off: h = 1 rad/s^2, bound 1e-9 (observed ~1e-14).
TEST(PropertiesArmature, MassMatrixIsFiniteDifferenceOfRneaInAcceleration) {
  constexpr double h = 1.0;
  for (const Arm& arm : arms_with_armature()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(15);
    Data data;
    for (const State& s : random_states(arm.model)) {
      const LinkWrenches f = random_wrenches(random);
      Matrix7 fd;
      for (int j = 0; j < kNumJoints; ++j) {
        Vector7 plus, minus;
        rnea(arm.model, data, s.q, s.dq, s.ddq + h * Vector7::Unit(j), f, plus);
        rnea(arm.model, data, s.q, s.dq, s.ddq - h * Vector7::Unit(j), f, minus);
        fd.col(j) = (plus - minus) / (2.0 * h);
      }
      ASSERT_TRUE(near_rel(mass_of(arm.model, s.q), fd, kExact));
    }
  }
}

// KDL's joint inertia (KDL::Joint's `inertia`, added by ChainIdSolver_RNE and ChainDynParam) is the
// same rotor model: inverse dynamics, mass matrix and forward dynamics agree with KDL's (absolute
// 1e-9, as in test_kdl.cpp).
TEST(PropertiesArmature, MatchesKdlJointInertia) {
  for (const Arm& arm : arms_with_armature()) {
    SCOPED_TRACE(arm.name);
    KdlPeer kdl(arm.model);
    Data data;
    for (const State& s : random_states(arm.model)) {
      Vector7 tau;
      rnea(arm.model, data, s.q, s.dq, s.ddq, tau);
      ASSERT_TRUE(near(tau, kdl.rnea(s.q, s.dq, s.ddq), 1e-9));
      ASSERT_TRUE(near(mass_of(arm.model, s.q), kdl.mass(s.q), 1e-9));
      aba(arm.model, data, s.q, s.dq, tau);
      ASSERT_TRUE(near(data.ddq, kdl.forward_dynamics(s.q, s.dq, tau), 1e-9));
    }
  }
}

// A rotor inertia is non-negative and finite; anything else is refused by name.
TEST(PropertiesArmature, NegativeOrNonFiniteArmatureRejected) {
  for (const double bad : {-0.1, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    ModelParameters p = physical_arms().front().model.parameters();
    p.armature[3] = bad;
    try {
      const Model model(p);
      ADD_FAILURE() << "accepted armature " << bad;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("armature"), std::string::npos) << e.what();
    }
  }
}

// ---------------------------------------------------------------------------------------------
// External wrenches in inverse dynamics

// By virtual work, a wrench f_i acting on link i (force and moment about the link origin, in link
// frame i) is equivalent to joint torques J_i^T f_i, with J_i the Jacobian of frame i's origin. The
// motors then need tau = rnea(no contact) - sum_i J_i^T f_i. Checked twice: with the body Jacobian
// (rows in frame i, f_i used as given) and with the zero Jacobian (rows in the base frame, the
// force and moment rotated by O_R_i; the moment stays about the same point, frame i's origin).
TEST(PropertiesExternalWrench, RneaSubtractsJacobianTransposeOfLinkWrenches) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(10);
    Data data;
    for (const State& s : random_states(arm.model)) {
      const LinkWrenches f = random_wrenches(random);
      Vector7 free, loaded;
      rnea(arm.model, data, s.q, s.dq, s.ddq, free);
      rnea(arm.model, data, s.q, s.dq, s.ddq, f, loaded);

      forward_kinematics(arm.model, data, s.q);
      ASSERT_TRUE(near_rel(loaded, Vector7(free - generalized_wrench_force(data, f)), kExact));

      Vector7 via_base = Vector7::Zero();
      Matrix6x7 J;
      for (int i = 0; i < kNumJoints; ++i) {
        zero_jacobian(data, static_cast<Frame>(i), J);
        const Matrix3& R = data.O_T_joint[i].rotation;
        Vector6 f_base;
        f_base << R * f[i].head<3>(), R * f[i].tail<3>();
        via_base += J.transpose() * f_base;
      }
      ASSERT_TRUE(near_rel(loaded, Vector7(free - via_base), kExact));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Jacobians

// Column j of the zero Jacobian is the velocity of the frame for dq = e_j: the central difference
// of its position, and of its orientation through the log map, log(R(q+h e_j) R(q-h e_j)^T) / 2h
// (the spatial angular velocity). h = 1e-6 rad: truncation ~h^2 ~ 1e-12 m, round-off ~eps/h ~
// 1e-10 (observed 1.3e-10); bound 1e-8.
TEST(PropertiesJacobian, ZeroJacobianIsFiniteDifferenceOfPoseForAllFrames) {
  constexpr double h = 1e-6;
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    for (const State& s : random_states(arm.model)) {
      for (const Frame frame : kAllFrames) {
        SCOPED_TRACE("frame " + std::to_string(static_cast<int>(frame)));
        Matrix6x7 fd;
        for (int j = 0; j < kNumJoints; ++j) {
          const Vector7 step = h * Vector7::Unit(j);
          const Transform plus = pose_of(arm.model, s.q + step, frame);
          const Transform minus = pose_of(arm.model, s.q - step, frame);
          const Eigen::AngleAxisd rotation(Matrix3(plus.rotation * minus.rotation.transpose()));
          fd.col(j) << (plus.translation - minus.translation) / (2.0 * h), rotation.angle() * rotation.axis() / (2.0 * h);
        }
        ASSERT_TRUE(near_rel(zero_jacobian_of(arm.model, s.q, frame), fd, 1e-8));
      }
    }
  }
}

// point_jacobian's column j is the velocity of a point riding on link `link` for dq = e_j: the
// central difference of the point carried by the link's frame (fixed in it at q), joints past the
// link moving it not at all. Same step and bound as above.
TEST(PropertiesJacobian, PointJacobianIsFiniteDifferenceOfACarriedPoint) {
  constexpr double h = 1e-6;
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    Data data;
    for (const State& s : random_states(arm.model)) {
      forward_kinematics(arm.model, data, s.q);
      for (int link = 1; link <= kNumJoints; ++link) {
        const Transform& frame = data.O_T_joint[link - 1];
        const Vector3 point = frame.translation + frame.rotation * Vector3(0.05, -0.03, 0.11);   // any point on the link
        const Vector3 local = frame.rotation.transpose() * (point - frame.translation);
        auto carried = [&](const Vector7& q) {
          Data moved;
          forward_kinematics(arm.model, moved, q);
          const Transform& f = moved.O_T_joint[link - 1];
          return Vector3(f.translation + f.rotation * local);
        };
        Matrix3x7 fd;
        for (int j = 0; j < kNumJoints; ++j)
          fd.col(j) = (carried(s.q + h * Vector7::Unit(j)) - carried(s.q - h * Vector7::Unit(j))) / (2.0 * h);
        ASSERT_TRUE(near_rel(point_jacobian(data, link, point), fd, 1e-8)) << "link " << link;
      }
    }
  }
}

// The body Jacobian is the zero Jacobian with both row blocks expressed in the frame itself.
TEST(PropertiesJacobian, BodyJacobianIsRotatedZeroJacobian) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    Data data;
    for (const State& s : random_states(arm.model)) {
      forward_kinematics(arm.model, data, s.q);
      for (const Frame frame : kAllFrames) {
        Matrix6x7 J0, Jb;
        zero_jacobian(data, frame, J0);
        body_jacobian(data, frame, Jb);
        const Matrix3& R = frame_pose(data, frame).rotation;
        Matrix6x7 rotated;
        rotated << R * Jb.topRows<3>(), R * Jb.bottomRows<3>();
        ASSERT_TRUE(near_rel(rotated, J0, kExact));
      }
    }
  }
}

// dJ/dt = d/ds J(q + s dq) at s = 0, by a central difference with h = 1e-6 s (|dq| <= 2 rad/s):
// truncation ~1e-11, round-off ~1e-10 (observed 2e-10); bound 1e-8.
TEST(PropertiesJacobian, TimeDerivativeIsFiniteDifferenceAlongVelocity) {
  constexpr double h = 1e-6;
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    Data data;
    for (const State& s : random_states(arm.model)) {
      forward_kinematics(arm.model, data, s.q);
      for (const Frame frame : kAllFrames) {
        SCOPED_TRACE("frame " + std::to_string(static_cast<int>(frame)));
        Matrix6x7 J_dot;
        zero_jacobian_time_derivative(data, frame, s.dq, J_dot);
        const Matrix6x7 fd =
            (zero_jacobian_of(arm.model, s.q + h * s.dq, frame) - zero_jacobian_of(arm.model, s.q - h * s.dq, frame)) /
            (2.0 * h);
        ASSERT_TRUE(near_rel(J_dot, fd, 1e-8));
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Gravity

// g(q) = dV/dq with V = -sum m_i g . c_i(q), the potential energy computed from the CoM positions
// of the parameters (a physical law, independent of the recursion). Central difference, h = 1e-6
// rad: with V ~ 1e2 J the round-off is ~eps V / h ~ 1e-8 N m and the truncation ~h^2 |d3V| ~
// 1e-10 N m (observed 5e-9 relative); bound 1e-7 relative to 1 + |g| (|g| up to ~50 N m).
TEST(PropertiesGravity, TorqueIsGradientOfPotentialEnergy) {
  constexpr double h = 1e-6;
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    for (const State& s : random_states(arm.model)) {
      Vector7 gradient;
      for (int j = 0; j < kNumJoints; ++j) {
        const Vector7 step = h * Vector7::Unit(j);
        gradient[j] = (potential_energy(arm.model, s.q + step) - potential_energy(arm.model, s.q - step)) / (2.0 * h);
      }
      ASSERT_TRUE(near_rel(gravity_of(arm.model, s.q), gradient, 1e-7));
    }
  }
}

// The gravity torque is linear in the gravity vector: g(q; a G1 + b G2) = a g(q; G1) + b g(q; G2).
TEST(PropertiesGravity, TorqueIsLinearInGravityVector) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(11);
    EXPECT_TRUE(near_rel(gravity_of(with_gravity(arm.model, Vector3::Zero()), Vector7::Zero()), Vector7::Zero(), 0.0));
    for (const State& s : random_states(arm.model)) {
      const Vector7 r = random.uniform(2.0);
      const double a = r[0], b = r[1];
      const Vector3 G1 = arm.model.gravity();
      const Vector3 G2 = 9.81 * r.tail<3>();
      const Vector7 g1 = gravity_of(arm.model, s.q);
      const Vector7 g2 = gravity_of(with_gravity(arm.model, G2), s.q);
      ASSERT_TRUE(near_rel(gravity_of(with_gravity(arm.model, a * G1), s.q), Vector7(a * g1), kExact));
      ASSERT_TRUE(near_rel(gravity_of(with_gravity(arm.model, a * G1 + b * G2), s.q), Vector7(a * g1 + b * g2), kExact));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Energy

// A frictionless arm swinging freely (tau = 0) conserves E = 0.5 dq^T M dq + V. Integrated with
// classical RK4 on (q, dq) using ABA, h = 1e-4 s for 2 s (20 000 steps), two random starts per
// arm (q within the limits, |dq| <= 1 rad/s; the arm then falls freely through any pose). RK4's
// global error is O(h^4) ~ 1e-16 per unit time scale, so the energy drift is round-off dominated
// (observed <= 5e-11 of the energy scale). We require |E - E0| <= 1e-8 * scale, scale =
// max(|E0|, |V|, T over the run, 1 J): a wrong Coriolis, gravity or inertia term breaks this by
// orders of magnitude, while an O(h^4) integrator error cannot reach it.
TEST(PropertiesEnergy, FrictionlessFreeSwingConservesEnergy) {
  constexpr double h = 1e-4;
  constexpr int kSteps = 20000;
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(12);
    Data data;
    const auto acceleration = [&](const Vector7& q, const Vector7& dq) {
      aba(arm.model, data, q, dq, Vector7::Zero());
      return Vector7(data.ddq);
    };
    for (int trial = 0; trial < 2; ++trial) {
      Vector7 q = random.q(arm.model.parameters().joint_limits);
      Vector7 dq = random.uniform(1.0);
      const double E0 = kinetic_energy(arm.model, q, dq) + potential_energy(arm.model, q);
      double scale = std::max(1.0, std::abs(E0)), worst = 0.0;
      for (int step = 1; step <= kSteps; ++step) {
        const Vector7 k1q = dq, k1v = acceleration(q, dq);
        const Vector7 k2q = dq + 0.5 * h * k1v, k2v = acceleration(q + 0.5 * h * k1q, k2q);
        const Vector7 k3q = dq + 0.5 * h * k2v, k3v = acceleration(q + 0.5 * h * k2q, k3q);
        const Vector7 k4q = dq + h * k3v, k4v = acceleration(q + h * k3q, k4q);
        q += h / 6.0 * (k1q + 2.0 * k2q + 2.0 * k3q + k4q);
        dq += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        if (step % 50 == 0) {
          const double T = kinetic_energy(arm.model, q, dq), V = potential_energy(arm.model, q);
          scale = std::max({scale, T, std::abs(V)});
          worst = std::max(worst, std::abs(T + V - E0));
        }
      }
      EXPECT_LE(worst, 1e-8 * scale) << "trial " << trial << ": E0 = " << E0 << " J, energy scale " << scale << " J";
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Friction

FrictionModel friction_set(const std::string& name) {
  ModelOptions o;
  o.friction = name;
  return make_model("panda", o).parameters().friction;
}

// Gaz sigmoid: zero at rest; opposes motion (tau_f has the sign of dq, since the sigmoid is
// increasing and shifted to pass through 0 at dq = 0); monotonically increasing in dq; and once
// saturated (|dq| > 6/phi2, sigmoid within e^-6 of its limits) tau_f(dq) + tau_f(-dq) equals the
// constant offset of its two asymptotes, phi1 (1 - 2 sigma(phi2 phi3)): odd up to that offset.
TEST(PropertiesFriction, GazSigmoidIsZeroAtRestOpposesMotionAndIncreases) {
  const FrictionModel f = friction_set("gaz2019");
  ASSERT_EQ(f.type, FrictionModel::Type::kGazSigmoid);
  EXPECT_TRUE(near_rel(friction_torque(f, Vector7::Zero()), Vector7::Zero(), 0.0));   // exactly zero

  RandomStates random(13);
  for (int k = 0; k < kNumStates; ++k) {
    Vector7 dq = random.uniform(5.0);
    for (int i = 0; i < kNumJoints; ++i)
      if (std::abs(dq[i]) < 1e-3) dq[i] = std::copysign(1e-3, dq[i]);
    const Vector7 tau = friction_torque(f, dq);
    for (int i = 0; i < kNumJoints; ++i) ASSERT_GT(tau[i] * dq[i], 0.0) << "joint " << i + 1 << " dq = " << dq[i];
  }

  for (int i = 0; i < kNumJoints; ++i) {
    double previous = -1e300;
    for (double v = -5.0; v <= 5.0; v += 1e-3) {
      const double tau = friction_torque(f, Vector7::Constant(v))[i];
      ASSERT_GE(tau, previous) << "joint " << i + 1 << " at dq = " << v;
      previous = tau;
    }
    const double saturated = 6.0 / f.phi2[i];
    const double offset = f.phi1[i] * (1.0 - 2.0 / (1.0 + std::exp(-f.phi2[i] * f.phi3[i])));
    for (const double v : {saturated, 2.0 * saturated, 10.0}) {
      const double sum = friction_torque(f, Vector7::Constant(v))[i] + friction_torque(f, Vector7::Constant(-v))[i];
      EXPECT_NEAR(sum, offset, 2.0 * std::exp(-6.0) * f.phi1[i]) << "joint " << i + 1 << " at |dq| = " << v;
    }
  }
}

// Linear model tau_f = f_v dq + f_c sign(dq) + f_o with the Gaz et al. CLS and OSI columns read
// from the JSON (at rest only the offset remains).
TEST(PropertiesFriction, LinearModelMatchesPublishedCoefficients) {
  const nlohmann::json& alternatives = franka_models().at("dynamics").at("panda_gaz2019_linear_friction_alternatives");
  for (const auto& [set, column] : {std::pair<std::string, std::string>{"gaz2019_linear_cls", "CLS"},
                                    std::pair<std::string, std::string>{"gaz2019_linear_osi", "OSI"}}) {
    SCOPED_TRACE(set);
    const FrictionModel f = friction_set(set);
    ASSERT_EQ(f.type, FrictionModel::Type::kLinear);
    const Vector7 fv = vector_from<7>(alternatives.at(column).at("f_v"));
    const Vector7 fc = vector_from<7>(alternatives.at(column).at("f_c"));
    const Vector7 fo = vector_from<7>(alternatives.at(column).at("f_o"));
    EXPECT_TRUE(near_rel(friction_torque(f, Vector7::Zero()), fo, 0.0));
    RandomStates random(14);
    for (int k = 0; k < kNumStates; ++k) {
      const Vector7 dq = random.uniform(3.0);
      Vector7 expected;
      for (int i = 0; i < kNumJoints; ++i) expected[i] = fv[i] * dq[i] + fc[i] * (dq[i] > 0.0 ? 1.0 : -1.0) + fo[i];
      ASSERT_TRUE(near_rel(friction_torque(f, dq), expected, 1e-14));
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Loads on the flange

RigidBodyInertia random_load(RandomStates& random, bool point_mass) {
  const Vector7 r = random.uniform(1.0);
  RigidBodyInertia load;
  load.mass = 1.0 + 0.5 * r[0];
  load.com = Vector3(0.05 * r[1], 0.05 * r[2], 0.08 + 0.05 * r[3]);
  if (!point_mass) {
    // A solid box of random size: physically valid inertia, then rotated about z by a random angle.
    const Vector3 size = Vector3(0.1, 0.08, 0.06) + 0.03 * r.tail<3>().cwiseAbs();
    const double m = load.mass;
    const Matrix3 box = Vector3(m / 12 * (size.y() * size.y() + size.z() * size.z()),
                                m / 12 * (size.x() * size.x() + size.z() * size.z()),
                                m / 12 * (size.x() * size.x() + size.y() * size.y()))
                            .asDiagonal();
    const Matrix3 R = Eigen::AngleAxisd(3.0 * r[4], Vector3::UnitZ()).toRotationMatrix();
    load.inertia = R * box * R.transpose();
  }
  return load;
}

// A point mass m at p on the flange adds exactly the torque that holds it against gravity:
// g_loaded(q) - g(q) = -J_p(q)^T (m G), J_p the translational Jacobian of the point p, built from
// the flange Jacobian as v_p = v_F + w x (p - o_F).
TEST(PropertiesLoad, PointMassOnFlangeAddsJacobianTransposeOfItsWeight) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(15);
    Data data;
    for (const State& s : random_states(arm.model)) {
      const RigidBodyInertia load = random_load(random, true);
      const Model loaded = with_load(arm.model, load);
      forward_kinematics(arm.model, data, s.q);
      Matrix6x7 J_F;
      zero_jacobian(data, Frame::kFlange, J_F);
      const Vector3 r = data.O_T_F.rotation * load.com;   // p - o_F in base coordinates
      const Eigen::Matrix<double, 3, 7> J_p = J_F.topRows<3>() - skew(r) * J_F.bottomRows<3>();
      const Vector7 expected = -J_p.transpose() * (load.mass * arm.model.gravity());
      ASSERT_TRUE(near_rel(Vector7(gravity_of(loaded, s.q) - gravity_of(arm.model, s.q)), expected, kExact));
    }
  }
}

// A rigid load on the flange is dynamically the same as link 7 made heavier: combine link 7 and
// the load by hand (CoM by mass weighting, inertia by the parallel-axis theorem, both in link
// frame 7) and compare the full inverse dynamics.
TEST(PropertiesLoad, FlangeLoadEqualsLink7WithTheLoadAddedByHand) {
  for (const Arm& arm : physical_arms()) {
    SCOPED_TRACE(arm.name);
    RandomStates random(16);
    Data data;
    for (const State& s : random_states(arm.model)) {
      const RigidBodyInertia load = random_load(random, false);
      const Model loaded = with_load(arm.model, load);

      ModelParameters p = arm.model.parameters();
      const Transform& T = p.link7_T_flange;
      const RigidBodyInertia link7 = p.links[6];
      const Vector3 load_com = T * load.com;
      const Matrix3 load_inertia = T.rotation * load.inertia * T.rotation.transpose();
      const double m = link7.mass + load.mass;
      const Vector3 com = (link7.mass * link7.com + load.mass * load_com) / m;
      const auto shift = [&](double mass, const Vector3& d) {   // parallel axis: m (|d|^2 1 - d d^T)
        return Matrix3(mass * (d.squaredNorm() * Matrix3::Identity() - d * d.transpose()));
      };
      p.links[6] = {m, com, link7.inertia + shift(link7.mass, link7.com - com) + load_inertia + shift(load.mass, load_com - com)};
      const Model by_hand(p);

      Vector7 tau_loaded, tau_by_hand;
      rnea(loaded, data, s.q, s.dq, s.ddq, tau_loaded);
      rnea(by_hand, data, s.q, s.dq, s.ddq, tau_by_hand);
      ASSERT_TRUE(near_rel(tau_loaded, tau_by_hand, kExact));
    }
  }
}

// Physical consistency and the log-Cholesky parametrisation (dynamics/regressor.hpp).
// The pseudo-inertia of a solid box is known in closed form: Sigma about its centre is
// m/12 diag(a^2, b^2, c^2) (the second moments), and about a point at -c from it Sigma + m c c^T.
TEST(PhysicalInertia, PseudoInertiaOfASolidBoxAndTheTriangleInequality) {
  const double m = 2.0, a = 0.3, b = 0.2, c = 0.1;
  const Vector3 com(0.05, -0.02, 0.1);
  const Matrix3 about_com = m / 12.0 * Vector3(b * b + c * c, a * a + c * c, a * a + b * b).asDiagonal();
  const LinkParameters p = link_parameters(SpatialInertia::from({m, com, about_com}));
  Eigen::Matrix4d expected = Eigen::Matrix4d::Zero();
  expected.topLeftCorner<3, 3>() = m / 12.0 * Vector3(a * a, b * b, c * c).asDiagonal();
  expected.topLeftCorner<3, 3>() += m * com * com.transpose();
  expected.topRightCorner<3, 1>() = m * com;
  expected.bottomLeftCorner<1, 3>() = m * com.transpose();
  expected(3, 3) = m;
  EXPECT_TRUE(near_rel(pseudo_inertia(p), expected, kExact));
  EXPECT_TRUE(physically_consistent(p));
  // Positive mass and a positive-definite inertia that breaks the triangle inequality (Izz > Ixx + Iyy)
  // are no body; neither is a negative mass.
  const LinkParameters impossible = link_parameters(SpatialInertia::from({m, com, Vector3(1.0, 1.0, 3.0).asDiagonal()}));
  EXPECT_FALSE(physically_consistent(impossible));
  EXPECT_THROW(to_log_cholesky(impossible), std::domain_error);
  LinkParameters negative = p;
  negative[0] = -m;
  EXPECT_FALSE(physically_consistent(negative));
}

TEST(PhysicalInertia, LogCholeskyRoundTripsEveryLinkAndAnyThetaIsAPhysicalBody) {
  for (const Arm& arm : physical_arms())
    for (int i = 0; i < kNumJoints; ++i) {
      const LinkParameters p = link_parameters(arm.model.body(i));
      ASSERT_TRUE(physically_consistent(p)) << arm.name << " link " << i + 1;
      EXPECT_TRUE(near_rel(from_log_cholesky(to_log_cholesky(p)), p, kExact)) << arm.name << " link " << i + 1;
    }
  std::mt19937_64 engine(3);
  std::normal_distribution<double> normal(0.0, 1.5);
  for (int draw = 0; draw < 1000; ++draw) {
    LinkParameters theta;
    for (double& t : theta) t = normal(engine);
    const LinkParameters p = from_log_cholesky(theta);
    const RigidBodyInertia body = rigid_body(spatial_inertia(p));
    ASSERT_GT(body.mass, 0.0) << theta.transpose();
    ASSERT_TRUE(is_physical_inertia(body.inertia)) << theta.transpose();  // positive definite, triangle inequality
    // One theta per body (to 1e-6: theta this spread makes ill-conditioned pseudo-inertias, whose
    // Cholesky factor loses digits).
    EXPECT_TRUE(near_rel(to_log_cholesky(p), theta, 1e-6));
  }
}

TEST(PhysicalInertia, LogCholeskyJacobianMatchesCentralDifferences) {
  std::mt19937_64 engine(4);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int draw = 0; draw < 20; ++draw) {
    LinkParameters theta;
    for (double& t : theta) t = normal(engine);
    const Eigen::Matrix<double, kLinkParameters, kLinkParameters> jacobian = from_log_cholesky_jacobian(theta);
    for (int k = 0; k < kLinkParameters; ++k) {
      const double h = 1e-6;
      const LinkParameters step = h * LinkParameters::Unit(k);
      const LinkParameters numeric = (from_log_cholesky(theta + step) - from_log_cholesky(theta - step)) / (2.0 * h);
      EXPECT_TRUE(near_rel(jacobian.col(k), numeric, 1e-7)) << "parameter " << k;
    }
  }
}

}  // namespace
}  // namespace csp::test
