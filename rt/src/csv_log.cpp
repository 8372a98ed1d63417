#include "csp/rt/csv_log.hpp"

#include <algorithm>
#include <charconv>
#include <stdexcept>

namespace csp::rt {
namespace {

void append(std::string& line, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), value);
  line += ',';
  line.append(buffer, result.ptr);
}

template <std::size_t N>
void append(std::string& line, const std::array<double, N>& values) {
  for (double v : values) append(line, v);
}

void header(std::string& line, const char* name, int count) {
  for (int i = 1; i <= count; ++i) line += ',' + std::string(name) + std::to_string(i);
}

}  // namespace

CsvLog::CsvLog(const std::string& path) : path_(path), out_(path, std::ios::out | std::ios::trunc) {
  if (!out_) throw std::runtime_error(path + ": cannot write the log file");
  std::string h = "t";
  header(h, "q", 7);
  header(h, "dq", 7);
  header(h, "tau_J", 7);
  header(h, "tau_J_d", 7);
  header(h, "q_d", 7);
  header(h, "dq_d", 7);
  header(h, "tau_ext_hat_filtered", 7);
  header(h, "O_F_ext_hat_K", 6);
  header(h, "O_T_EE_", 16);
  h += ",robot_mode,command_received,control_command_success_rate,current_errors\n";
  out_ << h;
}

CsvLog::~CsvLog() { out_.flush(); }

void CsvLog::write(const RobotState& s, const CycleInfo& cycle) {
  line_.clear();
  char buffer[32];
  const auto t = std::to_chars(buffer, buffer + sizeof(buffer), s.time.toSec());
  line_.append(buffer, t.ptr);
  append(line_, s.q);
  append(line_, s.dq);
  append(line_, s.tau_J);
  append(line_, s.tau_J_d);
  append(line_, s.q_d);
  append(line_, s.dq_d);
  append(line_, s.tau_ext_hat_filtered);
  append(line_, s.O_F_ext_hat_K);
  append(line_, s.O_T_EE);
  line_ += ',';
  line_ += robot_mode_name(s.robot_mode);
  line_ += cycle.command_received ? ",1" : ",0";
  append(line_, s.control_command_success_rate);
  // Error names joined by '|' keep the column free of commas.
  std::string errors(s.current_errors);
  for (char& ch : errors)
    if (ch == ',') ch = '|';
  errors.erase(std::remove(errors.begin(), errors.end(), ' '), errors.end());
  line_ += ',' + errors + '\n';
  out_ << line_;
  if (!out_) throw std::runtime_error(path_ + ": writing the log failed (disk full?)");
  ++rows_;
}

}  // namespace csp::rt
