// The OMPL set-up shared by the bridge's planners (ompl_common.hpp).
#include "ompl_common.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include <ompl/config.h>
#include <ompl/geometric/PathSimplifier.h>
#include <ompl/geometric/planners/informedtrees/BITstar.h>
#include <ompl/geometric/planners/prm/LazyPRMstar.h>
#include <ompl/geometric/planners/rrt/RRTConnect.h>
#include <ompl/geometric/planners/rrt/RRTstar.h>
#include <ompl/util/Console.h>
#include <ompl/util/RandomNumbers.h>

// The point of this library (ompl/ompl#601): Eigen as Debian's libompl was compiled with it.
static_assert(EIGEN_MAX_ALIGN_BYTES == 16, "csp_ompl_bridge must be compiled with EIGEN_MAX_ALIGN_BYTES=16");

namespace csp::planners::ompl_bridge {

std::string ompl_version() {
  return std::to_string(OMPL_MAJOR_VERSION) + "." + std::to_string(OMPL_MINOR_VERSION) + "." +
         std::to_string(OMPL_PATCH_VERSION);
}

std::vector<std::string> planner_names() { return {"rrtconnect", "rrtstar", "bitstar", "lazyprmstar"}; }

namespace detail {
namespace {

std::string joints_text(const Joints& q) {
  std::string text = "[";
  for (std::size_t j = 0; j < q.size(); ++j) {
    char number[32];
    std::snprintf(number, sizeof number, "%s%.6g", j == 0 ? "" : ", ", q[j]);
    text += number;
  }
  return text + "]";
}

void check_inside(const char* field, const Joints& q, const Request& request) {
  for (std::size_t j = 0; j < q.size(); ++j) {
    if (!std::isfinite(q[j]) || q[j] < request.lower[j] || q[j] > request.upper[j])
      throw std::invalid_argument(std::string("plan request: ") + field + "[" + std::to_string(j) + "] = " +
                                  std::to_string(q[j]) + " is outside the bounds [" + std::to_string(request.lower[j]) +
                                  ", " + std::to_string(request.upper[j]) + "]");
  }
}

// OMPL's messages go to stderr (its default handler prints information to stdout, which belongs to
// CSP's JSON output), warnings and errors only. While begin_plan re-seeds, OMPL's error "Random
// number generation already started" is expected (see begin_plan) and dropped.
class StderrHandler : public ompl::msg::OutputHandler {
 public:
  void log(const std::string& text, ompl::msg::LogLevel level, const char* /*filename*/, int /*line*/) override {
    if (reseeding && level == ompl::msg::LOG_ERROR) return;
    const char* kind = level >= ompl::msg::LOG_ERROR ? "error" : level == ompl::msg::LOG_WARN ? "warning" : "info";
    std::fprintf(stderr, "OMPL %s: %s\n", kind, text.c_str());
  }
  bool reseeding = false;
};

StderrHandler& handler() {
  static StderrHandler instance;
  return instance;
}

}  // namespace

void check_request(const Request& request, const Callbacks& callbacks, bool need_motion_check) {
  for (std::size_t j = 0; j < request.lower.size(); ++j) {
    if (!std::isfinite(request.lower[j]) || !std::isfinite(request.upper[j]) || !(request.lower[j] < request.upper[j]))
      throw std::invalid_argument("plan request: bounds of joint " + std::to_string(j + 1) + " are not lower < upper: [" +
                                  std::to_string(request.lower[j]) + ", " + std::to_string(request.upper[j]) + "]");
  }
  check_inside("start", request.start, request);
  check_inside("goal", request.goal, request);
  if (request.seed < 1 || request.seed > std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("plan request: seed = " + std::to_string(request.seed) + " is outside 1 .. 4294967295");
  if (request.max_iterations < 1)
    throw std::invalid_argument("plan request: max_iterations = " + std::to_string(request.max_iterations) + " must be >= 1");
  if (request.simplify_steps < 0)
    throw std::invalid_argument("plan request: simplify_steps = " + std::to_string(request.simplify_steps) + " must be >= 0");
  if (!(request.range >= 0.0) || !std::isfinite(request.range))
    throw std::invalid_argument("plan request: range = " + std::to_string(request.range) + " must be >= 0");
  if (!callbacks.is_valid) throw std::invalid_argument("plan request: the is_valid callback is missing");
  if (need_motion_check && !callbacks.motion_is_free)
    throw std::invalid_argument("plan request: the motion_is_free callback is missing (a certified segment check is required)");
  if (!callbacks.is_valid(request.start))
    throw std::invalid_argument("plan request: the start " + joints_text(request.start) + " is invalid (in collision)");
  if (!callbacks.is_valid(request.goal))
    throw std::invalid_argument("plan request: the goal " + joints_text(request.goal) + " is invalid (in collision)");
}

std::unique_lock<std::mutex> begin_plan(std::uint64_t seed) {
  static std::mutex mutex;
  std::unique_lock<std::mutex> lock(mutex);
  ompl::msg::useOutputHandler(&handler());
  ompl::msg::setLogLevel(ompl::msg::LOG_WARN);
  // RNG::setSeed reseeds the generator of the per-RNG seeds (RandomNumbers.cpp, RNGSeedGenerator::
  // setSeed, OMPL 1.5.2 and still 2.0): before any RNG exists it also records the seed as the
  // "first seed"; afterwards it logs an error ("will not lead to deterministic sampling", true only
  // of RNGs that already exist) but reseeds all the same. Every RNG of this plan is created after
  // this call, in program order, so each draws the same seed in any process and in any plan.
  handler().reseeding = true;
  ompl::RNG::setSeed(static_cast<std::uint_fast32_t>(seed));
  handler().reseeding = false;
  return lock;
}

std::shared_ptr<ob::RealVectorStateSpace> make_joint_space(const Request& request) {
  auto space = std::make_shared<ob::RealVectorStateSpace>(static_cast<unsigned int>(request.lower.size()));
  ob::RealVectorBounds bounds(static_cast<unsigned int>(request.lower.size()));
  for (std::size_t j = 0; j < request.lower.size(); ++j) {
    bounds.setLow(static_cast<unsigned int>(j), request.lower[j]);
    bounds.setHigh(static_cast<unsigned int>(j), request.upper[j]);
  }
  space->setBounds(bounds);
  return space;
}

Joints to_joints(const ob::StateSpace& space, const ob::State* state) {
  Joints q{};
  for (unsigned int j = 0; j < q.size(); ++j) q[j] = *space.getValueAddressAtIndex(state, j);
  return q;
}

void from_joints(const ob::StateSpace& space, const Joints& q, ob::State* state) {
  for (unsigned int j = 0; j < q.size(); ++j) *space.getValueAddressAtIndex(state, j) = q[j];
}

ValidityChecker::ValidityChecker(ob::SpaceInformation* si, const Callbacks& callbacks)
    : ob::StateValidityChecker(si), callbacks_(callbacks) {
  specs_.clearanceComputationType = callbacks.clearance ? ob::StateValidityCheckerSpecs::EXACT
                                                        : ob::StateValidityCheckerSpecs::NONE;
}

bool ValidityChecker::isValid(const ob::State* state) const {
  return callbacks_.is_valid(to_joints(*si_->getStateSpace(), state));
}

double ValidityChecker::clearance(const ob::State* state) const {
  return callbacks_.clearance ? callbacks_.clearance(to_joints(*si_->getStateSpace(), state)) : 0.0;
}

CertifiedMotionValidator::CertifiedMotionValidator(ob::SpaceInformation* si, const Callbacks& callbacks)
    : ob::MotionValidator(si), callbacks_(callbacks) {}

bool CertifiedMotionValidator::checkMotion(const ob::State* s1, const ob::State* s2) const {
  const ob::StateSpace& space = *si_->getStateSpace();
  const bool free = callbacks_.motion_is_free(to_joints(space, s1), to_joints(space, s2));
  ++(free ? valid_ : invalid_);
  return free;
}

bool CertifiedMotionValidator::checkMotion(const ob::State* s1, const ob::State* s2,
                                           std::pair<ob::State*, double>& last_valid) const {
  if (checkMotion(s1, s2)) return true;
  const ob::StateSpace& space = *si_->getStateSpace();
  const Joints a = to_joints(space, s1);
  double fraction = 0.0;   // s1 itself is valid (the planners only extend from valid states)
  double step = 0.5;
  ob::State* candidate = si_->allocState();
  for (int halving = 0; halving < 10; ++halving, step *= 0.5) {
    space.interpolate(s1, s2, fraction + step, candidate);
    if (callbacks_.motion_is_free(a, to_joints(space, candidate))) fraction += step;
  }
  if (last_valid.first != nullptr) space.interpolate(s1, s2, fraction, last_valid.first);
  last_valid.second = fraction;
  si_->freeState(candidate);
  return false;
}

ob::PlannerPtr make_planner(const std::string& name, const ob::SpaceInformationPtr& si, double range) {
  if (name == "rrtconnect") {
    auto planner = std::make_shared<og::RRTConnect>(si);
    if (range > 0.0) planner->setRange(range);
    return planner;
  }
  if (name == "rrtstar") {
    auto planner = std::make_shared<og::RRTstar>(si);
    if (range > 0.0) planner->setRange(range);
    return planner;
  }
  if (name == "bitstar") return std::make_shared<og::BITstar>(si, "kBITstar");   // OMPL's name for its k-nearest default
  // PRM* would be the textbook choice, but OMPL's PRM::solve grows its roadmap in a second thread
  // (nondeterministic); LazyPRM* runs in the caller's thread.
  if (name == "lazyprmstar") {
    auto planner = std::make_shared<og::LazyPRMstar>(si);
    if (range > 0.0) planner->setRange(range);
    return planner;
  }
  std::string known;
  for (const auto& n : planner_names()) known += (known.empty() ? "" : ", ") + n;
  throw std::invalid_argument("plan request: planner \"" + name + "\" is not one of " + known);
}

IterationBudget::IterationBudget(long max_iterations) : max_(max_iterations) {}

ob::PlannerTerminationCondition IterationBudget::condition() {
  return ob::PlannerTerminationCondition([this] { return ++used_ > max_; });
}

std::vector<Joints> waypoints(const og::PathGeometric& path) {
  std::vector<Joints> result;
  const ob::StateSpace& space = *path.getSpaceInformation()->getStateSpace();
  for (std::size_t i = 0; i < path.getStateCount(); ++i) result.push_back(to_joints(space, path.getState(i)));
  return result;
}

bool path_is_free(const std::vector<Joints>& path, const Callbacks& callbacks) {
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (!callbacks.is_valid(path[i])) return false;
    if (i > 0 && !callbacks.motion_is_free(path[i - 1], path[i])) return false;
  }
  return !path.empty();
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool solve_within_budget(og::SimpleSetup& setup, const Request& request, const std::string& search, Result& result,
                         std::chrono::steady_clock::time_point started) {
  result.planner = setup.getPlanner()->getName();
  IterationBudget budget(request.max_iterations);
  const ob::PlannerStatus status = setup.solve(budget.condition());
  result.iterations = budget.used();
  result.cap_hit = budget.exhausted();
  // The solution path is the problem definition's own copy. OMPL 1.5.2's LazyPRM frees its roadmap
  // only in clear() (its destructor leaks it; fixed upstream by ompl/ompl#909).
  setup.getPlanner()->clear();
  if (status == ob::PlannerStatus::EXACT_SOLUTION) return true;
  if (status == ob::PlannerStatus::APPROXIMATE_SOLUTION) {
    result.best_attempt = waypoints(setup.getSolutionPath());
    result.best_distance = setup.getProblemDefinition()->getSolutionDifference();
  }
  result.message = "no " + search + " within " + std::to_string(request.max_iterations) + " iterations of " +
                   result.planner + " (OMPL: " + status.asString() + ")";
  result.seconds = seconds_since(started);
  return false;
}

void simplify(og::PathGeometric& path, const ob::SpaceInformationPtr& si, int steps) {
  if (steps <= 0) return;
  og::PathSimplifier simplifier(si);
  const auto n = static_cast<unsigned int>(steps);
  simplifier.reduceVertices(path, n, n / 2);
  simplifier.shortcutPath(path, n, n / 2);
  simplifier.reduceVertices(path, n, n / 2);
}

Result finish(Result result, std::vector<Joints> path, bool passed, const std::string& failure) {
  if (passed) {
    result.solved = true;
    result.waypoints = std::move(path);
  } else {
    result.best_attempt = std::move(path);
    result.message = "the path " + result.planner + " returned failed the final check (" + failure + ")";
  }
  return result;
}

}  // namespace detail
}  // namespace csp::planners::ompl_bridge
