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
};

// Throws std::runtime_error if the log cannot be read or has no scenario record (not a CSP log).
ResimulationReport resimulate(const std::string& log_path);

struct PlaybackOptions {
  double speed = 1.0;   // 1: recorded timing; 2: twice as fast; 0: as fast as possible
  std::string lcm_url = kDefaultLcmUrl;
  const std::atomic<bool>* stop = nullptr;
};
// Publishes every event of the log on its channel; returns the number published.
uint64_t play_back(const std::string& log_path, const PlaybackOptions& options);

}  // namespace csp::bridge
