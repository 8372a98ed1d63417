// The bridge without a network: message round trips, strict decoding, the FCI rule of the
// robot server, its equality with the in-process loop, LCM logs, replay, CSV import/export.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>

#include "bridge_support.hpp"
#include "csp/bridge/controllers.hpp"
#include "csp/bridge/csv_convert.hpp"
#include "csp/bridge/replay.hpp"
#include "csp/bridge/server.hpp"
#include "csp/rt/controllers.hpp"
#include "csp/rt/csv_log.hpp"

namespace csp::bridge {
namespace {

rt::Scenario default_scenario() { return rt::load_scenario(rt::default_scenario_path()); }

// An emulator state with every kind of field non-trivial: a motion, a reflex, errors.
rt::RobotState busy_state() {
  rt::Emulator emulator(default_scenario().emulator);
  emulator.start_motion(rt::ControlMode::kTorque);
  for (int i = 0; i < 30; ++i) emulator.step(nullptr);   // 20 lost in a row: a reflex
  return emulator.state();
}

template <typename T>
void expect_round_trip(const T& message) {
  const std::vector<uint8_t> bytes = encode(message);
  T decoded;
  ASSERT_EQ(decode_exact(bytes.data(), static_cast<int>(bytes.size()), decoded), Rejection::kNone);
  EXPECT_EQ(encode(decoded), bytes);
}

TEST(BridgeMessages, EveryTypeRoundTrips) {
  const rt::RobotState s = busy_state();
  ASSERT_TRUE(s.last_motion_errors.communication_constraints_violation);
  const robot_state_t m = to_message(s, 1234567, true);
  expect_round_trip(m);
  // RobotState -> message -> RobotState -> message: nothing lost, bit for bit.
  std::string field;
  EXPECT_EQ(state_difference(m, to_message(from_message(m), 1234567, true), field), 0.0);
  EXPECT_EQ(field, "");
  EXPECT_EQ(from_message(m).robot_mode, rt::RobotMode::kReflex);
  EXPECT_EQ(from_message(m).time, s.time);
  EXPECT_EQ(rt::ErrorSet(from_message(m).last_motion_errors), rt::ErrorSet(s.last_motion_errors));

  for (rt::ControlMode mode : {rt::ControlMode::kTorque, rt::ControlMode::kJointPosition, rt::ControlMode::kJointVelocity}) {
    const rt::Command command{(Vector7() << 1, -2, 3.5, 1e-300, -0.0, 7, 1e300).finished(), true};
    const std::vector<uint8_t> bytes = encode_command(mode, 42, command, 99);
    ReceivedCommand received;
    ASSERT_EQ(decode_command(bytes.data(), static_cast<int>(bytes.size()), received), Rejection::kNone);
    EXPECT_EQ(received.mode, mode);
    EXPECT_EQ(received.message_id, 42);
    EXPECT_EQ(received.command.values, command.values);
    EXPECT_TRUE(received.command.motion_finished);
  }
  config_request_t request{};
  request.request = config_request_t::SET_LOAD;
  request.load_mass = 0.5;
  request.F_x_Cload[2] = 0.1;
  expect_round_trip(request);
  config_reply_t reply{};
  reply.error = "setLoad: not allowed while a motion is running";
  expect_round_trip(reply);
  status_t status{};
  status.lost_commands = 20;
  status.last_reflex = "[communication_constraints_violation]";
  expect_round_trip(status);
  expect_round_trip(scenario_message(default_scenario(), "ARM2_"));
  event_t event{};
  event.text = "control session started (torque)";
  expect_round_trip(event);
}

TEST(BridgeMessages, StrictDecodingNamesTheProblem) {
  const std::vector<uint8_t> command = encode_command(rt::ControlMode::kTorque, 1, rt::Command{}, 0);
  ReceivedCommand received;
  EXPECT_EQ(decode_command(command.data(), static_cast<int>(command.size()) - 1, received), Rejection::kTruncated);
  EXPECT_EQ(decode_command(command.data(), 3, received), Rejection::kTruncated);
  std::vector<uint8_t> longer = command;
  longer.push_back(0);
  EXPECT_EQ(decode_command(longer.data(), static_cast<int>(longer.size()), received), Rejection::kOversized);
  const std::vector<uint8_t> state = encode(to_message(busy_state(), 0, false));
  EXPECT_EQ(decode_command(state.data(), static_cast<int>(state.size()), received), Rejection::kFingerprint);
  config_request_t request;
  EXPECT_EQ(decode_exact(command.data(), static_cast<int>(command.size()), request), Rejection::kFingerprint);
}

// The server core with a recorder of what it sends.
struct TestServer {
  explicit TestServer(const rt::EmulatorSettings& settings)
      : robot(settings), server(robot, channels, [this](const std::string& channel, const std::vector<uint8_t>& bytes) { sent.emplace_back(channel, bytes); },
               [this](const std::string& line) { diagnostics.push_back(line); }) {}

