#include "csp/planners/transfer.hpp"

#include <cstdio>
#include <stdexcept>

#include "csp/planners/ompl_bridge.hpp"

namespace csp::planners {
namespace {

namespace bridge = ompl_bridge;

bridge::Joints to_joints(const Vector7& q) {
  bridge::Joints joints{};
  for (int j = 0; j < kNumJoints; ++j) joints[static_cast<std::size_t>(j)] = q[j];
  return joints;
}

Vector7 to_vector(const bridge::Joints& joints) {
  Vector7 q;
  for (int j = 0; j < kNumJoints; ++j) q[j] = joints[static_cast<std::size_t>(j)];
  return q;
}

std::vector<Vector7> to_vectors(const std::vector<bridge::Joints>& path) {
  std::vector<Vector7> result;
  for (const auto& joints : path) result.push_back(to_vector(joints));
  return result;
}

std::string number(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

void check_pose(const Scene& scene, ClearanceChecker& checker, const JointLimits& limits, double margin,
                const char* role, const NamedPose& pose) {
  const std::string what = "scene " + scene.name + ": " + role + " pose \"" + pose.name + "\"";
  for (int j = 0; j < kNumJoints; ++j) {
    const double low = limits.q_min[j] + margin, high = limits.q_max[j] - margin;
    if (!(pose.q[j] >= low && pose.q[j] <= high))
      throw std::invalid_argument(what + ": joint " + std::to_string(j + 1) + " = " + number(pose.q[j]) +
                                  " rad is outside [" + number(low) + ", " + number(high) + "] (its limits minus the " +
                                  number(margin) + " rad margin)");
  }
  const StateClearance c = checker.check(pose.q);
  if (c.clearance < 0.0)
    throw std::invalid_argument(what + " is in collision: " + std::string(c.moving) + " vs " + std::string(c.other) +
                                " (" + std::string(c.obstacle_class) + "), distance " + number(c.distance) +
                                " m, clearance " + number(c.clearance) + " m (required " +
                                number(c.distance - c.clearance) + " m)");
}

}  // namespace

TransferPlan plan_transfer(const Scene& scene, ClearanceChecker& checker, const JointLimits& limits,
                           const NamedPose& from, const NamedPose& to, const TransferOptions& options) {
  if (!(options.limit_margin >= 0.0))
    throw std::invalid_argument("transfer: limit_margin = " + number(options.limit_margin) + " must be >= 0");
  check_pose(scene, checker, limits, options.limit_margin, "start", from);
  check_pose(scene, checker, limits, options.limit_margin, "goal", to);

  bridge::Request request;
  request.start = to_joints(from.q);
  request.goal = to_joints(to.q);
  request.lower = to_joints(limits.q_min.array() + options.limit_margin);
  request.upper = to_joints(limits.q_max.array() - options.limit_margin);
  request.planner = options.planner;
  request.seed = options.seed;
  request.max_iterations = options.max_iterations;
  request.simplify_steps = options.simplify_steps;

  TransferPlan plan;
  bridge::Callbacks callbacks;
  callbacks.is_valid = [&](const bridge::Joints& q) {
    ++plan.state_checks;
    return checker.is_valid(to_vector(q));
  };
  callbacks.clearance = [&](const bridge::Joints& q) { return checker.check(to_vector(q)).clearance; };
  callbacks.motion_is_free = [&](const bridge::Joints& a, const bridge::Joints& b) {
    ++plan.motion_checks;
    return checker.motion_is_free(to_vector(a), to_vector(b));
  };

  bridge::Result result;
  try {
    result = bridge::plan_transfer(request, callbacks);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument("scene " + scene.name + ": transfer " + from.name + " -> " + to.name + ": " + e.what());
  }
  plan.status = result.solved ? PlannerStatus::kExactSolution : PlannerStatus::kNoSolution;
  plan.waypoints = to_vectors(result.waypoints);
  plan.best_attempt = to_vectors(result.best_attempt);
  plan.best_distance = result.best_distance;
  plan.iterations = result.iterations;
  plan.cap_hit = result.cap_hit;
  plan.seconds = result.seconds;
  plan.planner = result.planner;
  plan.message = result.message.empty() ? "" : "scene " + scene.name + ": transfer " + from.name + " -> " + to.name +
                                                   ": " + result.message;
  return plan;
}

std::vector<std::string> transfer_planners() { return ompl_bridge::planner_names(); }
std::string ompl_version() { return ompl_bridge::ompl_version(); }

}  // namespace csp::planners
