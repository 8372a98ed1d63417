// LCM log files in the format lcm-logger writes (readable by lcm-logplayer and lcm-spy), and the
// scenario record that lets replay rebuild the emulator of a CSP log.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

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
  [[noreturn]] void fail_write();

  std::string path_;
  std::unique_ptr<lcm::LogFile> file_;
  std::map<std::string, uint64_t> counts_;
  uint64_t events_ = 0;
};

// One event of an LCM log.
struct LogEvent {
  int64_t eventnum = 0;
  int64_t timestamp = 0;   // [us]
  std::string channel;
  int32_t datalen = 0;
  const void* data = nullptr;   // valid until the next read
};

// A stretch of a log that could not be read, and how much of it was skipped.
struct LogDamage {
  uint64_t offset = 0;          // byte offset where the damage begins
  uint64_t bytes_skipped = 0;   // bytes passed over to the next readable event (or the end)
  std::string what;             // e.g. "data length 2147483647 runs past the end of the file"
};

// Reads lcm-logger's format itself (big-endian: sync word 0xEDA1DA01, event number, timestamp,
// channel length, data length, channel, data) and checks every header before trusting it:
// liblcm 1.3.1's reader overflows on a data length of 0x7FFFFFFF and reads through NULL. A damaged
// header is skipped up to the next sync word that starts a valid header, as lcm-logplayer does,
// and every skip is recorded, so that no reader can take a partial log for a whole one.
class LogReader {
 public:
  explicit LogReader(const std::string& path);   // throws std::runtime_error naming the file
  ~LogReader();
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;

  // The next event, or null at the end of the log.
  const LogEvent* next();
  const std::string& path() const { return path_; }
  uint64_t events() const { return events_; }
  const std::vector<LogDamage>& damage() const { return damage_; }
  // One line naming every damaged stretch and the bytes skipped; empty for an intact log.
  std::string damage_summary() const;

 private:
  // Reads a header at the current offset into event_; empty if it is valid, else why not.
  std::string read_header();
  // After damage at `offset`: the offset of the next valid header, or the file size.
  uint64_t resynchronise(uint64_t offset);

  std::string path_;
  std::FILE* file_ = nullptr;
  uint64_t size_ = 0, offset_ = 0, events_ = 0;
  LogEvent event_;
  std::vector<uint8_t> data_;
  std::vector<LogDamage> damage_;
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
