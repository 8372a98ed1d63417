// The FCI server without a network (bridge/fci/server.hpp): requests as libfranka sends them, byte
// for byte, and the robot's answers, states and reactions. The wire layout itself is checked
// against libfranka's headers in test_fci_protocol_v*.cpp; libfranka's own examples against
// `csp fci` in tests/fci.
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "csp/fci/device_server.hpp"
#include "csp/fci/server.hpp"
#include "csp/rt/scenario.hpp"

namespace {

using namespace csp;
using fci::Command;
using fci::Status;

// A request as libfranka builds it: the header (its size counting itself) and the payload.
template <typename Header>
std::vector<uint8_t> request_bytes(uint32_t command, uint32_t command_id, const void* payload, std::size_t payload_size) {
  Header header;
  header.command = static_cast<decltype(header.command)>(command);
  header.command_id = command_id;
  header.size = static_cast<uint32_t>(sizeof(header) + payload_size);
  std::vector<uint8_t> bytes(header.size);
  std::memcpy(bytes.data(), &header, sizeof(header));
  if (payload_size > 0) std::memcpy(bytes.data() + sizeof(header), payload, payload_size);
  return bytes;
}

// A client's view of one FciServer: it sends requests and keeps the robot's replies.
class Client {
 public:
  explicit Client(fci::Version version, const rt::CommandFaults& faults = {})
      : scenario_(rt::load_scenario(rt::shipped_scenario_path("libfranka_panda"))),
        robot_(scenario_.emulator),
        server_(robot_, version, [this] { return model_library(); }, [this](const std::string& line) { lines.push_back(line); }, faults) {
    server_.open_connection([this](const std::vector<uint8_t>& bytes) { replies.push_back(bytes); });
  }

  fci::FciServer& server() { return server_; }
  rt::Emulator& robot() { return robot_; }
  // The current state packet, held 8-byte aligned (a packed struct's own alignment is 1): its
  // arrays of doubles may then be read through references; its last double needs a copy (+).
  struct alignas(8) State : fci::RobotStatePacket {};
  State state() const { return {server_.state_packet()}; }

  // A request message as libfranka builds it (request_bytes), with the next command id.
  template <typename Payload>
  std::vector<uint8_t> message(uint32_t command_code, const Payload* payload, std::size_t payload_size) {
    return request_bytes<fci::MessageHeader>(command_code, next_id_++, payload, payload_size);
  }
  template <typename Payload>
  bool send(Command command, const Payload& payload) {
    const std::vector<uint8_t> bytes = message(fci::command_code(command, server_.version()), &payload, sizeof(payload));
    return server_.receive_tcp(bytes.data(), bytes.size());
  }
  bool send(Command command) {
    const std::vector<uint8_t> bytes = message<uint8_t>(fci::command_code(command, server_.version()), nullptr, 0);
    return server_.receive_tcp(bytes.data(), bytes.size());
  }
  uint32_t last_id() const { return next_id_ - 1; }

  bool connect(fci::Version version) {
    fci::ConnectRequest request;
    request.version = version;
    request.udp_port = 40000;
    return send(Command::kConnect, request);
  }

  // The reply's header and status byte.
  struct Reply {
    fci::MessageHeader header;
    uint8_t status = 0;
    std::vector<uint8_t> rest;
  };
  Reply reply(std::size_t k) const {
    Reply r;
    const std::vector<uint8_t>& bytes = replies.at(k);
    EXPECT_GE(bytes.size(), sizeof(r.header) + 1);
    std::memcpy(&r.header, bytes.data(), sizeof(r.header));
    EXPECT_EQ(r.header.size, bytes.size()) << "a reply's size counts the whole message";
    r.status = bytes[sizeof(r.header)];
    r.rest.assign(bytes.begin() + sizeof(r.header) + 1, bytes.end());
    return r;
  }
  uint8_t code(Command command, Status status) const { return fci::status_code(command, status, server_.version()); }

  // One cycle with the command a libfranka control loop sends: it answers the current state.
  void cycle(const fci::RobotCommandPacketV7& command) {
    alignas(8) fci::RobotCommandPacketV7 packet = command;
    packet.message_id = server_.state_packet().message_id;
    server_.receive_udp(&packet, fci::robot_command_size(server_.version()));
    server_.step();
  }
  void cycle_without_command() { server_.step(); }

  std::vector<std::vector<uint8_t>> replies;
  std::vector<std::string> lines;
  std::vector<uint8_t> library = {0x7f, 'E', 'L', 'F', 1, 2, 3};
  bool library_fails = false;

 private:
  std::vector<uint8_t> model_library() {
    if (library_fails) throw std::runtime_error("no library here");
    return library;
  }

