#include "csp/bridge/lcm_log.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace csp::bridge {
namespace {

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read the file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error(path.string() + ": cannot write the file");
}

}  // namespace

LogWriter::LogWriter(const std::string& path) : path_(path), file_(std::make_unique<lcm::LogFile>(path, "w")) {
  if (!file_->good()) throw std::runtime_error(path + ": cannot write the LCM log");
}

void LogWriter::write(const std::string& channel, const void* data, int size, int64_t utime) {
  lcm::LogEvent event{};
  event.timestamp = utime;
  event.channel = channel;
  event.datalen = size;
  event.data = const_cast<void*>(data);   // LogFile::writeEvent does not write through it
  if (file_->writeEvent(&event) != 0) throw std::runtime_error(path_ + ": writing the LCM log failed (disk full?)");
  ++counts_[channel];
  ++events_;
}

uint64_t LogWriter::count(const std::string& channel) const {
  const auto it = counts_.find(channel);
  return it == counts_.end() ? 0 : it->second;
}

void LogWriter::flush() { std::fflush(file_->getFilePtr()); }

LogReader::LogReader(const std::string& path) : path_(path) {
  if (!std::filesystem::is_regular_file(path)) throw std::runtime_error(path + ": no such LCM log file");
  file_ = std::make_unique<lcm::LogFile>(path, "r");
  if (!file_->good()) throw std::runtime_error(path + ": cannot read the LCM log");
}

scenario_t scenario_message(const rt::Scenario& scenario, const std::string& channel_prefix) {
  scenario_t m;
  m.utime = now_utime();
  m.path = scenario.path;
  m.text = read_text(scenario.path);
  m.robot_path = scenario.robot_file;
  m.robot_text = read_text(scenario.robot_file);
  m.seed = static_cast<int64_t>(scenario.seed);
  m.clock = scenario.clock == rt::Clock::kLockstep ? "lockstep" : "realtime";
  m.channel_prefix = channel_prefix;
  return m;
}

rt::Scenario scenario_from_message(const scenario_t& m) {
  // load_scenario reads files and finds the robot file relative to the scenario: rebuild both.
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("csp-replay-" + std::to_string(getpid()) + "-" + std::to_string(now_utime()));
  std::filesystem::create_directories(dir);
  rt::Scenario scenario;
  try {
    YAML::Node root = YAML::Load(m.text);
    root["robot"] = "robot.yaml";
    write_text(dir / "robot.yaml", m.robot_text);
    YAML::Emitter out;
    out << root;
    write_text(dir / "scenario.yaml", out.c_str());
    scenario = rt::load_scenario((dir / "scenario.yaml").string());
  } catch (...) {
    std::filesystem::remove_all(dir);
    throw;
  }
  std::filesystem::remove_all(dir);
  scenario.path = m.path;
  scenario.robot_file = m.robot_path;
  scenario.seed = static_cast<uint64_t>(m.seed);
  scenario.emulator.seed = scenario.seed;
  scenario.command_faults.seed = scenario.seed + 1;   // as load_scenario derives it
  scenario.clock = m.clock == "realtime" ? rt::Clock::kRealtime : rt::Clock::kLockstep;
  return scenario;
}

EmulateLogRecorder::EmulateLogRecorder(const std::string& path, const rt::Scenario& scenario, const rt::Emulator& emulator,
                                       rt::ControlMode mode)
    : log_(path), mode_(mode) {
  const int64_t utime = now_utime();
  log_.write(channels_.scenario, encode(scenario_message(scenario, "")), utime);
  log_.write(channels_.state, encode(to_message(emulator.state(), utime, false)), utime);
  // run_motion starts the motion in the first cycle, as a controller's START_MOTION would.
  config_request_t start{};
  start.utime = utime;
  start.request = config_request_t::START_MOTION;
  start.control_mode = control_mode_code(mode);
  log_.write(channels_.config, encode(start), utime);
}

void EmulateLogRecorder::record(const rt::RobotState& state, const rt::CycleInfo& cycle) {
  const int64_t utime = now_utime();
  // Only what reached the robot is a received message; the command answered the previous state.
  if (cycle.command_received)
    log_.write(channels_.command, encode_command(mode_, static_cast<int64_t>(state.time.toMSec()) - 1, cycle.command, utime), utime);
  log_.write(channels_.state, encode(to_message(state, utime, cycle.command_received)), utime);
}

}  // namespace csp::bridge
