// A session log as a model-based reader's input (run/session_log.hpp): the robot it recorded and
// its joint samples, CSV or LCM.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <variant>

#include "bridge_support.hpp"
#include "csp/run/observers.hpp"
#include "csp/run/sources.hpp"
#include "csp/run/session_log.hpp"
#include "support.hpp"

namespace csp::run {
namespace {

const std::string kPanda = std::string(CSP_SOURCE_DIR) + "/configs/robots/panda.yaml";
const std::string kFr3 = std::string(CSP_SOURCE_DIR) + "/configs/robots/fr3.yaml";

// One short run of the default scenario (the Franka Hand on a Panda) logged as `csp emulate --lcm-log
// LCM --log CSV` logs it.
rt::Scenario record_run(const std::string& lcm_log, const std::string& csv_log) {
  rt::Scenario scenario = rt::load_scenario(test::kDefaultScenario);
  scenario.duration = 0.2;
  Run run(scenario);
  ControllerSource controller(run);
  LcmLogObserver lcm(lcm_log, run, controller.controller().mode);
  CsvLogObserver csv(csv_log, run.emulator());
  run.observe(lcm);
  run.observe(csv);
  EXPECT_TRUE(run.run(controller).observer_failure.empty());
  return scenario;
}

// The two logs of one run, removed with this object.
struct Logs {
  Logs() : scenario(record_run(lcm, csv)) {}
  ~Logs() {
    std::filesystem::remove(lcm);
    std::filesystem::remove(csv);
  }
  std::string lcm = test::temp_path("session.lcmlog"), csv = test::temp_path("session.csv");
  rt::Scenario scenario;   // declared after the paths: the run writes them
};

// Not given: the robot file and end effector the run recorded, not the defaults; the copy of the
// recorded robot file lives as long as the answer.
TEST(SessionLog, GivesBackTheRecordedRobotFileAndEndEffector) {
  const Logs logs;
  std::string copy;
  {
    const SessionRobot robot = session_robot(logs.lcm, "CSP_STATE", {kFr3, "none", false, false});
    ASSERT_TRUE(robot.recorded);
    copy = robot.robot_file;
    EXPECT_TRUE(robot.robot_file_recorded);
    EXPECT_EQ(test::read_text(robot.robot_file), test::read_text(logs.scenario.robot_file));
    EXPECT_EQ(robot.recorded->recorded_path, logs.scenario.robot_file);
    EXPECT_EQ(robot.end_effector, "hand");   // default.yaml's end_effector
    EXPECT_EQ(robot.recorded_scenario, logs.scenario.path);
    EXPECT_EQ(robot.used, "the robot's recorded scenario " + logs.scenario.path + ": its robot file " + logs.scenario.robot_file +
                              ", its end effector hand");
    EXPECT_TRUE(robot.notes.empty());
  }
  EXPECT_FALSE(std::filesystem::exists(copy));
}

// Given: the given robot file and end effector, with a note for each that differs from the recording;
// a copy of the recorded robot file elsewhere does not differ.
TEST(SessionLog, UsesAGivenRobotAndNotesWhereItDiffersFromTheRecording) {
  const Logs logs;
  const SessionRobot other = session_robot(logs.lcm, "CSP_STATE", {kFr3, "none", true, true});
  EXPECT_EQ(other.robot_file, kFr3);
  EXPECT_EQ(other.end_effector, "none");
  EXPECT_FALSE(other.robot_file_recorded);
  EXPECT_EQ(other.used, "the robot's recorded scenario " + logs.scenario.path + ": --robot " + kFr3 + ", --ee none");
  const std::vector<std::string> notes{
      "--robot " + kFr3 + " differs from the robot file it recorded (" + logs.scenario.robot_file + ")",
      "--ee none differs from the end effector it recorded (hand)"};
  EXPECT_EQ(other.notes, notes);

  const std::string same = test::temp_path("same_robot.yaml");
  std::ofstream(same) << test::read_text(logs.scenario.robot_file);
  const SessionRobot recorded = session_robot(logs.lcm, "CSP_STATE", {same, "hand", true, true});
  EXPECT_EQ(recorded.robot_file, same);
  EXPECT_TRUE(recorded.notes.empty()) << recorded.notes.front();
  std::filesystem::remove(same);
}

// A scenario whose scene mounts a tool: its end effector is taken, the tool is not, and a note says so.
TEST(SessionLog, SaysThatTheScenesToolIsNotTaken) {
  const rt::Scenario scenario = rt::load_scenario(std::string(CSP_SOURCE_DIR) + "/configs/scenarios/medical/ultrasound_abdomen_scan.yaml");
  const std::string log = test::temp_path("tool.lcmlog");
  {
    const rt::Emulator emulator(scenario.emulator);
    const bridge::EmulateLogRecorder recorder(log, scenario, emulator, rt::ControlMode::kTorque);   // the record and the first state
  }
  const SessionRobot robot = session_robot(log, "CSP_STATE", {kPanda, "hand", false, false});
  EXPECT_EQ(robot.end_effector, "none");   // the scenario names none
  EXPECT_EQ(robot.notes, std::vector<std::string>{"its scenario's scene mounts a tool, which is not taken (give it as --load-*)"});
  std::filesystem::remove(log);
}

// No record of the channel's robot (another robot's channel, a CSV log): the given robot, nothing to say.
TEST(SessionLog, WithoutARecordOfTheChannelsRobotUsesTheGivenOne) {
  const Logs logs;
  for (const auto& [log, channel] : {std::pair{logs.lcm, "ARM2_STATE"}, std::pair{logs.csv, "CSP_STATE"}}) {
    const SessionRobot robot = session_robot(log, channel, {kFr3, "none", false, false});
    EXPECT_FALSE(robot.recorded) << log;
    EXPECT_FALSE(robot.robot_file_recorded);
    EXPECT_EQ(robot.robot_file, kFr3);
    EXPECT_EQ(robot.end_effector, "none");
    EXPECT_TRUE(robot.used.empty());
    EXPECT_TRUE(robot.notes.empty());
  }
}

// The CSV and the LCM log of one run, each told apart by its content, hold the same samples in every
// column group; a channel without states is refused, naming the file.
TEST(SessionLog, CsvAndLcmLogsOfOneRunReadToTheSameSamples) {
  const Logs logs;
  const JointLog csv = read_joint_log(logs.csv, "CSP_STATE"), lcm = read_joint_log(logs.lcm, "CSP_STATE");
  EXPECT_EQ(csv.size(), 201u);   // the start state and 200 cycles
  ASSERT_EQ(lcm.size(), csv.size());
  for (const ColumnGroup& group : kJointLogSchema)
    std::visit([&](auto member) { EXPECT_TRUE(csv.*member == lcm.*member) << group.name; }, group.member);
  try {
    read_joint_log(logs.lcm, "ARM2_STATE");
    ADD_FAILURE() << "read a channel without states";
  } catch (const JointLogError& e) {
    EXPECT_NE(std::string(e.what()).find(logs.lcm), std::string::npos) << e.what();
  }
}

// `csp gap` on a log whose recorded robot file cannot be loaded: one line that names the recording
// and asks for --robot (what was used is said only with a verdict); with --robot given, the error is
// the given file's own.
TEST(SessionLog, GapAsksForRobotWhenTheRecordedRobotFileCannotBeUsed) {
  const rt::Scenario scenario = rt::load_scenario(test::kDefaultScenario);
  const std::string log = test::temp_path("broken_robot.lcmlog"), out = test::temp_path("broken_robot.out");
  {
    scenario_t record = bridge::scenario_message(scenario, "");
    record.robot_text = "name: broken\n";
    bridge::LogWriter writer(log);
    writer.write("CSP_SCENARIO", bridge::encode(record), 0);
  }
  test::Process recorded({CSP_EXECUTABLE, "gap", "--log", log}, out);
  ASSERT_EQ(recorded.wait(std::chrono::seconds(30)), 2);
  const std::string said = recorded.output();
  EXPECT_EQ(said.rfind("csp gap: the robot file recorded in " + log + " (" + scenario.robot_file + ") cannot be used: ", 0), 0u)
      << said;
  EXPECT_EQ(said.find('\n'), said.size() - 1) << said;
  EXPECT_NE(said.find("; give --robot\n"), std::string::npos) << said;

  const std::string missing = test::temp_path("no_robot.yaml");
  test::Process given({CSP_EXECUTABLE, "gap", "--log", log, "--robot", missing}, out);
  ASSERT_EQ(given.wait(std::chrono::seconds(30)), 2);
  const std::string told = given.output();
  EXPECT_EQ(told.rfind("csp gap: " + missing + ": ", 0), 0u) << told;
  EXPECT_EQ(told.find('\n'), told.size() - 1) << told;
  EXPECT_EQ(told.find("give --robot"), std::string::npos) << told;
  for (const std::string& f : {log, out}) std::filesystem::remove(f);
}

}  // namespace
}  // namespace csp::run
