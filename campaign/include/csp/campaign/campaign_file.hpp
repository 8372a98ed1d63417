// A campaign file (docs/campaign.md): a base scenario, the axes to sweep, how many runs, what a
// failure is. Loading validates every key and throws ConfigError naming the file, the key and what
// was expected (the Field reader of robot and scenario files); every axis's parameter is applied
// once to the base scenario while loading, so an unknown parameter is an error of the file.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace csp::campaign {

// One swept parameter (cases.hpp lists the names; `scenario`: which base scenario). Exactly one way
// of choosing its values:
struct Axis {
  enum class Kind { kValues, kUniform, kNormal };
  std::string parameter;
  Kind kind = Kind::kValues;
  std::vector<double> values;   // kValues: a grid axis (every case of the grid takes each value)
  // kUniform: drawn in [low, high) (given, or a `csp gap` verdict's interval); kNormal: clipped to it
  double low = 0.0, high = 0.0;
  double mean = 0.0, sd = 0.0;   // kNormal
};

struct Campaign {
  std::string path;            // the campaign file
  // The base scenario (absolute), or a `scenario` axis's alternatives: that axis's values are
  // indices into this list (a grid axis).
  std::vector<std::string> scenarios;
  std::vector<std::string> scenario_names;   // the `scenario` axis's values as written (the table's)
  std::optional<double> duration;   // overrides the scenario's [s]
  uint64_t seed = 1;           // each case's seed derives from it and the case's index
  int runs = 1;                // cases per point of the grid (random axes drawn anew each)
  std::vector<Axis> axes;
  // A run fails on a reflex, or when a metric exceeds its limit here (metric name -> largest value held).
  std::map<std::string, double> limits;
  std::string worst_by;        // the metric that ranks the worst runs in the report
  std::vector<std::string> kept;   // the metrics results.csv keeps (empty: all; runs/<id>.json has all)
  // Each run's log diagnosed by `csp gap` against the robot's own model (docs/gap.md): its verdict
  // and what is left unexplained join the metrics. About 0.05 s per second of run.
  bool gap_verdict = false;
};

// Throws ConfigError (file: key: expected ...) for a bad file.
Campaign load_campaign(const std::string& path);

}  // namespace csp::campaign
