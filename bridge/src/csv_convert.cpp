#include "csp/bridge/csv_convert.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>

#include "csp/bridge/lcm_log.hpp"
#include "csp/rt/csv_log.hpp"

namespace csp::bridge {

ExportReport for_each_logged_state(const std::string& log_path, const std::string& state_channel,
                                   const std::function<void(const rt::RobotState&, bool command_received)>& visit,
                                   const Progress& progress) {
  LogReader log(log_path);
  ExportReport report;
  StateCoverage coverage;
  std::optional<robot_state_t> last;
  for (const LogEvent* event = log.next(); event; event = log.next()) {
    if (log.events() % 4096 == 0) csp::report(progress, "reading the log (MB)", 1e-6 * log.offset(), 1e-6 * log.size());
    if (event->channel != state_channel) continue;
    robot_state_t m;
    if (std::string refused = read_state_event(*event, m); !refused.empty()) {
      if (report.rejected++ == 0) report.refused = log_path + ": " + refused;
      continue;
    }
    std::string differing_field;
    if (last && m.message_id == last->message_id && (state_difference(m, *last, differing_field), differing_field.empty())) {
      ++report.repeated;   // the same state again (utime aside): a republication
      continue;
    }
    last = m;
    coverage.add(m.message_id);
    visit(from_message(m), m.command_received != 0);
    ++report.rows;
  }
  report.damage = log.damage_summary();
  report.missing = coverage.missing();
  return report;
}

bool is_lcm_log(const std::string& path) {
  std::error_code error;   // (a path that cannot be reached is no LCM log: its reader names the problem)
  if (!std::filesystem::is_regular_file(path, error)) return false;   // never open a FIFO: it would wait for a writer
  std::ifstream in(path, std::ios::binary);
  unsigned char magic[4] = {};
  in.read(reinterpret_cast<char*>(magic), sizeof(magic));
  // lcm-logger's event header starts with the sync word 0xEDA1DA01, big-endian.
  return in.gcount() == 4 && magic[0] == 0xED && magic[1] == 0xA1 && magic[2] == 0xDA && magic[3] == 0x01;
}

ExportReport export_csv(const std::string& log_path, const std::string& csv_path, const std::string& state_channel,
                        const Progress& progress) {
  rt::CsvLog csv(csv_path);
  const ExportReport report = for_each_logged_state(
      log_path, state_channel,
      [&](const rt::RobotState& state, bool command_received) {
        rt::CycleInfo cycle;
        cycle.command_received = command_received;
        csv.write(state, cycle);
      },
      progress);
  csv.flush();   // the last rows: a write error is the export's error
  return report;
}

JointLog read_joint_log_lcm(const std::string& log_path, const std::string& state_channel, const Progress& progress) {
  JointLog log;
  log.source = log_path;
  const ExportReport read = for_each_logged_state(
      log_path, state_channel,
      [&](const rt::RobotState& state, bool command_received) { rt::append_state(log, state, command_received); }, progress);
  if (!read.damage.empty())
    throw JointLogError(read.damage + "; `csp log export` writes the readable part as CSV if that is what you want to diagnose");
  if (!read.refused.empty())
    throw JointLogError(read.refused + (read.rejected > 1 ? " (and " + std::to_string(read.rejected - 1) + " more)" : "") +
                        "; `csp log export` writes the other states as CSV if that is what you want to diagnose");
  if (log.size() < 2)
    throw JointLogError(log_path + ": expected at least 2 robot states on channel " + state_channel + ", got " +
                        std::to_string(log.size()));
  check_joint_log(log);
  return log;
}

uint64_t import_csv(const std::string& csv_path, const std::string& log_path, const std::string& state_channel) {
  const JointLog csv = read_joint_log_csv(csv_path);
  LogWriter log(log_path);
  for (std::size_t row = 0; row < csv.size(); ++row) {
    const rt::RobotState state = rt::state_from_row(csv, row);
    const bool command_received = csv.command_received.empty() || csv.command_received[row] != 0.0;
    // utime is int64 microseconds: refuse a time it cannot hold (and t < 0) before converting.
    if (!(csv.t[row] >= 0.0 && csv.t[row] < 9e12))
      throw JointLogError(csv_path + ": row " + std::to_string(row + 1) + ": t = " + std::to_string(csv.t[row]) +
                          " s: expected 0 <= t < 9e12 s");
    const auto utime = static_cast<int64_t>(std::llround(csv.t[row] * 1e6));
    robot_state_t m = to_message(state, utime, command_received);
    m.message_id = static_cast<int64_t>(row);   // unique per row: two rows may fall in the same millisecond
    log.write(state_channel, encode(m), utime);
  }
  log.flush();   // the last events: a write error is the import's error
  return csv.size();
}

}  // namespace csp::bridge
