// `csp replay`: re-simulate a CSP log (feed its recorded messages to a fresh emulator built from
// its scenario record and compare the states), or play any LCM log back onto a bus like
// lcm-logplayer.
#pragma once

#include <atomic>
#include <string>

#include "csp/bridge/messages.hpp"
#include "csp/dynamics/progress.hpp"
#include "csp/rt/control_loop.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::bridge {

struct ResimulationReport {
  std::string scenario;             // where the scenario came from: the log's record, or --scenario
  uint64_t states = 0;              // recorded states compared
  uint64_t differing_states = 0;    // not bit-identical (utime aside)
  double max_difference = 0.0;      // largest |recorded - re-simulated| over all numeric fields
  std::string first_difference;     // "time 1234 ms: q" for the first differing state
  uint64_t messages = 0;            // commands and requests fed to the emulator
  std::string damage;               // LogReader::damage_summary(): empty for an intact log
  // What the recording misses (no scenario record, states before its first, gaps in the message
  // ids; StateCoverage), in one line; empty when it holds the run whole. The states it holds are
  // compared all the same: a missed state is re-simulated, a missed command shows as a difference.
  std::string missing;
  // Bit for bit, and over the whole log: a damaged log, or one of which no state was compared, is
  // never reported identical.
  bool identical() const { return states > 0 && differing_states == 0 && damage.empty(); }
};

// A recording of a CSP session to re-simulate: a `csp serve --log`, `csp can serve --log` or
// `csp emulate --lcm-log` file, or lcm-logger's recording of the bus (other channels and prefixes
// mixed in, begun late). The scenario is the scenario file `scenario_path` if given, else the log's
// first CSP_SCENARIO record, wherever it is; the channels are those of that record's prefix, or
// without a record those of the first state channel (a name ending in CSP_STATE). Throws
// std::runtime_error if the log cannot be read, has no scenario record and no `scenario_path` is
// given, or holds no robot state channel.
struct Recording {
  Recording(const std::string& log_path, const std::string& scenario_path = "");

  std::string log_path;
  rt::Scenario scenario;          // the robot to re-simulate it on
  std::string scenario_origin;    // ResimulationReport::scenario
  Channels channels;
  std::string missing;            // what the log misses before it is read through (no record)
  bool has_config_replies = false;   // a recording of the server's side (not csp emulate's)
};

struct ResimulationOptions {
  rt::CycleObserver after_cycle;             // after each re-simulated cycle (may be empty)
  const std::atomic<bool>* stop = nullptr;   // set to end the re-simulation where it is
  Progress progress;                         // MB of the log re-simulated
};

// Feeds the recording's commands and requests to `robot` (the run's, built from
// recording.scenario) cycle by cycle and compares each recorded state with the re-simulated one.
// run::LogReplaySource is the front end.
ResimulationReport resimulate(const Recording& recording, rt::Emulator& robot, const ResimulationOptions& options);
// The same on a robot of its own.
ResimulationReport resimulate(const std::string& log_path, const std::string& scenario_path = "",
                              const Progress& progress = {});

struct PlaybackOptions {
  double speed = 1.0;       // 1: recorded timing; 2: twice as fast; 0: as fast as possible
  double max_gap = 10.0;    // [s] of log time: a timestamp jump beyond it (or backwards) is not waited for
  std::string lcm_url = kDefaultLcmUrl;
  const std::atomic<bool>* stop = nullptr;
  Progress progress;        // MB of the log published
};
// The speeds play_back accepts besides 0: slower would wait for years, faster is "as fast as possible".
inline constexpr double kMinPlaybackSpeed = 1e-3, kMaxPlaybackSpeed = 1e6;

struct PlaybackReport {
  uint64_t published = 0;
  uint64_t timestamp_jumps = 0;   // gaps over max_gap or backwards: published at once
  std::string damage;             // LogReader::damage_summary()
};
// Publishes every event of the log on its channel at the recorded pace.
PlaybackReport play_back(const std::string& log_path, const PlaybackOptions& options);

}  // namespace csp::bridge