  rt::Scenario scenario_;
  rt::Emulator robot_;
  fci::FciServer server_;
  uint32_t next_id_ = 0;
};

fci::MoveRequest move(fci::MoveMotionGeneratorMode generator, fci::MoveControllerMode controller) {
  fci::MoveRequest request;
  request.motion_generator_mode = static_cast<uint32_t>(generator);
  request.controller_mode = static_cast<uint32_t>(controller);
  request.maximum_path_deviation = {0, 1, 2};   // libfranka's defaults; the robot does not use them
  return request;
}

// Holds the joints where they are: a joint position command of the current q_d.
fci::RobotCommandPacketV7 hold(const Client::State& state, bool finished = false) {
  alignas(8) fci::RobotCommandPacketV7 command{};
  command.motion.q_c = state.q_d;
  command.motion.motion_generation_finished = finished;
  return command;
}

TEST(FciServer, ConnectAnswersWithTheRobotsVersionAndRefusesAnother) {
  for (const fci::Version version : {fci::kPandaVersion, fci::kFr3Version}) {
    Client client(version);
    EXPECT_FALSE(client.server().client_udp_port());
    EXPECT_TRUE(client.connect(version));
    ASSERT_EQ(client.replies.size(), 1u);
    const Client::Reply ok = client.reply(0);
    EXPECT_EQ(ok.header.command, 0u);
    EXPECT_EQ(ok.header.command_id, client.last_id());
    EXPECT_EQ(ok.status, 0);
    ASSERT_EQ(ok.rest.size(), 2u);
    EXPECT_EQ(ok.rest[0] | ok.rest[1] << 8, version);
    EXPECT_EQ(client.server().client_udp_port(), 40000);

    // libfranka 0.9 at an FR3, 0.13 at a Panda: refused with the robot's version, then closed.
    const fci::Version other = version == fci::kPandaVersion ? fci::kFr3Version : fci::kPandaVersion;
    Client refused(version);
    EXPECT_FALSE(refused.connect(other));
    const Client::Reply no = refused.reply(0);
    EXPECT_EQ(no.status, refused.code(Command::kConnect, Status::kIncompatibleLibraryVersion));
    EXPECT_EQ(no.rest[0] | no.rest[1] << 8, version);
    EXPECT_EQ(refused.server().counters().refused_versions, 1u);
    EXPECT_FALSE(refused.server().client_udp_port());
  }
}

TEST(FciServer, AMessageSplitAnywhereIsTheSameMessage) {
  Client client(fci::kFr3Version);
  fci::ConnectRequest request;
  request.version = fci::kFr3Version;
  request.udp_port = 1234;
  const std::vector<uint8_t> bytes = client.message(0, &request, sizeof(request));
  for (uint8_t b : bytes) EXPECT_TRUE(client.server().receive_tcp(&b, 1));
  ASSERT_EQ(client.replies.size(), 1u);
  EXPECT_EQ(client.server().client_udp_port(), 1234);
  // Two requests in one segment: both answered.
  fci::JointImpedanceRequest stiffness{{3000, 3000, 3000, 2500, 2500, 2000, 2000}};
  std::vector<uint8_t> two = client.message(fci::command_code(Command::kSetJointImpedance, fci::kFr3Version), &stiffness, sizeof(stiffness));
  const std::vector<uint8_t> recover = client.message<uint8_t>(fci::command_code(Command::kAutomaticErrorRecovery, fci::kFr3Version), nullptr, 0);
  two.insert(two.end(), recover.begin(), recover.end());
  EXPECT_TRUE(client.server().receive_tcp(two.data(), two.size()));
  ASSERT_EQ(client.replies.size(), 3u);
  EXPECT_EQ(client.reply(1).status, 0);
  EXPECT_EQ(client.reply(2).header.command, fci::command_code(Command::kAutomaticErrorRecovery, fci::kFr3Version));
}

TEST(FciServer, MalformedMessagesCloseTheConnectionWithAReason) {
  {  // not Connect first
    Client client(fci::kPandaVersion);
    EXPECT_FALSE(client.send(Command::kStopMove));
    EXPECT_EQ(client.server().counters().protocol_errors, 1u);
    ASSERT_FALSE(client.lines.empty());
    EXPECT_NE(client.lines.back().find("the first message must be Connect"), std::string::npos) << client.lines.back();
  }
  {  // a size that is not the command's, judged from the header alone (no waiting for 4 GB)
    Client client(fci::kPandaVersion);
    ASSERT_TRUE(client.connect(fci::kPandaVersion));
    fci::MessageHeader header{fci::command_code(Command::kSetLoad, fci::kPandaVersion), 7, 0xFFFFFFF0u};
    EXPECT_FALSE(client.server().receive_tcp(reinterpret_cast<const uint8_t*>(&header), sizeof(header)));
    EXPECT_NE(client.lines.back().find("SetLoad of 4294967280 bytes (expected 116)"), std::string::npos) << client.lines.back();
  }
  {  // a code the version does not have (version 7 has no SetFilters: 12 is past its last command)
    Client client(fci::kFr3Version);
    ASSERT_TRUE(client.connect(fci::kFr3Version));
    fci::MessageHeader header{12, 1, 12};
    EXPECT_FALSE(client.server().receive_tcp(reinterpret_cast<const uint8_t*>(&header), sizeof(header)));
    EXPECT_NE(client.lines.back().find("command 12 is not a request of FCI version 7"), std::string::npos) << client.lines.back();
  }
}

TEST(FciServer, AMotionRunsAndItsMoveIsAnsweredWhenItFinishes) {
  for (const fci::Version version : {fci::kPandaVersion, fci::kFr3Version}) {
    Client client(version);
    ASSERT_TRUE(client.connect(version));
    const Client::State idle = client.state();
    EXPECT_EQ(idle.motion_generator_mode, fci::StateMotionGeneratorMode::kIdle);
    EXPECT_EQ(idle.controller_mode, fci::StateControllerMode::kOther);
    EXPECT_EQ(idle.robot_mode, fci::StateRobotMode::kIdle);

    ASSERT_TRUE(client.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kJointPosition, fci::MoveControllerMode::kJointImpedance)));
    const uint32_t move_id = client.last_id();
    // Accepted: MotionStarted at once (libfranka's startMotion waits for it), the outcome at the end.
    ASSERT_EQ(client.replies.size(), 2u);
    EXPECT_EQ(client.reply(1).header.command_id, move_id);
    EXPECT_EQ(client.reply(1).status, client.code(Command::kMove, Status::kMotionStarted));
    // The state shows the motion as libfranka's startMotion waits for it.
    client.cycle_without_command();
    const Client::State moving = client.state();
    EXPECT_EQ(moving.motion_generator_mode, fci::StateMotionGeneratorMode::kJointPosition);
    EXPECT_EQ(moving.controller_mode, fci::StateControllerMode::kJointImpedance);
    EXPECT_EQ(moving.robot_mode, fci::StateRobotMode::kMove);
    EXPECT_EQ(moving.message_id, idle.message_id + 1);

