// Progress of a long command on stderr: stage, percentage, rate and time left, redrawn in place on
// a terminal; quiet when stderr is not a terminal unless --progress asks for it (then one line a
// second, for logs). One summary line at the end either way. stdout stays the command's result.
#pragma once

#include <chrono>
#include <string>
#include <string_view>

#include <CLI/CLI.hpp>

#include "csp/dynamics/progress.hpp"

namespace csp::cli {

// --progress: show progress also when stderr is not a terminal.
void add_progress_flag(CLI::App& command, bool& forced);

class ProgressMeter {
 public:
  // `command` prefixes every line ("csp gap"); `unit` names what `done` counts ("samples").
  ProgressMeter(std::string command, bool forced);
  ~ProgressMeter();
  ProgressMeter(const ProgressMeter&) = delete;
  ProgressMeter& operator=(const ProgressMeter&) = delete;

  void update(std::string_view stage, double done, double total);
  // The callback the libraries take (csp::Progress); valid while this meter lives.
  Progress callback();
  // Clears the progress line and prints "<command>: <summary> (<seconds> s)".
  void finish(const std::string& summary);

 private:
  using Clock = std::chrono::steady_clock;
  void clear_line();

  std::string command_;
  bool shown_ = false, terminal_ = false, line_open_ = false, finished_ = false;
  Clock::time_point start_, stage_start_, last_draw_;
  std::string stage_;
  double drawn_fraction_ = 0.0;   // of the stage, at the last line drawn
};

}  // namespace csp::cli
