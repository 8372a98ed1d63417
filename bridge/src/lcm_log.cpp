#include "csp/bridge/lcm_log.hpp"

#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "csp/io/joint_log.hpp"   // output_file_problem
#include "csp/io/yaml_field.hpp"

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

constexpr uint32_t kSyncWord = 0xEDA1DA01;
constexpr uint64_t kHeaderBytes = 4 + 8 + 8 + 4 + 4;

// A folder of its own under the system's temporary directory, for files rebuilt from a record.
std::filesystem::path temporary_folder(const std::string& purpose) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("csp-" + purpose + "-" + std::to_string(getpid()) + "-" + std::to_string(now_utime()));
  std::filesystem::create_directories(dir);
  return dir;
}

std::string count_of(uint64_t n, const std::string& thing) { return std::to_string(n) + " " + thing + (n == 1 ? "" : "s"); }

uint64_t big_endian(const uint8_t* bytes, int count) {
  uint64_t value = 0;
  for (int i = 0; i < count; ++i) value = (value << 8) | bytes[i];
  return value;
}

}  // namespace

LogWriter::LogWriter(const std::string& path) : path_(path) {
  if (const std::string problem = output_file_problem(path); !problem.empty())
    throw std::runtime_error(path + ": cannot write the LCM log: " + problem);
  file_ = std::make_unique<lcm::LogFile>(path, "w");
  if (!file_->good()) throw std::runtime_error(path + ": cannot write the LCM log (" + std::strerror(errno) + ")");
}

void LogWriter::write(const std::string& channel, const void* data, int size, int64_t utime) {
  if (!file_) throw std::runtime_error(failure_.empty() ? path_ + ": the LCM log was closed" : failure_);
  lcm::LogEvent event{};
  event.timestamp = utime;
  event.channel = channel;
  event.datalen = size;
  event.data = const_cast<void*>(data);   // LogFile::writeEvent does not write through it
  if (file_->writeEvent(&event) != 0) fail_write(errno);
  ++counts_[channel];
  ++events_;
}

void LogWriter::fail_write(int error) {
  // Part of an event may have reached the file: cut it after the last whole event, so that what
  // was written stays a valid log (the constructor took only a regular file on a disk).
  file_.reset();
  std::error_code code;
  try {
    LogReader written(path_);
    while (written.next()) {
    }
    const std::vector<LogDamage>& damage = written.damage();
    if (!damage.empty() && damage.back().offset + damage.back().bytes_skipped == std::filesystem::file_size(path_, code))
      std::filesystem::resize_file(path_, damage.back().offset, code);
  } catch (const std::exception&) {   // unreadable now: the file stays as the system left it
  }
  failure_ = path_ + ": writing the LCM log failed (" + (error != 0 ? std::strerror(error) : "disk full or the file system refused it") +
             "); the file ends at its last whole event";
  throw std::runtime_error(failure_);
}

uint64_t LogWriter::count(const std::string& channel) const {
  const auto it = counts_.find(channel);
  return it == counts_.end() ? 0 : it->second;
}

void LogWriter::flush() {
  if (!file_) {
    if (!failure_.empty()) throw std::runtime_error(failure_);
    return;
  }
  if (std::fflush(file_->getFilePtr()) != 0) fail_write(errno);
}

LogReader::LogReader(const std::string& path) : path_(path) {
  // A FIFO or a device would block or never end: only regular files are logs.
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) throw std::runtime_error(path + ": no such LCM log file");
  size_ = std::filesystem::file_size(path, error);
  file_ = error ? nullptr : std::fopen(path.c_str(), "rb");
  if (!file_) throw std::runtime_error(path + ": cannot read the LCM log");
}

LogReader::~LogReader() { std::fclose(file_); }