    for (int k = 0; k < 50; ++k) client.cycle(hold(client.state()));
    EXPECT_EQ(client.robot().counters().lost_commands, 1u);   // the cycle libfranka spends waiting for the state
    client.cycle(hold(client.state(), true));
    ASSERT_EQ(client.replies.size(), 3u);
    const Client::Reply done = client.reply(2);
    EXPECT_EQ(done.header.command, fci::command_code(Command::kMove, version));
    EXPECT_EQ(done.header.command_id, move_id);
    EXPECT_EQ(done.status, client.code(Command::kMove, Status::kSuccess));
    EXPECT_FALSE(client.server().in_motion());
    EXPECT_EQ(client.state().motion_generator_mode, fci::StateMotionGeneratorMode::kIdle);
  }
}

TEST(FciServer, AReflexAbortsTheMoveAndShowsItsErrorUntilRecovery) {
  for (const fci::Version version : {fci::kPandaVersion, fci::kFr3Version}) {
    Client client(version);
    ASSERT_TRUE(client.connect(version));
    ASSERT_TRUE(client.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kJointPosition, fci::MoveControllerMode::kJointImpedance)));
    client.cycle(hold(client.state()));
    alignas(8) fci::RobotCommandPacketV7 jump = hold(client.state());
    jump.motion.q_c[0] += 0.5;   // 0.5 rad in 1 ms: libfranka's joint_motion_generator_velocity_limits_violation
    client.cycle(jump);
    ASSERT_EQ(client.replies.size(), 3u);
    EXPECT_EQ(client.reply(2).status, client.code(Command::kMove, Status::kReflexAborted));
    const Client::State reflex = client.state();
    EXPECT_EQ(reflex.robot_mode, fci::StateRobotMode::kReflex);
    const int velocity = fci::wire_error_index(rt::Error::joint_motion_generator_velocity_limits_violation);
    EXPECT_TRUE(reflex.reflex_reason[velocity]);
    EXPECT_TRUE(reflex.errors[velocity]);

    // A Move in Reflex mode is refused; recovery clears the errors and the next motion starts.
    ASSERT_TRUE(client.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kJointVelocity, fci::MoveControllerMode::kJointImpedance)));
    EXPECT_EQ(client.reply(3).status, client.code(Command::kMove, Status::kCommandNotPossibleRejected));
    for (int k = 0; k < 500; ++k) client.cycle_without_command();   // the brakes close
    ASSERT_TRUE(client.send(Command::kAutomaticErrorRecovery));
    EXPECT_EQ(client.reply(4).status, 0);
    client.cycle_without_command();
    const Client::State recovered = client.state();
    EXPECT_EQ(recovered.robot_mode, fci::StateRobotMode::kIdle);
    EXPECT_FALSE(recovered.errors[velocity]);
    EXPECT_TRUE(recovered.reflex_reason[velocity]) << "the last motion's errors stay, as on the robot";
    ASSERT_TRUE(client.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kJointPosition, fci::MoveControllerMode::kJointImpedance)));
    EXPECT_EQ(client.replies.size(), 6u);
    EXPECT_EQ(client.reply(5).status, client.code(Command::kMove, Status::kMotionStarted));
    EXPECT_TRUE(client.server().in_motion());
  }
}

