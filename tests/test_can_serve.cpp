// The drives in front of the RobotServer (bridge/can server_arm, docs/can.md): Franka's semantics
// on top of CiA 402, checked against an in-process Emulator given the same quantized commands
// (bit for bit), against `csp replay`'s re-simulation of the session log, and against the
// physics (gravity). Frames are written byte by byte from the CiA 301/402 text.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <set>
#include <tuple>
#include <string>
#include <vector>

#include "csp/bridge/replay.hpp"
#include "csp/can/serve.hpp"
#include "csp/can/server_arm.hpp"
#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/arrays.hpp"

namespace csp::can {
namespace {

std::string temp_log(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("csp-can-serve-test-" + std::to_string(getpid()) + "-" + name)).string();
}

Frame frame(uint32_t id, std::initializer_list<uint8_t> bytes) {
  Frame f;
  f.id = id;
  f.dlc = static_cast<uint8_t>(bytes.size());
  std::copy(bytes.begin(), bytes.end(), f.data.begin());
  return f;
}

// Per-mille torque steps of joint j (0x6076: 3000 mN m joints 1-4, 500 mN m joints 5-7).
double torque_step(int j) { return j < 4 ? 3e-3 : 0.5e-3; }

// The ServerArm, recording the emulator's joint positions after each cycle.
class RecordingArm : public Arm {
 public:
  explicit RecordingArm(const std::string& log)
      : scenario(rt::load_scenario(rt::default_scenario_path())), robot(scenario.emulator), arm(robot, scenario, log, [](const std::string&) {}) {}
  ArmState cycle(const ArmCommand& command) override {
    const ArmState state = arm.cycle(command);
    q.push_back(arm.server().emulator().state().q);
    return state;
  }
  ArmState measured() const override { return arm.measured(); }
  rt::Scenario scenario;
  rt::Emulator robot;
  ServerArm arm;
  std::vector<std::array<double, 7>> q;
};

class CanServe : public ::testing::Test {
 protected:
  std::string log = temp_log(::testing::UnitTest::GetInstance()->current_test_info()->name());
  RecordingArm arm{log};
  DriveBus bus{BusSettings{}, arm};

  ~CanServe() override { std::filesystem::remove(log); }

