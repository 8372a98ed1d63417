// The CANopen joint drives (bridge/can, docs/can.md). Expected frames are written from the CiA 301
// and CiA 402 specification text (SDO command specifiers, abort codes, NMT, heartbeat and 402
// statusword masks), byte by byte, not produced by the encoder under test. The EDS is read back
// by Debian's python3 configparser and by the unmodified python-canopen; the decoder is fuzzed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <random>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "csp/can/drive_bus.hpp"
#include "csp/can/export.hpp"

namespace csp::can {
namespace {

// The robot behind the drives in these tests: records every command, returns a set state, and
// clears its errors on error recovery (what the emulator's automatic_error_recovery does).
class TestArm : public Arm {
 public:
  ArmState state;
  std::vector<ArmCommand> commands;
  ArmState cycle(const ArmCommand& command) override {
    commands.push_back(command);
    if (command.error_recovery) state.errors = rt::ErrorSet{};
    return state;
  }
  ArmState measured() const override { return state; }
};

class CanBus : public ::testing::Test {
 protected:
  TestArm arm;
  DriveBus bus{BusSettings{}, arm};

  // Sends one frame (candump notation) and returns what the nodes answered.
  std::vector<std::string> send(const std::string& frame) {
    bus.clear_sent();
    bus.receive(parse_frame(frame));
    return sent();
  }
  std::vector<std::string> sent() const {
    std::vector<std::string> frames;
    for (const Frame& f : bus.sent()) frames.push_back(to_string(f));
    return frames;
  }
  std::vector<std::string> sync() { return send("080#"); }
  // Statusword of `node` from its TPDO1 in the frames sent.
  int statusword_in(const std::vector<std::string>& frames, int node) {
    char prefix[8];
    std::snprintf(prefix, sizeof prefix, "%03X#", 0x180 + node);
    for (const std::string& f : frames)
      if (f.rfind(prefix, 0) == 0) return std::stoi(f.substr(4, 2), nullptr, 16) | std::stoi(f.substr(6, 2), nullptr, 16) << 8;
    return -1;
  }
  // Statusword of `node` read by SDO (expedited upload of 0x6041: answer 0x4B, 2 bytes).
  int statusword_by_sdo(int node) {
    char request[32];
    std::snprintf(request, sizeof request, "%03X#4041600000000000", 0x600 + node);
    const std::vector<std::string> reply = send(request);
    EXPECT_EQ(reply.size(), 1u);
    EXPECT_EQ(reply[0].substr(0, 12), (std::ostringstream() << std::hex << std::uppercase << 0x580 + node).str() + "#4B416000");
    return std::stoi(reply[0].substr(12, 2), nullptr, 16) | std::stoi(reply[0].substr(14, 2), nullptr, 16) << 8;
  }
  // RPDO1 (controlword, target torque per mille) to every node.
  void rpdo1_all(int controlword, int torque) {
    for (int n = 1; n <= 7; ++n) {
      char frame[32];
      std::snprintf(frame, sizeof frame, "%03X#%02X%02X%02X%02X", 0x200 + n, controlword & 0xFF, (controlword >> 8) & 0xFF,
                    torque & 0xFF, (torque >> 8) & 0xFF);
      bus.receive(parse_frame(frame));
    }
  }
  void enable_all() {
    send("000#0100");
    for (int cw : {0x06, 0x07, 0x0F}) {
      rpdo1_all(cw, 0);
      sync();
    }
  }
};

// Masks and values of CiA 402's statusword table (also python-canopen's State402.SW_MASK).
bool in_state(int statusword, int mask, int value) { return (statusword & mask) == value; }

TEST(CanFrame, CandumpNotationRoundTripsAndBadTextIsNamed) {
  const Frame f = parse_frame("602#2B40600006000000");
  EXPECT_EQ(f.id, 0x602u);
  EXPECT_EQ(f.dlc, 8);
  EXPECT_EQ(f.data[0], 0x2B);
  EXPECT_EQ(f.data[4], 0x06);
  EXPECT_EQ(to_string(f), "602#2B40600006000000");
  EXPECT_EQ(to_string(parse_frame("080#")), "080#");
  for (const char* bad : {"602", "#00", "800#00", "602#2B4", "602#GG", "602#001122334455667788"})
    EXPECT_THROW(parse_frame(bad), std::invalid_argument) << bad;
}

TEST(CanObjectTable, SortedUniqueAndCiaConstants) {
  const ObjectTable t = object_table(panda_joint_drive(1));
  for (size_t i = 1; i < t.entries.size(); ++i)
    EXPECT_TRUE(t.entries[i - 1].index < t.entries[i].index ||
                (t.entries[i - 1].index == t.entries[i].index && t.entries[i - 1].subindex < t.entries[i].subindex));
  for (const Object& o : t.objects) {
    ASSERT_GT(o.count, 0);
    EXPECT_EQ(t.entries[o.first].index, o.index);
    if (t.entries[o.first].name == "Highest sub-index supported") {
      EXPECT_EQ(t.entries[o.first].default_value, t.entries[o.first + o.count - 1].subindex);
    }
  }
  // CiA 402: device type 0x0192 (402) with 0x0002 (servo drive); 0x6502 bit mode-1 for 8, 9, 10.
  EXPECT_EQ(t.entries[t.find(0x1000, 0)].default_value, 0x00020192);
  EXPECT_EQ(t.entries[t.find(0x6502, 0)].default_value, (1 << 7) | (1 << 8) | (1 << 9));
  // Every libfranka error has a sub-index of 0x2002 named after it.
  EXPECT_EQ(t.entries[t.find(0x2002, 32)].name, "communication_constraints_violation");
}

TEST(CanObjectTable, TorqueScalingCoversFrankaLimitsWithDocumentedResolution) {
  // tau_max of Panda/FR3 (configs/robots/panda.yaml): 87 N m joints 1-4, 12 N m joints 5-7.
  const double tau_max[7] = {87, 87, 87, 87, 12, 12, 12};
  for (int j = 1; j <= 7; ++j) {
    const JointDrive d = panda_joint_drive(j);
    const double step = d.rated_torque_mNm * 1e-6;   // per mille of rated torque [N m]
    EXPECT_GE(32767 * step, tau_max[j - 1]) << "joint " << j;
    EXPECT_NEAR(d.max_torque_per_mille * step, tau_max[j - 1], step / 2);
    EXPECT_LE(step, j <= 4 ? 0.003 : 0.0005);
    EXPECT_LT(d.position_min_urad, d.position_max_urad);
  }
  EXPECT_EQ(panda_joint_drive(4).position_max_urad, -69800);
  EXPECT_EQ(panda_joint_drive(6).position_max_urad, 3752500);
}

// --- SDO server, golden frames from CiA 301 ---------------------------------------------------
TEST_F(CanBus, BootUpMessagesThenExpeditedSdo) {
  EXPECT_EQ(sent(), (std::vector<std::string>{"701#00", "702#00", "703#00", "704#00", "705#00", "706#00", "707#00"}));
  // Download 2 bytes (0x2B) of controlword 0x06 to node 2 -> confirmation 0x60.
  EXPECT_EQ(send("602#2B40600006000000"), std::vector<std::string>{"582#6040600000000000"});
  // Upload 0x1000 (0x40) -> 4 bytes expedited (0x43): 0x00020192 little-endian.
  EXPECT_EQ(send("601#4000100000000000"), std::vector<std::string>{"581#4300100092010200"});
  EXPECT_EQ(send("607#4002650000000000"), std::vector<std::string>{"587#4302650080030000"});
  // 1 byte (0x4F): modes of operation display = 10 (CST) by default.
  EXPECT_EQ(send("601#4061600000000000"), std::vector<std::string>{"581#4F6160000A000000"});
  // Rated torque of joint 5: 500 mN m.
  EXPECT_EQ(send("605#4076600000000000"), std::vector<std::string>{"585#43766000F4010000"});
  // Heartbeat producer time 0x1017 = 0x01F4 ms, written and read back.
  EXPECT_EQ(send("601#2B171000F4010000"), std::vector<std::string>{"581#6017100000000000"});
  EXPECT_EQ(send("601#4017100000000000"), std::vector<std::string>{"581#4B171000F4010000"});
  // Download without size indication (0x22) takes the object's size.
  EXPECT_EQ(send("601#2217100064000000"), std::vector<std::string>{"581#6017100000000000"});
  EXPECT_EQ(send("601#4017100000000000"), std::vector<std::string>{"581#4B17100064000000"});
  // Frames for other nodes, and SDO requests shorter than 8 bytes, get no answer.
  EXPECT_TRUE(send("608#4000100000000000").empty());
  EXPECT_TRUE(send("601#40001000").empty());
}

TEST_F(CanBus, SegmentedUploadOfDeviceName) {
  // "CSP emulated Franka joint drive": 31 = 0x1F bytes; initiate answer 0x41 (segmented, size given).
  EXPECT_EQ(send("601#4008100000000000"), std::vector<std::string>{"581#410810001F000000"});
  // Segments: toggle alternates 0x00/0x10; 7 bytes each; the last has n = 7 - 3 = 4 and c = 1: 0x09.
  EXPECT_EQ(send("601#6000000000000000"), std::vector<std::string>{"581#0043535020656D75"});   // "CSP emu"
  EXPECT_EQ(send("601#7000000000000000"), std::vector<std::string>{"581#106C617465642046"});   // "lated F"
  EXPECT_EQ(send("601#6000000000000000"), std::vector<std::string>{"581#0072616E6B61206A"});   // "ranka j"
  EXPECT_EQ(send("601#7000000000000000"), std::vector<std::string>{"581#106F696E74206472"});   // "oint dr"
  EXPECT_EQ(send("601#6000000000000000"), std::vector<std::string>{"581#0969766500000000"});   // "ive", last
  // A segment request with no transfer running: unknown command 0x05040001.
  EXPECT_EQ(send("601#6000000000000000"), std::vector<std::string>{"581#8000000001000405"});
}

TEST_F(CanBus, SegmentedDownloadAndToggleErrors) {
  // Initiate segmented download of 2 bytes (0x21, size 2), one segment with n = 5, c = 1 (0x0B).
  EXPECT_EQ(send("601#2117100002000000"), std::vector<std::string>{"581#6017100000000000"});
  EXPECT_EQ(send("601#0BE8030000000000"), std::vector<std::string>{"581#2000000000000000"});
  EXPECT_EQ(send("601#4017100000000000"), std::vector<std::string>{"581#4B171000E8030000"});
  // 3 bytes (n = 4, c = 1: 0x09) for a 2-byte object: abort 0x06070012 instead of the confirmation.
  EXPECT_EQ(send("601#2117100003000000"), std::vector<std::string>{"581#6017100000000000"});
  EXPECT_EQ(send("601#09E8030100000000"), std::vector<std::string>{"581#8017100012000706"});
  // A first segment with the toggle bit set: abort 0x05030000.
  EXPECT_EQ(send("601#2117100002000000"), std::vector<std::string>{"581#6017100000000000"});
  EXPECT_EQ(send("601#1BE8030000000000"), std::vector<std::string>{"581#8017100000000305"});
  // Upload segments with the wrong toggle: abort 0x05030000 naming 0x1008.
  EXPECT_EQ(send("601#4008100000000000"), std::vector<std::string>{"581#410810001F000000"});
  EXPECT_EQ(send("601#7000000000000000"), std::vector<std::string>{"581#8008100000000305"});
}

TEST_F(CanBus, EveryAbortCode) {
  const std::vector<std::pair<std::string, std::string>> cases{
      {"601#4034120000000000", "581#8034120000000206"},   // 0x06020000 object does not exist
      {"601#4018100900000000", "581#8018100911000906"},   // 0x06090011 sub-index does not exist
      {"601#2340600006000000", "581#8040600012000706"},   // 0x06070012 length too high (4 bytes to U16)
      {"601#2F17100005000000", "581#8017100013000706"},   // 0x06070013 length too low (1 byte to U16)
      {"601#2B41600000000000", "581#8041600002000106"},   // 0x06010002 write a read-only object
      {"601#2300100000000000", "581#8000100002000106"},   // 0x06010002 write a const object
      {"601#4003200000000000", "581#8003200001000106"},   // 0x06010001 read a write-only object
      {"601#2F6060000B000000", "581#8060600031000906"},   // 0x06090031 value too high (mode 11)
      {"601#2F60600007000000", "581#8060600032000906"},   // 0x06090032 value too low (mode 7)
      {"601#E000000000000000", "581#8000000001000405"},   // 0x05040001 command specifier 7
      {"601#C000100000000000", "581#8000100001000405"},   // 0x05040001 block download (6): not supported
  };
  for (const auto& [request, reply] : cases) EXPECT_EQ(send(request), std::vector<std::string>{reply}) << request;
}

// --- NMT and heartbeat ------------------------------------------------------------------------
TEST_F(CanBus, NmtStatesAndHeartbeatBytes) {
  bus.clear_sent();
  bus.elapse(99'999);   // 0x1017 = 100 ms
  EXPECT_TRUE(sent().empty());
  bus.elapse(1);
  EXPECT_EQ(sent(), (std::vector<std::string>{"701#7F", "702#7F", "703#7F", "704#7F", "705#7F", "706#7F", "707#7F"}));
  EXPECT_TRUE(send("000#0100").empty());   // start all: no answer
  bus.clear_sent();
  bus.elapse(100'000);
  EXPECT_EQ(sent().front(), "701#05");
  send("000#0203");   // stop node 3
  bus.clear_sent();
  bus.elapse(100'000);
  EXPECT_EQ(sent()[2], "703#04");
  EXPECT_TRUE(send("603#4000100000000000").empty());   // no SDO in stopped
  send("000#8003");   // node 3 to pre-operational
  EXPECT_EQ(send("603#4000100000000000"), std::vector<std::string>{"583#4300100092010200"});
  // Reset communication: communication objects back to their defaults, application objects kept.
  send("601#2B17100032000000");
  send("601#2F60600008000000");
  EXPECT_EQ(send("000#8201"), std::vector<std::string>{"701#00"});
  EXPECT_EQ(send("601#4017100000000000"), std::vector<std::string>{"581#4B17100064000000"});
  EXPECT_EQ(send("601#4060600000000000"), std::vector<std::string>{"581#4F60600008000000"});
  // Reset node: everything back, boot-up in pre-operational.
  EXPECT_EQ(send("000#8101"), std::vector<std::string>{"701#00"});
  EXPECT_EQ(send("601#4060600000000000"), std::vector<std::string>{"581#4F6060000A000000"});
  EXPECT_EQ(bus.node(0).nmt_state(), NmtState::kPreOperational);
  // Malformed NMT frames are ignored.
  send("000#01");
  EXPECT_EQ(bus.node(0).nmt_state(), NmtState::kPreOperational);
}

TEST_F(CanBus, HeartbeatConsumerTimeoutFaultsWithEmcy8130) {
  send("000#0100");
  // 0x1016 sub 1: master node 0x7F, 50 ms.
  EXPECT_EQ(send("601#2316100132007F00"), std::vector<std::string>{"581#6016100100000000"});
  send("77F#05");
  bus.clear_sent();
  bus.elapse(50'000);
  EXPECT_TRUE(sent().empty());
  bus.elapse(1);
  // EMCY: code 0x8130, error register 0x11 (generic + communication), no Franka error, joint 1.
  EXPECT_EQ(sent(), std::vector<std::string>{"081#308111FF01000000"});
  EXPECT_TRUE(in_state(statusword_by_sdo(1), 0x4F, 0x0F));   // fault reaction active
}

// --- CiA 402 ----------------------------------------------------------------------------------
TEST_F(CanBus, StateWalkBySdoUnderSpecMasks) {
  EXPECT_TRUE(in_state(statusword_by_sdo(2), 0x4F, 0x40));   // switch on disabled
  send("602#2B40600006000000");
  EXPECT_TRUE(in_state(statusword_by_sdo(2), 0x6F, 0x21));   // ready to switch on
  send("602#2B40600007000000");
  EXPECT_TRUE(in_state(statusword_by_sdo(2), 0x6F, 0x23));   // switched on
  send("602#2B4060000F000000");
  EXPECT_TRUE(in_state(statusword_by_sdo(2), 0x6F, 0x27));   // operation enabled
  send("602#2B40600007000000");
  EXPECT_TRUE(in_state(statusword_by_sdo(2), 0x6F, 0x23));   // disable operation
  send("602#2B40600000000000");
  EXPECT_TRUE(in_state(statusword_by_sdo(2), 0x4F, 0x40));   // disable voltage
}

TEST_F(CanBus, StateWalkByRpdoShowsInTheNextTpdo) {
  send("000#0100");
  rpdo1_all(0x06, 0);
  EXPECT_TRUE(in_state(statusword_in(sync(), 1), 0x4F, 0x40));   // sampled at the SYNC, before the latch
  EXPECT_TRUE(in_state(statusword_in(sync(), 1), 0x6F, 0x21));
  rpdo1_all(0x07, 0);
  sync();
  EXPECT_TRUE(in_state(statusword_in(sync(), 4), 0x6F, 0x23));
  rpdo1_all(0x0F, 0);
  sync();
  const std::vector<std::string> frames = sync();
  for (int n = 1; n <= 7; ++n) EXPECT_TRUE(in_state(statusword_in(frames, n), 0x6F, 0x27)) << n;
  EXPECT_EQ(bus.node(6).drive_state(), DriveState::kOperationEnabled) << drive_state_name(bus.node(6).drive_state());
  EXPECT_EQ(bus.node(6).nmt_state(), NmtState::kOperational) << nmt_state_name(bus.node(6).nmt_state());
  EXPECT_TRUE(arm.commands.back().joints[6].operation_enabled);
}

TEST_F(CanBus, QuickStopThenSwitchOnDisabled) {
  enable_all();
  rpdo1_all(0x02, 0);   // quick stop
  sync();
  EXPECT_TRUE(in_state(statusword_by_sdo(3), 0x6F, 0x07));
  sync();   // 0x605A = 2: the stop is over -> switch on disabled
  EXPECT_TRUE(in_state(statusword_by_sdo(3), 0x4F, 0x40));
}

TEST_F(CanBus, ReflexFaultsEveryJointWithEmcyAndFaultResetRecovers) {
  enable_all();
  arm.state.errors.set(rt::Error::joint_velocity_violation);   // libfranka index 3
  rpdo1_all(0x0F, 0);
  const std::vector<std::string> frames = sync();
  // EMCY 0xFF04 (0xFF01 + 3), error register 0x81 (generic + manufacturer), error 3, joint n.
  for (int n = 1; n <= 7; ++n) {
    char emcy[32];
    std::snprintf(emcy, sizeof emcy, "%03X#04FF8103%02X000000", 0x80 + n, n);
    EXPECT_NE(std::find(frames.begin(), frames.end(), emcy), frames.end()) << emcy;
    EXPECT_TRUE(in_state(statusword_by_sdo(n), 0x4F, 0x0F)) << n;   // fault reaction active
  }
  EXPECT_EQ(send("601#4002200400000000"), std::vector<std::string>{"581#4F02200401000000"});   // 0x2002 sub 4
  sync();
  EXPECT_TRUE(in_state(statusword_by_sdo(5), 0x4F, 0x08));   // fault
  EXPECT_FALSE(arm.commands.back().joints[0].operation_enabled);
  // Fault reset: bit 7 rising edge -> switch on disabled, EMCY 0x0000, automatic error recovery.
  rpdo1_all(0x80, 0);
  const std::vector<std::string> reset = sync();
  EXPECT_NE(std::find(reset.begin(), reset.end(), "081#000000FF01000000"), reset.end());
  EXPECT_TRUE(arm.commands.back().error_recovery);
  EXPECT_TRUE(in_state(statusword_by_sdo(1), 0x4F, 0x40));
  sync();
  EXPECT_FALSE(arm.commands.back().error_recovery);   // once per reset
  EXPECT_TRUE(in_state(statusword_by_sdo(1), 0x4F, 0x40));
}

TEST_F(CanBus, CommunicationConstraintsViolationIsEmcy8250) {
  enable_all();
  arm.state.errors.set(rt::Error::communication_constraints_violation);   // libfranka index 31
  const std::vector<std::string> frames = sync();
  EXPECT_NE(std::find(frames.begin(), frames.end(), "081#5082111F01000000"), frames.end());
  EXPECT_NE(std::find(frames.begin(), frames.end(), "087#5082111F07000000"), frames.end());
}

TEST(CanEmcy, EveryReflexSendsTheCodeDocumented) {
  std::ifstream docs(CSP_SOURCE_DIR "/docs/can.md");
  ASSERT_TRUE(docs) << "docs/can.md";
  const std::regex row(R"(\| (\d+) \| (\w+) \| 0x([0-9A-F]{4}) \|)");
  int rows = 0;
  for (std::string line; std::getline(docs, line);) {
    std::smatch m;
    if (!std::regex_match(line, m, row)) continue;
    const int error = std::stoi(m[1]);
    ASSERT_LT(error, rt::kNumErrors);
    EXPECT_EQ(m[2].str(), rt::error_name(static_cast<rt::Error>(error)));
    TestArm arm;
    DriveBus bus(BusSettings{}, arm);
    bus.receive(parse_frame("000#0100"));
    arm.state.errors.set(static_cast<rt::Error>(error));
    bus.clear_sent();
    bus.on_sync();
    const std::string code = m[3].str();
    char emcy[32];   // joint 3's EMCY: code little-endian, register, error index, joint
    std::snprintf(emcy, sizeof emcy, "083#%s%s%02X%02X03000000", code.substr(2, 2).c_str(), code.substr(0, 2).c_str(),
                  error == static_cast<int>(rt::Error::communication_constraints_violation) ? 0x11 : 0x81, error);
    std::vector<std::string> frames;
    for (const Frame& f : bus.sent()) frames.push_back(to_string(f));
    EXPECT_NE(std::find(frames.begin(), frames.end(), emcy), frames.end()) << emcy;
    ++rows;
  }
  EXPECT_EQ(rows, rt::kNumErrors);
}

// --- PDOs ------------------------------------------------------------------------------------
TEST_F(CanBus, SyncLatchingAppliesAnRpdoAtTheNextSync) {
  enable_all();
  const size_t k = arm.commands.size();
  rpdo1_all(0x0F, 1000);   // after SYNC k: 1000 per mille = 3 N m (joints 1-4), 0.5 N m (5-7)
  EXPECT_EQ(arm.commands.size(), k);
  EXPECT_EQ(arm.commands.back().joints[0].target_torque, 0.0);
  sync();   // SYNC k+1
  ASSERT_EQ(arm.commands.size(), k + 1);
  EXPECT_NEAR(arm.commands.back().joints[0].target_torque, 3.0, 1e-12);
  EXPECT_NEAR(arm.commands.back().joints[6].target_torque, 0.5, 1e-12);
  EXPECT_TRUE(arm.commands.back().complete);
  sync();   // no RPDO: lost, the last target stays latched
  EXPECT_FALSE(arm.commands.back().complete);
  EXPECT_NEAR(arm.commands.back().joints[0].target_torque, 3.0, 1e-12);
  EXPECT_EQ(bus.counters().lost_cycles, 1u);
  send("201#0F00E803");   // only joint 1: a torn cycle
  sync();
  EXPECT_EQ(bus.counters().torn_cycles, 1u);
  EXPECT_FALSE(arm.commands.back().complete);
}

TEST_F(CanBus, TorqueLimitedToMaxTorqueWithStatuswordBit11) {
  enable_all();
  rpdo1_all(0x0F, 32000);   // 96 N m asked; 0x6072 = 29000 per mille = 87 N m
  sync();
  EXPECT_NEAR(arm.commands.back().joints[0].target_torque, 87.0, 1e-9);
  EXPECT_NEAR(arm.commands.back().joints[4].target_torque, 12.0, 1e-9);
  rpdo1_all(0x0F, 32000);
  EXPECT_TRUE(statusword_in(sync(), 1) & 0x0800);
}

TEST_F(CanBus, TpdoCarriesTheMeasuredStateInDocumentedScaling) {
  send("000#0100");
  arm.state.joints[0].q = 0.5;            // 500000 urad = 0x0007A120
  arm.state.joints[0].tau_J = -3.0;       // -1000 per mille of 3000 mN m = 0xFC18
  arm.state.joints[0].dq = -0.000002;     // -2 urad/s
  sync();
  const std::vector<std::string> frames = sync();
  EXPECT_NE(std::find(frames.begin(), frames.end(), "181#400220A1070018FC"), frames.end());
  // TPDO2: velocity -2 (FEFFFFFF), tau_ext 0, mode display 10.
  EXPECT_NE(std::find(frames.begin(), frames.end(), "281#FEFFFFFF00000A"), frames.end());
}

TEST_F(CanBus, PdoRemapBySdoAsACiA302Master) {
  EXPECT_EQ(send("601#23001A0108006160"), std::vector<std::string>{"581#80001A0122000008"});   // PDO valid: 0x08000022
  EXPECT_EQ(send("601#2300180181010080"), std::vector<std::string>{"581#6000180100000000"});   // COB-ID bit 31: invalid
  EXPECT_EQ(send("601#23001A0108006160"), std::vector<std::string>{"581#80001A0122000008"});   // sub 0 still 3
  EXPECT_EQ(send("601#2F001A0000000000"), std::vector<std::string>{"581#60001A0000000000"});
  EXPECT_EQ(send("601#23001A0120000010"), std::vector<std::string>{"581#80001A0141000406"});   // 0x1000 not mappable
  EXPECT_EQ(send("601#23001A0108006160"), std::vector<std::string>{"581#60001A0100000000"});   // 0x6061, 8 bits
  EXPECT_EQ(send("601#23001A0220006460"), std::vector<std::string>{"581#60001A0200000000"});   // 0x6064, 32 bits
  EXPECT_EQ(send("601#23001A0320006C60"), std::vector<std::string>{"581#60001A0300000000"});   // 0x606C, 32 bits
  EXPECT_EQ(send("601#2F001A0003000000"), std::vector<std::string>{"581#80001A0042000406"});   // 72 bits: 0x06040042
  EXPECT_EQ(send("601#2F001A0002000000"), std::vector<std::string>{"581#60001A0000000000"});
  EXPECT_EQ(bus.node(0).value(0x1A00, 0), 2);
  EXPECT_EQ(send("601#2300180181010000"), std::vector<std::string>{"581#6000180100000000"});   // valid again
  EXPECT_EQ(send("601#2300180182010000"), std::vector<std::string>{"581#8000180130000906"});   // new id while valid
  EXPECT_EQ(send("601#2F00180200000000"), std::vector<std::string>{"581#8000180230000906"});   // TPDO type 0
  send("000#0101");
  arm.state.joints[0].q = 0.5;
  sync();
  const std::vector<std::string> frames = sync();
  EXPECT_NE(std::find(frames.begin(), frames.end(), "181#0A20A10700"), frames.end());   // mode 10, 500000 urad
  // The remap survives until reset communication restores the default mapping.
  send("000#8201");
  EXPECT_EQ(send("601#40001A0000000000"), std::vector<std::string>{"581#4F001A0003000000"});
}

// CiA 301 7.3.5, "restricted CAN-IDs": NMT 0x000, 0x001-0x07F, 0x101-0x180, SDO 0x581-0x5FF and
// 0x601-0x67F, 0x6E0-0x6FF, heartbeat 0x701-0x77F, 0x780-0x7FF; no SYNC, TIME, EMCY, PDO or SDO may
// use them. A COB-ID (bits 0-10, bit 31 = "does not exist") written by SDO expedited download of
// 4 bytes (0x23) is refused with abort 0x06090030 (invalid value for parameter) when it switches the
// object on with a restricted id or the SYNC's 0x080, or moves an object that exists.
TEST_F(CanBus, RestrictedCanIdsAreRefusedForPdosAndEmcy) {
  const std::vector<uint32_t> refused{0x000, 0x001, 0x07F, 0x080, 0x101, 0x180, 0x581, 0x5FF,
                                      0x601, 0x67F, 0x6E0, 0x6FF, 0x701, 0x77F, 0x780, 0x7FF};
  const std::vector<uint32_t> allowed{0x100, 0x190, 0x580, 0x600, 0x680, 0x6DF, 0x700};
  // "601#23 <index LE> <sub> <value LE>"; the answer 60 (done) or 80 + abort code LE.
  const auto download = [&](int index, int sub, uint32_t value) {
    char request[32];
    std::snprintf(request, sizeof request, "601#23%02X%02X%02X%02X%02X%02X%02X", index & 0xFF, index >> 8, sub, value & 0xFF,
                  (value >> 8) & 0xFF, (value >> 16) & 0xFF, value >> 24);
    return send(request);
  };
  const auto answer = [](int index, int sub, const char* tail) {
    char reply[32];
    std::snprintf(reply, sizeof reply, "581#%s%02X%02X%02X%s", tail[0] == '6' ? "60" : "80", index & 0xFF, index >> 8, sub, tail + 2);
    return std::vector<std::string>{reply};
  };
  const char* done = "6000000000";
  const char* invalid_value = "8030000906";   // 0x06090030 little-endian
  // TPDO1 (0x1800), RPDO2 (0x1401) and EMCY (0x1014, no sub-index).
  for (const auto& [index, sub] : {std::pair{0x1800, 1}, std::pair{0x1401, 1}, std::pair{0x1014, 0}}) {
    // A valid object cannot be moved, not even to a free id: bit 31 first.
    EXPECT_EQ(download(index, sub, 0x1F0), answer(index, sub, invalid_value)) << std::hex << index;
    EXPECT_EQ(download(index, sub, 0x80000000u | 0x1F0), answer(index, sub, done)) << std::hex << index;
    for (uint32_t id : refused) {
      EXPECT_EQ(download(index, sub, id), answer(index, sub, invalid_value)) << std::hex << index << " id " << id;
      EXPECT_EQ(download(index, sub, 0x80000000u | id), answer(index, sub, done)) << std::hex << index << " id " << id;   // off: any id
    }
    for (uint32_t id : allowed) {
      EXPECT_EQ(download(index, sub, id), answer(index, sub, done)) << std::hex << index << " id " << id;
      EXPECT_EQ(download(index, sub, 0x80000000u | id), answer(index, sub, done)) << std::hex << index << " id " << id;
    }
  }
  // Nothing the refused writes asked for reaches the bus: switched on at free ids, the objects send
  // there, and no frame goes out on a restricted id or the SYNC's.
  download(0x1800, 1, 0x190);
  download(0x1014, 0, 0x0F1);
  std::vector<std::string> frames = send("000#0100");
  for (const char* request : {"080#", "201#0F", "080#"})   // an RPDO shorter than its mapping: EMCY 0x8210
    for (const std::string& f : send(request)) frames.push_back(f);
  EXPECT_NE(std::find(frames.begin(), frames.end(), "0F1#108200FF01000000"), frames.end());
  EXPECT_EQ(std::count_if(frames.begin(), frames.end(), [](const std::string& f) { return f.rfind("190#", 0) == 0; }), 2);
  EXPECT_EQ(std::count_if(frames.begin(), frames.end(), [](const std::string& f) { return f.rfind("181#", 0) == 0; }), 0);
  for (const std::string& f : frames) {
    const uint32_t id = std::stoul(f.substr(0, 3), nullptr, 16);
    EXPECT_FALSE(is_restricted_can_id(id) || id == kSync) << f;
  }
}

// A drive says it follows its target (statusword bit 12) only while the robot runs a motion on the
// targets; when the motion ends with the drive still in operation enabled (another drive left),
// bit 12 clears and the drive sends EMCY 0xFF00 (error register unchanged, no libfranka error).
TEST_F(CanBus, DrivesLeftEnabledWhenTheMotionEndsClearBit12AndSendEmcyFF00) {
  send("000#0100");
  for (int cw : {0x06, 0x07}) {
    rpdo1_all(cw, 0);
    sync();
  }
  rpdo1_all(0x0F, 0);
  sync();   // enabled; the arm has not started a motion (TestArm: motion = false)
  for (int n = 1; n <= 7; ++n) {
    EXPECT_TRUE(in_state(statusword_by_sdo(n), 0x6F, 0x27)) << n;
    EXPECT_EQ(statusword_by_sdo(n) & 0x1000, 0) << n;   // enabled, but nothing acts on the target
  }
  arm.state.motion = true;
  rpdo1_all(0x0F, 0);
  sync();
  for (int n = 1; n <= 7; ++n) EXPECT_EQ(statusword_by_sdo(n) & 0x1000, 0x1000) << n;
  EXPECT_EQ(statusword_in(sync(), 4) & 0x1000, 0x1000);   // and the TPDO1 carries it
  // Joint 3 leaves operation enabled (disable operation, 0x07): the robot's motion ends.
  arm.state.motion = false;
  rpdo1_all(0x0F, 0);
  send("203#07000000");
  const std::vector<std::string> frames = sync();
  for (int n = 1; n <= 7; ++n) {
    char emcy[32];   // code 0xFF00 little-endian, error register 0, libfranka error 0xFF (none), joint n
    std::snprintf(emcy, sizeof emcy, "%03X#00FF00FF%02X000000", 0x80 + n, n);
    EXPECT_EQ(std::count(frames.begin(), frames.end(), emcy), n == 3 ? 0 : 1) << emcy;
    const int statusword = statusword_by_sdo(n);
    EXPECT_TRUE(in_state(statusword, 0x6F, n == 3 ? 0x23 : 0x27)) << n;
    EXPECT_EQ(statusword & 0x1000, 0) << n;
  }
  EXPECT_EQ(statusword_in(sync(), 4) & 0x1000, 0);
  // Once: the next cycles send no more.
  rpdo1_all(0x0F, 0);
  const std::vector<std::string> later = sync();
  EXPECT_EQ(std::count_if(later.begin(), later.end(), [](const std::string& f) { return f.rfind("08", 0) == 0; }), 0);
}

TEST_F(CanBus, ShortRpdoIsNotProcessedEmcy8210) {
  enable_all();
  EXPECT_EQ(send("201#0F"), std::vector<std::string>{"081#108200FF01000000"});
  EXPECT_EQ(send("201#0F00000000"), std::vector<std::string>{"081#208200FF01000000"});   // too long: used, EMCY 0x8220
  EXPECT_EQ(bus.counters().ignored_frames, 0u);
  send("7E5#0102");   // nobody's COB-ID
  EXPECT_EQ(bus.counters().ignored_frames, 1u);
}

// --- EDS and DBC -----------------------------------------------------------------------------
std::string run(const std::string& command) {
  std::string output;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return "";
  char buffer[4096];
  while (size_t n = fread(buffer, 1, sizeof buffer, pipe)) output.append(buffer, n);
  const int status = pclose(pipe);
  if (status != 0) output += "\nexit status " + std::to_string(status);
  return output;
}

std::string write_eds(int joint) {
  const std::string path = ::testing::TempDir() + "csp_joint" + std::to_string(joint) + ".eds";
  std::ofstream(path) << make_eds(panda_joint_drive(joint));
  return path;
}

// What every entry should read as: "index sub datatype access pdo default low high name".
std::set<std::string> expected_entries(int joint, int node) {
  const ObjectTable t = object_table(panda_joint_drive(joint));
  std::set<std::string> lines;
  for (const Entry& e : t.entries) {
    std::ostringstream line;
    const int bits = 8 * size_of(e.type);
    const bool full_range = e.type == DataType::kVisibleString ||
                            (is_signed(e.type) ? e.low == -(int64_t{1} << (bits - 1)) && e.high == (int64_t{1} << (bits - 1)) - 1
                                               : e.low == 0 && e.high == (int64_t{1} << bits) - 1);
    line << std::hex << std::uppercase << e.index << ' ' << std::dec << int{e.subindex} << ' ' << static_cast<int>(e.type)
         << ' ' << access_name(e.access) << ' ' << (e.pdo_mappable ? 1 : 0) << ' ';
    if (e.access == Access::kWriteOnly) line << '-';
    else if (e.type == DataType::kVisibleString) line << e.text;
    else line << e.default_value + (e.plus_node_id ? node : 0);
    if (full_range) line << " - -";
    else line << ' ' << e.low << ' ' << e.high;
    line << ' ' << e.name;
    lines.insert(line.str());
  }
  return lines;
}

std::set<std::string> lines_of(const std::string& text) {
  std::set<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) lines.insert(line);
  return lines;
}

TEST(CanEds, ReadBackByPythonConfigparserObjectByObject) {
  const std::string script = ::testing::TempDir() + "read_eds.py";
  std::ofstream(script) << R"(import configparser, re, sys
c = configparser.ConfigParser(interpolation=None)
c.optionxform = str
c.read(sys.argv[1])
node = int(sys.argv[2])
def number(s, signed_bits):
    s = s.strip()
    if '$NODEID' in s:
        return int(s.replace('$NODEID', '').lstrip('+'), 0) + node
    v = int(s, 0)
    return v
listed = []
for section in ('MandatoryObjects', 'OptionalObjects', 'ManufacturerObjects'):
    n = int(c[section]['SupportedObjects'])
    listed += [int(c[section][str(i)], 0) for i in range(1, n + 1)]
for section in c.sections():
    m = re.fullmatch(r'([0-9A-F]{4})(?:sub([0-9A-F]+))?', section)
    if not m:
        continue
    s = c[section]
    index = int(m.group(1), 16)
    if m.group(2) is None and int(s['ObjectType'], 0) in (8, 9):
        subs = [x for x in c.sections() if x.startswith(m.group(1) + 'sub')]
        assert int(s['SubNumber']) == len(subs), section
        print('OBJECT %X %d %s' % (index, len(subs), s['ParameterName']))
        continue
    if m.group(2) is None:
        print('OBJECT %X 1 %s' % (index, s['ParameterName']))
    sub = int(m.group(2), 16) if m.group(2) else 0
    dt = int(s['DataType'], 0)
    if 'DefaultValue' not in s:
        default = '-'
    elif dt == 9:
        default = s['DefaultValue']
    else:
        default = str(number(s['DefaultValue'], 0))
    low = str(number(s['LowLimit'], 0)) if 'LowLimit' in s else '-'
    high = str(number(s['HighLimit'], 0)) if 'HighLimit' in s else '-'
    print('%X %d %d %s %s %s %s %s %s' % (index, sub, dt, s['AccessType'], s['PDOMapping'], default, low, high, s['ParameterName']))
print('LISTED ' + ' '.join('%X' % i for i in sorted(listed)))
)";
  for (int joint : {1, 5}) {
    const std::string output = run("/usr/bin/python3 " + script + " " + write_eds(joint) + " " + std::to_string(joint));
    std::set<std::string> read = lines_of(output), objects;
    std::string listed;
    for (auto it = read.begin(); it != read.end();) {
      if (it->rfind("OBJECT ", 0) == 0) objects.insert(*it), it = read.erase(it);
      else if (it->rfind("LISTED ", 0) == 0) listed = *it, it = read.erase(it);
      else ++it;
    }
    EXPECT_EQ(read, expected_entries(joint, joint)) << output;
    const ObjectTable t = object_table(panda_joint_drive(joint));
    std::set<std::string> expected_objects;
    std::string expected_listed = "LISTED";
    for (const Object& o : t.objects) {
      std::ostringstream line;
      line << "OBJECT " << std::hex << std::uppercase << o.index << std::dec << ' ' << o.count << ' ' << o.name;
      expected_objects.insert(line.str());
      std::ostringstream index;
      index << ' ' << std::hex << std::uppercase << o.index;
      expected_listed += index.str();
    }
    EXPECT_EQ(objects, expected_objects);
    EXPECT_EQ(listed, expected_listed);
  }
}

TEST(CanEds, PythonCanopenImportsItAsTheSameDictionary) {
  // The unmodified python-canopen (shared/vendor, MIT) on Debian's python3-can.
  const std::string vendor = CSP_SHARED_DATA_DIR "/../vendor/python-canopen";
  const std::string script = ::testing::TempDir() + "import_od.py";
  std::ofstream(script) << R"(import sys
sys.path.insert(0, sys.argv[1])
import canopen
od = canopen.import_od(sys.argv[2], int(sys.argv[3]))
def show(v):
    default = '-' if v.default is None else v.default
    print('%X %d %d %s %s %s' % (v.index, v.subindex, v.data_type, v.access_type, int(v.pdo_mappable), default))
for obj in od.values():
    if isinstance(obj, canopen.objectdictionary.ODVariable):
        show(obj)
    else:
        for v in obj.values():
            show(v)
)";
  for (int joint : {2, 7}) {
    const int node = joint;
    const std::string output =
        run("/usr/bin/python3 " + script + " " + vendor + " " + write_eds(joint) + " " + std::to_string(node) + " 2>&1");
    std::set<std::string> expected;
    for (const std::string& line : expected_entries(joint, node)) {
      // keep "index sub datatype access pdo default"
      std::istringstream in(line);
      std::string index, sub, type, access, pdo, value;
      in >> index >> sub >> type >> access >> pdo;
      std::getline(in, value);
      value = value.substr(1);
      const ObjectTable t = object_table(panda_joint_drive(joint));
      const Entry& e = t.entries[t.find(static_cast<uint16_t>(std::stoi(index, nullptr, 16)), static_cast<uint8_t>(std::stoi(sub)))];
      const std::string default_text = e.type == DataType::kVisibleString ? e.text : value.substr(0, value.find(' '));
      expected.insert(index + ' ' + sub + ' ' + type + ' ' + access + ' ' + pdo + ' ' + default_text);
    }
    EXPECT_EQ(lines_of(output), expected) << output;
  }
}

struct DbcSignal {
  int start, bits;
  bool is_signed;
  double factor;
};

TEST(CanDbc, DecodesTheBusTpdosBackToTheMeasuredState) {
  const std::string dbc = make_dbc(BusSettings{});
  // Only plain decimals for factors (some DBC readers drop signals written with exponents).
  const std::regex signal_line(R"re( SG_ (\w+) : (\d+)\|(\d+)@1([+-]) \(([0-9.]+),0\) \[[-0-9.]+\|[-0-9.]+\] "[^"]*" \w+)re");
  const std::regex message_line(R"(BO_ (\d+) (\w+): (\d) (\w+))");
  std::map<uint32_t, std::map<std::string, DbcSignal>> messages;
  uint32_t current = 0;
  std::istringstream in(dbc);
  int signals = 0;
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_match(line, m, message_line)) {
      current = static_cast<uint32_t>(std::stoul(m[1]));
      messages[current];
    }
    else if (line.rfind(" SG_", 0) == 0) {
      ASSERT_TRUE(std::regex_match(line, m, signal_line)) << line;
      messages[current][m[1]] = {std::stoi(m[2]), std::stoi(m[3]), m[4] == "-", std::stod(m[5])};
      ++signals;
    }
  }
  EXPECT_EQ(messages.size(), 2u + 7u * 8u);   // NMT, SYNC; per joint 4 RPDOs, 2 TPDOs, EMCY, heartbeat
  TestArm arm;
  DriveBus bus(BusSettings{}, arm);
  const double q[7] = {0.1, -1.2, 2.5, -2.0, 0.7, 3.1, -2.8};
  for (int j = 0; j < 7; ++j) {
    arm.state.joints[j].q = q[j];
    arm.state.joints[j].tau_J = (j < 4 ? 40.0 : 7.0) * (j % 2 ? -1 : 1);
    arm.state.joints[j].dq = 0.3 * j - 1.0;
    arm.state.joints[j].tau_ext_hat_filtered = 0.25 * j;
  }
  bus.receive(parse_frame("000#0100"));
  bus.on_sync();
  bus.clear_sent();
  bus.on_sync();
  int decoded = 0;
  for (const Frame& f : bus.sent()) {
    ASSERT_TRUE(messages.count(f.id)) << to_string(f);
    const int j = static_cast<int>(f.id & 0x7F) - 1;
    for (const auto& [name, s] : messages[f.id]) {
      uint64_t raw = 0;
      for (int b = 0; b < s.bits; ++b) raw |= static_cast<uint64_t>((f.data[(s.start + b) / 8] >> ((s.start + b) % 8)) & 1) << b;
      double value = static_cast<double>(raw);
      if (s.is_signed && (raw >> (s.bits - 1))) value -= std::ldexp(1.0, s.bits);
      value *= s.factor;
      const JointMeasurement& m = arm.state.joints[j];
      double expected = NAN;
      if (name == "position_actual_value") expected = m.q;
      if (name == "torque_actual_value") expected = m.tau_J;
      if (name == "velocity_actual_value") expected = m.dq;
      if (name == "tau_ext_hat_filtered") expected = m.tau_ext_hat_filtered;
      if (std::isnan(expected)) continue;
      EXPECT_NEAR(value, expected, s.factor / 2 + 1e-12) << name << " joint " << j + 1;
      ++decoded;
    }
  }
  EXPECT_EQ(decoded, 7 * 4);
  EXPECT_GT(signals, 7 * 15);
}

// --- The decoder under random frames -----------------------------------------------------------
TEST(CanFuzz, AMillionRandomFramesNoCrashAndOnlyValidReplies) {
  TestArm arm;
  DriveBus bus(BusSettings{}, arm);
  std::mt19937_64 rng(20261123);
  const uint32_t functions[] = {0x000, 0x080, 0x180, 0x200, 0x280, 0x300, 0x400, 0x500, 0x600, 0x700};
  const double specials[] = {0.0, 1e300, -1e300, NAN, INFINITY, -INFINITY, 3.0};
  uint64_t replies = 0;
  for (int i = 0; i < 1'000'000; ++i) {
    Frame f;
    const uint64_t r = rng();
    f.id = (r & 1) ? static_cast<uint32_t>((r >> 8) & 0x7FF) : functions[(r >> 8) % 10] + static_cast<uint32_t>((r >> 16) % 9);
    f.dlc = static_cast<uint8_t>((r >> 24) % 10);   // 9: malformed
    const uint64_t data = rng();
    for (int b = 0; b < 8; ++b) f.data[b] = static_cast<uint8_t>(data >> (8 * b));
    if ((r >> 32) % 5 == 0) f.data[0] = static_cast<uint8_t>(0x20 * ((r >> 40) % 8) | (f.data[0] & 0x1F));
    if ((r >> 44) % 1000 == 0) {   // the robot's state: sometimes absurd values, sometimes a reflex
      for (auto& m : arm.state.joints) m.q = m.dq = m.tau_J = specials[(r >> 50) % 7];
      arm.state.errors = rt::ErrorSet{};
      if ((r >> 53) & 1) arm.state.errors.set(static_cast<rt::Error>((r >> 54) % rt::kNumErrors));
    }
    bus.receive(f);
    if (i % 97 == 0) bus.elapse(static_cast<uint32_t>(rng() % 200'000));
    for (const Frame& reply : bus.sent()) {
      ASSERT_TRUE(is_valid(reply)) << to_string(reply);
      if ((reply.id & 0x780) == kSdoTx) {
        ASSERT_EQ(reply.dlc, 8);
      }
    }
    replies += bus.sent().size();
    bus.clear_sent();
    arm.commands.clear();
  }
  EXPECT_GT(replies, 10'000u);
  EXPECT_GT(bus.counters().syncs, 1'000u);
}

}  // namespace
}  // namespace csp::can