TEST(FciServer, AClientThatVanishesMidMotionEndsItAsTheRobotWould) {
  Client client(fci::kFr3Version);
  ASSERT_TRUE(client.connect(fci::kFr3Version));
  ASSERT_TRUE(client.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kJointVelocity, fci::MoveControllerMode::kJointImpedance)));
  for (int k = 0; k < 10; ++k) client.cycle(fci::RobotCommandPacketV7{});   // zero velocity
  client.server().close_connection();
  EXPECT_EQ(client.server().counters().client_losses, 1u);
  for (int k = 0; k < 30 && client.server().in_motion(); ++k) client.cycle_without_command();
  EXPECT_FALSE(client.server().in_motion());
  const Client::State state = client.state();
  EXPECT_EQ(state.robot_mode, fci::StateRobotMode::kReflex);
  EXPECT_TRUE(state.reflex_reason[fci::wire_error_index(rt::Error::communication_constraints_violation)]);
  EXPECT_EQ(client.replies.size(), 2u) << "no answer goes to a client that has gone";

  // The robot outlives its client: the next one finds it where it stopped, in Reflex mode.
  client.server().open_connection([&](const std::vector<uint8_t>& bytes) { client.replies.push_back(bytes); });
  ASSERT_TRUE(client.connect(fci::kFr3Version));
  EXPECT_EQ(client.state().robot_mode, fci::StateRobotMode::kReflex);
  EXPECT_EQ(client.state().message_id, state.message_id);
}

TEST(FciServer, CommandsThatAnswerNoCurrentStateAreLost) {
  Client client(fci::kPandaVersion);
  ASSERT_TRUE(client.connect(fci::kPandaVersion));
  alignas(8) fci::RobotCommandPacketV7 command = hold(client.state());
  client.server().receive_udp(&command, fci::robot_command_size(fci::kPandaVersion));
  EXPECT_EQ(client.server().counters().rejected_commands, 1u) << "no motion runs";
  ASSERT_TRUE(client.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kJointPosition, fci::MoveControllerMode::kJointImpedance)));
  command.message_id = client.state().message_id + 5;
  client.server().receive_udp(&command, fci::robot_command_size(fci::kPandaVersion));
  EXPECT_EQ(client.server().counters().stale_commands, 1u);
  client.server().receive_udp(&command, fci::robot_command_size(fci::kFr3Version));   // version 7's size at a Panda
  EXPECT_EQ(client.server().counters().rejected_commands, 2u);
  EXPECT_FALSE(client.server().answered());
  const uint64_t lost = client.robot().counters().lost_commands;
  client.cycle_without_command();
  EXPECT_EQ(client.robot().counters().lost_commands, lost + 1);
}

