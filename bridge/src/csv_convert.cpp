#include "csp/bridge/csv_convert.hpp"

#include <charconv>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "csp/bridge/lcm_log.hpp"
#include "csp/rt/csv_log.hpp"

namespace csp::bridge {
namespace {

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
  return cells;
}

// Column index of `name`, or none.
std::optional<std::size_t> column(const std::vector<std::string>& header, const std::string& name) {
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == name) return i;
  return std::nullopt;
}

// The columns name1..name7; all of them, or none if `optional` and the first is missing.
std::vector<std::size_t> joint_columns(const std::vector<std::string>& header, const std::string& name, bool optional,
                                       const std::string& path) {
  std::vector<std::size_t> columns;
  if (optional && !column(header, name + "1")) return columns;
  for (int i = 1; i <= 7; ++i) {
    const std::optional<std::size_t> c = column(header, name + std::to_string(i));
    if (!c) throw std::runtime_error(path + ": line 1: expected a column `" + name + std::to_string(i) + "`");
    columns.push_back(*c);
  }
  return columns;
}

}  // namespace

ExportReport export_csv(const std::string& log_path, const std::string& csv_path, const std::string& state_channel) {
  LogReader log(log_path);
  rt::CsvLog csv(csv_path);
  ExportReport report;
  std::optional<robot_state_t> last;
  for (const LogEvent* event = log.next(); event; event = log.next()) {
    if (event->channel != state_channel) continue;
    robot_state_t m;
    if (decode_exact(event->data, event->datalen, m) != Rejection::kNone) {
      ++report.rejected;
      continue;
    }
    std::string differing_field;
    if (last && m.message_id == last->message_id && (state_difference(m, *last, differing_field), differing_field.empty())) {
      ++report.repeated;   // the same state again (utime aside): a republication
      continue;
    }
    last = m;
    rt::CycleInfo cycle;
    cycle.command_received = m.command_received != 0;
    csv.write(from_message(m), cycle);
    ++report.rows;
  }
  return report;
}

uint64_t import_csv(const std::string& csv_path, const std::string& log_path, const std::string& state_channel) {
  std::ifstream in(csv_path);
  if (!in) throw std::runtime_error(csv_path + ": cannot read the CSV file");
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(csv_path + ": empty file (expected a header line)");
  const std::vector<std::string> header = split(line);
  const std::optional<std::size_t> t_column = column(header, "t");
  if (!t_column) throw std::runtime_error(csv_path + ": line 1: expected a column `t`");
  const std::vector<std::size_t> q = joint_columns(header, "q", false, csv_path), dq = joint_columns(header, "dq", false, csv_path),
                                  tau_J = joint_columns(header, "tau_J", false, csv_path),
                                  tau_J_d = joint_columns(header, "tau_J_d", true, csv_path);

  LogWriter log(log_path);
  uint64_t rows = 0;
  for (uint64_t line_number = 2; std::getline(in, line); ++line_number) {
    if (line.empty()) continue;
    const std::vector<std::string> cells = split(line);
    const auto number = [&](std::size_t c) {
      double value = 0.0;
      const std::string& cell = c < cells.size() ? cells[c] : std::string();
      const auto result = std::from_chars(cell.data(), cell.data() + cell.size(), value);
      if (result.ec != std::errc() || result.ptr != cell.data() + cell.size() || !std::isfinite(value))
        throw std::runtime_error(csv_path + ": line " + std::to_string(line_number) + ", column `" + header[c] +
                                 "`: expected a finite number, got `" + cell + "`");
      return value;
    };
    const double t = number(*t_column);
    if (t < 0.0) throw std::runtime_error(csv_path + ": line " + std::to_string(line_number) + ": expected t >= 0");
    rt::RobotState s;
    for (int i = 0; i < 7; ++i) {
      s.q[i] = number(q[i]);
      s.dq[i] = number(dq[i]);
      s.tau_J[i] = number(tau_J[i]);
      if (!tau_J_d.empty()) s.tau_J_d[i] = number(tau_J_d[i]);
    }
    s.robot_mode = rt::RobotMode::kMove;
    s.time = rt::Duration(static_cast<uint64_t>(std::llround(t * 1e3)));
    const auto utime = static_cast<int64_t>(std::llround(t * 1e6));
    robot_state_t m = to_message(s, utime, true);
    m.message_id = static_cast<int64_t>(rows);   // unique per row: two rows may fall in the same millisecond
    log.write(state_channel, encode(m), utime);
    ++rows;
  }
  return rows;
}

}  // namespace csp::bridge
