#include "progress.hpp"

#include <cmath>
#include <cstdio>
#include <unistd.h>

#include "csp/io/svg_plot.hpp"   // format

namespace csp::cli {

void add_progress_flag(CLI::App& command, bool& forced) {
  command.add_flag("--progress", forced,
                   "Show progress (stage, rate, time left) on stderr also when it is not a terminal");
}

ProgressMeter::ProgressMeter(std::string command, bool forced)
    : command_(std::move(command)), terminal_(isatty(STDERR_FILENO) == 1) {
  shown_ = terminal_ || forced;
  start_ = stage_start_ = last_draw_ = Clock::now();
}

ProgressMeter::~ProgressMeter() { clear_line(); }   // an exception on the way out: no half line left

namespace {

std::string duration_text(double seconds) {
  if (!std::isfinite(seconds)) return "?";
  if (seconds < 1) return "<1 s";
  if (seconds < 60) return format("%.0f s", std::ceil(seconds));
  return format("%d min %02d s", static_cast<int>(seconds) / 60, static_cast<int>(seconds) % 60);
}

// 2.3 M/s, 850/s: three digits at most.
std::string rate_text(double per_second) {
  if (per_second >= 1e6) return format("%.3g M/s", per_second * 1e-6);
  if (per_second >= 1e3) return format("%.3g k/s", per_second * 1e-3);
  return format("%.3g/s", per_second);
}

}  // namespace

void ProgressMeter::update(std::string_view stage, double done, double total) {
  if (!shown_ || finished_) return;
  const Clock::time_point now = Clock::now();
  const bool new_stage = stage != stage_;
  if (new_stage) {
    stage_ = stage;
    stage_start_ = now;
  }
  // A terminal is redrawn 10 times a second; a log gets a line at each new stage, then one a
  // second or every tenth of the stage, whichever comes first.
  const double since_draw = std::chrono::duration<double>(now - last_draw_).count();
  const double fraction = total > 0 ? done / total : 0.0;
  const bool due = terminal_ ? since_draw >= 0.1 : (since_draw >= 1.0 || fraction >= drawn_fraction_ + 0.1);
  if (!new_stage && !due) return;
  last_draw_ = now;
  drawn_fraction_ = fraction;

  const double stage_seconds = std::chrono::duration<double>(now - stage_start_).count();
  const double rate = stage_seconds > 0 ? done / stage_seconds : 0.0;
  std::string text = command_ + ": " + stage_;
  if (total > 0) {
    text += format(" %3.0f%% (%.0f/%.0f", 100.0 * std::clamp(done / total, 0.0, 1.0), done, total);
    if (rate > 0 && done > 0)
      text += ", " + rate_text(rate) + ", " + duration_text((total - done) / rate) + " left";
    text += ")";
  }
  if (terminal_) {
    std::fprintf(stderr, "\r%s\033[K", text.c_str());
    line_open_ = true;
  } else {
    std::fprintf(stderr, "%s\n", text.c_str());
  }
  std::fflush(stderr);
}

Progress ProgressMeter::callback() {
  return [this](std::string_view stage, double done, double total) { update(stage, done, total); };
}

void ProgressMeter::clear_line() {
  if (!line_open_) return;
  std::fprintf(stderr, "\r\033[K");
  line_open_ = false;
}

void ProgressMeter::finish(const std::string& summary) {
  clear_line();
  finished_ = true;
  const double seconds = std::chrono::duration<double>(Clock::now() - start_).count();
  std::fprintf(stderr, "%s: %s (%.1f s)\n", command_.c_str(), summary.c_str(), seconds);
  std::fflush(stderr);
}

}  // namespace csp::cli