TEST(FciServer, TheScenariosFaultsLoseCommandsOnTheWay) {
  // Half the commands lost: the robot's success rate over its last 100 cycles shows it.
  rt::CommandFaults lossy;
  lossy.loss_probability = 0.5;
  Client client(fci::kPandaVersion, lossy);
  ASSERT_TRUE(client.connect(fci::kPandaVersion));
  ASSERT_TRUE(client.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kJointPosition, fci::MoveControllerMode::kJointImpedance)));
  for (int k = 0; k < 300; ++k) client.cycle(hold(client.state()));
  const uint64_t lost = client.server().counters().injected_losses;
  EXPECT_GT(lost, 100u);
  EXPECT_LT(lost, 200u);
  EXPECT_EQ(client.robot().counters().lost_commands, lost);
  EXPECT_GT(+client.state().control_command_success_rate, 0.3);
  EXPECT_LT(+client.state().control_command_success_rate, 0.7);

  // A burst of 20 lost commands 10 ms into the motion: the robot's communication reflex.
  rt::CommandFaults burst;
  burst.bursts = {{0.010, 20}};
  Client bursty(fci::kFr3Version, burst);
  ASSERT_TRUE(bursty.connect(fci::kFr3Version));
  ASSERT_TRUE(bursty.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kJointPosition, fci::MoveControllerMode::kJointImpedance)));
  int cycles = 0;
  while (bursty.server().in_motion() && cycles < 100) {
    bursty.cycle(hold(bursty.state()));
    ++cycles;
  }
  EXPECT_EQ(cycles, 30);
  EXPECT_EQ(bursty.server().counters().injected_losses, 20u);
  EXPECT_TRUE(bursty.state().reflex_reason[fci::wire_error_index(rt::Error::communication_constraints_violation)]);
}

TEST(FciServer, SettingsAreAppliedBetweenMotionsAndRefusedWithTheRobotsStatus) {
  Client client(fci::kFr3Version);
  ASSERT_TRUE(client.connect(fci::kFr3Version));
  fci::LoadRequest load{0.5, {0.0, 0.0, 0.05}, {1e-3, 0, 0, 0, 1e-3, 0, 0, 0, 1e-3}};
  ASSERT_TRUE(client.send(Command::kSetLoad, load));
  EXPECT_EQ(client.reply(1).status, 0);
  client.cycle_without_command();
  EXPECT_EQ(client.state().m_load, 0.5);
  EXPECT_EQ(client.state().F_x_Cload[2], 0.05);

  fci::JointImpedanceRequest nan{{3000, 3000, 3000, 2500, 2500, 2000, std::nan("")}};
  ASSERT_TRUE(client.send(Command::kSetJointImpedance, nan));
  EXPECT_EQ(client.reply(2).status, client.code(Command::kSetJointImpedance, Status::kInvalidArgumentRejected));
  fci::EEToKRequest skewed{{2, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}};
  ASSERT_TRUE(client.send(Command::kSetEEToK, skewed));
  EXPECT_EQ(client.reply(3).status, client.code(Command::kSetEEToK, Status::kInvalidArgumentRejected));

  ASSERT_TRUE(client.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kJointPosition, fci::MoveControllerMode::kJointImpedance)));
  ASSERT_TRUE(client.send(Command::kSetLoad, load));
  EXPECT_EQ(client.reply(5).status, client.code(Command::kSetLoad, Status::kCommandNotPossibleRejected));
  ASSERT_TRUE(client.send(Command::kAutomaticErrorRecovery));
  EXPECT_EQ(client.reply(6).status, client.code(Command::kAutomaticErrorRecovery, Status::kCommandNotPossibleRejected));
}

TEST(FciServer, StopMoveEndsTheMotionAndPreemptsItsMove) {
  Client client(fci::kPandaVersion);
  ASSERT_TRUE(client.connect(fci::kPandaVersion));
  ASSERT_TRUE(client.send(Command::kStopMove));   // nothing to stop: no error
  EXPECT_EQ(client.reply(1).status, 0);
  ASSERT_TRUE(client.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kCartesianVelocity, fci::MoveControllerMode::kCartesianImpedance)));
  const uint32_t move_id = client.last_id();
  for (int k = 0; k < 5; ++k) client.cycle(fci::RobotCommandPacketV7{});
  ASSERT_TRUE(client.send(Command::kStopMove));
  ASSERT_EQ(client.replies.size(), 5u);
  EXPECT_EQ(client.reply(3).header.command, fci::command_code(Command::kStopMove, fci::kPandaVersion));
  EXPECT_EQ(client.reply(3).status, 0);
  EXPECT_EQ(client.reply(4).header.command_id, move_id);
  EXPECT_EQ(client.reply(4).status, client.code(Command::kMove, Status::kPreempted));
  client.cycle_without_command();
  EXPECT_EQ(client.state().robot_mode, fci::StateRobotMode::kIdle);
}

