// The report of a plan or of `csp plan check` (docs/planning.md): report.json (`passed` plus the
// failures, limit usage per joint, clearance per class, the engine's own figures, the emulator run of
// --verify) and report.md with SVG figures: limit usage per joint, clearance over time, singular
// values (excitations), side and top views of the tool path in the scene.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "csp/planners/plan_files.hpp"
#include "csp/planners/trajectory_check.hpp"

namespace csp::planners {

// --verify: the plan's scenario run on the emulator (apps/ fills it: planners does not use rt).
struct EmulatorRun {
  std::string robot;                     // the robot file's name (panda, fr3)
  std::vector<std::string> reflex;       // libfranka's error names of the reflex; empty: none
  double reflex_t = 0.0;                 // [s]
  double duration = 0.0;                 // [s] run
  Vector7 tracking_rms = Vector7::Zero(), tracking_max = Vector7::Zero();   // measured q - planned q [rad]
  Vector7 peak_tau_J_fraction = Vector7::Zero();                            // max |tau_J| / tau_max
  std::vector<ClassClearance> measured_clearance;   // of the measured q (ClearanceChecker), per class
  bool passed() const;                   // no reflex and the measured motion clear of every class
};

struct PlanReport {
  std::string title;                     // e.g. "csp plan excite ultrasound_abdomen (panda)"
  std::string command_line;
  std::string scene_name, robot_name;
  TrajectoryCheck check;                 // the independent check of the written trajectory
  nlohmann::json plan;                   // the engine's figures (identifiability, segments, ...); may be null
  std::vector<double> singular_values;   // of the scaled regressor (excitations), for the figure
  std::optional<EmulatorRun> verify;
  std::vector<std::string> problems;     // what else failed (no plan found, best attempt reported, ...)

  bool passed() const { return check.passed && problems.empty() && (!verify || verify->passed()); }
};

nlohmann::json to_json(const TrajectoryCheck& check);
nlohmann::json to_json(const PlanReport& report);

// report.json, report.md and the figures (limits.svg, clearance.svg, tool_path.svg, and
// singular_values.svg when there are singular values) into `dir` (created if needed).
void write_report(const std::string& dir, const PlanReport& report, const Scene& scene);

}  // namespace csp::planners
