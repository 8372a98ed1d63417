// csp emulate: run a scenario on the emulated robot with its built-in controller and report the
// tracking error, reflexes and timing; optionally write the per-cycle CSV log.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "progress.hpp"
#include "csp/bridge/lcm_log.hpp"
#include "csp/io/svg_plot.hpp"
#include "csp/rt/controllers.hpp"
#include "csp/rt/csv_log.hpp"
#include "csp/rt/medical_metrics.hpp"

namespace csp::cli {
namespace {

struct EmulateArguments {
  ScenarioArguments scenario;
  std::optional<long long> seed;
  std::string log;
  std::string lcm_log;
  std::string report;   // medical scenarios: the figures' directory
  bool progress = false;
};

// Tracking error of q against the scenario's reference trajectory, and the largest estimated
// external torque, accumulated cycle by cycle.
class Summary {
 public:
  Summary(std::shared_ptr<const rt::JointReference> trajectory, const Vector7& q0)
      : trajectory_(std::move(trajectory)), q0_(q0) {}

  void add(const rt::RobotState& state, double motion_time) {
    Vector7 q_ref, dq_ref, ddq_ref;
    trajectory_->evaluate(q0_, motion_time, q_ref, dq_ref, ddq_ref);
    const Vector7 error = Vector7(state.q.data()) - q_ref;
    squared_error_ += error.cwiseAbs2();
    max_error_ = max_error_.cwiseMax(error.cwiseAbs());
    max_tau_ext_ = max_tau_ext_.cwiseMax(Vector7(state.tau_ext_hat_filtered.data()).cwiseAbs());
    ++count_;
  }

  void print() const {
    if (count_ == 0) return;
    const Vector7 rms = (squared_error_ / static_cast<double>(count_)).cwiseSqrt();
    auto row = [](const char* name, const Vector7& v, double scale) {
      std::printf("  %-34s", name);
      for (int i = 0; i < kNumJoints; ++i) std::printf(" %8.3f", scale * v[i]);
      std::printf("\n");
    };
    std::printf("  %-34s %8s %8s %8s %8s %8s %8s %8s\n", "joint", "1", "2", "3", "4", "5", "6", "7");
    row("tracking error RMS [mrad]", rms, 1e3);
    row("tracking error max [mrad]", max_error_, 1e3);
    row("max |tau_ext_hat_filtered| [N m]", max_tau_ext_, 1.0);
  }

