// Internal to csp_ompl_bridge: the OMPL set-up shared by plan_transfer (transfer.cpp) and
// plan_on_manifold (constrained.cpp). Compiled only inside the bridge (16-byte Eigen, hidden symbols).
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <ompl/base/MotionValidator.h>
#include <ompl/base/Planner.h>
#include <ompl/base/PlannerTerminationCondition.h>
#include <ompl/base/SpaceInformation.h>
#include <ompl/base/StateValidityChecker.h>
#include <ompl/base/spaces/RealVectorStateSpace.h>
#include <ompl/geometric/PathGeometric.h>
#include <ompl/geometric/SimpleSetup.h>

#include "csp/planners/ompl_bridge.hpp"

namespace csp::planners::ompl_bridge::detail {

namespace ob = ompl::base;
namespace og = ompl::geometric;

// Throws std::invalid_argument naming the field: bounds not finite or not lower < upper, start or
// goal outside them, seed outside 1 .. 2^32-1, max_iterations < 1, simplify_steps < 0, range < 0,
// no is_valid callback (and no motion_is_free when `need_motion_check`).
void check_request(const Request& request, const Callbacks& callbacks, bool need_motion_check);

// OMPL's random numbers, logging and planner registry are process-global: one plan at a time per
// process. The returned lock is held for the whole plan. It routes OMPL's messages to stderr
// (warnings and errors only; OMPL prints to stdout by default) and re-seeds OMPL's seed generator
// with `seed`, so that every RNG the plan creates afterwards (samplers, planner, simplifier) draws
// the same seeds in any process (see the definition for why OMPL 1.5.2 allows this).
std::unique_lock<std::mutex> begin_plan(std::uint64_t seed);

// R^7 with the request's bounds.
std::shared_ptr<ob::RealVectorStateSpace> make_joint_space(const Request& request);

// The first 7 reals of any state of a space built on make_joint_space (for a constrained space, the
// ambient state), in the order of getValueAddressAtIndex.
Joints to_joints(const ob::StateSpace& space, const ob::State* state);
void from_joints(const ob::StateSpace& space, const Joints& q, ob::State* state);

// isValid = callbacks.is_valid; clearance = callbacks.clearance (0 if not given).
class ValidityChecker : public ob::StateValidityChecker {
 public:
  ValidityChecker(ob::SpaceInformation* si, const Callbacks& callbacks);
  bool isValid(const ob::State* state) const override;
  double clearance(const ob::State* state) const override;

 private:
  const Callbacks& callbacks_;
};

// checkMotion = callbacks.motion_is_free (certified for the whole straight segment); never a
// discrete check at a resolution.
class CertifiedMotionValidator : public ob::MotionValidator {
 public:
  CertifiedMotionValidator(ob::SpaceInformation* si, const Callbacks& callbacks);
  bool checkMotion(const ob::State* s1, const ob::State* s2) const override;
  // The last state certified free (halving toward s1, 10 times), and its fraction of the motion.
  bool checkMotion(const ob::State* s1, const ob::State* s2, std::pair<ob::State*, double>& last_valid) const override;

 private:
  const Callbacks& callbacks_;
};

// The planner named by Request::planner (see planner_names()); range > 0 sets the tree planners' step.
ob::PlannerPtr make_planner(const std::string& name, const ob::SpaceInformationPtr& si, double range);

// Terminates after `max_iterations` checks (planners check once per loop iteration); no clock.
class IterationBudget {
 public:
  explicit IterationBudget(long max_iterations);
  ob::PlannerTerminationCondition condition();
  long used() const { return used_ < max_ ? used_ : max_; }
  bool exhausted() const { return used_ > max_; }

 private:
  long max_;
  long used_ = 0;
};

std::vector<Joints> waypoints(const og::PathGeometric& path);

// True if every vertex is valid and every segment certified free (the final check of a returned path).
bool path_is_free(const std::vector<Joints>& path, const Callbacks& callbacks);

double seconds_since(std::chrono::steady_clock::time_point start);

// Solves within request.max_iterations and fills result's planner, iterations and cap_hit. Without an
// exact solution: the best attempt (OMPL's approximate solution), a message naming `search`, the time;
// returns false.
bool solve_within_budget(og::SimpleSetup& setup, const Request& request, const std::string& search, Result& result,
                         std::chrono::steady_clock::time_point started);

// The simplifier with fixed step counts (simplify(maxTime) would depend on the clock): reduceVertices
// drops redundant vertices, shortcutPath connects random points of non-adjacent segments (each
// shortcut checked by the space information's motion validator), reduceVertices removes what is left.
void simplify(og::PathGeometric& path, const ob::SpaceInformationPtr& si, int steps);

// The end of a plan: the path is the solution if it passed its final check, else the best attempt
// with a message saying why (`failure`).
Result finish(Result result, std::vector<Joints> path, bool passed, const std::string& failure);

}  // namespace csp::planners::ompl_bridge::detail
