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

// The scenario options shared by `csp emulate` and `csp serve`: [SCENARIO] --clock --duration.
struct ScenarioArguments {
  std::string scenario;   // empty: configs/scenarios/default.yaml
  std::string clock;      // empty: the scenario's
  std::optional<double> duration;

  void add_to(CLI::App& command, const std::string& clock_help);
  // The scenario file with --clock and --duration applied (UsageError on a bad duration).
  rt::Scenario load() const;
};

// The flag a run polls to end as its duration would: set by Ctrl-C (SIGINT) and SIGTERM from now
// on, false until then. One flag for the process (a signal handler sees only globals).
std::atomic<bool>& stop_on_signals();

// The timing of a run, the same lines for every front end (rt::TimingReport); `round_trip` names
// what the round trip measured ("controller compute time", "state -> command").
void print_timing(const rt::TimingReport& timing, const char* round_trip);

// How a run ended early, the same line for every front end (run::RunResult): an observer that failed
// (a log that could not be written: exit status 1) or a signal (`signal_status`). `robot_time`:
// where it ended [s]. Returns the exit status, nullopt for a run that went to its end.
std::optional<int> print_early_end(const std::string& observer_failure, bool stopped, double robot_time, int signal_status);

}  // namespace csp::cli