  const rt::Emulator& emulator() const { return arm.arm.server().emulator(); }
  void sync() { bus.receive(frame(kSync, {})); }
  void rpdo1(int node, uint16_t controlword, int16_t torque) {
    bus.receive(frame(kRpdo1 + node, {uint8_t(controlword), uint8_t(controlword >> 8), uint8_t(torque), uint8_t(uint16_t(torque) >> 8)}));
  }
  void rpdo2(int node, int32_t position) {
    const auto p = static_cast<uint32_t>(position);
    bus.receive(frame(kRpdo2 + node, {uint8_t(p), uint8_t(p >> 8), uint8_t(p >> 16), uint8_t(p >> 24), 0, 0}));
  }
  void controlword_all(uint16_t controlword) {
    for (int n = 1; n <= 7; ++n) rpdo1(n, controlword, 0);
    sync();
  }
  // NMT start all, then shutdown / switch on / enable operation by RPDO1.
  void enable() {
    bus.receive(frame(kNmt, {0x01, 0x00}));
    for (uint16_t cw : {0x06, 0x07, 0x0F}) controlword_all(cw);
  }
  int statusword(int joint) const { return static_cast<int>(bus.node(joint).value(0x6041, 0)); }
  // EMCY frames (0x80 + node) with `code` in the frames sent since the last clear.
  int emcy_count(uint16_t code) const {
    int n = 0;
    for (const Frame& f : bus.sent())
      if (f.id > 0x80 && f.id <= 0x87 && f.dlc == 8 && get_le(f.data.data(), 2) == code) ++n;
    return n;
  }
};

// The torque profile of the tests: smooth sines well inside libfranka's torque-rate limit.
int16_t profile(int joint, int cycle) {
  const double amplitude = joint < 4 ? 1.0 : 0.1;   // [N m]
  const double tau = amplitude * std::sin(2.0 * M_PI * (1.0 + 0.3 * joint) * cycle * 1e-3);
  return static_cast<int16_t>(std::lround(tau / torque_step(joint)));
}

TEST_F(CanServe, CstSessionEqualsTheInProcessEmulatorBitForBitAndReplaysFromItsLog) {
  enable();
  const std::size_t idle_cycles = arm.q.size();   // the walk's cycles, before the motion
  ASSERT_EQ(statusword(0) & 0x6F, 0x27);
  constexpr int kCycles = 1000;
  std::vector<Vector7> commands;
  for (int k = 0; k < kCycles; ++k) {
    Vector7 tau;
    for (int n = 1; n <= 7; ++n) {
      rpdo1(n, 0x0F, profile(n - 1, k));
      tau[n - 1] = profile(n - 1, k) * torque_step(n - 1);
    }
    commands.push_back(tau);
    sync();
  }
  EXPECT_TRUE(emulator().in_motion()) << emulator().reflex_reason() << " " << emulator().counters().motion_cycles;
  EXPECT_EQ(arm.arm.counters().motions, 1u);
  EXPECT_EQ(emulator().counters().lost_commands, 0u);

  // The same quantized commands, in process: the RPDOs latched at SYNC k are the command of cycle k.
  rt::Emulator reference(rt::load_scenario(rt::default_scenario_path()).emulator);
  // The SYNC that latched "enable operation" started the motion, with the zero torque of the
  // walk's last RPDO1 as its first command.
  for (std::size_t k = 0; k + 1 < idle_cycles; ++k) reference.step(nullptr);
  reference.start_motion(rt::ControlMode::kTorque);
  const rt::Command zero;
  reference.step(&zero);
  int differing = 0;
  double moved = 0.0;
  for (int k = 0; k < kCycles; ++k) {
    rt::Command c;
    c.values = commands[k];
    reference.step(&c);
    const auto& q = arm.q[idle_cycles + k];
    if (std::memcmp(q.data(), reference.state().q.data(), sizeof(double) * 7) != 0) ++differing;
    moved = std::max(moved, std::abs(q[0] - arm.q[idle_cycles - 1][0]));
  }
  EXPECT_EQ(differing, 0);
  EXPECT_GT(moved, 1e-3);   // the profile really moved the arm

  // The session log re-simulates bit for bit.
  arm.arm.log()->flush();
  const bridge::ResimulationReport replay = bridge::resimulate(log);
  EXPECT_TRUE(replay.identical()) << replay.first_difference;
  EXPECT_EQ(replay.states, arm.q.size() + 1);
}


TEST_F(CanServe, TwentyCyclesWithoutRpdoAreCommunicationConstraintsViolationOnEveryJointAndFaultResetRecovers) {
  enable();
  for (int k = 0; k < 19; ++k) sync();   // 19 cycles lost: the robot extrapolates
  EXPECT_TRUE(emulator().in_motion());
  bus.clear_sent();
  sync();   // the 20th
  EXPECT_FALSE(emulator().in_motion());
  EXPECT_TRUE(rt::has(emulator().state().current_errors, rt::Error::communication_constraints_violation));
  EXPECT_EQ(emcy_count(0x8250), 7);
  for (int j = 0; j < 7; ++j) {
    EXPECT_EQ(statusword(j) & 0x4F, 0x0F) << "joint " << j + 1;   // fault reaction active (CiA 402 mask 0x4F)
    EXPECT_EQ(bus.node(j).value(0x2002, 32), 1);                   // sub 32 = error 31
    EXPECT_EQ(bus.node(j).value(0x1001, 0) & 0x11, 0x11);          // generic + communication
  }
  // Fault reaction active lasts the cycle the robot brakes in, then fault.
  controlword_all(0x00);
  for (int j = 0; j < 7; ++j) EXPECT_EQ(statusword(j) & 0x4F, 0x08) << "joint " << j + 1;
  // Fault reset (rising edge of controlword bit 7) = automatic error recovery.
  bus.clear_sent();
  controlword_all(0x80);
  EXPECT_FALSE(bool(emulator().state().current_errors));
  EXPECT_EQ(arm.arm.counters().recoveries, 1u);
  EXPECT_EQ(emcy_count(0x0000), 7);   // error reset
  for (int j = 0; j < 7; ++j) EXPECT_EQ(statusword(j) & 0x4F, 0x40) << "joint " << j + 1;   // switch on disabled
  // And the arm can be enabled again for a new motion.
  for (uint16_t cw : {0x06, 0x07, 0x0F}) controlword_all(cw);
  EXPECT_TRUE(emulator().in_motion());
  EXPECT_EQ(arm.arm.counters().motions, 2u);
}

TEST_F(CanServe, ATorqueJumpIsControllerTorqueDiscontinuityOnEveryJoint) {
  enable();
  bus.clear_sent();
  for (int n = 1; n <= 7; ++n) rpdo1(n, 0x0F, n == 1 ? 20000 : 0);   // 60 N m in one millisecond
  sync();
  EXPECT_TRUE(rt::has(emulator().state().current_errors, rt::Error::controller_torque_discontinuity));
  EXPECT_EQ(emcy_count(0xFF1E), 7);
  sync();
  for (int j = 0; j < 7; ++j) EXPECT_EQ(statusword(j) & 0x4F, 0x08) << "joint " << j + 1;
}

TEST_F(CanServe, CspFollowsTheTargetPositionLikeTheInProcessJointPositionMode) {
  bus.receive(frame(kNmt, {0x01, 0x00}));
  std::array<int32_t, 7> start{};
  for (int n = 1; n <= 7; ++n) bus.receive(frame(kRpdo4 + n, {kModeCsp}));
  for (uint16_t cw : {0x06, 0x07}) controlword_all(cw);
  const std::size_t idle_cycles = arm.q.size();
  // Enable and the first targets in the same cycle: the start pose q_d (0x6062), in 1 urad steps.
  for (int n = 1; n <= 7; ++n) {
    start[n - 1] = static_cast<int32_t>(bus.node(n - 1).value(0x6062, 0));
    rpdo2(n, start[n - 1]);
  }
  controlword_all(0x0F);
  ASSERT_TRUE(emulator().in_motion());
  EXPECT_EQ(*arm.arm.server().session(), rt::ControlMode::kJointPosition);
  // Joint 4 follows a smooth rest-to-rest move of 0.1 rad over 2 s (1 - cos).
  std::vector<Vector7> targets;
  constexpr int kCycles = 2000;
  for (int k = 1; k <= kCycles; ++k) {
    Vector7 q;
    for (int n = 1; n <= 7; ++n) {
      const double offset = n == 4 ? 0.05 * (1.0 - std::cos(M_PI * k / kCycles)) : 0.0;
      const auto raw = static_cast<int32_t>(start[n - 1] + std::lround(offset * 1e6));
      rpdo2(n, raw);
      rpdo1(n, 0x0F, 0);
      q[n - 1] = raw * 1e-6;
    }
    targets.push_back(q);
    sync();
  }
  ASSERT_TRUE(emulator().in_motion()) << emulator().reflex_reason();
  EXPECT_NEAR(emulator().state().q[3], start[3] * 1e-6 + 0.1, 1e-3);

  rt::Emulator reference(rt::load_scenario(rt::default_scenario_path()).emulator);
  for (std::size_t k = 0; k < idle_cycles; ++k) reference.step(nullptr);
  reference.start_motion(rt::ControlMode::kJointPosition);
  rt::Command first;
  for (int j = 0; j < 7; ++j) first.values[j] = start[j] * 1e-6;
  reference.step(&first);
  for (int k = 0; k < kCycles; ++k) {
    rt::Command c;
    c.values = targets[k];
    reference.step(&c);
  }
  EXPECT_EQ(std::memcmp(reference.state().q.data(), emulator().state().q.data(), sizeof(double) * 7), 0);
  // Leaving operation enabled finishes the motion (no reflex).
  controlword_all(0x07);
  sync();
  EXPECT_FALSE(emulator().in_motion());
  EXPECT_FALSE(bool(emulator().state().current_errors)) << emulator().reflex_reason();
}

// Frames as candump writes them (ID#DATA), to compare with frames written from the spec.
std::vector<std::string> frames_sent(const DriveBus& bus) {
  std::vector<std::string> frames;
  for (const Frame& f : bus.sent()) frames.push_back(to_string(f));
  return frames;
}

bool contains(const std::vector<std::string>& frames, const std::string& frame) {
  return std::find(frames.begin(), frames.end(), frame) != frames.end();
}

// Little-endian hex of a 32-bit value, as it stands in a frame.
std::string le32(int64_t value) {
  char hex[9];
  const auto v = static_cast<uint32_t>(value);
  std::snprintf(hex, sizeof hex, "%02X%02X%02X%02X", v & 0xFF, (v >> 8) & 0xFF, (v >> 16) & 0xFF, v >> 24);
  return hex;
}

TEST_F(CanServe, BeforeTheFirstSyncTheDrivesReportTheRobotsTruePosition) {
  const rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
  // Libfranka's "ready" pose: joint 2 at -0.785398 rad = -785398 urad = 0xFFF4040A, joint 4 at
  // -2356194 urad = 0xFFDC0C1E. SDO upload (CiA 301): request 40 6064:00, answer 43 (4 bytes).
  ASSERT_EQ(scenario.emulator.q_initial[1], -0.785398);
  bus.clear_sent();
  bus.receive(parse_frame("602#4064600000000000"));
  EXPECT_EQ(frames_sent(bus), std::vector<std::string>{"582#436460000A04F4FF"});
  bus.clear_sent();
  bus.receive(parse_frame("604#4064600000000000"));
  EXPECT_EQ(frames_sent(bus), std::vector<std::string>{"584#436460001E0CDCFF"});
  // Every joint: position 0x6064 and position demand 0x6062 = the start pose, torque 0x6077 = the
  // robot's tau_J (gravity: joint 2 carries the arm), all before any SYNC and before NMT start.
  const rt::RobotState& s = emulator().state();
  for (int n = 1; n <= 7; ++n) {
    const std::string q = le32(std::lround(scenario.emulator.q_initial[n - 1] * 1e6));
    for (const char* index : {"6460", "6260"}) {
      bus.clear_sent();
      bus.receive(parse_frame(std::string("60") + char('0' + n) + "#40" + index + "0000000000"));
      EXPECT_EQ(frames_sent(bus), std::vector<std::string>{std::string("58") + char('0' + n) + "#43" + index + "00" + q}) << "joint " << n;
    }
    EXPECT_EQ(bus.node(n - 1).value(0x6077, 0), std::lround(s.tau_J[n - 1] / torque_step(n - 1))) << "joint " << n;
  }
  EXPECT_GT(std::abs(bus.node(1).value(0x6077, 0)), 1000);   // joint 2 holds the arm: > 3 N m
  EXPECT_TRUE(arm.q.empty());                                 // no cycle has run

  // The first TPDO1 after NMT start: statusword 0x0240 (switch on disabled, remote), the
  // position, the torque; TPDO2 velocity 0 (the arm rests), tau_ext, mode display 10.
  bus.receive(frame(kNmt, {0x01, 0x00}));
  const rt::RobotState before_sync = emulator().state();
  bus.clear_sent();
  sync();
  const std::vector<std::string> first = frames_sent(bus);
  for (int n = 1; n <= 7; ++n) {
    char tau[5];
    const auto raw = static_cast<uint16_t>(std::lround(before_sync.tau_J[n - 1] / torque_step(n - 1)));
    std::snprintf(tau, sizeof tau, "%02X%02X", raw & 0xFF, raw >> 8);
    EXPECT_TRUE(contains(first, std::string("18") + char('0' + n) + "#4002" + le32(std::lround(scenario.emulator.q_initial[n - 1] * 1e6)) + tau))
        << "joint " << n;
  }
  // Joint 2's position bytes as the spec lays them out: statusword 4002, then 0A04F4FF.
  EXPECT_EQ(std::count_if(first.begin(), first.end(), [](const std::string& f) { return f.rfind("182#40020A04F4FF", 0) == 0; }), 1);
  // A reset node restores the objects' defaults, but the position stays the robot's, not 0.
  bus.receive(frame(kNmt, {0x81, 0x02}));
  bus.clear_sent();
  bus.receive(parse_frame("602#4064600000000000"));
  EXPECT_EQ(frames_sent(bus), std::vector<std::string>{"582#436460000A04F4FF"});
}

// The session log's event records (CSP_EVENT) with their text.
std::vector<std::string> logged_events(const std::string& path) {
  bridge::LogReader reader(path);
  std::vector<std::string> texts;
  for (const bridge::LogEvent* e = reader.next(); e; e = reader.next()) {
    event_t event;
    if (e->channel == bridge::Channels{}.event && bridge::decode_exact(e->data, e->datalen, event) == bridge::Rejection::kNone)
      texts.push_back(event.text);
  }
  return texts;
}

TEST_F(CanServe, MixedModesRunNoMotionSendEmcy6320FromEachEnabledDriveAndLogAnError) {
  bus.receive(frame(kNmt, {0x01, 0x00}));
  bus.receive(frame(kRpdo4 + 7, {kModeCsp}));   // joint 7 in CSP, joints 1-6 in CST (the default)
  for (uint16_t cw : {0x06, 0x07}) controlword_all(cw);
  bus.clear_sent();
  controlword_all(0x0F);   // the SYNC that latches "enable operation"
  EXPECT_FALSE(emulator().in_motion());
  EXPECT_EQ(arm.arm.counters().motions, 0u);
  EXPECT_EQ(arm.arm.counters().mixed_modes, 1u);
  // EMCY (CiA 301): code 0x6320 little-endian, error register 0 (no fault), CSP's bytes:
  // libfranka error 0xFF (none), the joint, three zeros. One per enabled drive.
  const std::vector<std::string> frames = frames_sent(bus);
  for (int n = 1; n <= 7; ++n)
    EXPECT_TRUE(contains(frames, std::string("08") + char('0' + n) + "#206300FF0" + char('0' + n) + "000000")) << "joint " << n;
  EXPECT_EQ(emcy_count(0x6320), 7);
  for (int j = 0; j < 7; ++j) EXPECT_EQ(statusword(j) & 0x6F, 0x27) << "joint " << j + 1;   // still enabled, no fault
  // Once per mix: the next cycles send no more.
  bus.clear_sent();
  controlword_all(0x0F);
  EXPECT_EQ(emcy_count(0x6320), 0);

  // The master puts joint 7 in CST too, then disables and enables: one torque motion.
  bus.receive(frame(kRpdo4 + 7, {kModeCst}));
  controlword_all(0x07);
  controlword_all(0x0F);
  ASSERT_TRUE(emulator().in_motion());
  EXPECT_EQ(*arm.arm.server().session(), rt::ControlMode::kTorque);
  // Joint 3 switches to CSP during the motion: the motion finishes without a reflex, and the
  // seven enabled drives send EMCY 0x6320 again.
  bus.clear_sent();
  bus.receive(frame(kRpdo4 + 3, {kModeCsp}));
  controlword_all(0x0F);
  EXPECT_EQ(emcy_count(0x6320), 7);
  sync();
  EXPECT_FALSE(emulator().in_motion());
  EXPECT_FALSE(bool(emulator().state().current_errors)) << emulator().reflex_reason();
  EXPECT_EQ(arm.arm.counters().mixed_modes, 2u);

  // The session log has an error record for each mix, naming the joints' modes.
  arm.arm.log()->flush();
  std::vector<std::string> errors;
  for (const std::string& text : logged_events(log))
    if (text.rfind("error: ", 0) == 0) errors.push_back(text);
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_NE(errors[0].find("different modes of operation (joint 1 CST, 2 CST, 3 CST, 4 CST, 5 CST, 6 CST, 7 CSP)"), std::string::npos)
      << errors[0];
  EXPECT_NE(errors[1].find("(joint 1 CST, 2 CST, 3 CSP, 4 CST, 5 CST, 6 CST, 7 CST)"), std::string::npos) << errors[1];
  // And the log still replays bit for bit (replay skips events).
  const bridge::ResimulationReport replay = bridge::resimulate(log);
  EXPECT_TRUE(replay.identical()) << replay.first_difference;
}

// Issue 25, item 12: a drive that does not act on its target must not say it does. Statusword bit
// 12 (CiA 402, CSP/CSV/CST: "drive follows the command value") is set only while the robot runs a
// motion on the targets; when one drive leaves operation enabled mid-motion the motion ends, and
// every drive left in operation enabled clears bit 12 and sends EMCY 0xFF00; the session log names
// them. Frames written from the CiA 301 EMCY layout: code LE, error register, CSP's bytes.
TEST_F(CanServe, WhenOneDriveLeavesOperationEnabledMidMotionTheOthersSayTheirTargetsAreIgnored) {
  bus.receive(frame(kNmt, {0x01, 0x00}));
  // A master enabling the drives one by one by SDO (as python-canopen's state setter does): six
  // drives in operation enabled, no motion yet, so none of them says it follows its target.
  for (int n = 1; n <= 6; ++n)
    for (uint8_t cw : {0x06, 0x07, 0x0F}) bus.receive(frame(kSdoRx + n, {0x2B, 0x40, 0x60, 0x00, cw, 0x00, 0, 0}));
  bus.clear_sent();
  sync();
  for (int j = 0; j < 6; ++j) {
    EXPECT_EQ(statusword(j) & 0x6F, 0x27) << "joint " << j + 1;
    EXPECT_EQ(statusword(j) & 0x1000, 0) << "joint " << j + 1;
  }
  EXPECT_EQ(emcy_count(0xFF00), 0);   // never followed: nothing stopped
  for (uint8_t cw : {0x06, 0x07, 0x0F}) bus.receive(frame(kSdoRx + 7, {0x2B, 0x40, 0x60, 0x00, cw, 0x00, 0, 0}));
  controlword_all(0x0F);
  ASSERT_TRUE(emulator().in_motion());
  for (int j = 0; j < 7; ++j) EXPECT_EQ(statusword(j) & 0x1000, 0x1000) << "joint " << j + 1;

  // 0.3 N m on joint 7 (600 per mille of 500 mN m), ramped: it turns while the motion runs.
  for (int k = 1; k <= 100; ++k) {
    for (int n = 1; n <= 7; ++n) rpdo1(n, 0x0F, n == 7 ? static_cast<int16_t>(6 * k) : 0);
    sync();
  }
  EXPECT_TRUE(emulator().in_motion()) << emulator().reflex_reason();
  // Joint 3 leaves operation enabled (disable operation): the motion ends without a reflex.
  bus.clear_sent();
  for (int n = 1; n <= 7; ++n) rpdo1(n, n == 3 ? 0x07 : 0x0F, n == 7 ? 600 : 0);
  sync();
  EXPECT_FALSE(emulator().in_motion());
  EXPECT_FALSE(bool(emulator().state().current_errors)) << emulator().reflex_reason();
  const std::vector<std::string> frames = frames_sent(bus);
  for (int n = 1; n <= 7; ++n) {
    const std::string emcy = std::string("08") + char('0' + n) + "#00FF00FF0" + char('0' + n) + "000000";
    EXPECT_EQ(std::count(frames.begin(), frames.end(), emcy), n == 3 ? 0 : 1) << emcy;
    EXPECT_EQ(statusword(n - 1) & 0x6F, n == 3 ? 0x23 : 0x27) << "joint " << n;   // the six stay enabled
    EXPECT_EQ(statusword(n - 1) & 0x1000, 0) << "joint " << n;                    // and say the target is ignored
  }
  // The torque on joint 7 is ignored from now on, and its drive keeps saying so; no more EMCYs.
  bus.clear_sent();
  for (int k = 0; k < 100; ++k) {
    for (int n = 1; n <= 7; ++n) rpdo1(n, n == 3 ? 0x07 : 0x0F, n == 7 ? 600 : 0);
    sync();
  }
  EXPECT_FALSE(emulator().in_motion());
  EXPECT_EQ(statusword(6) & 0x1000, 0);
  EXPECT_EQ(emcy_count(0xFF00), 0);
  EXPECT_EQ(arm.arm.counters().abandoned_motions, 1u);
  EXPECT_EQ(arm.arm.counters().ignored_cycles, 1u + 101u);   // the six alone before, and since

  // Joint 3 enabled again: a new motion, and every drive follows its target again.
  for (int n = 1; n <= 7; ++n) rpdo1(n, 0x0F, 0);
  sync();
  ASSERT_TRUE(emulator().in_motion()) << emulator().reflex_reason();
  EXPECT_EQ(arm.arm.counters().motions, 2u);
  for (int j = 0; j < 7; ++j) EXPECT_EQ(statusword(j) & 0x1000, 0x1000) << "joint " << j + 1;

  // The session log says what happened, naming the drive that left and the ones left enabled.
  arm.arm.log()->flush();
  std::vector<std::string> errors;
  for (const std::string& text : logged_events(log))
    if (text.rfind("error: ", 0) == 0) errors.push_back(text);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_NE(errors[0].find("joint 3 left operation enabled: the motion ended; joints 1, 2, 4, 5, 6, 7 stay in operation enabled "
                           "with their targets ignored (statusword bit 12 clear, EMCY 0xFF00 from each)"),
            std::string::npos)
      << errors[0];
  const bridge::ResimulationReport replay = bridge::resimulate(log);
  EXPECT_TRUE(replay.identical()) << replay.first_difference;
}

// The stateful fuzz of tests/can_vcan (master.py fuzz) in process, so that it runs in every build,
// the sanitized one too: random NMT commands, COB-ID writes (restricted, SYNC, free, defaults, bit
// 31 on or off), PDO remaps, controlwords, modes and cycles with RPDO1s, in front of the real
// robot. After each step: no frame on a restricted CAN-ID or the SYNC's, every frame on an id in
// use; a COB-ID write accepted exactly when CiA 301 allows it; statusword bit 12 only in
// operation enabled, and after a cycle exactly when the robot runs a motion; a drive losing it
// while it stays enabled sends EMCY 0xFF00.
TEST(CanServeFuzz, RandomStatefulSequencesKeepTheInvariants) {
  RecordingArm arm("");
  DriveBus bus{BusSettings{}, arm};
  const rt::Emulator& emulator = arm.arm.server().emulator();
  std::mt19937 rng(20261129);
  const auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<unsigned>(n)); };
  // A node's COB-ID objects and their default function codes (+ node id).
  const std::vector<std::array<uint32_t, 3>> objects{{0x1014, 0, 0x080}, {0x1400, 1, 0x200}, {0x1401, 1, 0x300}, {0x1402, 1, 0x400},
                                                     {0x1403, 1, 0x500}, {0x1800, 1, 0x180}, {0x1801, 1, 0x280}};
  std::array<std::array<uint32_t, 7>, 8> cob{};   // [node][object]
  std::array<bool, 8> operational{}, followed{};
  std::array<uint16_t, 8> controlword{};
  const auto reset_model = [&](int n) {
    for (std::size_t o = 0; o < objects.size(); ++o) cob[n][o] = objects[o][2] + static_cast<uint32_t>(n);
    operational[n] = false;
  };
  for (int n = 1; n <= 7; ++n) reset_model(n), controlword[n] = 0x0F;
  bus.receive(frame(kNmt, {0x01, 0x00}));
  for (int n = 1; n <= 7; ++n) operational[n] = true;
  const auto ids_in_use = [&] {
    std::set<uint32_t> ids;
    for (int n = 1; n <= 7; ++n) {
      ids.insert(0x580 + n), ids.insert(0x700 + n);
      for (std::size_t o : {0u, 5u, 6u})   // EMCY, TPDO1, TPDO2: what a drive sends on
        if (!(cob[n][o] & kCobIdInvalid)) ids.insert(cob[n][o] & 0x7FF);
    }
    return ids;
  };
  std::vector<Frame> step_frames;
  const auto receive = [&](const Frame& f) {
    bus.clear_sent();
    bus.receive(f);
    step_frames.insert(step_frames.end(), bus.sent().begin(), bus.sent().end());
  };
  // Expedited SDO download; the abort code or 0.
  const auto download = [&](int node, uint16_t index, uint8_t sub, uint32_t value, int size) {
    receive(frame(kSdoRx + node, {uint8_t(0x23 | (4 - size) << 2), uint8_t(index), uint8_t(index >> 8), sub, uint8_t(value),
                                  uint8_t(value >> 8), uint8_t(value >> 16), uint8_t(value >> 24)}));
    const Frame& answer = step_frames.back();
    EXPECT_EQ(answer.id, kSdoRx - 0x80 + node);
    return answer.data[0] == 0x80 ? static_cast<uint32_t>(get_le(&answer.data[4], 4)) : 0u;
  };
  const std::vector<uint32_t> restricted{0x000, 0x001, 0x07F, 0x101, 0x180, 0x581, 0x5FF, 0x601, 0x67F, 0x6E0, 0x6FF, 0x701, 0x77F, 0x780, 0x7FF};
  int accepted_cob_writes = 0, refused_cob_writes = 0, motions_seen = 0, targets_ignored = 0;
  std::set<uint32_t> ids_before = ids_in_use();
  for (int step = 0; step < 2000; ++step) {
    step_frames.clear();
    const int kind = pick(16);
    bool cycles = false;
    if (kind == 0) {   // NMT: start, pre-operational, stop then start, reset node, reset communication
      const uint8_t command = std::array<uint8_t, 6>{0x01, 0x01, 0x80, 0x02, 0x81, 0x82}[pick(6)];
      const int node = pick(8);
      receive(frame(kNmt, {command, uint8_t(node)}));
      if (command == 0x02) receive(frame(kNmt, {0x01, uint8_t(node)}));
      for (int n = 1; n <= 7; ++n) {
        if (node != 0 && node != n) continue;
        if (command == 0x81 || command == 0x82) reset_model(n);
        else operational[n] = command != 0x80;
      }
    } else if (kind <= 4) {   // a COB-ID write
      const int n = 1 + pick(7);
      const std::size_t o = static_cast<std::size_t>(pick(7));
      const int choice = pick(10);
      uint32_t id = choice < 4 ? restricted[pick(static_cast<int>(restricted.size()))]
                    : choice < 5 ? 0x080u
                    : choice < 8 ? std::array<uint32_t, 6>{0x100, 0x190, 0x3F0, 0x580, 0x680, 0x700}[pick(6)] + static_cast<uint32_t>(pick(8))
                                 : objects[o][2] + static_cast<uint32_t>(n);
      const uint32_t value = id | (pick(2) ? kCobIdInvalid : 0);
      const uint32_t current = cob[n][o];
      id = value & 0x7FF;
      const bool allowed = (value & kCobIdInvalid) ||
                           (((current & kCobIdInvalid) || value == current) && !is_restricted_can_id(id) && id != kSync);
      const uint32_t code = download(n, static_cast<uint16_t>(objects[o][0]), static_cast<uint8_t>(objects[o][1]), value, 4);
      ASSERT_EQ(code, allowed ? 0u : 0x06090030u) << "step " << step << ": node " << n << " 0x" << std::hex << objects[o][0]
                                                  << " from 0x" << current << " to 0x" << value;
      if (code == 0) cob[n][o] = value;
      ++(code == 0 ? accepted_cob_writes : refused_cob_writes);
    } else if (kind <= 6) {   // a PDO remap, sometimes left half done
      const int n = 1 + pick(7);
      const std::size_t o = 1 + static_cast<std::size_t>(pick(6));
      const uint16_t index = static_cast<uint16_t>(objects[o][0]);
      const bool rpdo = index < 0x1800;
      const std::vector<uint32_t> mappable = rpdo ? std::vector<uint32_t>{0x60400010, 0x60710010, 0x607A0020, 0x60FF0020, 0x60600008}
                                                  : std::vector<uint32_t>{0x60410010, 0x60640020, 0x606C0020, 0x60610008, 0x10010008};
      const int count = pick(4);
      std::vector<std::tuple<uint16_t, uint8_t, uint32_t, int>> requests{{index, 1, cob[n][o] | kCobIdInvalid, 4},
                                                                          {uint16_t(index + 0x200), 0, 0, 1}};
      for (int i = 0; i < count; ++i) requests.emplace_back(uint16_t(index + 0x200), uint8_t(i + 1), mappable[pick(5)], 4);
      requests.emplace_back(uint16_t(index + 0x200), 0, count, 1);
      requests.emplace_back(index, 1, cob[n][o] & ~kCobIdInvalid, 4);
      const std::size_t done = pick(5) == 0 ? 1 + static_cast<std::size_t>(pick(static_cast<int>(requests.size()))) : requests.size();
      for (std::size_t r = 0; r < done; ++r) {
        const auto [i, sub, value, size] = requests[r];
        const uint32_t code = download(n, i, sub, value, size);
        EXPECT_TRUE(code == 0 || code == 0x06040042 || code == 0x06090030 || code == 0x08000022) << std::hex << code;
        if (i == index && code == 0) cob[n][o] = value;
      }
    } else if (kind <= 9) {   // controlwords by SDO to one drive or all: one, or the walk to operation enabled
      const bool walk = pick(2);
      const std::vector<uint16_t> words = walk ? std::vector<uint16_t>{0x00, 0x80, 0x06, 0x07, 0x0F}
                                               : std::vector<uint16_t>{std::array<uint16_t, 8>{0x06, 0x07, 0x0F, 0x0F, 0x0F, 0x00, 0x02, 0x80}[pick(8)]};
      const int only = pick(walk ? 4 : 2) ? 0 : 1 + pick(7);
      for (int n = 1; n <= 7; ++n) {
        if (only != 0 && only != n) continue;
        for (uint16_t cw : words) EXPECT_EQ(download(n, 0x6040, 0, cw, 2), 0u);
        controlword[n] = words.back();
      }
    } else if (kind == 10) {   // a mode of operation
      const int mode = std::array<int, 4>{8, 9, 10, 10}[pick(4)];
      const int only = pick(3) == 0 ? 1 + pick(7) : 0;
      for (int n = 1; n <= 7; ++n) {
        if (only == 0 || only == n) {
          EXPECT_EQ(download(n, 0x6060, 0, static_cast<uint32_t>(mode), 1), 0u);
        }
      }
    } else {   // cycles: RPDO1 (controlword, zero torque) on each node's RPDO1 COB-ID, then SYNC
      cycles = true;
      for (int k = 1 + pick(10); k > 0; --k) {
        for (int n = 1; n <= 7; ++n)
          if (!(cob[n][1] & kCobIdInvalid)) receive(frame(cob[n][1] & 0x7FF, {uint8_t(controlword[n]), 0, 0, 0}));
        receive(frame(kSync, {}));
      }
    }
    // The invariants.
    std::set<uint32_t> ids = ids_in_use();
    ids.insert(ids_before.begin(), ids_before.end());
    std::set<int> emcy_ff00;
    for (const Frame& f : step_frames) {
      const bool sdo_or_heartbeat = (f.id > 0x580 && f.id <= 0x587) || (f.id > 0x700 && f.id <= 0x707);
      ASSERT_TRUE(f.id != kSync && (sdo_or_heartbeat || !is_restricted_can_id(f.id))) << "step " << step << ": " << to_string(f);
      ASSERT_TRUE(ids.count(f.id)) << "step " << step << ": " << to_string(f);
      if (f.dlc == 8 && f.data[0] == 0x00 && f.data[1] == 0xFF) emcy_ff00.insert(f.data[4]);
    }
    for (int n = 1; n <= 7; ++n) {
      const int word = static_cast<int>(bus.node(n - 1).value(0x6041, 0));
      const bool follows = word & 0x1000;
      ASSERT_TRUE(!follows || (word & 0x6F) == 0x27) << "step " << step << ": node " << n << " statusword " << word;
      if (cycles) {
        // After a cycle the statusword says what the robot does: bit 12 exactly when it runs a motion
        // and the drive is enabled.
        ASSERT_EQ(follows, (word & 0x6F) == 0x27 && emulator.in_motion()) << "step " << step << ": node " << n;
        if (followed[n] && !follows && (word & 0x6F) == 0x27) {
          ASSERT_TRUE(emcy_ff00.count(n) || (cob[n][0] & kCobIdInvalid)) << "step " << step << ": node " << n << " lost bit 12 silently";
          ++targets_ignored;
        }
        followed[n] = follows;
      } else {
        followed[n] = followed[n] && follows;
      }
    }
    motions_seen += cycles && emulator.in_motion() ? 1 : 0;
    ids_before = ids_in_use();
  }
  // The walk reached what it is for.
  EXPECT_GT(accepted_cob_writes, 50);
  EXPECT_GT(refused_cob_writes, 50);
  EXPECT_GT(motions_seen, 20);
  EXPECT_GT(targets_ignored, 5);
}

