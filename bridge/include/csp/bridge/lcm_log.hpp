// LCM log files in the format lcm-logger writes (readable by lcm-logplayer and lcm-spy), and the
// scenario record that lets replay rebuild the emulator of a CSP log.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <map>
#include <memory>
#include <string>

#include "csp/bridge/messages.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::bridge {

class LogWriter {
 public:
  explicit LogWriter(const std::string& path);   // throws std::runtime_error naming the file
  void write(const std::string& channel, const void* data, int size, int64_t utime);
  void write(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
    write(channel, bytes.data(), static_cast<int>(bytes.size()), utime);
  }
  // Events written on `channel` so far.
  uint64_t count(const std::string& channel) const;
  uint64_t events() const { return events_; }
  const std::string& path() const { return path_; }
  void flush();

 private:
  std::string path_;
  std::unique_ptr<lcm::LogFile> file_;
  std::map<std::string, uint64_t> counts_;
  uint64_t events_ = 0;
};

class LogReader {
 public:
  explicit LogReader(const std::string& path);   // throws std::runtime_error naming the file
  // The next event, or null at the end of the log.
  const lcm::LogEvent* next() { return file_->readNextEvent(); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::unique_ptr<lcm::LogFile> file_;
};

// The scenario as a log records it: the scenario and robot files' texts and the effective seed.
scenario_t scenario_message(const rt::Scenario& scenario, const std::string& channel_prefix);
// The scenario back from its record (the files are rebuilt in a temporary folder).
rt::Scenario scenario_from_message(const scenario_t& message);

// `csp emulate --lcm-log FILE`: records an in-process run as a CSP log that `csp replay`
// re-simulates. Construct it after the emulator and before run_motion; call record() from the
// LoopOptions observer.
class EmulateLogRecorder {
 public:
  EmulateLogRecorder(const std::string& path, const rt::Scenario& scenario, const rt::Emulator& emulator, rt::ControlMode mode);
  void record(const rt::RobotState& state, const rt::CycleInfo& cycle);
  const LogWriter& log() const { return log_; }

 private:
  LogWriter log_;
  Channels channels_;
  rt::ControlMode mode_;
};

}  // namespace csp::bridge
