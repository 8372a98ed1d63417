// libfranka's logging (franka/logging/*), the log a ControlException carries as CSV, and the
// exceptions' constructors.
#include <iostream>
#include <map>
#include <mutex>
#include <sstream>

#include "franka/exception.h"
#include "franka/logging/cout_logging_sink.hpp"
#include "franka/logging/logger.hpp"
#include "franka/logging/robot_state_log.hpp"

namespace franka {
namespace {

// The registered sinks by name.
struct Sinks {
  std::mutex mutex;
  std::map<std::string, std::shared_ptr<LoggingSinkInterface>> by_name;
};
Sinks& sinks() {
  static Sinks instance;
  return instance;
}

template <typename Log>
void to_every_sink(Log log) {
  Sinks& s = sinks();
  std::lock_guard<std::mutex> lock(s.mutex);
  for (auto& entry : s.by_name) log(*entry.second);
}

template <std::size_t N>
void write_values(std::ostream& out, const std::array<double, N>& values) {
  for (double v : values) out << v << ',';
}

template <std::size_t N>
void write_names(std::ostream& out, const char* name) {
  for (std::size_t i = 0; i < N; ++i) out << name << '[' << i << "],";
}

}  // namespace

namespace logging {

auto addLogger(const std::shared_ptr<LoggingSinkInterface>& logger) -> void {
  Sinks& s = sinks();
  std::lock_guard<std::mutex> lock(s.mutex);
  s.by_name[logger->getName()] = logger;
}

auto removeLogger(const std::string& logger_name) -> void {
  Sinks& s = sinks();
  std::lock_guard<std::mutex> lock(s.mutex);
  s.by_name.erase(logger_name);
}

auto removeAllLoggers() -> void {
  Sinks& s = sinks();
  std::lock_guard<std::mutex> lock(s.mutex);
  s.by_name.clear();
}

auto logInfo(const std::string& message) -> void {
  to_every_sink([&](LoggingSinkInterface& sink) { sink.logInfo(message); });
}
auto logWarn(const std::string& message) -> void {
  to_every_sink([&](LoggingSinkInterface& sink) { sink.logWarn(message); });
}
auto logError(const std::string& message) -> void {
  to_every_sink([&](LoggingSinkInterface& sink) { sink.logError(message); });
}

}  // namespace logging

auto CoutLoggingSink::getName() const -> std::string { return "CoutLoggingSink"; }
auto CoutLoggingSink::logInfo(const std::string& message) -> void { std::cout << "INFO: " << message << std::endl; }
auto CoutLoggingSink::logWarn(const std::string& message) -> void { std::cout << "WARNING: " << message << std::endl; }
auto CoutLoggingSink::logError(const std::string& message) -> void { std::cout << "ERROR: " << message << std::endl; }

// One row per record: the state's time, joint states and torques, then the command of each kind.
std::string logToCSV(const std::vector<Record>& log) {
  std::ostringstream out;
  out.precision(17);
  out << "time,";
  write_names<7>(out, "q");
  write_names<7>(out, "q_d");
  write_names<7>(out, "dq");
  write_names<7>(out, "dq_d");
  write_names<7>(out, "tau_J");
  write_names<7>(out, "tau_J_d");
  write_names<16>(out, "O_T_EE");
  write_names<16>(out, "O_T_EE_c");
  out << "control_command_success_rate,";
  write_names<7>(out, "cmd_q_c");
  write_names<7>(out, "cmd_dq_c");
  write_names<16>(out, "cmd_O_T_EE_c");
  write_names<6>(out, "cmd_O_dP_EE_c");
  write_names<7>(out, "cmd_tau_J");
  out << '\n';
  for (const Record& r : log) {
    out << r.state.time.toMSec() << ',';
    write_values(out, r.state.q);
    write_values(out, r.state.q_d);
    write_values(out, r.state.dq);
    write_values(out, r.state.dq_d);
    write_values(out, r.state.tau_J);
    write_values(out, r.state.tau_J_d);
    write_values(out, r.state.O_T_EE);
    write_values(out, r.state.O_T_EE_c);
    out << r.state.control_command_success_rate << ',';
    write_values(out, r.command.joint_positions.q);
    write_values(out, r.command.joint_velocities.dq);
    write_values(out, r.command.cartesian_pose.O_T_EE);
    write_values(out, r.command.cartesian_velocities.O_dP_EE);
    write_values(out, r.command.torques.tau_J);
    out << '\n';
  }
  return out.str();
}

IncompatibleVersionException::IncompatibleVersionException(uint16_t server_version, uint16_t library_version) noexcept
    : Exception("libfranka: Incompatible library version (server version: " + std::to_string(server_version) +
                ", library version: " + std::to_string(library_version) + ")."),
      server_version(server_version),
      library_version(library_version) {}

ControlException::ControlException(const std::string& what, std::vector<franka::Record> log) noexcept
    : Exception(what), log(std::move(log)) {}

}  // namespace franka
