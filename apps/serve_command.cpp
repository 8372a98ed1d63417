// csp serve: the emulated robot on an LCM bus for a controller in another process
// (docs/bridge.md): a run whose command source is the bus; optionally records the session as an
// LCM log and the robot's cycles as a CSV log.
#include <atomic>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>

#include "commands.hpp"
#include "view_option.hpp"
#include "csp/bridge/lcm_url.hpp"
#include "csp/run/observers.hpp"
#include "csp/run/sources.hpp"

namespace csp::cli {
namespace {


struct ServeArguments {
  ScenarioArguments scenario;
  std::string lcm_url = bridge::kDefaultLcmUrl;
  std::string prefix;
  std::string log, csv;
  double lockstep_timeout = 1.0;
  bool wait = false;
  ViewOption view;
};

int run_serve(const ServeArguments& args) {
  const rt::Scenario scenario = args.scenario.load();
  Outputs()
      .file("--log", args.log)
      .file("--csv", args.csv)
      .input("the scenario", scenario.path)
      .input("the scenario's robot file", scenario.robot_file)
      .check();
  bridge::ServeOptions options;
  options.clock = scenario.clock;
  options.duration = scenario.duration;
  // Bounded: the timeout becomes integer nanoseconds (an infinite one would overflow the conversion).
  if (!(args.lockstep_timeout > 0.0 && args.lockstep_timeout <= 3600.0))
    throw UsageError("--lockstep-timeout: expected a positive number of seconds, at most 3600");
  options.lcm_url = bridge::checked_lcm_url(args.lcm_url);   // before anything is printed
  options.channel_prefix = args.prefix;
  options.log_path = args.log;
  options.lockstep_timeout = args.lockstep_timeout;
  options.wait_for_controller = args.wait;
  run::Run run(scenario);
  const std::unique_ptr<run::CsvLogObserver> csv = run::observe_csv_log(run, args.csv);
  const std::unique_ptr<LiveViewSession> live_view = start_live_view(args.view, run, "csp serve " + scenario.name);
  run::LcmBusSource bus(options);

  std::printf("csp serve: %s (%s), %s clock, %.3f s on %s, channels %sCSP_*\n", scenario.name.c_str(), scenario.path.c_str(),
              options.clock == rt::Clock::kLockstep ? "lockstep" : "real-time", options.duration, options.lcm_url.c_str(),
              options.channel_prefix.c_str());
  std::fflush(stdout);
  // Ctrl-C / SIGTERM end the run cleanly: the logs keep every cycle run.
  const run::RunResult result = run.run(bus, &stop_on_signals());
  if (live_view) live_view->end(run, result);
  const std::string log_failure = flush_logs(result.observer_failure, csv.get());   // (the LCM log: bridge::serve)

  const bridge::ServeReport& r = bus.report();
  const bridge::ServerCounters& c = r.counters;
  print_timing(r.timing, "round trip state -> command");
  std::printf("  sessions %llu, motion cycles %llu, lost commands %llu (longest run %d), reflexes %llu\n",
              static_cast<unsigned long long>(c.sessions), static_cast<unsigned long long>(r.emulator.motion_cycles),
              static_cast<unsigned long long>(r.emulator.lost_commands), r.emulator.max_consecutive_lost,
              static_cast<unsigned long long>(r.emulator.reflexes));
  std::printf("  rejected messages: fingerprint %llu, truncated %llu, oversized %llu, stale %llu, wrong mode %llu, "
              "no session %llu; non-finite commands %llu, refused requests %llu\n",
              static_cast<unsigned long long>(c.rejected_fingerprint), static_cast<unsigned long long>(c.rejected_truncated),
              static_cast<unsigned long long>(c.rejected_oversized), static_cast<unsigned long long>(c.rejected_stale),
              static_cast<unsigned long long>(c.rejected_wrong_mode), static_cast<unsigned long long>(c.rejected_no_session),
              static_cast<unsigned long long>(c.non_finite_commands), static_cast<unsigned long long>(c.refused_requests));
  if (!r.last_reflex.empty()) std::printf("  last reflex: %s\n", r.last_reflex.c_str());
  if (!args.log.empty())
    std::printf("  log: %s (%llu events, %llu states)\n", args.log.c_str(), static_cast<unsigned long long>(r.log_events),
                static_cast<unsigned long long>(r.state_messages));
  if (csv) std::printf("  CSV log: %s (%llu rows)\n", args.csv.c_str(), static_cast<unsigned long long>(csv->log().rows()));
  // A signal is how a serve is meant to end: exit status 0.
  return print_early_end(log_failure, result.stopped, run.emulator().state().time.toSec(), 0).value_or(0);
}

}  // namespace

Command add_serve_command(CLI::App& app) {
  auto args = std::make_shared<ServeArguments>();
  CLI::App* cmd = app.add_subcommand("serve", "Run a scenario's robot on LCM for an external controller (docs/bridge.md)");
  args->scenario.add_to(*cmd, "lockstep (each cycle waits for its command) or realtime (1 kHz wall clock)");
  cmd->add_option("--lcm-url", args->lcm_url, "LCM provider URL")->capture_default_str();
  cmd->add_option("--prefix", args->prefix, "Prefix of every channel name (several robots on one bus)");
  cmd->add_option("--log", args->log, "Record the session as an LCM log file");
  cmd->add_option("--csv", args->csv, "Write the per-cycle CSV log of the robot (docs/joint-log.md; csp gap reads it)");
  cmd->add_option("--lockstep-timeout", args->lockstep_timeout, "Lockstep: how long a cycle waits for its command [s]")
      ->capture_default_str();
  cmd->add_flag("--wait", args->wait, "Lockstep: hold the first cycle until a controller starts a session");
  args->view.add_to(*cmd);
  return [args] { return run_serve(*args); };
}

}  // namespace csp::cli
