// The only OMPL-facing API of CSP (docs/planning-transfers.md). OMPL 1.5.2 lives behind it in the
// SHARED library csp_ompl_bridge, compiled with Debian's libompl's own Eigen settings (16-byte
// alignment, plain malloc: ompl/ompl#601) and hidden visibility, so that no Eigen or OMPL inline
// code is shared with the rest of CSP (built with -march=native). Therefore this header uses no
// Eigen and no OMPL type: plain arrays, vectors and std::function callbacks.
//
// Deterministic: the same Request and callbacks give the same waypoints, bit for bit, in any process
// (iteration caps, no timed termination, no threaded planner, OMPL's random numbers seeded per plan).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#if defined(CSP_OMPL_BRIDGE_BUILDING)
#define CSP_OMPL_BRIDGE_API __attribute__((visibility("default")))
#else
#define CSP_OMPL_BRIDGE_API
#endif

namespace csp::planners::ompl_bridge {

using Joints = std::array<double, 7>;

// What the planner may ask of the caller (all in joint space).
struct Callbacks {
  std::function<bool(const Joints&)> is_valid;            // required: the state is collision-free
  std::function<double(const Joints&)> clearance;         // optional: signed clearance [m] (OMPL's clearance())
  // Required for transfers: true only if NO state on the straight segment a -> b is invalid (a certified
  // check, e.g. ClearanceChecker::motion_is_free). OMPL's discrete check at its default resolution is never used.
  std::function<bool(const Joints&, const Joints&)> motion_is_free;
};

struct Request {
  Joints start{}, goal{};
  Joints lower{}, upper{};           // the state space's bounds [rad] (the joint limits minus a margin)
  std::string planner = "rrtconnect";   // rrtconnect | rrtstar | bitstar | lazyprmstar (planner_names())
  std::uint64_t seed = 1;            // 1 .. 2^32-1
  long max_iterations = 20000;       // the planner's budget: loop iterations (no wall-clock limit)
  int simplify_steps = 100;          // PathSimplifier budget per pass (reduceVertices, shortcutPath); 0: none
  double range = 0.0;                // the tree planners' step [rad]; 0: OMPL's default (0.2 x the space's extent)
};

// A constraint F(q) = 0 (R^7 -> R^codimension) with its analytic Jacobian, for OMPL's
// ProjectedStateSpace (Kingston, Moll & Kavraki, IJRR 2019).
struct ManifoldConstraint {
  int codimension = 0;
  std::function<void(const double* q, double* f)> function;                      // f: codimension values
  std::function<void(const double* q, double* jacobian_row_major)> jacobian;     // codimension x 7, row-major
  double tolerance = 1e-5;           // |F(q)| accepted as on the manifold
  double delta = 0.01;               // step along the manifold [rad] (OMPL's default 0.05 is too coarse near tissue)
};

struct Result {
  bool solved = false;               // an exact path, re-checked (every vertex valid, every segment certified free)
  std::vector<Joints> waypoints;     // start ... goal when solved, else empty
  // When not solved: the planner's best attempt (OMPL's approximate solution, if any) and how far
  // its end is from the goal (OMPL's goal distance) [rad]; -1 when there is none.
  std::vector<Joints> best_attempt;
  double best_distance = -1.0;
  long iterations = 0;               // planner loop iterations used
  bool cap_hit = false;              // the budget ran out
  double seconds = 0.0;              // wall time of set-up, solve and simplification (informative only)
  std::string planner;               // OMPL's name of the planner that ran
  std::string message;               // why not solved, or "" when solved
};

// A collision-free joint-space path from start to goal. Throws std::invalid_argument (naming the
// field) for a malformed request: unknown planner, a missing callback, bounds not lower < upper,
// start or goal outside the bounds or invalid, seed 0. Not finding a path is not an exception:
// solved = false, with message, iterations and the best attempt.
CSP_OMPL_BRIDGE_API Result plan_transfer(const Request& request, const Callbacks& callbacks);

// A path from start to goal on the manifold F(q) = 0 (both must be on it), with OMPL's constrained
// planning (ProjectedStateSpace + ConstrainedSpaceInformation). Errors as plan_transfer.
CSP_OMPL_BRIDGE_API Result plan_on_manifold(const Request& request, const Callbacks& callbacks,
                                            const ManifoldConstraint& constraint);

// The planners plan_transfer accepts, in Request::planner's spelling.
CSP_OMPL_BRIDGE_API std::vector<std::string> planner_names();

// "1.5.2": from OMPL_MAJOR/MINOR/PATCH_VERSION (Debian's config.h defines OMPL_VERSION as "").
CSP_OMPL_BRIDGE_API std::string ompl_version();

}  // namespace csp::planners::ompl_bridge
