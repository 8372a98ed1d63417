// csp fci: the emulated robot on the network as a Franka robot is (docs/fci.md), for an unmodified
// libfranka: a run whose command source is the FCI. The robot outlives its clients; the run ends
// on Ctrl-C (or --duration).
#include <atomic>
#include <cstdio>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "view_option.hpp"
#include "csp/fci/model_library.hpp"
#include "csp/io/robot_config.hpp"
#include "csp/run/fci_source.hpp"
#include "csp/run/observers.hpp"

namespace csp::cli {
namespace {

struct FciArguments {
  ScenarioArguments scenario;
  std::string address = "127.0.0.1";
  double lockstep_timeout = 1.0;
  std::string csv;
  ViewOption view;
};

// The protocol a robot speaks: an FR3 libfranka 0.13 (version 7), a Panda libfranka 0.9
// (version 5), as their system software does; a robot file names its arm.
fci::Version protocol_version(const rt::Scenario& scenario) {
  return load_robot_config(scenario.robot_file).name == "fr3" ? fci::kFr3Version : fci::kPandaVersion;
}

int run_fci(const FciArguments& args) {
  rt::Scenario scenario = args.scenario.load();
  if (args.scenario.clock.empty()) scenario.clock = rt::Clock::kRealtime;   // on the wire the robot keeps time
  Outputs()
      .file("--csv", args.csv)
      .input("the scenario", scenario.path)
      .input("the scenario's robot file", scenario.robot_file)
      .check();
  if (!(args.lockstep_timeout > 0.0 && args.lockstep_timeout <= 3600.0))
    throw UsageError("--lockstep-timeout: expected a positive number of seconds, at most 3600");
  run::Run run(scenario);
  const std::unique_ptr<run::CsvLogObserver> csv = run::observe_csv_log(run, args.csv);
  const std::unique_ptr<LiveViewSession> live_view = start_live_view(args.view, run, "csp fci " + scenario.name);

  fci::FciServeOptions options;
  options.address = args.address;
  options.version = protocol_version(scenario);
  options.clock = scenario.clock;
  options.lockstep_timeout = args.lockstep_timeout;
  options.duration = args.scenario.duration;
  options.faults = scenario.command_faults;
  if (scenario.has_hand) options.hand = scenario.hand;
  if (scenario.has_vacuum_gripper) options.vacuum_gripper = scenario.vacuum_gripper;
  // The robot's own model, as the robot serves its model library (read when a client asks).
  options.model_library = [&run] { return fci::model_library_for(run.emulator().internal_model().parameters()); };
  options.diagnostic = [](const std::string& line) { std::cerr << "csp fci: " << line << '\n'; };
  options.listening = [&] {
    std::printf("csp fci: %s (%s), FCI version %d (libfranka %s), %s clock, listening on %s:%d%s\n", scenario.name.c_str(),
                scenario.path.c_str(), options.version, options.version == fci::kFr3Version ? "0.13" : "0.9",
                rt::clock_name(options.clock), args.address.c_str(), fci::kCommandPort,
                options.hand ? " (the hand on 1338)" : options.vacuum_gripper ? " (the vacuum gripper on 1339)" : "");
    std::fflush(stdout);
  };
  run::FciSource network(options);
  // Ctrl-C / SIGTERM end the run cleanly: the logs keep every cycle run.
  const run::RunResult result = run.run(network, &stop_on_signals());
  if (live_view) live_view->end(run, result);
  const std::string log_failure = flush_logs(result.observer_failure, csv.get());

  const fci::FciServeReport& r = network.report();
  const fci::FciCounters& c = r.counters;
  print_timing(r.timing, "round trip state -> command");
  std::printf("  connections %llu (refused versions %llu), motions %llu, motion cycles %llu, lost commands %llu (longest run %d), "
              "reflexes %llu\n",
              static_cast<unsigned long long>(c.connections), static_cast<unsigned long long>(c.refused_versions),
              static_cast<unsigned long long>(c.motions), static_cast<unsigned long long>(r.emulator.motion_cycles),
              static_cast<unsigned long long>(r.emulator.lost_commands), r.emulator.max_consecutive_lost,
              static_cast<unsigned long long>(r.emulator.reflexes));
  std::printf("  refused requests %llu, protocol errors %llu, rejected command packets %llu, stale %llu, foreign packets %llu, "
              "clients lost in a motion %llu, lost by the scenario's faults %llu\n",
              static_cast<unsigned long long>(c.refused_requests), static_cast<unsigned long long>(c.protocol_errors),
              static_cast<unsigned long long>(c.rejected_commands), static_cast<unsigned long long>(c.stale_commands),
              static_cast<unsigned long long>(r.foreign_packets), static_cast<unsigned long long>(c.client_losses),
              static_cast<unsigned long long>(c.injected_losses));
  const auto print_device = [](const char* name, const std::optional<fci::DeviceCounters>& d) {
    if (!d) return;
    std::printf("  %s: connections %llu (refused versions %llu), commands %llu, failed %llu, protocol errors %llu\n", name,
                static_cast<unsigned long long>(d->connections), static_cast<unsigned long long>(d->refused_versions),
                static_cast<unsigned long long>(d->commands), static_cast<unsigned long long>(d->failed_commands),
                static_cast<unsigned long long>(d->protocol_errors));
  };
  print_device("gripper", r.gripper);
  print_device("vacuum gripper", r.vacuum_gripper);
  if (!r.last_reflex.empty()) std::printf("  last reflex: %s\n", r.last_reflex.c_str());
  if (csv) std::printf("  CSV log: %s (%llu rows)\n", args.csv.c_str(), static_cast<unsigned long long>(csv->log().rows()));
  // A signal is how the robot is switched off: exit status 0.
  return print_early_end(log_failure, result.stopped, run.emulator().state().time.toSec(), 0).value_or(0);
}

}  // namespace

Command add_fci_command(CLI::App& app) {
  auto args = std::make_shared<FciArguments>();
  CLI::App* cmd = app.add_subcommand("fci", "Run a scenario's robot on the network for an unmodified libfranka (FCI, docs/fci.md)");
  args->scenario.add_to(*cmd, "realtime (default: the robot's 1 kHz) or lockstep (a motion's cycle waits for its command)");
  cmd->add_option("--address", args->address, "The robot's IPv4 address (any 127.x.y.z on this machine)")->capture_default_str();
  cmd->add_option("--lockstep-timeout", args->lockstep_timeout, "Lockstep: how long a motion's cycle waits for its command [s]")
      ->capture_default_str();
  cmd->add_option("--csv", args->csv, "Write the per-cycle CSV log of the robot (docs/joint-log.md; csp gap reads it)");
  args->view.add_to(*cmd);
  return [args] { return run_fci(*args); };
}

}  // namespace csp::cli