// The master's torque that holds the arm against gravity (the robot's own model, quantized).
std::array<int16_t, 7> holding_torque(const rt::Emulator& emulator) {
  Data data;
  Vector7 g;
  gravity_torque(emulator.internal_model(), data, from_array<Vector7>(emulator.state().q), g);
  std::array<int16_t, 7> raw{};
  for (int j = 0; j < 7; ++j) raw[j] = static_cast<int16_t>(std::lround(g[j] / torque_step(j)));
  return raw;
}

// Holds the arm for 500 cycles, by the robot's gravity compensation (0x2000 = 1, zero torque) or
// by the master's torque (0x2000 = 0, g(q) sent); returns the final joint positions.
std::array<double, 7> hold(bool robot_compensates) {
  RecordingArm arm("");
  DriveBus bus{BusSettings{}, arm};
  const rt::Emulator& emulator = arm.arm.server().emulator();
  if (!robot_compensates) {
    // 0x2000 = 0 by SDO (expedited download of 1 byte, 0x2F) on every node: the answer is 0x60.
    for (int n = 1; n <= 7; ++n) {
      bus.clear_sent();
      bus.receive(frame(kSdoRx + n, {0x2F, 0x00, 0x20, 0x00, 0x00, 0, 0, 0}));
      EXPECT_EQ(bus.sent().at(0).data[0], 0x60);
    }
  }
  bus.receive(frame(kNmt, {0x01, 0x00}));
  for (int k = 0; k < 503; ++k) {
    const auto g = holding_torque(emulator);
    for (int n = 1; n <= 7; ++n) {
      const uint16_t cw = k == 0 ? 0x06 : k == 1 ? 0x07 : 0x0F;
      const int16_t torque = robot_compensates ? 0 : g[n - 1];
      bus.receive(frame(kRpdo1 + n, {uint8_t(cw), uint8_t(cw >> 8), uint8_t(torque), uint8_t(uint16_t(torque) >> 8)}));
    }
    bus.receive(frame(kSync, {}));
  }
  EXPECT_TRUE(emulator.in_motion()) << emulator.reflex_reason();
  return emulator.state().q;
}