std::string LogReader::read_header() {
  uint8_t header[kHeaderBytes];
  if (size_ - offset_ < kHeaderBytes) return "a header cut short (" + std::to_string(size_ - offset_) + " of 28 bytes)";
  if (std::fseek(file_, static_cast<long>(offset_), SEEK_SET) != 0 || std::fread(header, 1, kHeaderBytes, file_) != kHeaderBytes)
    return "a read error";
  if (big_endian(header, 4) != kSyncWord) return "no sync word";
  const auto channel_length = static_cast<int32_t>(big_endian(header + 20, 4));
  const auto data_length = static_cast<int32_t>(big_endian(header + 24, 4));
  if (channel_length < 1 || channel_length > LCM_MAX_CHANNEL_NAME_LENGTH)
    return "channel length " + std::to_string(channel_length) + " outside 1.." + std::to_string(LCM_MAX_CHANNEL_NAME_LENGTH);
  if (data_length < 0) return "negative data length " + std::to_string(data_length);
  const uint64_t remaining = size_ - offset_ - kHeaderBytes;
  if (static_cast<uint64_t>(channel_length) + static_cast<uint64_t>(data_length) > remaining)
    return "channel and data (" + std::to_string(channel_length) + " + " + std::to_string(data_length) +
           " bytes) run past the end of the file (" + std::to_string(remaining) + " bytes left)";
  event_.eventnum = static_cast<int64_t>(big_endian(header + 4, 8));
  event_.timestamp = static_cast<int64_t>(big_endian(header + 12, 8));
  event_.channel.resize(static_cast<std::size_t>(channel_length));
  data_.resize(static_cast<std::size_t>(data_length));
  event_.datalen = data_length;
  if (std::fread(event_.channel.data(), 1, event_.channel.size(), file_) != event_.channel.size() ||
      std::fread(data_.data(), 1, data_.size(), file_) != data_.size())
    return "a read error";
  event_.data = data_.data();
  return {};
}

uint64_t LogReader::resynchronise(uint64_t offset) {
  for (uint64_t candidate = offset + 1; candidate + kHeaderBytes <= size_; ++candidate) {
    uint8_t word[4];
    if (std::fseek(file_, static_cast<long>(candidate), SEEK_SET) != 0 || std::fread(word, 1, 4, file_) != 4) break;
    if (big_endian(word, 4) != kSyncWord) continue;
    offset_ = candidate;
    if (read_header().empty()) return candidate;
  }
  return size_;
}

const LogEvent* LogReader::next() {
  if (offset_ >= size_) return nullptr;
  const std::string problem = read_header();
  if (!problem.empty()) {
    const uint64_t damaged_at = offset_;
    const uint64_t resumed = resynchronise(damaged_at);
    damage_.push_back({damaged_at, resumed - damaged_at, problem});
    offset_ = resumed;
    if (resumed >= size_) return nullptr;
  }
  offset_ += kHeaderBytes + event_.channel.size() + data_.size();
  ++events_;
  return &event_;
}

std::string LogReader::damage_summary() const {
  if (damage_.empty()) return {};
  uint64_t skipped = 0;
  for (const LogDamage& d : damage_) skipped += d.bytes_skipped;
  std::string text = path_ + ": damaged log: " + std::to_string(skipped) + " of " + std::to_string(size_) + " bytes skipped (";
  for (std::size_t i = 0; i < damage_.size(); ++i) {
    if (i == 3) {
      text += "; and " + std::to_string(damage_.size() - 3) + " more";
      break;
    }
    text += (i ? "; " : "") + std::string("at byte ") + std::to_string(damage_[i].offset) + ": " + damage_[i].what + ", " +
            std::to_string(damage_[i].bytes_skipped) + " bytes skipped";
  }
  return text + ")";
}

