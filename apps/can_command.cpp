// csp can: the arm's joint drives on a CANopen bus (docs/can.md). `csp can serve` runs them on
// SocketCAN (a run whose command source is the CAN bus); `csp can eds` and `csp can dbc` print the files generated from the drives' object table.
#include <atomic>
#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

#include "commands.hpp"
#include "view_option.hpp"
#include "csp/can/export.hpp"
#include "csp/io/svg_plot.hpp"
#include "csp/run/can_source.hpp"
#include "csp/run/observers.hpp"

namespace csp::cli {
namespace {


struct CanArguments {
  int node = 1;
  std::string out;
  // serve
  ScenarioArguments scenario;
  std::string clock = "sync";
  std::string iface = "vcan0";
  bool sync_producer = false;
  double bitrate = 1e6;
  int split = 1;
  std::string log, csv;
  ViewOption view;   // serve
};

int write_text(const std::string& text, const std::string& path) {
  if (path.empty()) {
    std::cout << text;
    return 0;
  }
  Outputs().file("--out", path).check();
  write_text_file(path, text);
  return 0;
}

int run_serve(const CanArguments& args) {
  const rt::Scenario scenario = args.scenario.load();
  Outputs()
      .file("--log", args.log)
      .file("--csv", args.csv)
      .input("the scenario", scenario.path)
      .input("the scenario's robot file", scenario.robot_file)
      .check();
  can::CanServeOptions options;
  options.interface = args.iface;
  options.split = args.split;
  options.clock = args.clock == "realtime" ? rt::Clock::kRealtime : rt::Clock::kLockstep;
  options.sync_producer = args.sync_producer;
  options.bitrate = args.bitrate;
  options.log_path = args.log;
  options.duration = scenario.duration;
  std::vector<std::string> names;
  try {
    names = can::split_interfaces(args.iface, args.split);
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  std::string list;
  for (const std::string& n : names) {
    if (!list.empty()) list += ", ";
    list += n;
  }
  std::printf("csp can serve: %s (%s), %s clock%s, up to %.3f s on %s\n", scenario.name.c_str(), scenario.path.c_str(),
              args.clock.c_str(), args.sync_producer ? ", CSP sends SYNC" : ", the master sends SYNC", options.duration, list.c_str());
  std::fflush(stdout);
  run::Run run(scenario);
  const std::unique_ptr<run::CsvLogObserver> csv = run::observe_csv_log(run, args.csv);
  const std::unique_ptr<LiveViewSession> live_view = start_live_view(args.view, run, "csp can serve " + scenario.name);
  run::CanBusSource bus(options);
  // Ctrl-C / SIGTERM end the run cleanly: the logs keep every cycle run.
  const run::RunResult result = run.run(bus, &stop_on_signals());
  if (live_view) live_view->end(run, result);
  const std::string log_failure = flush_logs(result.observer_failure, csv.get());   // (the LCM log: the CAN source)

  const can::CanServeReport& r = bus.report();
  print_timing(r.timing, "round trip SYNC -> enabled RPDOs");
  std::printf("  motions %llu, motion cycles %llu, lost commands %llu (longest run %d), reflexes %llu, error recoveries %llu\n",
              static_cast<unsigned long long>(r.arm.motions), static_cast<unsigned long long>(r.emulator.motion_cycles),
              static_cast<unsigned long long>(r.emulator.lost_commands), r.emulator.max_consecutive_lost,
              static_cast<unsigned long long>(r.emulator.reflexes), static_cast<unsigned long long>(r.arm.recoveries));
  std::printf("  bus: SYNCs %llu, cycles without SYNC %llu, lost %llu, torn %llu, ignored frames %llu, mixed modes %llu\n",
              static_cast<unsigned long long>(r.bus.syncs), static_cast<unsigned long long>(r.bus.missing_syncs),
              static_cast<unsigned long long>(r.bus.lost_cycles), static_cast<unsigned long long>(r.bus.torn_cycles),
              static_cast<unsigned long long>(r.bus.ignored_frames), static_cast<unsigned long long>(r.arm.mixed_modes));
  std::printf("  targets ignored: %llu cycles with a drive in operation enabled and no motion on its target, "
              "%llu motions ended with drives left in operation enabled\n",
              static_cast<unsigned long long>(r.arm.ignored_cycles), static_cast<unsigned long long>(r.arm.abandoned_motions));
  for (const can::InterfaceReport& i : r.interfaces) {
    std::string joints;
    for (int j : i.joints) {
      if (!joints.empty()) joints += ",";
      joints += std::to_string(j);
    }
    std::printf("  %s (joints %s): %llu frames, %llu bits (worst-case stuffing), load at %.0f bit/s and 1 kHz: %.1f %% (%.0f bit/s of wall time); "
                "received %llu, dropped %llu (receive queue full), late %llu (handled > 1 ms after they came), sent %llu, skipped %llu, send failures %llu\n",
                i.name.c_str(), joints.c_str(), static_cast<unsigned long long>(i.load.frames()),
                static_cast<unsigned long long>(i.load.bits()), args.bitrate, i.load_percent,
                static_cast<double>(i.load.bits()) / r.timing.wall_seconds,
                static_cast<unsigned long long>(i.socket.received), static_cast<unsigned long long>(i.socket.dropped),
                static_cast<unsigned long long>(i.socket.late), static_cast<unsigned long long>(i.socket.sent),
                static_cast<unsigned long long>(i.socket.skipped), static_cast<unsigned long long>(i.socket.send_failures));
  }
  if (!r.last_reflex.empty()) std::printf("  last reflex: %s\n", r.last_reflex.c_str());
  if (!args.log.empty()) std::printf("  log: %s (%llu events)\n", args.log.c_str(), static_cast<unsigned long long>(r.log_events));
  if (csv) std::printf("  CSV log: %s (%llu rows)\n", args.csv.c_str(), static_cast<unsigned long long>(csv->log().rows()));
  // A signal is how a serve is meant to end: exit status 0.
  return print_early_end(log_failure, result.stopped, run.emulator().state().time.toSec(), 0).value_or(0);
}

}  // namespace

Command add_can_command(CLI::App& app) {
  auto args = std::make_shared<CanArguments>();
  CLI::App* cmd = app.add_subcommand("can", "The joint drives as CANopen CiA 402 nodes: serve on SocketCAN, EDS, DBC (docs/can.md)");
  cmd->require_subcommand(1);
  CLI::App* serve = cmd->add_subcommand("serve", "Run a scenario's arm as seven CiA 402 drives on SocketCAN (vcan0, can0, ...)");
  serve->add_option("scenario", args->scenario.scenario, "Scenario file (default: configs/scenarios/default.yaml)");
  serve->add_option("--iface", args->iface, "CAN interface (with --split: the first of numbered ones)")->capture_default_str();
  serve->add_option("--clock", args->clock, "sync: one cycle per SYNC; realtime: the 1 kHz deadline clock")
      ->check(CLI::IsMember({"sync", "realtime"}))
      ->capture_default_str();
  serve->add_flag("--sync-producer", args->sync_producer,
                  "CSP sends SYNC (realtime: every 1 ms; sync: once the enabled joints' RPDOs are in)");
  serve->add_option("--bitrate", args->bitrate, "Bitrate of the real bus the load is reported for [bit/s]")
      ->check(CLI::Range(1e3, 1e7))
      ->capture_default_str();
  serve->add_option("--split", args->split, "Spread the joints over this many interfaces (vcan0, vcan1, ...)")
      ->check(CLI::Range(1, 7))
      ->capture_default_str();
  serve->add_option("--log", args->log, "Record the session as an LCM log (csp replay re-simulates it)");
  serve->add_option("--csv", args->csv, "Write the per-cycle CSV log of the robot (docs/joint-log.md; csp gap reads it)");
  args->view.add_to(*serve);
  serve->add_option("--duration", args->scenario.duration, "Robot time to serve [s] (default: the scenario's)");
  CLI::App* eds = cmd->add_subcommand("eds", "Print the EDS (CiA 306) of a joint drive");
  eds->add_option("--node", args->node, "Node id 1..7 = joint 1..7 (the default assignment)")
      ->check(CLI::Range(1, 7))
      ->capture_default_str();
  eds->add_option("-o,--out", args->out, "Write to this file instead of stdout");
  CLI::App* dbc = cmd->add_subcommand("dbc", "Print the DBC of the bus (default mapping, nodes 1..7)");
  dbc->add_option("-o,--out", args->out, "Write to this file instead of stdout");
  return [args, eds, serve] {
    if (serve->parsed()) return run_serve(*args);
    if (eds->parsed()) return write_text(can::make_eds(can::panda_joint_drive(args->node)), args->out);
    return write_text(can::make_dbc(can::BusSettings{}), args->out);
  };
}

}  // namespace csp::cli