TEST(FciServer, TorqueControlIsAZeroVelocityMotionUnderTheExternalController) {
  // libfranka's control(torque_callback): kJointVelocity + kExternalController, zero velocities, the
  // user's torque in tau_J_d. Version 7 also has kNone (no motion generator).
  for (const auto generator : {fci::MoveMotionGeneratorMode::kJointVelocity, fci::MoveMotionGeneratorMode::kNone}) {
    Client client(fci::kFr3Version);
    ASSERT_TRUE(client.connect(fci::kFr3Version));
    ASSERT_TRUE(client.send(Command::kMove, move(generator, fci::MoveControllerMode::kExternalController)));
    fci::RobotCommandPacketV7 torque{};
    const std::array<double, 7> tau = {0, 0, 0, 0, 0, 0, 0.5};   // (tau_J_d lies at an odd offset: copied in)
    std::memcpy(reinterpret_cast<uint8_t*>(&torque) + offsetof(fci::RobotCommandPacketV7, tau_J_d), tau.data(), sizeof(tau));
    for (int k = 0; k < 20; ++k) client.cycle(torque);
    const Client::State state = client.state();
    EXPECT_EQ(state.controller_mode, fci::StateControllerMode::kExternalController);
    EXPECT_EQ(state.tau_J_d[6], 0.5);
    EXPECT_GT(state.dq[6], 0.0) << "the user's torque drives joint 7";
    if (generator == fci::MoveMotionGeneratorMode::kNone) torque.torque_command_finished = 1;
    else torque.motion.motion_generation_finished = true;
    client.cycle(torque);
    EXPECT_EQ(client.reply(2).status, 0);
  }
  Client panda(fci::kPandaVersion);   // version 5 has no kNone
  ASSERT_TRUE(panda.connect(fci::kPandaVersion));
  ASSERT_TRUE(panda.send(Command::kMove, move(fci::MoveMotionGeneratorMode::kNone, fci::MoveControllerMode::kExternalController)));
  EXPECT_EQ(panda.reply(1).status, panda.code(Command::kMove, Status::kInvalidArgumentRejected));
}

TEST(FciServer, TheModelLibraryFollowsItsResponseAndOnlyForX64Linux) {
  Client client(fci::kFr3Version);
  ASSERT_TRUE(client.connect(fci::kFr3Version));
  ASSERT_TRUE(client.send(Command::kLoadModelLibrary, fci::LoadModelLibraryRequest{0, 0}));
  EXPECT_EQ(client.reply(1).status, 0);
  EXPECT_EQ(client.reply(1).rest, client.library);
  ASSERT_TRUE(client.send(Command::kLoadModelLibrary, fci::LoadModelLibraryRequest{3, 0}));   // ARM64
  EXPECT_EQ(client.reply(2).status, client.code(Command::kLoadModelLibrary, Status::kError));
  EXPECT_TRUE(client.reply(2).rest.empty());
  client.library_fails = true;
  ASSERT_TRUE(client.send(Command::kLoadModelLibrary, fci::LoadModelLibraryRequest{0, 0}));
  EXPECT_EQ(client.reply(3).status, client.code(Command::kLoadModelLibrary, Status::kError));
  EXPECT_NE(client.lines.at(client.lines.size() - 2).find("LoadModelLibrary: no library here"), std::string::npos);
}

