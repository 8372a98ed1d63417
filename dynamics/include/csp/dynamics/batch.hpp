// RNEA and the inertial regressor over many states at once, for the callers that have many: the
// excitation design's regressor stacking, the gap tool's parts, campaigns. The Newton-Euler recursion
// of rnea and InertialRegressor runs on four states at a time, every scalar of the one-state
// algorithm a lane of one AVX2 register (structure of arrays across states), and the joint sines
// and cosines of all states go through the vectorised trig of the one-state path.
//
// The results equal the one-state algorithms' to rounding (1e-12 relative, tests/test_dynamics_batch.cpp),
// not bit for bit: the compiler fuses multiply-adds differently in the two forms. The one-state
// rnea stays what the emulator integrates with.
#pragma once

#include <Eigen/Core>

#include "csp/dynamics/model.hpp"
#include "csp/dynamics/regressor.hpp"

namespace csp {

// One column per state.
using JointMatrix = Eigen::Matrix<double, kNumJoints, Eigen::Dynamic>;

// N states (q, dq, ddq), column k the k-th state; the three must have the same number of columns.
struct StateBatch {
  JointMatrix q, dq, ddq;

  StateBatch() = default;
  explicit StateBatch(Eigen::Index states)
      : q(kNumJoints, states), dq(kNumJoints, states), ddq(kNumJoints, states) {}
  Eigen::Index size() const { return q.cols(); }
};

// tau.col(k) = rnea(model, q_k, dq_k, ddq_k) (armature included, no external wrenches), for each state.
// Throws std::invalid_argument when q, dq and ddq hold different numbers of states.
void rnea_batch(const Model& model, const StateBatch& states, JointMatrix& tau);

// The inertial regressors stacked (7 N x 70): rows 7 k .. 7 k + 6 are InertialRegressor(model) of
// state k, the shape the gap fits and the excitation design stack. Throws as rnea_batch.
void inertial_regressor_batch(const Model& model, const StateBatch& states, Eigen::MatrixXd& Y);

}  // namespace csp
