// csp replay: re-simulate a CSP log (a run whose command source is the log) and report how far the
// states differ from the recorded ones, or play a log back onto LCM like lcm-logplayer.
#include <atomic>
#include <cstdio>
#include <memory>

#include "cli_options.hpp"
#include "commands.hpp"
#include "progress.hpp"
#include "csp/bridge/replay.hpp"
#include "csp/run/observers.hpp"
#include "csp/run/sources.hpp"

namespace csp::cli {
namespace {


struct ReplayArguments {
  std::string log, scenario, csv;
  bool play = false;
  double speed = 1.0;
  double max_gap = 10.0;
  std::string lcm_url = bridge::kDefaultLcmUrl;
  bool progress = false;
};

int run_replay(const ReplayArguments& args) {
  if (args.play && !args.scenario.empty()) throw UsageError("--scenario: re-simulation only; --play publishes the log as it is");
  if (args.play && !args.csv.empty()) throw UsageError("--csv: re-simulation only; --play publishes the log as it is");
  Outputs().file("--csv", args.csv).input("the log", args.log).input("--scenario", args.scenario).check();
  if (args.play) {
    bridge::PlaybackOptions options;
    options.speed = args.speed;
    options.max_gap = args.max_gap;
    options.lcm_url = args.lcm_url;
    options.stop = &stop_on_signals();  // Ctrl-C / SIGTERM end the playback
    ProgressMeter progress("csp replay", args.progress);
    options.progress = progress.callback();
    const bridge::PlaybackReport r = bridge::play_back(args.log, options);
    // Nothing published is no playback (an empty file, or nothing readable in it), unless a signal
    // ended it before the first event.
    if (r.published == 0 && !options.stop->load())
      throw std::runtime_error(args.log + ": no event to publish (" +
                               (r.damage.empty() ? std::string("an empty log") : "nothing readable: " + r.damage) + ")");
    progress.finish(std::to_string(r.published) + " events published");
    std::printf("csp replay: published %llu events of %s on %s\n", static_cast<unsigned long long>(r.published), args.log.c_str(),
                args.lcm_url.c_str());
    if (r.timestamp_jumps > 0)
      std::printf("  %llu timestamps jumped backwards or by more than %g s: published without waiting\n",
                  static_cast<unsigned long long>(r.timestamp_jumps), args.max_gap);
    if (r.damage.empty()) return 0;
    std::fprintf(stderr, "csp replay: %s\n", r.damage.c_str());
    return 1;
  }
  const bridge::Recording recording(args.log, args.scenario);
  run::Run run(recording.scenario);
  const std::unique_ptr<run::CsvLogObserver> csv = run::observe_csv_log(run, args.csv);
  ProgressMeter progress("csp replay", args.progress);
  run::LogReplaySource replay(recording, progress.callback());
  // Ctrl-C / SIGTERM end the re-simulation where it is; what it compared is reported.
  const run::RunResult result = run.run(replay, &stop_on_signals());
  const std::string log_failure = flush_logs(result.observer_failure, csv.get());
  const bridge::ResimulationReport& r = replay.report();
  if (log_failure.empty())   // else the error is the one line on stderr
    progress.finish(std::to_string(r.states) + " states re-simulated: " +
                    (r.states == 0         ? std::string("nothing compared")
                     : r.identical()       ? std::string("identical, bit for bit")
                                           : std::to_string(r.differing_states) + " differ"));
  std::printf("csp replay: %s: re-simulated %llu states from %llu recorded commands and requests\n  scenario: %s\n",
              args.log.c_str(), static_cast<unsigned long long>(r.states), static_cast<unsigned long long>(r.messages),
              r.scenario.c_str());
  if (!r.missing.empty())
    std::fprintf(stderr, "csp replay: %s: not in the recording: %s (the recorded states are compared all the same)\n",
                 args.log.c_str(), r.missing.c_str());
  if (r.differing_states > 0)
    std::printf("  %llu states differ, max |difference| %.3g, first at %s\n", static_cast<unsigned long long>(r.differing_states),
                r.max_difference, r.first_difference.c_str());
  if (!r.damage.empty()) {
    std::printf("  NOT a full replay: only the readable part was re-simulated\n");
    std::fprintf(stderr, "csp replay: %s\n", r.damage.c_str());
  }
  if (csv) std::printf("  CSV log of the re-simulation: %s (%llu rows)\n", args.csv.c_str(), static_cast<unsigned long long>(csv->log().rows()));
  if (r.states == 0) std::printf("  no recorded state was compared\n");
  if (const std::optional<int> status = print_early_end(log_failure, result.stopped, run.emulator().state().time.toSec(), 130))
    return *status;
  // (resimulate refuses a log without a state to compare: only a stop ends a replay before one)
  if (r.identical()) std::printf("  identical to the recorded states, bit for bit\n");
  return r.identical() ? 0 : 1;
}

}  // namespace

Command add_replay_command(CLI::App& app) {
  auto args = std::make_shared<ReplayArguments>();
  CLI::App* cmd = app.add_subcommand("replay", "Re-simulate a CSP LCM log (default) or play a log back onto LCM (--play)");
  cmd->add_option("log", args->log, "LCM log file")->required();
  cmd->add_option("--scenario", args->scenario,
                  "The scenario the robot ran, for a recording without its CSP_SCENARIO record (used instead of the record if given)");
  cmd->add_option("--csv", args->csv, "Write the per-cycle CSV log of the re-simulated robot (docs/joint-log.md; csp gap reads it)");
  cmd->add_flag("--play", args->play, "Publish the log's events on LCM at their recorded timing, like lcm-logplayer");
  cmd->add_option("--speed", args->speed, "--play: speed factor (2: twice as fast, 0: as fast as possible)")->capture_default_str();
  cmd->add_option("--max-gap", args->max_gap, "--play: seconds of log time beyond which a timestamp jump is not waited for")
      ->capture_default_str();
  cmd->add_option("--lcm-url", args->lcm_url, "--play: LCM provider URL")->capture_default_str();
  add_progress_flag(*cmd, args->progress);
  return [args] { return run_replay(*args); };
}

}  // namespace csp::cli