 private:
  std::shared_ptr<const rt::JointReference> trajectory_;
  Vector7 q0_;
  Vector7 squared_error_ = Vector7::Zero(), max_error_ = Vector7::Zero(), max_tau_ext_ = Vector7::Zero();
  long long count_ = 0;
};

void print_percentiles(const char* name, const rt::Percentiles& p) {
  if (p.count == 0) return;
  std::printf("  %-34s p50 %.1f  p99 %.1f  p99.9 %.1f  max %.1f us (%zu samples)\n", name, p.p50, p.p99, p.p999,
              p.max, p.count);
}


int run_emulate(const EmulateArguments& args) {
  rt::Scenario scenario = args.scenario.load();
  if (args.seed) {
    if (*args.seed < 0) throw UsageError("--seed: expected a non-negative whole number");
    scenario.seed = static_cast<uint64_t>(*args.seed);
    scenario.emulator.seed = scenario.seed;
    scenario.command_faults.seed = scenario.seed + 1;
  }

  rt::Emulator emulator(scenario.emulator);
  const rt::BuiltinController builtin = rt::make_controller(scenario.controller, scenario.controller_faults, emulator);
  std::unique_ptr<rt::CsvLog> log;
  if (!args.log.empty()) log = std::make_unique<rt::CsvLog>(args.log);
  if (log) log->write(emulator.state(), rt::CycleInfo{});   // the state the motion starts from
  std::unique_ptr<bridge::EmulateLogRecorder> lcm_log;
  if (!args.lcm_log.empty())
    lcm_log = std::make_unique<bridge::EmulateLogRecorder>(args.lcm_log, scenario, emulator, builtin.mode);

  Summary summary(scenario.controller.trajectory, Vector7(emulator.state().q_d.data()));
  // A scene's task: the medical metrics (docs/medical.md) instead of the joint tracking summary.
  std::unique_ptr<rt::MedicalRecorder> medical;
  if (scenario.emulator.scene) medical = std::make_unique<rt::MedicalRecorder>(scenario, emulator, builtin.status);
  else if (!args.report.empty()) throw UsageError("--report: only for a scenario with a scene (configs/scenarios/medical/)");
  const uint64_t start_ms = emulator.state().time.toMSec();
  rt::LoopOptions options;
  options.clock = scenario.clock;
  options.faults = scenario.command_faults;
  options.max_duration = scenario.duration;
  // Ctrl-C (or SIGTERM) and a log that cannot be written end the motion as its duration would:
  // the robot holds, the summary is printed, the logs end with whole rows and events.
  std::atomic<bool>& interrupted = stop_on_signals();
  options.stop = &interrupted;
  std::string write_error;
  ProgressMeter progress("csp emulate", args.progress);
  options.observer = [&](const rt::RobotState& state, const rt::CycleInfo& cycle) {
    const double motion_time = static_cast<double>(state.time.toMSec() - start_ms) * 1e-3;
    if (state.time.toMSec() % 100 == 0) progress.update("simulated seconds", motion_time, scenario.duration);
    if (medical) medical->add(state, motion_time);
    else summary.add(state, motion_time);
    if (!write_error.empty()) return;
    try {
      if (log) log->write(state, cycle);
      if (lcm_log) lcm_log->record(state, cycle);
    } catch (const std::exception& e) {
      write_error = e.what();
      interrupted = true;
    }
  };

  std::printf("csp emulate: %s (%s)\n  robot %s, %s clock, %.3f s, seed %llu, controller %s (%s mode)\n",
              scenario.name.c_str(), scenario.path.c_str(), scenario.robot_file.c_str(),
              scenario.clock == rt::Clock::kLockstep ? "lockstep" : "real-time", scenario.duration,
              static_cast<unsigned long long>(scenario.seed), scenario.controller.type.c_str(),
              rt::control_mode_name(builtin.mode));
  rt::MotionResult result;
  std::string failure;
  try {
    result = rt::run_motion(emulator, builtin.mode, builtin.controller, options);
  } catch (const std::exception& e) {   // the controller threw: the robot is in Reflex, the log is complete
    failure = e.what();
  }

  const rt::EmulatorCounters& counters = emulator.counters();
  progress.finish(format("%llu cycles (%.3f s of motion)", static_cast<unsigned long long>(counters.motion_cycles),
                         static_cast<double>(counters.motion_cycles) * 1e-3));
  std::printf("  ran %llu cycles (%.3f s), lost commands %llu (longest run %d)\n",
              static_cast<unsigned long long>(counters.motion_cycles), static_cast<double>(counters.motion_cycles) * 1e-3,
              static_cast<unsigned long long>(counters.lost_commands), counters.max_consecutive_lost);
  summary.print();
  if (medical) {
    for (const rt::MedicalMetric& m : medical->metrics()) {
      if (std::isnan(m.value)) std::printf("  %-50s %10s\n", m.name.c_str(), "none");   // it did not happen
      else std::printf("  %-50s %10.3f %s\n", m.name.c_str(), m.value, m.unit.c_str());
    }
    if (!args.report.empty()) {
      medical->write_figures(args.report);
      std::printf("  figures: %s/force.svg, path.svg, penetration.svg\n", args.report.c_str());
    }
  }
  for (const std::string& warning : result.timing.warnings) std::printf("  warning: %s\n", warning.c_str());
  print_percentiles("controller compute time", result.timing.controller_compute_us);
  print_percentiles("wake-up latency after deadline", result.timing.wakeup_latency_us);
  if (scenario.clock == rt::Clock::kRealtime)
    std::printf("  overruns %llu, missed deadlines %llu\n", static_cast<unsigned long long>(result.timing.overruns),
                static_cast<unsigned long long>(result.timing.missed_deadlines));
  if (log) std::printf("  log: %s (%llu rows)\n", log->path().c_str(), static_cast<unsigned long long>(log->rows()));
  if (lcm_log)
    std::printf("  LCM log: %s (%llu events)\n", args.lcm_log.c_str(), static_cast<unsigned long long>(lcm_log->log().events()));

  const rt::RobotState& state = emulator.state();
  if (!write_error.empty()) {
    std::printf("  STOPPED at t = %.3f s: %s\n", state.time.toSec(), write_error.c_str());
    return 1;
  }
  if (interrupted) {
    std::printf("  STOPPED at t = %.3f s by a signal (Ctrl-C or SIGTERM)\n", state.time.toSec());
    return 130;
  }
  if (!failure.empty() || state.robot_mode == rt::RobotMode::kReflex) {
    std::printf("  REFLEX at t = %.3f s: %s\n", state.time.toSec(),
                emulator.reflex_reason().c_str());
    return 1;
  }
  std::printf("  finished without reflex\n");
  return 0;
}

}  // namespace

Command add_emulate_command(CLI::App& app) {
  auto args = std::make_shared<EmulateArguments>();
  CLI::App* cmd = app.add_subcommand("emulate", "Run a scenario on the emulated 1 kHz robot (configs/scenarios/)");
  args->scenario.add_to(*cmd, "lockstep (simulated time) or realtime (1 kHz wall clock)");
  cmd->add_option("--seed", args->seed, "Override the scenario's seed (sensor noise, command losses)");
  cmd->add_option("--log", args->log, "Write the per-cycle CSV log to this file");
  cmd->add_option("--lcm-log", args->lcm_log, "Record the run as an LCM log (csp replay, csp log export, lcm-spy)");
  cmd->add_option("--report", args->report, "Medical scenarios: write force, path and penetration figures (SVG) into this directory");
  add_progress_flag(*cmd, args->progress);
  return [args] { return run_emulate(*args); };
}

}  // namespace csp::cli
