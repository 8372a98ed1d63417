// plan_on_manifold: a path on the constraint manifold F(q) = 0 (docs/planning-task-paths.md), with
// OMPL's projection-based constrained planning (Kingston, Moll & Kavraki, IJRR 2019): states are
// sampled in R^7 and projected onto the manifold by Newton steps with the Jacobian; motions are
// geodesics of `delta`-long steps, each projected and checked.
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <ompl/base/ConstrainedSpaceInformation.h>
#include <ompl/base/Constraint.h>
#include <ompl/base/spaces/constraint/ProjectedStateSpace.h>
#include <ompl/geometric/SimpleSetup.h>

#include "ompl_common.hpp"

namespace csp::planners::ompl_bridge {

using namespace detail;

namespace {

// The caller's F and its Jacobian. Without a Jacobian callback OMPL's own numerical one is used
// (central differences: the baseline the benchmark compares with).
class CallbackConstraint : public ob::Constraint {
 public:
  explicit CallbackConstraint(const ManifoldConstraint& c)
      : ob::Constraint(7, static_cast<unsigned int>(c.codimension), c.tolerance), constraint_(c) {}

  void function(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::VectorXd> out) const override {
    const Eigen::Matrix<double, 7, 1> q = x;
    Eigen::VectorXd f(constraint_.codimension);
    constraint_.function(q.data(), f.data());
    out = f;
  }

  void jacobian(const Eigen::Ref<const Eigen::VectorXd>& x, Eigen::Ref<Eigen::MatrixXd> out) const override {
    if (!constraint_.jacobian) {
      ob::Constraint::jacobian(x, out);
      return;
    }
    const Eigen::Matrix<double, 7, 1> q = x;
    Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> J(constraint_.codimension, 7);
    constraint_.jacobian(q.data(), J.data());
    out = J;
  }

 private:
  const ManifoldConstraint& constraint_;
};

double residual(const ManifoldConstraint& c, const Joints& q) {
  std::vector<double> f(static_cast<std::size_t>(c.codimension));
  c.function(q.data(), f.data());
  double norm2 = 0.0;
  for (double v : f) norm2 += v * v;
  return std::sqrt(norm2);
}

void check_constraint(const Request& request, const ManifoldConstraint& c) {
  if (c.codimension < 1 || c.codimension > 6) throw std::invalid_argument("constraint.codimension: expected 1..6");
  if (!c.function) throw std::invalid_argument("constraint.function: required");
  if (!(c.tolerance > 0.0) || !(c.delta > 0.0)) throw std::invalid_argument("constraint.tolerance, delta: expected > 0");
  for (const Joints* q : {&request.start, &request.goal})
    if (!(residual(c, *q) <= c.tolerance))
      throw std::invalid_argument(std::string(q == &request.start ? "start" : "goal") + ": not on the manifold (|F| " +
                                  std::to_string(residual(c, *q)) + " > tolerance)");
}

}  // namespace

Result plan_on_manifold(const Request& request, const Callbacks& callbacks, const ManifoldConstraint& constraint) {
  check_request(request, callbacks, /*need_motion_check=*/false);
  check_constraint(request, constraint);
  const auto started = std::chrono::steady_clock::now();
  const auto plan_lock = begin_plan(request.seed);

  auto ambient = make_joint_space(request);
  auto space = std::make_shared<ob::ProjectedStateSpace>(ambient, std::make_shared<CallbackConstraint>(constraint));
  auto si = std::make_shared<ob::ConstrainedSpaceInformation>(space);
  space->setSpaceInformation(si.get());   // mandatory: the geodesic steps are checked through it
  space->setDelta(constraint.delta);
  si->setStateValidityChecker(std::make_shared<ValidityChecker>(si.get(), callbacks));

  og::SimpleSetup setup(si);
  ob::ScopedState<> start(space), goal(space);
  from_joints(*space, request.start, start.get());
  from_joints(*space, request.goal, goal.get());
  setup.setStartAndGoalStates(start, goal);
  setup.setPlanner(make_planner(request.planner, si, request.range));
  setup.setup();

  Result result;
  if (!solve_within_budget(setup, request, "path on the manifold", result, started)) return result;

  // Shortcuts are geodesics checked by the constrained motion validator. Then every geodesic is cut
  // into its delta steps: the returned states are on the manifold and at most about delta apart, each
  // one checked.
  og::PathGeometric& path = setup.getSolutionPath();
  simplify(path, si, request.simplify_steps);
  path.interpolate();
  std::vector<Joints> found = waypoints(path);
  result.seconds = seconds_since(started);
  const bool passed = std::all_of(found.begin(), found.end(), [&](const Joints& q) {
    return callbacks.is_valid(q) && residual(constraint, q) <= constraint.tolerance;
  });
  return finish(std::move(result), std::move(found), passed, "a state invalid or off the manifold");
}

}  // namespace csp::planners::ompl_bridge
