// One case as a run: the scenario's built-in controller (run::ControllerSource) with the observers
// that measure it (tracking, a scene's medical metrics), in this process. Deterministic from the
// case: the same case gives bit-identical metrics in any process.
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
  // then the command counters. Deterministic.
  std::vector<std::pair<std::string, double>> metrics;
  bool failed = false;         // a reflex or a metric over its limit
  std::string failure;         // why
  double wall_time_s = 0.0;    // the run's own time (not deterministic: kept apart)
};

Outcome run_case(const Campaign& campaign, const Case& c);

// The metrics' names for runs of `scenario`, in the order Outcome::metrics has them.
std::vector<std::string> metric_names(const rt::Scenario& scenario);

// runs/<id>.json
std::string outcome_json(const Outcome& outcome);
Outcome read_outcome_json(const std::string& path);

}  // namespace csp::campaign