TEST(CanServeGravity, WithoutTheRobotsCompensationTheMastersTorqueHoldsTheArmAsWellAsTheRobotDoes) {
  const std::array<double, 7> by_robot = hold(true), by_master = hold(false);
  // The difference: the master's quantization (3 / 0.5 mN m) and its one cycle of latency.
  for (int j = 0; j < 7; ++j) EXPECT_NEAR(by_master[j], by_robot[j], 1e-3) << "joint " << j + 1;
}

TEST_F(CanServe, WithTheRobotsGravityCompensationTheSameTorqueIsAJump) {
  // 0x2000 = 1 (default): the robot adds gravity itself, so a master sending it too commands a
  // jump of g(q) in the first cycle.
  bus.receive(frame(kNmt, {0x01, 0x00}));
  for (uint16_t cw : {0x06, 0x07, 0x0F}) {
    const auto g = holding_torque(emulator());
    for (int n = 1; n <= 7; ++n) rpdo1(n, cw, g[n - 1]);
    sync();
  }
  EXPECT_TRUE(rt::has(emulator().state().current_errors, rt::Error::controller_torque_discontinuity));
}

// The example controllers' law (bridge/examples/can_joint_impedance.*) on the in-memory bus with
// the bus's latency: the torque answers the TPDOs of the previous SYNC. Returns the cycles run
// before a reflex (all of them when none).
int impedance_cycles(const std::array<double, 7>& K, const std::array<double, 7>& D, int cycles) {
  RecordingArm arm("");
  DriveBus bus{BusSettings{}, arm};
  const rt::Emulator& emulator = arm.arm.server().emulator();
  bus.receive(frame(kNmt, {0x01, 0x00}));
  std::array<double, 7> q{}, dq{}, q0{}, tau{};
  const auto cycle = [&](uint16_t cw) {
    for (int n = 1; n <= 7; ++n) {
      const auto raw = static_cast<int16_t>(std::lround(tau[n - 1] / torque_step(n - 1)));
      bus.receive(frame(kRpdo1 + n, {uint8_t(cw), uint8_t(cw >> 8), uint8_t(raw), uint8_t(uint16_t(raw) >> 8)}));
    }
    bus.clear_sent();
    bus.receive(frame(kSync, {}));
    for (const Frame& f : bus.sent()) {
      const int j = static_cast<int>(f.id & 0x7F) - 1;
      if ((f.id & 0x780) == kTpdo1) q[j] = static_cast<int32_t>(get_le(&f.data[2], 4)) * 1e-6;
      if ((f.id & 0x780) == kTpdo2) dq[j] = static_cast<int32_t>(get_le(&f.data[0], 4)) * 1e-6;
    }
  };
  for (uint16_t cw : {0x06, 0x07, 0x0F, 0x0F}) cycle(cw);
  q0 = q;
  for (int k = 0; k < cycles; ++k) {
    cycle(0x0F);
    if (!emulator.in_motion()) return k;
    const double offset = 0.1 * (1.0 - std::cos(2.0 * M_PI * k * 1e-3 / 4.0));
    for (int j = 0; j < 7; ++j) tau[j] = K[j] * (q0[j] + (j == 0 || j == 3 ? offset : 0.0) - q[j]) - D[j] * dq[j];
  }
  return cycles;
}

