// `csp replay`: re-simulate a CSP log (feed its recorded messages to a fresh emulator built from
// its scenario record and compare the states), or play any LCM log back onto a bus like
// lcm-logplayer.
#pragma once

#include <atomic>
#include <string>

#include "csp/bridge/messages.hpp"

namespace csp::bridge {

struct ResimulationReport {
  uint64_t states = 0;              // recorded states compared
  uint64_t differing_states = 0;    // not bit-identical (utime aside)
  double max_difference = 0.0;      // largest |recorded - re-simulated| over all numeric fields
  std::string first_difference;     // "time 1234 ms: q" for the first differing state
  uint64_t messages = 0;            // commands and requests fed to the emulator
  std::string damage;               // LogReader::damage_summary(): empty for an intact log
  // Bit for bit, and over the whole log: a damaged log is never reported identical.
  bool identical() const { return differing_states == 0 && damage.empty(); }
};

// Throws std::runtime_error if the log cannot be read or has no scenario record (not a CSP log).
ResimulationReport resimulate(const std::string& log_path);

struct PlaybackOptions {
  double speed = 1.0;       // 1: recorded timing; 2: twice as fast; 0: as fast as possible
  double max_gap = 10.0;    // [s] of log time: a timestamp jump beyond it (or backwards) is not waited for
  std::string lcm_url = kDefaultLcmUrl;
  const std::atomic<bool>* stop = nullptr;
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
