// LCM log files in the format lcm-logger writes (readable by lcm-logplayer and lcm-spy), and the
// scenario record that lets replay rebuild the emulator of a CSP log.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "csp/bridge/messages.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::bridge {

// A write error (disk full, a file size limit) throws std::runtime_error naming the file and the
// system's reason; the file then ends at its last whole event and takes no more.
class LogWriter {
 public:
  // Throws std::runtime_error naming the file if it is no file to write (output_file_problem: a
  // device, a /proc entry, a directory, ...) or cannot be opened.
  explicit LogWriter(const std::string& path);
  void write(const std::string& channel, const void* data, int size, int64_t utime);
  void write(const std::string& channel, const std::vector<uint8_t>& bytes, int64_t utime) {
    write(channel, bytes.data(), static_cast<int>(bytes.size()), utime);
  }
  // Events written on `channel` so far.
  uint64_t count(const std::string& channel) const;
  uint64_t events() const { return events_; }
  const std::string& path() const { return path_; }
  void flush();   // throws as write does (the last events reach the file when it closes otherwise)

 private:
  [[noreturn]] void fail_write(int error);

  std::string path_;
  std::string failure_;   // the write error, once there was one
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
  uint64_t offset() const { return offset_; }   // bytes read so far, of size(): for progress
  uint64_t size() const { return size_; }
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

// The one rule every reader of a log's robot states applies (csp replay, csp log export, csp gap
// on an LCM log): an event on the state channel is a robot state if it decodes exactly as
// robot_state_t (its fingerprint, its length). Decodes it into `state` and returns empty, or says
// why not: "event 12 on CSP_STATE is not a robot_state_t (unknown type (fingerprint mismatch))".
std::string read_state_event(const LogEvent& event, robot_state_t& state);

// The scenario as a log records it: the scenario and robot files' texts and the effective seed.
// `csp serve` publishes it at its start, every second of robot time and at its end, so that a
// recording begun at any time (lcm-logger started after the server) holds it.
scenario_t scenario_message(const rt::Scenario& scenario, const std::string& channel_prefix);
// The scenario back from its record (the files are rebuilt in a temporary folder).
rt::Scenario scenario_from_message(const scenario_t& message);

// What a log holds, read once: its scenario records, wherever they are (a channel ending in
// CSP_SCENARIO that decodes as scenario_t; the first of each channel prefix, in the order the
// prefixes first appear; none when lcm-logger stopped before the server's first republication),
// and its channels in the order they first appear.
struct LogOutline {
  std::vector<scenario_t> scenario_records;
  std::vector<std::string> channels;
};
LogOutline outline(const std::string& log_path);

// The robot a scenario record names, for a reader of robot files (csp gap): a temporary copy of the
// recorded robot file, removed with this object, and the scenario's end effector.
class RecordedRobot {
 public:
  explicit RecordedRobot(const scenario_t& record);   // throws std::runtime_error if the record does not parse
  ~RecordedRobot();
  RecordedRobot(const RecordedRobot&) = delete;
  RecordedRobot& operator=(const RecordedRobot&) = delete;

  std::string robot_file;      // the temporary copy
  std::string recorded_path;   // where the robot file was when it was recorded
  std::string end_effector;    // the scenario's `end_effector` ("none" without one)
  bool scene_tool = false;     // the scenario's `scene` mounts its tool, which no named end effector is
};

// Which of a run's robot states a recording holds, from their message ids (the robot's time in ms:
// one per cycle from 0): the states before its first one, the gaps, and new runs (the ids start
// again lower: several server runs in one recording).
class StateCoverage {
 public:
  // One recorded state, in log order (republications of the same state already left out).
  void add(int64_t message_id);
  uint64_t states() const { return states_; }
  uint64_t before_first() const { return first_ < 0 ? 0 : static_cast<uint64_t>(first_); }
  uint64_t missing_in_gaps() const { return missing_; }
  uint64_t restarts() const { return restarts_; }
  // What the recording misses, in one clause ("the first 212 states (message ids 0-211); 3 states in
  // 2 gaps of message ids, the first after id 540"); empty when it holds the run whole.
  std::string missing() const;

 private:
  int64_t first_ = -1, last_ = -1, first_gap_after_ = -1;
  uint64_t states_ = 0, missing_ = 0, gaps_ = 0, restarts_ = 0;
};

// `csp emulate --lcm-log FILE`: records an in-process run as a CSP log that `csp replay`
// re-simulates. Construct it after the emulator and before run_motion; call record() from the
// LoopOptions observer.
class EmulateLogRecorder {
 public:
  EmulateLogRecorder(const std::string& path, const rt::Scenario& scenario, const rt::Emulator& emulator, rt::ControlMode mode);
  void record(const rt::RobotState& state, const rt::CycleInfo& cycle);
  const LogWriter& log() const { return log_; }
  void flush() { log_.flush(); }

 private:
  LogWriter log_;
  Channels channels_;
  rt::ControlMode mode_;
};

}  // namespace csp::bridge