TEST(FciServer, TheStatePacketIsTheRobotsState) {
  Client client(fci::kPandaVersion);
  const Client::State p = client.state();
  const rt::RobotState& s = client.robot().state();
  EXPECT_EQ(p.message_id, static_cast<uint64_t>(s.time.toMSec()));
  EXPECT_EQ(p.q, s.q);
  EXPECT_EQ(p.O_T_EE, s.O_T_EE);
  EXPECT_EQ(p.F_T_EE, s.F_T_EE);
  EXPECT_EQ(p.tau_J, s.tau_J);
  EXPECT_EQ(p.m_ee, s.m_ee);
  EXPECT_EQ(p.I_ee, s.I_ee);
  EXPECT_EQ(p.theta, s.theta);
  EXPECT_EQ(+p.control_command_success_rate, s.control_command_success_rate);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// The hand's server (port 1338)

namespace {

// A client of one device's server (the hand's or the pump's), on a scenario that has the device.
template <typename Device, typename StatePacket>
class DeviceClient {
 public:
  DeviceClient(const std::string& scenario, Device device)
      : scenario_(rt::load_scenario(rt::shipped_scenario_path(scenario))),
        robot_(scenario_.emulator),
        server_(robot_, std::move(device), [this](const std::string& line) { lines.push_back(line); }) {
    server_.open_connection([this](const std::vector<uint8_t>& bytes) { replies.push_back(bytes); });
  }

  template <typename Payload>
  bool send(uint16_t command, const Payload* payload, std::size_t payload_size) {
    const std::vector<uint8_t> bytes = request_bytes<fci::GripperMessageHeader>(command, next_id_++, payload, payload_size);
    return server_.receive_tcp(bytes.data(), bytes.size());
  }
  bool connect(uint16_t version) {
    const fci::GripperConnectRequest request{version, 50000};
    return send(0, &request, sizeof(request));
  }
  uint16_t status(std::size_t k) const {
    uint16_t s = 0;
    std::memcpy(&s, replies.at(k).data() + sizeof(fci::GripperMessageHeader), sizeof(s));
    return s;
  }
  uint32_t command_id(std::size_t k) const {
    fci::GripperMessageHeader h;
    std::memcpy(&h, replies.at(k).data(), sizeof(h));
    return h.command_id;
  }
  // Robot cycles until a reply arrives (at most `seconds`); the state messages seen meanwhile.
  std::vector<StatePacket> run_until_reply(double seconds) {
    std::vector<StatePacket> states;
    const std::size_t before = replies.size();
    for (int k = 0; k < static_cast<int>(seconds * 1000) && replies.size() == before; ++k) {
      robot_.step(nullptr);
      if (const auto bytes = server_.step()) {
        EXPECT_EQ(bytes->size(), sizeof(StatePacket));
        StatePacket state;
        std::memcpy(&state, bytes->data(), sizeof(state));
        states.push_back(state);
      }
    }
    return states;
  }

  fci::DeviceServer<Device>& server() { return server_; }
  const rt::Emulator& robot() const { return robot_; }
  std::vector<std::vector<uint8_t>> replies;
  std::vector<std::string> lines;

 private:
  rt::Scenario scenario_;
  rt::Emulator robot_;
  fci::DeviceServer<Device> server_;
  uint32_t next_id_ = 0;
};

// The hand of libfranka_fr3: a 30 mm object stands between the fingers.
class HandClient : public DeviceClient<rt::Hand, fci::GripperStatePacket> {
 public:
  HandClient() : DeviceClient("libfranka_fr3", rt::Hand(rt::load_scenario(rt::shipped_scenario_path("libfranka_fr3")).hand)) {}
  bool send(fci::GripperCommand command, const void* payload, std::size_t size) {
    return DeviceClient::send(static_cast<uint16_t>(command), static_cast<const uint8_t*>(payload), size);
  }
  template <typename Payload>
  bool send(fci::GripperCommand command, const Payload* payload, std::size_t size) {
    return send(command, static_cast<const void*>(payload), size);
  }
};

TEST(FciGripperServer, ConnectsAtVersion3AndRefusesAnother) {
  HandClient client;
  EXPECT_TRUE(client.connect(fci::kGripperVersion));
  EXPECT_EQ(client.status(0), 0);
  EXPECT_EQ(client.server().client_udp_port(), 50000);
  HandClient old;
  EXPECT_FALSE(old.connect(2));
  EXPECT_EQ(old.status(0), 1);   // kIncompatibleLibraryVersion
  EXPECT_EQ(old.server().counters().refused_versions, 1u);
}

TEST(FciGripperServer, ACommandIsAnsweredWhenTheFingersArrive) {
  HandClient client;   // libfranka_fr3: a 30 mm object stands between the fingers
  ASSERT_TRUE(client.connect(fci::kGripperVersion));
  const fci::GripperMoveRequest move{0.04, 0.1};   // from 80 mm to 40 mm at 0.1 m/s: 0.4 s + the reaction time
  ASSERT_TRUE(client.send(fci::GripperCommand::kMove, &move, sizeof(move)));
  EXPECT_EQ(client.replies.size(), 1u) << "answered when it ends, not before";
  const std::vector<fci::GripperStatePacket> states = client.run_until_reply(2.0);
  ASSERT_EQ(client.replies.size(), 2u);
  EXPECT_EQ(client.status(1), static_cast<uint16_t>(fci::GripperStatus::kSuccess));
  EXPECT_EQ(client.command_id(1), 1u);
  ASSERT_GE(states.size(), 4u) << "a state message about every 100 ms";
  EXPECT_LT(+states.back().width, +states.front().width);
  EXPECT_NEAR(client.server().device().state().width, 0.04, 1e-9);
  // A move through the object stops at it: unsuccessful, as libfranka's move() returning false.
  const fci::GripperMoveRequest through{0.02, 0.1};
  ASSERT_TRUE(client.send(fci::GripperCommand::kMove, &through, sizeof(through)));
  client.run_until_reply(2.0);
  ASSERT_EQ(client.replies.size(), 3u);
  EXPECT_EQ(client.status(2), static_cast<uint16_t>(fci::GripperStatus::kUnsuccessful));
  EXPECT_NEAR(client.server().device().state().width, 0.03, 1e-9);
}

TEST(FciGripperServer, ACommandTheHandRefusesFailsAtOnceAndTheConnectionStays) {
  HandClient client;
  ASSERT_TRUE(client.connect(fci::kGripperVersion));
  const fci::GripperMoveRequest too_wide{0.5, 0.1};
  EXPECT_TRUE(client.send(fci::GripperCommand::kMove, &too_wide, sizeof(too_wide)));
  ASSERT_EQ(client.replies.size(), 2u);
  EXPECT_EQ(client.status(1), static_cast<uint16_t>(fci::GripperStatus::kFail));
  const fci::GraspRequest nan{std::nan(""), 0.005, 0.005, 0.1, 20.0};
  EXPECT_TRUE(client.send(fci::GripperCommand::kGrasp, &nan, sizeof(nan)));
  EXPECT_EQ(client.status(2), static_cast<uint16_t>(fci::GripperStatus::kFail));
  EXPECT_EQ(client.server().counters().failed_commands, 2u);
  // A malformed message closes the connection with a reason.
  fci::GripperMessageHeader bad{static_cast<uint16_t>(fci::GripperCommand::kGrasp), 5, 12};
  EXPECT_FALSE(client.server().receive_tcp(reinterpret_cast<const uint8_t*>(&bad), sizeof(bad)));
  EXPECT_NE(client.lines.back().find("Grasp of 12 bytes (expected 50)"), std::string::npos) << client.lines.back();
}

TEST(FciGripperServer, StopAbortsTheRunningCommand) {
  HandClient client;
  ASSERT_TRUE(client.connect(fci::kGripperVersion));
  const fci::GripperMoveRequest move{0.0, 0.01};
  ASSERT_TRUE(client.send(fci::GripperCommand::kMove, &move, sizeof(move)));
  client.run_until_reply(0.3);
  ASSERT_TRUE(client.send(fci::GripperCommand::kStop, nullptr, 0));
  client.run_until_reply(1.0);
  client.run_until_reply(1.0);
  ASSERT_EQ(client.replies.size(), 3u);
  EXPECT_EQ(client.command_id(1), 1u);
  EXPECT_EQ(client.status(1), static_cast<uint16_t>(fci::GripperStatus::kAborted));
  EXPECT_EQ(client.command_id(2), 2u);
  EXPECT_EQ(client.status(2), static_cast<uint16_t>(fci::GripperStatus::kSuccess));
}

// The Cobot Pump's server (port 1339) on the default scenario: a 0.3 kg part under the cup.
TEST(FciVacuumGripperServer, SucksThePartAndTheArmCarriesItUntilDropOff) {
  DeviceClient<rt::VacuumPump, fci::VacuumStatePacket> client(
      "default", rt::VacuumPump(rt::load_scenario(rt::default_scenario_path()).vacuum_gripper));
  EXPECT_FALSE(client.connect(3)) << "the gripper's version is not the pump's";
  EXPECT_EQ(client.status(0), 1);
  client.server().open_connection([&](const std::vector<uint8_t>& bytes) { client.replies.push_back(bytes); });
  ASSERT_TRUE(client.connect(fci::kVacuumGripperVersion));
  EXPECT_EQ(client.status(1), 0);

  const fci::VacuumRequest vacuum{60, 0, 1000};   // 600 mbar, P0, 1 s
  ASSERT_TRUE(client.send(static_cast<uint16_t>(fci::VacuumCommand::kVacuum), &vacuum, sizeof(vacuum)));
  const std::vector<fci::VacuumStatePacket> states = client.run_until_reply(2.0);
  ASSERT_EQ(client.replies.size(), 3u);
  EXPECT_EQ(client.status(2), static_cast<uint16_t>(fci::GripperStatus::kSuccess));
  ASSERT_FALSE(states.empty());
  EXPECT_EQ(states.back().part_present, 1);
  EXPECT_GT(client.server().device().vacuum_level(), 500.0);

  const fci::DropOffRequest drop{1000};
  ASSERT_TRUE(client.send(static_cast<uint16_t>(fci::VacuumCommand::kDropOff), &drop, sizeof(drop)));
  client.run_until_reply(2.0);
  ASSERT_EQ(client.replies.size(), 4u);
  EXPECT_EQ(client.status(3), static_cast<uint16_t>(fci::GripperStatus::kSuccess));
  EXPECT_EQ(client.server().device().carried_object().mass, 0.0);

  const fci::VacuumRequest bad_profile{60, 7, 1000};
  ASSERT_TRUE(client.send(static_cast<uint16_t>(fci::VacuumCommand::kVacuum), &bad_profile, sizeof(bad_profile)));
  EXPECT_EQ(client.status(4), static_cast<uint16_t>(fci::GripperStatus::kFail));
  EXPECT_NE(client.lines.back().find("vacuum gripper: Vacuum failed: profile 7 is not P0..P3"), std::string::npos) << client.lines.back();
}

}  // namespace
