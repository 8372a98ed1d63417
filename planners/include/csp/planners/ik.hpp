// Inverse kinematics by damped least squares (Wampler 1986; Nakamura & Hanafusa 1986) on any set of
// equality rows f(q) = 0 (a task constraint, a TCP target), with a secondary objective in the
// null space of the rows: away from the joint limits and, below an influence distance, toward more
// clearance (Liegeois 1977). It is a local method: started from a seed it stays on the seed's IK
// branch for targets near the seed's, which is how the task keeps the scenes' branch.
#pragma once

#include <functional>

#include <Eigen/Core>

#include "csp/dynamics/model.hpp"
#include "csp/planners/checker.hpp"

namespace csp::planners {

// Equality rows at q: f (m rows) and their Jacobian df/dq (m x 7). Both resized by the callee.
using ConstraintRows = std::function<void(const Vector7& q, Eigen::VectorXd& f, Eigen::MatrixXd& jacobian)>;

struct IkOptions {
  int max_iterations = 300;
  double tolerance = 1e-10;          // |f| (2-norm) for convergence [m, or unitless for axis rows]
  double damping = 1e-6;             // lambda^2 of (J J^T + lambda^2 I)^-1
  double max_step = 0.1;             // joint step per iteration (infinity norm) [rad]
  double limit_margin = 0.05;        // kept inside the joint limits [rad]
  double nullspace_gain = 0.0;       // 0: minimum-norm steps only (a projection onto f = 0)
  double clearance_influence = 0.10; // the clearance term acts while the clearance is below this [m]
};

struct IkResult {
  Vector7 q = Vector7::Zero();
  bool converged = false;
  int iterations = 0;
  double residual = 0.0;    // |f(q)|
};

// dq = -J^T (J J^T + lambda^2 I)^-1 f + (I - J^+ J) k grad h, h = -sum_j ((q_j - mid_j)/range_j)^2
// + clearance term (its gradient by central differences of checker.check; checker may be null).
// Joints are clamped limit_margin inside the limits at every step.
IkResult solve_ik(const ConstraintRows& rows, const Vector7& seed, const JointLimits& limits,
                  ClearanceChecker* checker, const IkOptions& options = {});

// Five rows putting the TCP (the model's end-effector frame) at `position` with its z axis along the
// unit vector `axis`: p - position, x_EE . axis, y_EE . axis (z_EE = +axis on the seed's branch).
ConstraintRows tcp_target_rows(const Model& model, const Vector3& position, const Vector3& axis);

// The IK branch of a configuration: the elbow (origin of frame 4) above (+1) or below (-1) the line
// from the shoulder (frame 2) to the wrist (frame 6), in the vertical plane through that line, and
// the sign of sin(q6) (the wrist flip). DLS from a seed on a branch stays on it for nearby targets.
struct IkBranch {
  int elbow = 0;
  int wrist = 0;
  bool operator==(const IkBranch&) const = default;
};
IkBranch ik_branch(const Model& model, const Vector7& q);

}  // namespace csp::planners
