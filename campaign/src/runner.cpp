#include "csp/campaign/runner.hpp"

#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "csp/gap/diagnosis.hpp"
#include "csp/gap/idle.hpp"
#include "csp/io/robot_config.hpp"
#include "csp/run/observers.hpp"
#include "csp/run/sources.hpp"

namespace csp::campaign {
namespace {

// "contact force RMS error (scan)" -> "contact_force_rms_error_scan": a CSV column's name.
std::string column_name(const std::string& name) {
  std::string out;
  for (const char c : name) {
    if (std::isalnum(static_cast<unsigned char>(c))) out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    else if (!out.empty() && out.back() != '_') out += '_';
  }
  while (!out.empty() && out.back() == '_') out.pop_back();
  return out;
}

// What a run measures, in the order of metric_names.
struct Measured {
  std::vector<std::pair<std::string, double>> metrics;
  void add(const std::string& name, double value) { metrics.emplace_back(name, value); }
};

void add_task_metrics(Measured& out, const run::TrackingObserver* tracking, const run::MedicalObserver* medical) {
  if (medical) {
    for (const rt::MedicalMetric& m : medical->recorder().metrics()) out.add(column_name(m.name), m.value);
    return;
  }
  out.add("tracking_error_rms", tracking->rms_error().maxCoeff());   // [rad], the worst joint's
  out.add("tracking_error_max", tracking->max_error().maxCoeff());   // [rad]
  out.add("max_tau_ext", tracking->max_tau_ext().maxCoeff());        // [N m]
  out.add("peak_tau_J_fraction", tracking->peak_tau_J_fraction().maxCoeff());
}

void add_counters(Measured& out, const rt::EmulatorCounters& counters) {
  out.add("lost_commands", static_cast<double>(counters.lost_commands));
  out.add("max_consecutive_lost", counters.max_consecutive_lost);
  out.add("motion_cycles", static_cast<double>(counters.motion_cycles));
}

// csp gap on the run's log as `csp gap --log` diagnoses a session's LCM log (docs/gap.md): against
// the model of the scenario's robot file and end effector with the file's default inertial and
// friction sets (CSP's model of the arm, not the robot's own libfranka-like model), its idle
// stretches left out. NaN and why when it cannot be diagnosed (a run cut short by a reflex is too short).
std::string add_gap_verdict(Measured& out, const rt::Scenario& scenario, const JointLog* log) {
  double heldout_rms = NAN, unexplained = NAN;
  std::string verdict;
  if (log) {
    try {
      const gap::DiagnosisOptions options;
      ModelOptions model;
      model.end_effector = scenario.end_effector;
      const gap::Diagnosis d = gap::diagnose(Model(model_parameters(load_robot_config(scenario.robot_file), model)),
                                             gap::leave_out_idle(*log, options.filter).log, options);
      heldout_rms = std::sqrt(d.baseline_heldout_rms.squaredNorm() / kNumJoints);   // csp gap's "N m RMS per joint"
      unexplained = d.unexplained_fraction;
      for (const std::string& cause : d.causes) verdict += (verdict.empty() ? "" : "; ") + cause;
      if (verdict.empty()) verdict = "none";
    } catch (const std::exception& e) {
      verdict = std::string("not diagnosed: ") + e.what();
    }
  }
  out.add("gap_heldout_rms", heldout_rms);                 // [N m] before any effect is added
  out.add("gap_unexplained_fraction", unexplained);        // of its mean square, once the verdict's causes are
  return verdict;
}

}  // namespace

std::vector<std::string> metric_names(const rt::Scenario& scenario, bool gap_verdict) {
  const run::Run run(scenario);
  Measured measured;
  if (scenario.emulator.scene) {
    const run::MedicalObserver medical(run, nullptr);
    add_task_metrics(measured, nullptr, &medical);
  } else {
    const run::TrackingObserver tracking(run::TrackingObserver::Reference{}, run.emulator());
    add_task_metrics(measured, &tracking, nullptr);
  }
  add_counters(measured, run.emulator().counters());
  if (gap_verdict) add_gap_verdict(measured, scenario, nullptr);
  std::vector<std::string> names;
  for (const auto& metric : measured.metrics) names.push_back(metric.first);
  return names;
}

Outcome run_case(const Campaign& campaign, const Case& c) {
  const auto start = std::chrono::steady_clock::now();
  const rt::Scenario scenario = case_scenario(campaign, c);
  run::Run run(scenario);
  run::ControllerSource controller(run);
  // The task's measure, as csp emulate takes it: a scene's medical metrics, else joint tracking.
  std::unique_ptr<run::MedicalObserver> medical;
  std::unique_ptr<run::TrackingObserver> tracking;
  if (scenario.emulator.scene) {
    medical = std::make_unique<run::MedicalObserver>(run, controller.controller().status);
    run.observe(*medical);
  } else {
    tracking = std::make_unique<run::TrackingObserver>(run::scenario_reference(scenario, run.emulator()), run.emulator());
    run.observe(*tracking);
  }
  std::unique_ptr<run::JointLogRecorder> log;
  if (campaign.gap_verdict) {
    log = std::make_unique<run::JointLogRecorder>(run.emulator());
    run.observe(*log);
  }
  run.run(controller);

  Outcome outcome;
  outcome.id = c.id;
  outcome.reflex = controller.reflex();
  if (outcome.reflex) outcome.reflex_errors = controller.failure().empty() ? run.emulator().reflex_reason() : controller.failure();
  Measured measured;
  add_task_metrics(measured, tracking.get(), medical.get());
  add_counters(measured, run.emulator().counters());
  if (log) {
    log->log().source = "case " + c.id + "'s run";   // what a diagnosis error names
    outcome.gap_verdict = add_gap_verdict(measured, scenario, &log->log());
  }
  outcome.metrics = std::move(measured.metrics);

  if (outcome.reflex) outcome.failure = "reflex: " + outcome.reflex_errors;
  for (const auto& [name, value] : outcome.metrics) {
    const auto limit = campaign.limits.find(name);
    if (limit == campaign.limits.end() || !(value > limit->second)) continue;
    std::ostringstream why;
    why << name << " " << value << " > " << limit->second;
    outcome.failure += (outcome.failure.empty() ? "" : "; ") + why.str();
  }
  outcome.failed = !outcome.failure.empty();
  const rt::Percentiles& controller_time = controller.motion().timing.round_trip_us;
  outcome.controller_time_p99_us = controller_time.p99;
  outcome.controller_time_max_us = controller_time.max;
  outcome.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return outcome;
}

std::string outcome_json(const Outcome& outcome) {
  nlohmann::ordered_json j;
  j["id"] = outcome.id;
  j["reflex"] = outcome.reflex;
  j["reflex_errors"] = outcome.reflex_errors;
  j["failed"] = outcome.failed;
  j["failure"] = outcome.failure;
  nlohmann::ordered_json metrics = nlohmann::ordered_json::object();
  // A metric that did not happen (NaN: no breakthrough) is null.
  for (const auto& [name, value] : outcome.metrics) metrics[name] = std::isnan(value) ? nlohmann::ordered_json(nullptr) : nlohmann::ordered_json(value);
  j["metrics"] = metrics;
  if (!outcome.gap_verdict.empty()) j["gap_verdict"] = outcome.gap_verdict;
  j["controller_time_p99_us"] = outcome.controller_time_p99_us;
  j["controller_time_max_us"] = outcome.controller_time_max_us;
  j["wall_time_s"] = outcome.wall_time_s;
  return j.dump(1) + "\n";
}

Outcome read_outcome_json(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot be read");
  try {
    const nlohmann::ordered_json j = nlohmann::ordered_json::parse(in);
    Outcome outcome;
    outcome.id = j.at("id").get<std::string>();
    outcome.reflex = j.at("reflex").get<bool>();
    outcome.reflex_errors = j.at("reflex_errors").get<std::string>();
    outcome.failed = j.at("failed").get<bool>();
    outcome.failure = j.at("failure").get<std::string>();
    for (const auto& [name, value] : j.at("metrics").items())
      outcome.metrics.emplace_back(name, value.is_null() ? NAN : value.get<double>());
    outcome.gap_verdict = j.value("gap_verdict", std::string());
    outcome.controller_time_p99_us = j.at("controller_time_p99_us").get<double>();
    outcome.controller_time_max_us = j.at("controller_time_max_us").get<double>();
    outcome.wall_time_s = j.at("wall_time_s").get<double>();
    return outcome;
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": not a case's result (" + e.what() + ")");
  }
}

}  // namespace csp::campaign
