#include "csp/campaign/runner.hpp"

#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

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

}  // namespace

std::vector<std::string> metric_names(const rt::Scenario& scenario) {
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
  run.run(controller);

  Outcome outcome;
  outcome.id = c.id;
  outcome.reflex = controller.reflex();
  if (outcome.reflex) outcome.reflex_errors = controller.failure().empty() ? run.emulator().reflex_reason() : controller.failure();
  Measured measured;
  add_task_metrics(measured, tracking.get(), medical.get());
  add_counters(measured, run.emulator().counters());
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
    outcome.wall_time_s = j.at("wall_time_s").get<double>();
    return outcome;
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": not a case's result (" + e.what() + ")");
  }
}

}  // namespace csp::campaign
