// Command-line pieces shared by the csp subcommands.
#pragma once

#include <atomic>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "csp/io/robot_config.hpp"
#include "csp/rt/cycle_driver.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::cli {

// A wrong command-line value: the command prints "csp <command>: <message>" and exits with 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Parse "a,b,c" into exactly `count` finite numbers; `name` is the option for the message.
std::vector<double> parse_numbers(const std::string& text, std::size_t count, const std::string& name);
Vector7 parse_joint_vector(const std::string& text, const std::string& name);
Vector3 parse_vector3(const std::string& text, const std::string& name);

// --robot, --inertia, --friction, --limits, --ee, --load-*, --gravity: which Model to build.
struct ModelArguments {
  std::string robot = std::string(CSP_SOURCE_DIR) + "/configs/robots/panda.yaml";
  std::string inertia, friction, limits;
  std::string end_effector = "none";
  std::string load_mass, load_com, load_inertia, gravity;

  void add_to(CLI::App& command);
  // Loads the robot file and builds the model; throws ConfigError or UsageError.
  Model build() const;
};

// A scenario as a user names it: a file, or where no such file is, a shipped scenario's name
// ("default", "medical/ultrasound_abdomen_scan": configs/scenarios/NAME.yaml); the default if empty.
std::string scenario_path(const std::string& given);

// The scenario options shared by `csp emulate` and `csp serve`: [SCENARIO] --clock --duration.
struct ScenarioArguments {
  std::string scenario;   // empty: configs/scenarios/default.yaml
  std::string clock;      // empty: the scenario's
  std::optional<double> duration;

  void add_to(CLI::App& command, const std::string& clock_help);
  // The scenario file with --clock and --duration applied (UsageError on a bad duration).
  rt::Scenario load() const;
};

// The files a command writes and reads, checked before it runs (and before anything is printed):
// every output must be a file (or directory) that can be written, no two outputs may be the same
// file, and no output may be an input. The check creates and truncates nothing: a refused command
// leaves every file as it was.
class Outputs {
 public:
  // A file the command writes, named by `option`; nothing for an empty path (the option not given).
  Outputs& file(const std::string& option, const std::string& path);
  // A directory the command writes `names` into (created if missing); nothing for an empty path.
  Outputs& directory(const std::string& option, const std::string& path, const std::vector<std::string>& names);
  // A file the command reads (`what`: its option or role), which no output may be.
  Outputs& input(const std::string& what, const std::string& path);
  // Throws UsageError naming the option, the path and the problem, for the first problem found.
  void check() const;

 private:
  struct Entry {
    std::string option, path;
    std::string directory;   // a directory output's file: the directory
  };
  std::vector<Entry> files_, directories_, inputs_;
};

// The command being run ("emulate", "log", ...), for messages printed outside an exception.
void set_command_name(const std::string& name);
const std::string& command_name();

// The flag a run polls to end as its duration would: set by Ctrl-C (SIGINT) and SIGTERM from now
// on, false until then. One flag for the process (a signal handler sees only globals).
std::atomic<bool>& stop_on_signals();

// The timing of a run, the same lines for every front end (rt::TimingReport); `round_trip` names
// what the round trip measured ("controller compute time", "state -> command").
void print_timing(const rt::TimingReport& timing, const char* round_trip);

// How a run ended early, the same for every front end (run::RunResult): an observer that failed
// (a log that could not be written: the error on stderr as "csp <command>: ...", as every other
// error, exit status 2; the STOPPED line on stdout) or a signal (`signal_status`). `robot_time`:
// where it ended [s]. Returns the exit status, nullopt for a run that went to its end.
std::optional<int> print_early_end(const std::string& observer_failure, bool stopped, double robot_time, int signal_status);

// At a run's end, the logs' last rows and events to their files (each object may be null): what
// the first that fails says, empty if all were written. `failure`: a failure already known (an
// observer that failed during the run), returned as it is.
template <class... Logs>
std::string flush_logs(std::string failure, Logs*... logs) {
  const auto flush = [&](auto* log) {
    if (!log || !failure.empty()) return;
    try {
      log->flush();
    } catch (const std::exception& e) {
      failure = e.what();
    }
  };
  (flush(logs), ...);
  return failure;
}

}  // namespace csp::cli