  config_reply_t request(config_request_t r) {
    r.request_id = ++request_id;
    const std::vector<uint8_t> bytes = encode(r);
    server.receive(channels.config, bytes.data(), static_cast<int>(bytes.size()), 0);
    config_reply_t reply;
    EXPECT_EQ(sent.back().first, channels.config_reply);
    EXPECT_EQ(decode_exact(sent.back().second.data(), static_cast<int>(sent.back().second.size()), reply), Rejection::kNone);
    EXPECT_EQ(reply.request_id, request_id);
    return reply;
  }
  config_reply_t start(rt::ControlMode mode) {
    config_request_t r{};
    r.request = config_request_t::START_MOTION;
    r.control_mode = control_mode_code(mode);
    return request(r);
  }
  void command(rt::ControlMode mode, int64_t id, const rt::Command& c) {
    const std::vector<uint8_t> bytes = encode_command(mode, id, c, 0);
    server.receive(channels.command, bytes.data(), static_cast<int>(bytes.size()), 0);
  }

  Channels channels;
  std::vector<std::pair<std::string, std::vector<uint8_t>>> sent;
  std::vector<std::string> diagnostics;
  rt::Emulator robot;
  RobotServer server;
  int64_t request_id = 0;
};

TEST(BridgeServer, BadMessagesAreCountedAndTheRobotRunsOn) {
  TestServer t(default_scenario().emulator);
  ASSERT_TRUE(t.start(rt::ControlMode::kTorque).ok);
  const std::vector<uint8_t> good = encode_command(rt::ControlMode::kTorque, 0, rt::Command{}, 0);
  std::vector<uint8_t> oversized = good;
  oversized.resize(good.size() + 100, 0xff);
  t.server.receive(t.channels.command, good.data(), static_cast<int>(good.size()) - 8, 0);
  t.server.receive(t.channels.command, oversized.data(), static_cast<int>(oversized.size()), 0);
  t.server.receive(t.channels.command, "garbage!garbage!", 16, 0);
  t.server.receive(t.channels.config, good.data(), static_cast<int>(good.size()), 0);
  t.command(rt::ControlMode::kJointPosition, 0, rt::Command{});   // wrong mode
  t.command(rt::ControlMode::kTorque, 5, rt::Command{});          // answers no published state
  EXPECT_FALSE(t.server.answered());
  t.command(rt::ControlMode::kTorque, 0, rt::Command{});
  EXPECT_TRUE(t.server.answered());
  t.command(rt::ControlMode::kTorque, 0, rt::Command{});          // a second answer
  t.server.step(0);
  const ServerCounters& c = t.server.counters();
  EXPECT_EQ(c.rejected_truncated, 1u);
  EXPECT_EQ(c.rejected_oversized, 1u);
  EXPECT_EQ(c.rejected_fingerprint, 2u);
  EXPECT_EQ(c.rejected_wrong_mode, 1u);
  EXPECT_EQ(c.rejected_stale, 2u);
  EXPECT_EQ(t.server.emulator().counters().lost_commands, 0u);
  EXPECT_TRUE(t.server.in_session());
  EXPECT_EQ(t.server.state_message(0).command_received, 1);
  EXPECT_GE(t.diagnostics.size(), 5u);
}

TEST(BridgeServer, TwentyLostCommandsEndTheSessionAndConfigurationWaitsForIdle) {
  TestServer t(default_scenario().emulator);
  config_request_t impedance{};
  impedance.request = config_request_t::SET_JOINT_IMPEDANCE;
  std::fill(std::begin(impedance.K_theta), std::end(impedance.K_theta), 1000.0);
  EXPECT_TRUE(t.request(impedance).ok);
  impedance.K_theta[3] = -1.0;
  const config_reply_t negative = t.request(impedance);
  EXPECT_FALSE(negative.ok);
  EXPECT_NE(negative.error.find("setJointImpedance"), std::string::npos);
  config_request_t unknown{};
  unknown.request = 99;
  EXPECT_FALSE(t.request(unknown).ok);
  t.command(rt::ControlMode::kTorque, 0, rt::Command{});
  EXPECT_EQ(t.server.counters().rejected_no_session, 1u);

  ASSERT_TRUE(t.start(rt::ControlMode::kTorque).ok);
  EXPECT_FALSE(t.start(rt::ControlMode::kTorque).ok);   // already running
  impedance.K_theta[3] = 1000.0;
  const config_reply_t during = t.request(impedance);
  EXPECT_FALSE(during.ok);
  EXPECT_NE(during.error.find("not allowed while a motion is running"), std::string::npos);
  int cycles = 0;
  while (t.server.in_session() && cycles < 100) {
    t.server.step(0);
    ++cycles;
  }
  EXPECT_EQ(cycles, 20);   // the 20th lost command in a row ends the motion
  const robot_state_t s = t.server.state_message(0);
  EXPECT_EQ(s.robot_mode, robot_state_t::MODE_REFLEX);
  EXPECT_TRUE(from_message(s).last_motion_errors.communication_constraints_violation);
  config_request_t recovery{};
  recovery.request = config_request_t::AUTOMATIC_ERROR_RECOVERY;
  EXPECT_TRUE(t.request(recovery).ok);
  // Recovered, the robot is idle and its status still names the last reflex (CSP_STATUS.last_reflex).
  EXPECT_EQ(t.server.state_message(0).robot_mode, robot_state_t::MODE_IDLE);
  EXPECT_NE(t.server.emulator().reflex_reason().find("communication_constraints_violation"), std::string::npos)
      << t.server.emulator().reflex_reason();
  EXPECT_TRUE(t.start(rt::ControlMode::kJointPosition).ok);
}

// The server fed with a controller's answers gives the in-process loop's states, bit for bit.
TEST(BridgeServer, SameStatesAsTheInProcessLoop) {
  const rt::Scenario scenario = default_scenario();
  const double duration = 0.5;
  std::vector<robot_state_t> in_process;
  {
    rt::Emulator emulator(scenario.emulator);
    rt::LoopOptions options;
    options.observer = [&](const rt::RobotState& s, const rt::CycleInfo& c) { in_process.push_back(to_message(s, 0, c.command_received)); };
    rt::run_motion(emulator, rt::ControlMode::kTorque,
                   joint_impedance_controller(example_joint_stiffness(), example_joint_damping(), example_excitation(0.2), duration),
                   options);
  }
  TestServer t(scenario.emulator);
  const rt::Controller controller =
      joint_impedance_controller(example_joint_stiffness(), example_joint_damping(), example_excitation(0.2), duration);
  ASSERT_TRUE(t.start(rt::ControlMode::kTorque).ok);
  rt::Duration period(0);
  std::vector<robot_state_t> served;
  while (t.server.in_session()) {
    const rt::Command c = controller(t.server.emulator().state(), period);
    t.command(rt::ControlMode::kTorque, t.server.message_id(), c);
    t.server.step(0);
    served.push_back(t.server.state_message(0));
    period = rt::Duration(1);
  }
  ASSERT_EQ(served.size(), in_process.size());
  ASSERT_EQ(served.size(), 501u);
  for (std::size_t i = 0; i < served.size(); ++i) {
    std::string field;
    ASSERT_EQ(state_difference(served[i], in_process[i], field), 0.0) << "cycle " << i << ": " << field;
  }
}

// csp emulate --lcm-log: the recorder's log re-simulates bit for bit, and its export is the
// CSV log of the same run, byte for byte.
TEST(BridgeLog, EmulateLogReplaysBitForBitAndExportsAsTheCsvLog) {
  rt::Scenario scenario = default_scenario();
  scenario.duration = 0.4;
  const std::string lcm_log = test::temp_path("emulate.lcmlog"), csv = test::temp_path("emulate.csv"),
                    exported = test::temp_path("exported.csv");
  {
    rt::Emulator emulator(scenario.emulator);
    const rt::BuiltinController builtin = rt::make_controller(scenario.controller, scenario.controller_faults, emulator);
    EmulateLogRecorder recorder(lcm_log, scenario, emulator, builtin.mode);
    rt::CsvLog csv_log(csv);
    csv_log.write(emulator.state(), rt::CycleInfo{});
    rt::LoopOptions options;
    options.max_duration = scenario.duration;
    options.faults.loss_probability = 0.05;   // lost commands are part of what replay reproduces
    options.observer = [&](const rt::RobotState& s, const rt::CycleInfo& c) {
      recorder.record(s, c);
      csv_log.write(s, c);
    };
    rt::run_motion(emulator, builtin.mode, builtin.controller, options);
    EXPECT_GT(emulator.counters().lost_commands, 0u);
  }
  const ResimulationReport replay = resimulate(lcm_log);
  EXPECT_EQ(replay.states, 401u);   // the start state and 400 cycles
  EXPECT_EQ(replay.differing_states, 0u) << replay.first_difference;

  const ExportReport r = export_csv(lcm_log, exported, "CSP_STATE");
  EXPECT_EQ(r.rows, 401u);
  std::ifstream a(csv), b(exported);
  const std::string text_a((std::istreambuf_iterator<char>(a)), {}), text_b((std::istreambuf_iterator<char>(b)), {});
  EXPECT_EQ(text_a, text_b);
  for (const std::string& f : {lcm_log, csv, exported}) std::filesystem::remove(f);
}

TEST(BridgeLog, ReplayNoticesATamperedLog) {
  rt::Scenario scenario = default_scenario();
  const std::string path = test::temp_path("tampered.lcmlog");
  {
    rt::Emulator emulator(scenario.emulator);
    const rt::BuiltinController builtin = rt::make_controller(scenario.controller, scenario.controller_faults, emulator);
    EmulateLogRecorder recorder(path, scenario, emulator, builtin.mode);
    rt::LoopOptions options;
    options.max_duration = 0.1;
    options.observer = [&](const rt::RobotState& s, const rt::CycleInfo& c) {
      rt::RobotState changed = s;
      if (s.time.toMSec() == 50) changed.q[3] += 1e-12;
      recorder.record(changed, c);
    };
    rt::run_motion(emulator, builtin.mode, builtin.controller, options);
  }
  const ResimulationReport replay = resimulate(path);
  EXPECT_EQ(replay.differing_states, 1u);
  EXPECT_EQ(replay.first_difference, "time 50 ms: q");
  EXPECT_NEAR(replay.max_difference, 1e-12, 1e-15);
  std::filesystem::remove(path);
}

// A session as a logger on the bus records it, written in-process: `cycles` cycles of the robot
// server, idle until `start`, then a joint impedance session; the bus order a recording may have,
// with the START_MOTION request before the state of the cycle the server took it in (it arrived
// while that state was being published) and its reply after; the scenario record republished at
// `record_at`; another robot's states and a foreign channel mixed in. Events before cycle `first`
// are not in the recording.
void write_bus_recording(const std::string& path, const rt::Scenario& scenario, int first, int record_at, int start, int cycles) {
  LogWriter log(path);
  const Channels channels("ARM1_"), other("ARM2_");
  const std::vector<uint8_t> record = encode(scenario_message(scenario, "ARM1_"));
  std::vector<std::pair<std::string, std::vector<uint8_t>>> replies;
  rt::Emulator robot(scenario.emulator);
  RobotServer server(robot, channels, [&](const std::string& channel, const std::vector<uint8_t>& bytes) {
    if (channel == channels.config_reply) replies.emplace_back(channel, bytes);
  }, [](const std::string&) {});
  const rt::Controller controller =
      joint_impedance_controller(example_joint_stiffness(), example_joint_damping(), example_excitation(0.2), 0.2);
  rt::Duration period(0);
  const auto recorded = [&](int cycle, const std::string& channel, const std::vector<uint8_t>& bytes) {
    if (cycle >= first) log.write(channel, bytes, 1'000'000 + 1000 * cycle);
  };
  for (int cycle = 0; cycle < cycles; ++cycle) {
    if (cycle == 0 || cycle == record_at) recorded(cycle, channels.scenario, record);
    config_request_t start_motion{};
    start_motion.request = config_request_t::START_MOTION;
    start_motion.request_id = 7;
    start_motion.control_mode = control_mode_code(rt::ControlMode::kTorque);
    if (cycle == start) recorded(cycle, channels.config, encode(start_motion));   // on the bus before the state
    recorded(cycle, channels.state, encode(server.state_message(0)));
    recorded(cycle, other.state, encode(to_message(rt::RobotState{}, 0, false)));
    recorded(cycle, "TEST_MARKER", {1, 2, 3});
    if (cycle == start) {
      const std::vector<uint8_t> bytes = encode(start_motion);
      server.receive(channels.config, bytes.data(), static_cast<int>(bytes.size()), 0);
      for (const auto& [channel, reply] : replies) recorded(cycle, channel, reply);
    }
    if (server.in_session()) {
      const std::vector<uint8_t> command =
          encode_command(rt::ControlMode::kTorque, server.message_id(), controller(server.emulator().state(), period), 0);
      period = rt::Duration(1);
      server.receive(channels.command, command.data(), static_cast<int>(command.size()), 0);
      recorded(cycle, channels.command, command);
    }
    server.step(0);
  }
}

// A recording begun late, its scenario record republished in the middle, other channels mixed in:
// re-simulated bit for bit from the robot's start, with what it misses named; without any record,
// from --scenario, and refused without it.
TEST(BridgeLog, ReplaysARecordingOfTheBusBegunLate) {
  const rt::Scenario scenario = default_scenario();
  const std::string path = test::temp_path("bus.lcmlog"), bare = test::temp_path("bus-no-record.lcmlog");
  write_bus_recording(path, scenario, 100, 250, 200, 500);
  const ResimulationReport replay = resimulate(path);
  EXPECT_EQ(replay.states, 400u);
  EXPECT_EQ(replay.differing_states, 0u) << replay.first_difference;
  EXPECT_TRUE(replay.identical());
  EXPECT_EQ(replay.missing, "the first 100 states (message ids 0-99)");
  EXPECT_NE(replay.scenario.find("the log's CSP_SCENARIO record"), std::string::npos) << replay.scenario;
  const ExportReport exported = for_each_logged_state(path, "ARM1_CSP_STATE", [](const rt::RobotState&, bool) {});
  EXPECT_EQ(exported.rows, 400u);
  EXPECT_EQ(exported.missing, replay.missing);

  write_bus_recording(bare, scenario, 100, -1, 200, 500);
  try {
    resimulate(bare);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no CSP_SCENARIO record"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("--scenario FILE"), std::string::npos) << e.what();
  }
  const ResimulationReport from_file = resimulate(bare, rt::default_scenario_path());
  EXPECT_TRUE(from_file.identical()) << from_file.first_difference;
  EXPECT_EQ(from_file.states, 400u);
  EXPECT_EQ(from_file.missing, "no CSP_SCENARIO record; the first 100 states (message ids 0-99)");
  for (const std::string& f : {path, bare}) std::filesystem::remove(f);
}

TEST(BridgeLog, RejectsWhatIsNotACspLog) {
  EXPECT_THROW(resimulate(test::temp_path("missing.lcmlog")), std::runtime_error);
  const std::string path = test::temp_path("foreign.lcmlog");
  {
    LogWriter log(path);
    log.write("OTHER", "abc", 3, 0);
  }
  try {
    resimulate(path);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("CSP_SCENARIO"), std::string::npos);
  }
  std::filesystem::remove(path);
}

// Columns of a CSV file by name.
std::map<std::string, std::vector<std::string>> read_columns(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  std::stringstream header(line);
  for (std::string cell; std::getline(header, cell, ',');) names.push_back(cell);
  std::map<std::string, std::vector<std::string>> columns;
  while (std::getline(in, line)) {
    std::stringstream row(line);
    std::size_t i = 0;
    for (std::string cell; std::getline(row, cell, ',') && i < names.size(); ++i) columns[names[i]].push_back(cell);
  }
  return columns;
}

TEST(BridgeLog, RealPandaCsvRoundTrips) {
  const std::string real = std::string(CSP_SHARED_DATA_DIR) + "/real/panda_exciting_traj_1.csv";
  const std::string log = test::temp_path("real.lcmlog"), csv = test::temp_path("real.csv");
  const uint64_t rows = import_csv(real, log, "CSP_STATE");
  const ExportReport exported = export_csv(log, csv, "CSP_STATE");
  EXPECT_EQ(exported.rows, rows);
  auto original = read_columns(real), round_trip = read_columns(csv);
  ASSERT_EQ(original["t"].size(), rows);
  ASSERT_GT(rows, 20000u);
  for (const std::string name : {"q", "dq", "tau_J"})
    for (int i = 1; i <= 7; ++i) {
      const std::string column = name + std::to_string(i);
      ASSERT_EQ(round_trip[column].size(), rows) << column;
      for (std::size_t r = 0; r < rows; ++r)
        ASSERT_EQ(std::stod(round_trip[column][r]), std::stod(original[column][r])) << column << " row " << r;
    }
  // Time: the robot state's resolution is 1 ms (libfranka's RobotState::time).
  for (std::size_t r = 0; r < rows; ++r) ASSERT_NEAR(std::stod(round_trip["t"][r]), std::stod(original["t"][r]), 0.5e-3 + 1e-12);
  for (const std::string& f : {log, csv}) std::filesystem::remove(f);
}

TEST(BridgeLog, ImportNamesTheBadCell) {
  const std::string bad = test::temp_path("bad.csv"), log = test::temp_path("bad.lcmlog");
  {
    std::ofstream out(bad);
    out << "t,q1,q2,q3,q4,q5,q6,q7,dq1,dq2,dq3,dq4,dq5,dq6,dq7,tau_J1,tau_J2,tau_J3,tau_J4,tau_J5,tau_J6,tau_J7\n";
    out << "0,1,2,3,4,5,6,7,1,2,3,4,5,6,7,1,2,3,4,5,6,7\n";
    out << "0.001,1,2,3,4,x,6,7,1,2,3,4,5,6,7,1,2,3,4,5,6,7\n";
  }
  try {
    import_csv(bad, log, "CSP_STATE");
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), bad + ":3: column 6 (q5): expected a finite number, got `x`");
  }
  for (const std::string& f : {log, bad}) std::filesystem::remove(f);
}

}  // namespace
}  // namespace csp::bridge
