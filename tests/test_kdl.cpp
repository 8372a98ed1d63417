// Cross-checks against KDL (tests/kdl_peer.hpp), an independent implementation: on seeded
// random states, CSP and KDL must agree on inverse dynamics, mass matrix, gravity, Coriolis,
// forward dynamics, EE Jacobian and all frame poses.
//
// Tolerance: 1e-9 absolute everywhere. The largest values compared are joint torques of some
// 10-100 N m and joint accelerations of a few 10 rad/s^2, so 1e-9 absolute is still >= 1e-11
// relative. Observed worst cases (printed by each test): poses and Jacobians ~1e-15, mass matrix
// ~5e-15, torques ~1e-13; forward dynamics up to ~6e-11 on the FR3 without hand, whose light
// link 7 makes M(q) ill-conditioned, so the solve amplifies round-off.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "kdl_peer.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

constexpr int kStatesPerCase = 1000;
constexpr unsigned kSeed = 20240917;
constexpr double kKdlMaxVelocity = 2.5;        // rad/s
constexpr double kKdlMaxAcceleration = 10.0;   // rad/s^2
constexpr double kTolerance = 1e-9;

struct Case {
  std::string name;
  std::string robot;
  ModelOptions options;
};

std::vector<Case> cases() {
  ModelOptions panda_hand;
  panda_hand.inertia = "gaz2019";
  panda_hand.end_effector = "hand";

  ModelOptions panda_urdf;
  panda_urdf.inertia = "franka_ros_urdf";

  // Beyond the reference configurations: exercises the load lumping and a gravity vector off the z axis.
  ModelOptions fr3_loaded;
  fr3_loaded.end_effector = "hand";
  RigidBodyInertia load;
  load.mass = 1.3;
  load.com = Vector3(0.02, -0.015, 0.07);
  load.inertia << 0.004, 0.0002, -0.0003, 0.0002, 0.003, 0.0001, -0.0003, 0.0001, 0.002;
  fr3_loaded.load = load;
  fr3_loaded.gravity = Vector3(0.6, -1.1, -9.7);

  return {{"panda_gaz2019_hand", "panda", panda_hand},
          {"panda_franka_ros_urdf", "panda", panda_urdf},
          {"fr3", "fr3", ModelOptions{}},
          {"fr3_hand_load_tilted_gravity", "fr3", fr3_loaded}};
}

// Runs `error(model, peer, data, state)` -> max |CSP - KDL| over kStatesPerCase seeded states of
// every case, prints the worst value and expects it below kTolerance.
template <class Error>
void expect_agreement(const char* quantity, Error&& error) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    const Model model = make_model(c.robot, c.options);
    KdlPeer peer(model);
    Data data;
    RandomStates random(kSeed);
    double worst = 0.0;
    int worst_state = -1;
    for (int k = 0; k < kStatesPerCase; ++k) {
      State s;
      s.q = random.q(model.parameters().joint_limits);
      s.dq = random.uniform(kKdlMaxVelocity);
      s.ddq = random.uniform(kKdlMaxAcceleration);
      const double e = error(model, peer, data, s);
      if (!std::isfinite(e)) {
        ADD_FAILURE() << quantity << ": non-finite difference at state " << k;
        return;
      }
      if (e > worst) {
        worst = e;
        worst_state = k;
      }
    }
    std::printf("[ KDL      ] %-16s %-30s max |CSP - KDL| = %.3g\n", quantity, c.name.c_str(), worst);
    EXPECT_LE(worst, kTolerance) << quantity << ", worst state " << worst_state;
  }
}

// max(a, b), NaN if either is NaN.
double nan_max(double a, double b) { return std::isnan(a) || a > b ? a : b; }

// Largest |a_ij - b_ij|, NaN if any difference is NaN. (A plain loop: Eigen's vectorised
// maxCoeff drops NaNs, and GCC 12 warns about its AVX-512 path.)
template <class A, class B>
double max_abs_difference(const A& a, const B& b) {
  double worst = 0.0;
  for (Eigen::Index c = 0; c < a.cols(); ++c) {
    for (Eigen::Index r = 0; r < a.rows(); ++r) worst = nan_max(std::abs(a(r, c) - b(r, c)), worst);
  }
  return worst;
}

double pose_difference(const Transform& a, const Transform& b) {
  return nan_max(max_abs_difference(a.rotation, b.rotation), max_abs_difference(a.translation, b.translation));
}

