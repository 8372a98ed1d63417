#include "csp/run/session_log.hpp"

#include <fstream>
#include <sstream>

#include "csp/bridge/csv_convert.hpp"
#include "csp/io/mcap.hpp"
#include "csp/run/mcap_export.hpp"

namespace csp::run {
namespace {

// A given robot file's text, empty if it cannot be read: it then differs from the recording, and
// building the model from it names the file and what is wrong with it.
std::string text_or_empty(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

SessionRobot session_robot(const std::string& log_path, const std::string& state_channel, const GivenRobot& given) {
  SessionRobot robot;
  robot.robot_file = given.robot_file;
  robot.end_effector = given.end_effector;
  std::vector<scenario_t> records;
  if (mcap::is_mcap_file(log_path)) {
    // An MCAP file CSP wrote holds one session, its record in "csp.session" (mcap_export.hpp).
    if (std::optional<scenario_t> session = recorded_session(log_path)) records.push_back(*session);
  } else if (bridge::is_lcm_log(log_path)) {
    records = bridge::outline(log_path).scenario_records;
    std::erase_if(records, [&](const scenario_t& r) { return bridge::Channels(r.channel_prefix).state != state_channel; });
  }
  if (records.empty()) {
    robot.record.path = "(none: the robot given for the log)";
    robot.record.text = "end_effector: " + given.end_effector + "\n";
    robot.record.robot_path = given.robot_file;
    robot.record.robot_text = text_or_empty(given.robot_file);
    return robot;
  }
  const auto record = records.begin();

  robot.recorded = std::make_unique<bridge::RecordedRobot>(*record);
  const bridge::RecordedRobot& recorded = *robot.recorded;
  robot.recorded_scenario = record->path;
  robot.record = *record;
  if (!given.robot_file_given) {
    robot.robot_file = recorded.robot_file;
    robot.robot_file_recorded = true;
  } else if (text_or_empty(given.robot_file) != record->robot_text) {
    robot.notes.push_back("--robot " + given.robot_file + " differs from the robot file it recorded (" + recorded.recorded_path + ")");
  }
  if (!given.end_effector_given) robot.end_effector = recorded.end_effector;
  else if (given.end_effector != recorded.end_effector)
    robot.notes.push_back("--ee " + given.end_effector + " differs from the end effector it recorded (" + recorded.end_effector + ")");
  if (recorded.scene_tool)
    robot.notes.push_back(given.takes_scene_tool ? "its scenario's scene mounts a tool: its TCP is the end effector"
                                                 : "its scenario's scene mounts a tool, which is not taken (give it as --load-*)");
  robot.used = "the robot's recorded scenario " + record->path + ": " +
               (given.robot_file_given ? "--robot " + given.robot_file : "its robot file " + recorded.recorded_path) +
               (given.end_effector_given ? ", --ee " : ", its end effector ") + robot.end_effector;
  return robot;
}

JointLog read_joint_log(const std::string& path, const std::string& state_channel) {
  if (mcap::is_mcap_file(path)) return read_joint_log_mcap(path);
  return bridge::is_lcm_log(path) ? bridge::read_joint_log_lcm(path, state_channel) : read_joint_log_csv(path);
}

}  // namespace csp::run
