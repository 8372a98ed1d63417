#include "csp/planners/ik.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "csp/dynamics/algorithms.hpp"

namespace csp::planners {
namespace {

// Gradient of the secondary objective h (to be increased): centred joints, and clearance while it
// is below the influence distance.
Vector7 secondary_gradient(const Vector7& q, const JointLimits& limits, ClearanceChecker* checker,
                           const IkOptions& options) {
  const Vector7 mid = 0.5 * (limits.q_min + limits.q_max);
  const Vector7 range = limits.q_max - limits.q_min;
  Vector7 gradient = (-2.0 * (q - mid).array() / range.array().square()).matrix();
  if (checker == nullptr) return gradient;
  if (checker->check(q).clearance >= options.clearance_influence) return gradient;
  constexpr double h = 1e-5;   // central differences of the (piecewise smooth) clearance
  for (int j = 0; j < kNumJoints; ++j) {
    Vector7 plus = q, minus = q;
    plus[j] += h;
    minus[j] -= h;
    gradient[j] += (checker->check(plus).clearance - checker->check(minus).clearance) / (2.0 * h) / options.clearance_influence;
  }
  return gradient;
}

}  // namespace

IkResult solve_ik(const ConstraintRows& rows, const Vector7& seed, const JointLimits& limits,
                  ClearanceChecker* checker, const IkOptions& options) {
  const Vector7 lo = limits.q_min.array() + options.limit_margin;
  const Vector7 hi = limits.q_max.array() - options.limit_margin;
  IkResult result;
  result.q = seed.cwiseMax(lo).cwiseMin(hi);
  Eigen::VectorXd f;
  Eigen::MatrixXd J;
  for (result.iterations = 0; result.iterations < options.max_iterations; ++result.iterations) {
    rows(result.q, f, J);
    result.residual = f.norm();
    const Eigen::MatrixXd JJt = J * J.transpose() + options.damping * Eigen::MatrixXd::Identity(J.rows(), J.rows());
    const Eigen::LDLT<Eigen::MatrixXd> solver(JJt);
    Vector7 step = -J.transpose() * solver.solve(f);
    Vector7 null_step = Vector7::Zero();
    if (options.nullspace_gain > 0.0) {
      const Vector7 g = options.nullspace_gain * secondary_gradient(result.q, limits, checker, options);
      null_step = g - J.transpose() * solver.solve(J * g);   // (I - J^+ J) g
      step += null_step;
    }
    const bool done = result.residual <= options.tolerance && null_step.norm() < 1e-7;
    if (done) break;
    const double largest = step.cwiseAbs().maxCoeff();
    if (largest > options.max_step) step *= options.max_step / largest;
    result.q = (result.q + step).cwiseMax(lo).cwiseMin(hi);
  }
  rows(result.q, f, J);
  result.residual = f.norm();
  result.converged = result.residual <= options.tolerance;
  return result;
}

ConstraintRows tcp_target_rows(const Model& model, const Vector3& position, const Vector3& axis) {
  return [&model, position, axis, data = Data(), jacobian = Matrix6x7()](const Vector7& q, Eigen::VectorXd& f,
                                                                          Eigen::MatrixXd& J) mutable {
    forward_kinematics(model, data, q);
    zero_jacobian(data, Frame::kEndEffector, jacobian);
    const Transform& T = frame_pose(data, Frame::kEndEffector);
    const Vector3 x = T.rotation.col(0), y = T.rotation.col(1);
    f.resize(5);
    J.resize(5, kNumJoints);
    f.head<3>() = T.translation - position;
    f[3] = x.dot(axis);
    f[4] = y.dot(axis);
    J.topRows<3>() = jacobian.topRows<3>();
    // d(x.w)/dq_i = (omega_i x x).w = omega_i.(x x w)
    J.row(3) = x.cross(axis).transpose() * jacobian.bottomRows<3>();
    J.row(4) = y.cross(axis).transpose() * jacobian.bottomRows<3>();
  };
}

IkBranch ik_branch(const Model& model, const Vector7& q) {
  Data data;
  forward_kinematics(model, data, q);
  const Vector3 shoulder = data.O_T_joint[1].translation;
  const Vector3 elbow = data.O_T_joint[3].translation;
  const Vector3 wrist = data.O_T_joint[5].translation;
  const Vector3 line = (wrist - shoulder).normalized();
  const Vector3 offset = (elbow - shoulder) - (elbow - shoulder).dot(line) * line;
  // "above": along the component of the vertical perpendicular to the line
  const Vector3 up = Vector3::UnitZ() - line.z() * line;
  return {offset.dot(up) >= 0.0 ? 1 : -1, std::sin(q[5]) >= 0.0 ? 1 : -1};
}

}  // namespace csp::planners
