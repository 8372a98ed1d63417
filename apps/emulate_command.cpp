// csp emulate: run a scenario on the emulated robot with its built-in controller and report the
// tracking error, reflexes and timing; optionally write the per-cycle CSV log and the figures.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "commands.hpp"
#include "progress.hpp"
#include "view_option.hpp"
#include "csp/io/svg_plot.hpp"
#include "csp/run/observers.hpp"
#include "csp/run/sources.hpp"

namespace csp::cli {
namespace {

// What --report may write (a scene's task: no tracking error, and its own three).
const std::vector<std::string> kReportFigures{"joint_positions.svg", "tracking_error.svg", "joint_torques.svg",
                                              "limits.svg",          "ee_path.svg",        "force.svg",
                                              "path.svg",            "penetration.svg"};

struct EmulateArguments {
  ScenarioArguments scenario;
  std::optional<long long> seed;
  std::string log;
  std::string lcm_log;
  std::string report;   // the figures' directory
  bool progress = false;
  ViewOption view;
};

// The tracking summary: RMS and max error of q against the scenario's trajectory, and the largest
// estimated external torque.
void print_tracking(const run::TrackingObserver& tracking) {
  if (tracking.cycles() == 0) return;
  auto row = [](const char* name, const Vector7& v, double scale) {
    std::printf("  %-34s", name);
    for (int i = 0; i < kNumJoints; ++i) std::printf(" %8.3f", scale * v[i]);
    std::printf("\n");
  };
  std::printf("  %-34s %8s %8s %8s %8s %8s %8s %8s\n", "joint", "1", "2", "3", "4", "5", "6", "7");
  row("tracking error RMS [mrad]", tracking.rms_error(), 1e3);
  row("tracking error max [mrad]", tracking.max_error(), 1e3);
  row("max |tau_ext_hat_filtered| [N m]", tracking.max_tau_ext(), 1.0);
}

int run_emulate(const EmulateArguments& args) {
  rt::Scenario scenario = args.scenario.load();
  if (args.seed) {
    if (*args.seed < 0) throw UsageError("--seed: expected a non-negative whole number");
    scenario.seed = static_cast<uint64_t>(*args.seed);
    scenario.emulator.seed = scenario.seed;
    scenario.command_faults.seed = scenario.seed + 1;
  }
  // Before the run and before any file is opened: a refused output leaves every file as it was.
  Outputs()
      .file("--log", args.log)
      .file("--lcm-log", args.lcm_log)
      .directory("--report", args.report, kReportFigures)
      .input("the scenario", scenario.path)
      .input("the scenario's robot file", scenario.robot_file)
      .check();

  // The run and its observers: progress, the task's measure (a scene's medical metrics, else the
  // joint tracking), the logs.
  run::Run run(scenario);
  run::ControllerSource controller(run);
  ProgressMeter progress("csp emulate", args.progress);
  run::ProgressObserver progress_observer(progress.callback(), "simulated seconds", scenario.duration, run.emulator());
  run.observe(progress_observer);
  std::unique_ptr<run::MedicalObserver> medical;
  std::unique_ptr<run::TrackingObserver> tracking;
  if (scenario.emulator.scene) {
    medical = std::make_unique<run::MedicalObserver>(run, controller.controller().status);
    run.observe(*medical);
  }
  // A scene's task has no joint trajectory to track: its figures show the joints without one.
  if (!scenario.emulator.scene || !args.report.empty()) {
    tracking = std::make_unique<run::TrackingObserver>(
        scenario.emulator.scene ? run::TrackingObserver::Reference{} : run::scenario_reference(scenario, run.emulator()),
        run.emulator());
    if (!args.report.empty()) tracking->keep_figures();
    run.observe(*tracking);
  }
  const std::unique_ptr<run::CsvLogObserver> log = run::observe_csv_log(run, args.log);
  std::unique_ptr<run::LcmLogObserver> lcm_log;
  if (!args.lcm_log.empty()) {
    lcm_log = std::make_unique<run::LcmLogObserver>(args.lcm_log, run, controller.controller().mode);
    run.observe(*lcm_log);
  }

  std::printf("csp emulate: %s (%s)\n  robot %s, %s clock, %.3f s, seed %llu, controller %s (%s mode)\n",
              scenario.name.c_str(), scenario.path.c_str(), scenario.robot_file.c_str(), rt::clock_name(scenario.clock),
              scenario.duration, static_cast<unsigned long long>(scenario.seed), scenario.controller.type.c_str(),
              rt::control_mode_name(controller.controller().mode));
  const std::unique_ptr<LiveViewSession> live_view = start_live_view(args.view, run, "csp emulate " + scenario.name);
  // A live view waits for its page: the run is shown from its first cycle.
  if (live_view) live_view->wait_for_page(stop_on_signals());
  // Ctrl-C (or SIGTERM) and a log that cannot be written end the motion as its duration would:
  // the robot holds, the summary is printed, the logs end with whole rows and events.
  const run::RunResult result = run.run(controller, &stop_on_signals());
  // The logs' last rows: a write error there ends the command as one during the run does.
  const std::string log_failure = flush_logs(result.observer_failure, log.get(), lcm_log.get());

  const rt::EmulatorCounters& counters = run.emulator().counters();
  if (log_failure.empty())   // else the error is the one line on stderr
    progress.finish(format("%llu cycles (%.3f s of motion)", static_cast<unsigned long long>(counters.motion_cycles),
                           static_cast<double>(counters.motion_cycles) * 1e-3));
  std::printf("  ran %llu cycles (%.3f s), lost commands %llu (longest run %d)\n",
              static_cast<unsigned long long>(counters.motion_cycles), static_cast<double>(counters.motion_cycles) * 1e-3,
              static_cast<unsigned long long>(counters.lost_commands), counters.max_consecutive_lost);
  if (tracking && !medical) print_tracking(*tracking);
  if (medical) {
    for (const rt::MedicalMetric& m : medical->recorder().metrics()) {
      if (std::isnan(m.value)) std::printf("  %-50s %10s\n", m.name.c_str(), "none");   // it did not happen
      else std::printf("  %-50s %10.3f %s\n", m.name.c_str(), m.value, m.unit.c_str());
    }
    if (!args.report.empty()) medical->recorder().write_figures(args.report);
  }
  if (!args.report.empty()) {
    tracking->write_figures(args.report, scenario.name);
    std::printf("  figures in %s: joint_positions.svg,%s joint_torques.svg, limits.svg, ee_path.svg%s\n",
                args.report.c_str(), medical ? "" : " tracking_error.svg,",
                medical ? ", force.svg, path.svg, penetration.svg" : "");
  }
  print_timing(controller.motion().timing, "controller compute time");
  if (log) std::printf("  log: %s (%llu rows)\n", log->log().path().c_str(), static_cast<unsigned long long>(log->log().rows()));
  if (lcm_log) std::printf("  LCM log: %s (%llu events)\n", args.lcm_log.c_str(), static_cast<unsigned long long>(lcm_log->events()));

  const rt::RobotState& state = run.emulator().state();
  if (live_view) {
    const std::string how = controller.reflex() ? "reflex: " + run.emulator().reflex_reason()
                                                : (result.stopped ? "stopped" : "finished without reflex");
    live_view->finish(run, format("%s at t = %.3f s", how.c_str(), state.time.toSec()), log_failure.empty() ? args.log : "");
    if (!result.stopped) live_view->serve_until_signal();
  }
  if (const std::optional<int> status = print_early_end(log_failure, result.stopped, state.time.toSec(), 130))
    return *status;
  if (controller.reflex() || state.robot_mode == rt::RobotMode::kReflex) {
    std::printf("  REFLEX at t = %.3f s: %s\n", state.time.toSec(), run.emulator().reflex_reason().c_str());
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
  cmd->add_option("--report", args->report,
                  "Write the run's figures (SVG) into this directory: joint positions, tracking error, joint torques "
                  "with their limits, limit usage, end-effector path; a scene's task adds force, path and penetration");
  add_progress_flag(*cmd, args->progress);
  args->view.add_to(*cmd);
  return [args] { return run_emulate(*args); };
}

}  // namespace csp::cli
