// One case as a run: the scenario's built-in controller (run::ControllerSource) with the observers
// that measure it (tracking, a scene's medical metrics; its log for `csp gap` when the campaign asks),
// in this process. Deterministic from the case: the same case gives bit-identical metrics in any
// process; only the timing (the machine's) is not.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "csp/campaign/cases.hpp"

namespace csp::campaign {

struct Outcome {
  std::string id;
  bool reflex = false;
  std::string reflex_errors;   // libfranka's error names, or what the controller did wrong
  // In a fixed order: tracking (no scene) or the scene's medical metrics (NaN: did not happen),
  // then the command counters, then (gap_verdict) csp gap's. Deterministic.
  std::vector<std::pair<std::string, double>> metrics;
  // gap_verdict: csp gap's causes, most important first ("payload; joint_friction"), "none", or why
  // the log could not be diagnosed ("not diagnosed: ...").
  std::string gap_verdict;
  bool failed = false;         // a reflex or a metric over its limit
  std::string failure;         // why
  // Not deterministic (the machine's load): kept apart. The controller's compute time per cycle
  // (state handed out -> command back, rt::TimingReport's round trip) and the run's own time.
  double controller_time_p99_us = 0.0, controller_time_max_us = 0.0;
  double wall_time_s = 0.0;
};

Outcome run_case(const Campaign& campaign, const Case& c);

// The metrics' names for runs of `scenario`, in the order Outcome::metrics has them.
std::vector<std::string> metric_names(const rt::Scenario& scenario, bool gap_verdict);

// runs/<id>.json
std::string outcome_json(const Outcome& outcome);
Outcome read_outcome_json(const std::string& path);

}  // namespace csp::campaign
