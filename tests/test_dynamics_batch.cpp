// The batched RNEA and inertial regressor (dynamics/batch.hpp, issue 29) against the one-state
// algorithms, state by state: seeded random states of the Panda (gaz2019 with the Hand, with and
// without armature, with a load) and the FR3; batch sizes that fill the four lanes, leave some
// empty, one state and none; gravity tilted, zero, and the arm at rest. Tolerance 1e-12 relative
// to the largest entry of the one-state result: only rounding may differ.
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "csp/dynamics/batch.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

constexpr double kBatchRelative = 1e-12;

// (name, model) pairs.
std::vector<std::pair<std::string, Model>> batch_arms() {
  ModelOptions gaz_with_hand;
  gaz_with_hand.inertia = "gaz2019";
  gaz_with_hand.end_effector = "hand";
  const Model panda = make_model("panda", gaz_with_hand);
  ModelParameters with_armature = panda.parameters();
  with_armature.armature << 0.195, 0.195, 0.195, 0.195, 0.074, 0.074, 0.074;
  const RigidBodyInertia load{1.5, Vector3(0.02, -0.01, 0.08), Matrix3::Identity() * 2e-3};
  return {{"panda", panda},
          {"panda_armature", Model(with_armature)},
          {"panda_load", with_load(panda, load)},
          {"panda_tilted_gravity", with_gravity(panda, Vector3(1.2, -0.7, -9.7))},
          {"fr3", make_model("fr3")}};
}

StateBatch random_batch(const Model& model, Eigen::Index states, unsigned seed) {
  RandomStates random(seed);
  StateBatch batch(states);
  for (Eigen::Index k = 0; k < states; ++k) {
    batch.q.col(k) = random.q(model.parameters().joint_limits);
    batch.dq.col(k) = random.uniform(2.5);
    batch.ddq.col(k) = random.uniform(10.0);
  }
  return batch;
}

// Within 1e-12 of the largest entry of the one-state result.
template <typename A, typename B>
::testing::AssertionResult batch_near(const Eigen::MatrixBase<A>& batched, const Eigen::MatrixBase<B>& one_state) {
  return near(batched, one_state, kBatchRelative * one_state.cwiseAbs().maxCoeff());
}

// 0 and 1 state, a multiple of the four lanes, and one, two and three lanes left over.
const std::vector<Eigen::Index> kBatchSizes = {0, 1, 2, 3, 4, 5, 8, 11, 64, 201};

TEST(DynamicsBatch, RneaEqualsTheOneStateRneaStateByState) {
  for (const auto& [name, model] : batch_arms()) {
    for (const Eigen::Index n : kBatchSizes) {
      SCOPED_TRACE(name + ", " + std::to_string(n) + " states");
      const StateBatch batch = random_batch(model, n, 29 + static_cast<unsigned>(n));
      JointMatrix tau;
      rnea_batch(model, batch, tau);
      ASSERT_EQ(tau.cols(), n);
      Data data;
      for (Eigen::Index k = 0; k < n; ++k) {
        Vector7 expected;
        rnea(model, data, batch.q.col(k), batch.dq.col(k), batch.ddq.col(k), expected);
        ASSERT_TRUE(batch_near(tau.col(k), expected)) << "state " << k;
      }
    }
  }
}

TEST(DynamicsBatch, RegressorEqualsTheOneStateRegressorStateByState) {
  for (const auto& [name, model] : batch_arms()) {
    const InertialRegressor regressor(model);
    Eigen::Matrix<double, kInertialParameters, 1> pi;
    for (int i = 0; i < kNumJoints; ++i) pi.segment<kLinkParameters>(kLinkParameters * i) = link_parameters(model.body(i));
    for (const Eigen::Index n : kBatchSizes) {
      SCOPED_TRACE(name + ", " + std::to_string(n) + " states");
      const StateBatch batch = random_batch(model, n, 3 + static_cast<unsigned>(n));
      Eigen::MatrixXd Y;
      inertial_regressor_batch(model, batch, Y);
      ASSERT_EQ(Y.rows(), kNumJoints * n);
      ASSERT_EQ(Y.cols(), kInertialParameters);
      JointMatrix tau;
      rnea_batch(model, batch, tau);
      Data data;
      for (Eigen::Index k = 0; k < n; ++k) {
        const auto rows = Y.middleRows<kNumJoints>(kNumJoints * k);
        ASSERT_TRUE(batch_near(rows, regressor(data, batch.q.col(k), batch.dq.col(k), batch.ddq.col(k)))) << "state " << k;
        // The standard parameters reproduce the batched inverse dynamics.
        ASSERT_TRUE(batch_near(rows * pi + model.armature().cwiseProduct(batch.ddq.col(k)), tau.col(k))) << "state " << k;
      }
    }
  }
}

// At rest only gravity acts: the batched RNEA is g(q); without gravity the arm at rest needs no torque.
TEST(DynamicsBatch, AtRestTheTorqueIsGravityAndWithoutGravityNone) {
  for (const auto& [name, model] : batch_arms()) {
    SCOPED_TRACE(name);
    StateBatch batch = random_batch(model, 13, 7);
    batch.dq.setZero();
    batch.ddq.setZero();
    JointMatrix tau;
    rnea_batch(model, batch, tau);
    Data data;
    for (Eigen::Index k = 0; k < batch.size(); ++k) {
      Vector7 g;
      gravity_torque(model, data, batch.q.col(k), g);
      ASSERT_TRUE(batch_near(tau.col(k), g)) << "state " << k;
    }
    const Model weightless = with_gravity(model, Vector3::Zero());
    rnea_batch(weightless, batch, tau);
    EXPECT_EQ(tau, JointMatrix::Zero(kNumJoints, batch.size()));
    Eigen::MatrixXd Y;
    inertial_regressor_batch(weightless, batch, Y);
    EXPECT_EQ(Y, Eigen::MatrixXd::Zero(kNumJoints * batch.size(), kInertialParameters));
  }
}

TEST(DynamicsBatch, StatesOfDifferentCountsAreRejected) {
  const Model model = make_model("panda");
  StateBatch batch = random_batch(model, 5, 1);
  batch.ddq.resize(kNumJoints, 4);
  JointMatrix tau;
  Eigen::MatrixXd Y;
  EXPECT_THROW(rnea_batch(model, batch, tau), std::invalid_argument);
  EXPECT_THROW(inertial_regressor_batch(model, batch, Y), std::invalid_argument);
}

}  // namespace
}  // namespace csp::test