TEST(KdlPeerChain, HasSevenRevoluteSegmentsAndAFixedEndEffector) {
  for (const Case& c : cases()) {
    SCOPED_TRACE(c.name);
    KdlPeer peer(make_model(c.robot, c.options));
    // Franka's first MDH row has a = alpha = 0, so there is no fixed base segment.
    EXPECT_EQ(peer.num_dynamics_segments(), 7);
    EXPECT_EQ(peer.num_segments(), 8);
  }
}

TEST(KdlCrossCheck, InverseDynamics) {
  expect_agreement("rnea", [](const Model& model, KdlPeer& peer, Data& data, const State& s) {
    Vector7 tau;
    rnea(model, data, s.q, s.dq, s.ddq, tau);
    return max_abs_difference(tau, peer.rnea(s.q, s.dq, s.ddq));
  });
}

TEST(KdlCrossCheck, MassMatrix) {
  expect_agreement("mass matrix", [](const Model& model, KdlPeer& peer, Data& data, const State& s) {
    crba(model, data, s.q);
    return max_abs_difference(data.mass_matrix, peer.mass(s.q));
  });
}

TEST(KdlCrossCheck, Gravity) {
  expect_agreement("gravity", [](const Model& model, KdlPeer& peer, Data& data, const State& s) {
    Vector7 g;
    gravity_torque(model, data, s.q, g);
    return max_abs_difference(g, peer.gravity(s.q));
  });
}

TEST(KdlCrossCheck, CoriolisVector) {
  expect_agreement("coriolis", [](const Model& model, KdlPeer& peer, Data& data, const State& s) {
    Vector7 c;
    coriolis_torque(model, data, s.q, s.dq, c);
    return max_abs_difference(c, peer.coriolis(s.q, s.dq));
  });
}

// KDL has no Coriolis matrix; C(q,dq) dq must still be KDL's Coriolis vector.
TEST(KdlCrossCheck, CoriolisMatrixTimesVelocity) {
  expect_agreement("C(q,dq) dq", [](const Model& model, KdlPeer& peer, Data& data, const State& s) {
    coriolis_matrix(model, data, s.q, s.dq);
    const Vector7 c = data.coriolis_matrix * s.dq;
    return max_abs_difference(c, peer.coriolis(s.q, s.dq));
  });
}

// Torques from KDL's inverse dynamics, so the accelerations stay of the size of s.ddq.
TEST(KdlCrossCheck, ForwardDynamicsAba) {
  expect_agreement("aba", [](const Model& model, KdlPeer& peer, Data& data, const State& s) {
    const Vector7 tau = peer.rnea(s.q, s.dq, s.ddq);
    aba(model, data, s.q, s.dq, tau);
    return max_abs_difference(data.ddq, peer.forward_dynamics(s.q, s.dq, tau));
  });
}

TEST(KdlCrossCheck, ForwardDynamicsCholesky) {
  expect_agreement("fd cholesky", [](const Model& model, KdlPeer& peer, Data& data, const State& s) {
    const Vector7 tau = peer.rnea(s.q, s.dq, s.ddq);
    forward_dynamics_cholesky(model, data, s.q, s.dq, tau);
    return max_abs_difference(data.ddq, peer.forward_dynamics(s.q, s.dq, tau));
  });
}

TEST(KdlCrossCheck, EndEffectorJacobian) {
  expect_agreement("EE jacobian", [](const Model& model, KdlPeer& peer, Data& data, const State& s) {
    forward_kinematics(model, data, s.q);
    Matrix6x7 J;
    zero_jacobian(data, Frame::kEndEffector, J);
    return max_abs_difference(J, peer.ee_jacobian(s.q));
  });
}

TEST(KdlCrossCheck, EndEffectorPose) {
  expect_agreement("EE pose", [](const Model& model, KdlPeer& peer, Data& data, const State& s) {
    forward_kinematics(model, data, s.q);
    return pose_difference(frame_pose(data, Frame::kEndEffector), peer.ee_pose(s.q));
  });
}

// Joint frames 1..7, flange and EE, from one KDL call for all segments.
TEST(KdlCrossCheck, AllFramePoses) {
  expect_agreement("frame poses", [](const Model& model, KdlPeer& peer, Data& data, const State& s) {
    forward_kinematics(model, data, s.q);
    const auto kdl = peer.frame_poses(s.q);
    double worst = 0.0;
    for (int k = 0; k < KdlPeer::kNumFrames; ++k)
      worst = nan_max(pose_difference(frame_pose(data, static_cast<Frame>(k)), kdl[k]), worst);
    return worst;
  });
}

}  // namespace
}  // namespace csp::test