TEST(CanServeExamples, TheExamplesGainsAreStableWithTheBusLatency) {
  EXPECT_EQ(impedance_cycles({300, 300, 300, 300, 120, 60, 20}, {25, 25, 25, 10, 8, 5, 2}, 3000), 3000);
  // libfranka's gains oscillated at two cycles' latency on a frictionless wrist; the Panda plant's
  // static friction damps that, so only the examples' own gains are asserted (docs/can.md).
}

TEST(CanBusLoad, FrameLengthsAreCanbusloadsWorstCase) {
  // can-utils canbusload (default: worst-case stuffing), measured on vcan in the notes: an 11-bit
  // frame of 0 / 4 / 8 data bytes counts 55 / 95 / 135 bits.
  EXPECT_EQ(frame_bits(0), 55u);
  EXPECT_EQ(frame_bits(4), 95u);
  EXPECT_EQ(frame_bits(8), 135u);
  // One default CST cycle of the seven drives on one bus: SYNC, 7 RPDO1 (4 B), 7 TPDO1 (8 B),
  // 7 TPDO2 (7 B) = 2540 bits: 254 % of 1 Mbit/s at 1 kHz (the notes' table, worst case).
  EXPECT_EQ(frame_bits(0) + 7 * (frame_bits(4) + frame_bits(8) + frame_bits(7)), 2540u);
}

TEST(CanSplit, JointsSpreadOverNumberedInterfacesInBlocks) {
  EXPECT_EQ(split_interfaces("vcan0", 1), std::vector<std::string>{"vcan0"});
  EXPECT_EQ(split_interfaces("vcan2", 3), (std::vector<std::string>{"vcan2", "vcan3", "vcan4"}));
  EXPECT_THROW(split_interfaces("can", 2), std::invalid_argument);
  EXPECT_THROW(split_interfaces("vcan0", 8), std::invalid_argument);
  std::vector<int> per_interface(4);
  for (int j = 0; j < 7; ++j) ++per_interface[interface_of_joint(j, 4)];
  EXPECT_EQ(per_interface, (std::vector<int>{2, 2, 2, 1}));   // 4 buses: at most 2 joints, 63-77 % each at 1 Mbit/s
  for (int j = 0; j < 7; ++j) EXPECT_EQ(interface_of_joint(j, 1), 0);
}

}  // namespace
}  // namespace csp::can