std::string read_state_event(const LogEvent& event, robot_state_t& state) {
  const Rejection rejection = decode_exact(event.data, event.datalen, state);
  if (rejection == Rejection::kNone) return {};
  return "event " + std::to_string(event.eventnum) + " on " + event.channel + " is not a robot_state_t (" +
         rejection_name(rejection) + ")";
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
  const std::filesystem::path dir = temporary_folder("replay");
  rt::Scenario scenario;
  try {
    YAML::Node root = parse_yaml_text(m.text, "the recorded scenario " + m.path);
    root["robot"] = "robot.yaml";
    write_text(dir / "robot.yaml", m.robot_text);
    YAML::Emitter out;
    out << root;
    write_text(dir / "scenario.yaml", out.c_str());
    scenario = rt::load_scenario((dir / "scenario.yaml").string());
  } catch (const std::exception& e) {
    // Name the recorded files, not the temporary copies that are about to be removed.
    std::string what = printable_key(e.what());   // yaml-cpp may quote a control character
    for (const auto& [copy, original] : {std::pair{(dir / "robot.yaml").string(), "the recorded robot file " + m.robot_path},
                                         std::pair{(dir / "scenario.yaml").string(), "the recorded scenario " + m.path}})
      for (std::size_t at = what.find(copy); at != std::string::npos; at = what.find(copy, at + original.size()))
        what.replace(at, copy.size(), original);
    std::filesystem::remove_all(dir);
    throw std::runtime_error("the scenario record cannot be rebuilt: " + what);
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

LogOutline outline(const std::string& log_path) {
  static const std::string kName = "CSP_SCENARIO";
  LogReader log(log_path);
  LogOutline outline;
  std::vector<scenario_t>& records = outline.scenario_records;
  for (const LogEvent* event = log.next(); event; event = log.next()) {
    const std::string& channel = event->channel;
    if (std::find(outline.channels.begin(), outline.channels.end(), channel) == outline.channels.end())
      outline.channels.push_back(channel);
    if (channel.size() < kName.size() || channel.compare(channel.size() - kName.size(), kName.size(), kName) != 0) continue;
    scenario_t record;
    if (decode_exact(event->data, event->datalen, record) != Rejection::kNone) continue;
    const bool known = std::any_of(records.begin(), records.end(),
                                   [&](const scenario_t& r) { return r.channel_prefix == record.channel_prefix; });
    if (!known) records.push_back(record);
  }
  return outline;
}

RecordedRobot::RecordedRobot(const scenario_t& record) : recorded_path(record.robot_path) {
  try {
    const YAML::Node root = parse_yaml_text(record.text, "the recorded scenario " + record.path);
    end_effector = root["end_effector"] ? root["end_effector"].as<std::string>() : "none";
    scene_tool = static_cast<bool>(root["scene"]);
  } catch (const std::exception& e) {
    throw std::runtime_error("the scenario record cannot be read: " + printable_key(e.what()));
  }
  robot_file = (temporary_folder("robot") / "robot.yaml").string();
  write_text(robot_file, record.robot_text);
}

RecordedRobot::~RecordedRobot() {
  std::error_code error;
  std::filesystem::remove_all(std::filesystem::path(robot_file).parent_path(), error);
}

void StateCoverage::add(int64_t message_id) {
  if (states_++ == 0) {
    first_ = last_ = message_id;
    return;
  }
  if (message_id <= last_) {
    ++restarts_;
  } else if (message_id > last_ + 1) {
    if (gaps_++ == 0) first_gap_after_ = last_;
    missing_ += static_cast<uint64_t>(message_id - last_ - 1);
  }
  last_ = message_id;
}

std::string StateCoverage::missing() const {
  std::vector<std::string> parts;
  if (before_first() > 0)
    parts.push_back("the first " + count_of(before_first(), "state") + " (message ids 0-" + std::to_string(first_ - 1) + ")");
  if (gaps_ > 0)
    parts.push_back(count_of(missing_, "state") + " in " + count_of(gaps_, "gap") + " of message ids, the first after id " +
                    std::to_string(first_gap_after_));
  if (restarts_ > 0) parts.push_back("message ids start again " + count_of(restarts_, "time") + " (several runs in one recording)");
  std::string text;
  for (const std::string& part : parts) text += (text.empty() ? "" : "; ") + part;
  return text;
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
