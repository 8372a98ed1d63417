// CSP's pure-Python LCM client (bridge/python/csp_lcm.py) with the Python types lcm-gen writes, against
// LCM's C library (csp serve, lcm-logger, this process's lcm::LCM) and against datagrams written here from
// LCM's protocol description (docs/content/udp-multicast-protocol.md in LCM's source); python_float.py
// end to end. Python runs with -S (no site-packages): a python3-lcm installed on the host cannot stand in
// for csp_lcm. The tests of one process run one after the other, so two of them may share a port.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <map>
#include <random>

#include "bridge_support.hpp"
#include "csp/bridge/messages.hpp"
#include "csp/bridge/replay.hpp"
#include "csp/rt/emulator.hpp"
#include "csp/rt/scenario.hpp"
#include "support.hpp"

namespace csp::bridge {
namespace {

using namespace std::chrono_literals;

const std::string kTypes = CSP_LCM_PYTHON_TYPES;   // build/bridge/python
const std::string kClient = std::string(CSP_SOURCE_DIR) + "/bridge/python";
const std::string kExample = std::string(CSP_SOURCE_DIR) + "/bridge/examples/python_float.py";
const std::string kPeer = std::string(CSP_SOURCE_DIR) + "/tests/python_lcm_peer.py";

// python3 running `args` with `python_path` as PYTHONPATH.
std::vector<std::string> python(const std::string& python_path, std::vector<std::string> args) {
  args.insert(args.begin(), {"/usr/bin/env", "PYTHONPATH=" + python_path, "/usr/bin/python3", "-S"});
  return args;
}

std::string random_bytes(std::size_t size, unsigned seed) {
  std::mt19937 random(seed);
  std::string bytes(size, '\0');
  for (char& b : bytes) b = static_cast<char>(random() & 0xFF);
  return bytes;
}

std::string write_file(const std::string& name, const std::string& bytes) {
  const std::string path = test::temp_path(name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

// python_lcm_peer.py echo on `url`, and an LCM object of this process (LCM's C library) that collects its
// answers: the payload of every message on an ECHO_* channel, by channel, in order.
struct EchoPeer {
  EchoPeer(const std::string& url, const std::string& name)
      : lcm(url), process(python(kTypes + ":" + kClient, {kPeer, "echo", url}), test::temp_path(name)) {
    lcm.subscribeFunction("ECHO_.*", &EchoPeer::on_answer, this);
  }
  static void on_answer(const lcm::ReceiveBuffer* buffer, const std::string& channel, EchoPeer* self) {
    self->answers[channel].emplace_back(static_cast<const char*>(buffer->data), buffer->data_size);
  }
  // Handles answers until each of `channels` has one (true) or 20 s have passed, calling `send` every
  // 100 ms meanwhile (what is sent before the peer has subscribed is lost).
  bool wait_for(const std::vector<std::string>& channels, const std::function<void()>& send) {
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    const auto answered = [&] {
      return std::all_of(channels.begin(), channels.end(), [&](const std::string& c) { return !answers[c].empty(); });
    };
    while (!answered() && std::chrono::steady_clock::now() < deadline) {
      send();
      for (int i = 0; i < 5 && !answered(); ++i) lcm.handleTimeout(20);
    }
    return answered();
  }
  // TEST_STOP until the peer has exited, then the answers still under way; the peer's exit code.
  int stop() {
    int code = -1;
    for (int i = 0; i < 100 && code < 0; ++i) {
      lcm.publish("TEST_STOP", "", 0);
      code = process.wait(100ms);
    }
    while (lcm.handleTimeout(50) > 0) {
    }
    return code;
  }

  lcm::LCM lcm;
  test::Process process;
  std::map<std::string, std::vector<std::string>> answers;
};

// (b) python_float.py drives csp serve (lockstep): no command lost, each command is the damping law
// applied to the state it answers (decoded by CSP's C++ types), and the session replays bit for bit.
TEST(BridgePython, PythonFloatDrivesLockstepServerWithoutLoss) {
  const std::string url = test::unique_lcm_url(4), log = test::temp_path("python-float.lcmlog");
  test::Process server({CSP_EXECUTABLE, "serve", test::kDefaultScenario, "--clock", "lockstep", "--wait", "--duration", "1.1",
                        "--lockstep-timeout", "5", "--lcm-url", url, "--log", log},
                       test::temp_path("serve-python.out"));
  test::Process controller(python(kTypes + ":" + kClient, {kExample, "--lcm-url", url, "--duration", "1", "--timeout", "30"}),
                           test::temp_path("python-float.out"));
  ASSERT_EQ(controller.wait(60s), 0) << controller.output();
  ASSERT_EQ(server.wait(30s), 0) << server.output();
  EXPECT_NE(controller.output().find("python_float: 1001 commands, ended at t = 1.001 s in Idle (LCM client: csp_lcm)"), std::string::npos)
      << controller.output();

  std::map<int64_t, robot_state_t> states;
  std::vector<torque_command_t> commands;
  status_t status;
  LogReader reader(log);
  for (const LogEvent* e = reader.next(); e; e = reader.next()) {
    if (e->channel == "CSP_STATE") {
      robot_state_t s;
      ASSERT_EQ(decode_exact(e->data, e->datalen, s), Rejection::kNone);
      states[s.message_id] = s;
    } else if (e->channel == "CSP_COMMAND") {
      torque_command_t c;
      ASSERT_EQ(decode_exact(e->data, e->datalen, c), Rejection::kNone);
      commands.push_back(c);
    } else if (e->channel == "CSP_STATUS") {
      ASSERT_EQ(decode_exact(e->data, e->datalen, status), Rejection::kNone);
    }
  }
  EXPECT_EQ(states.size(), 1101u);
  EXPECT_EQ(status.sessions, 1);
  EXPECT_EQ(status.motion_cycles, 1001);
  EXPECT_EQ(status.lost_commands, 0);
  EXPECT_EQ(status.rejected_fingerprint + status.rejected_truncated + status.rejected_oversized + status.rejected_stale +
                status.rejected_wrong_mode + status.rejected_no_session,
            0);
  ASSERT_EQ(commands.size(), 1001u);
  for (std::size_t k = 0; k < commands.size(); ++k) {
    ASSERT_EQ(commands[k].message_id, commands[0].message_id + static_cast<int64_t>(k));
    const robot_state_t& answered = states.at(commands[k].message_id);
    for (int j = 0; j < 7; ++j) ASSERT_EQ(commands[k].tau_J[j], -2.0 * answered.dq[j]) << "command " << k << ", joint " << j;
    ASSERT_EQ(commands[k].motion_finished, k + 1 == commands.size());
  }

  const ResimulationReport replay = resimulate(log);
  EXPECT_EQ(replay.states, states.size());
  EXPECT_EQ(replay.differing_states, 0u) << replay.first_difference;
  std::filesystem::remove(log);
}

// (a) What csp_lcm publishes, a message in one datagram and one in two fragments, lcm-logger (LCM's
// C library) records byte for byte.
TEST(BridgePython, LcmLoggerRecordsWhatPythonPublishes) {
  const std::string url = test::unique_lcm_url(6), recorded = test::temp_path("python-logger.lcmlog");
  const std::string small = random_bytes(3000, 1), big = random_bytes(100'000, 2);
  const std::string small_file = write_file("small.bin", small), big_file = write_file("big.bin", big);
  test::Process logger({"/usr/bin/lcm-logger", "--lcm-url=" + url, "-f", "--flush-interval=10", recorded},
                       test::temp_path("python-logger.out"));
  lcm::LCM probe(url);
  ASSERT_TRUE(probe.good());
  ASSERT_TRUE(test::wait_until_logged(probe, recorded, "ready")) << logger.output();
  test::Process publisher(python(kTypes + ":" + kClient, {kPeer, "publish", url, "TEST_SMALL", small_file, "TEST_BIG", big_file}),
                          test::temp_path("python-publish.out"));
  ASSERT_EQ(publisher.wait(30s), 0) << publisher.output();
  ASSERT_TRUE(test::wait_until_logged(probe, recorded, "end")) << logger.output();
  logger.signal(SIGINT);
  ASSERT_EQ(logger.wait(10s), 0) << logger.output();

  std::map<std::string, std::vector<std::string>> logged;
  LogReader reader(recorded);
  for (const LogEvent* e = reader.next(); e; e = reader.next())
    logged[e->channel].emplace_back(static_cast<const char*>(e->data), e->datalen);
  ASSERT_EQ(logged["TEST_SMALL"].size(), 1u);
  ASSERT_EQ(logged["TEST_BIG"].size(), 1u);
  EXPECT_TRUE(logged["TEST_SMALL"][0] == small);
  EXPECT_TRUE(logged["TEST_BIG"][0] == big);
  for (const std::string& f : {recorded, small_file, big_file}) std::filesystem::remove(f);
}

// (c) A 150 000-byte message that LCM's C library sends in three fragments, and a robot_state_t from
// CSP's C++ types: csp_lcm reassembles the first, the generated Python type decodes and re-encodes the
// second, and both come back (through csp_lcm's publish and LCM's C library) byte for byte.
TEST(BridgePython, PythonReassemblesFragmentsOfLcmsCLibrary) {
  // A receive buffer for all three fragments: Python reads them only when it calls handle().
  const std::string url = test::unique_lcm_url(7) + "&recv_buf_size=1000000";
  const std::string big = random_bytes(150'000, 3);
  rt::Emulator emulator(rt::load_scenario(test::kDefaultScenario).emulator);
  emulator.step(nullptr);
  robot_state_t message = to_message(emulator.state(), 1'700'000'000'000'000, true);
  message.current_errors[3] = message.last_motion_errors[40] = 1;   // boolean arrays: lcm-gen 1.3.1's weak spot
  const std::vector<uint8_t> state = encode(message);
  EchoPeer peer(url, "python-echo.out");
  ASSERT_TRUE(peer.lcm.good());
  const bool answered = peer.wait_for({"ECHO_TEST_BIG", "ECHO_TEST_STATE"}, [&] {
    peer.lcm.publish("TEST_BIG", big.data(), static_cast<unsigned>(big.size()));
    peer.lcm.publish("TEST_STATE", state.data(), static_cast<unsigned>(state.size()));
  });
  ASSERT_EQ(peer.stop(), 0) << peer.process.output();
  ASSERT_TRUE(answered) << peer.process.output();
  for (const std::string& echo : peer.answers["ECHO_TEST_BIG"]) EXPECT_TRUE(echo == big);
  for (const std::string& echo : peer.answers["ECHO_TEST_STATE"]) EXPECT_TRUE(echo == std::string(state.begin(), state.end()));
  // The peer subscribes to "TEST_.*": a regex for the whole channel name, so not to its own ECHO_TEST_*.
  for (const auto& [channel, messages] : peer.answers) EXPECT_NE(channel.rfind("ECHO_ECHO_", 0), 0u) << channel;
}

// Datagrams written here from LCM's protocol description.
std::string big_endian(uint32_t value) {
  const uint32_t n = htonl(value);
  return std::string(reinterpret_cast<const char*>(&n), 4);
}
std::string short_datagram(uint32_t magic, uint32_t sequence, const std::string& channel, const std::string& payload) {
  return big_endian(magic) + big_endian(sequence) + channel + '\0' + payload;
}
// Fragment `number` of `count` of a message: its payload bytes [offset, offset + piece.size()).
std::string fragment(uint32_t sequence, const std::string& channel, std::size_t size, std::size_t offset, uint16_t number,
                     uint16_t count, const std::string& piece) {
  const uint32_t numbers = (static_cast<uint32_t>(number) << 16) | count;
  return big_endian(0x4c433033) + big_endian(sequence) + big_endian(static_cast<uint32_t>(size)) +
         big_endian(static_cast<uint32_t>(offset)) + big_endian(numbers) + (number == 0 ? channel + '\0' : "") + piece;
}

// The reassembly's edge cases, from one sender: fragments out of order are put in place; a message
// that lost a fragment, one whose fragment lies beyond its size and one with a wrong magic are dropped,
// and the messages after them still arrive.
TEST(BridgePython, PythonReassemblyFollowsLcmsProtocol) {
  const std::string url = test::unique_lcm_url(7);
  const int port = std::stoi(url.substr(url.rfind(':') + 1));
  EchoPeer peer(url, "python-protocol.out");
  ASSERT_TRUE(peer.lcm.good());
  ASSERT_TRUE(peer.wait_for({"ECHO_TEST_READY"}, [&] { peer.lcm.publish("TEST_READY", "", 0); })) << peer.process.output();

  const std::string a = random_bytes(3000, 4), b = random_bytes(2000, 5), c = random_bytes(2500, 6), d = random_bytes(500, 7);
  const std::vector<std::string> datagrams = {
      fragment(100, "TEST_A", 3000, 2000, 2, 3, a.substr(2000)),   // A: 3 fragments, last first
      fragment(100, "TEST_A", 3000, 0, 0, 3, a.substr(0, 1000)),
      fragment(100, "TEST_A", 3000, 1000, 1, 3, a.substr(1000, 1000)),
      fragment(101, "TEST_B", 2000, 0, 0, 2, b.substr(0, 1000)),   // B: its fragment 1 never comes
      fragment(102, "TEST_C", 2500, 1000, 1, 2, c.substr(1000)),   // C: complete, out of order
      fragment(102, "TEST_C", 2500, 0, 0, 2, c.substr(0, 1000)),
      fragment(103, "TEST_D", 500, 0, 0, 2, d.substr(0, 300)),     // D: its second fragment ends beyond 500 bytes
      fragment(103, "TEST_D", 500, 300, 1, 2, d.substr(300) + "overflow"),
      short_datagram(0x4c433031, 104, "TEST_E", "wrong magic"),
      short_datagram(0x4c433032, 105, "TEST_END", "end"),   // one sender's datagrams arrive in order on loopback
  };
  const int sender = socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(sender, 0);
  sockaddr_in group{};
  group.sin_family = AF_INET;
  group.sin_port = htons(static_cast<uint16_t>(port));
  inet_pton(AF_INET, "239.255.76.67", &group.sin_addr);
  for (const std::string& datagram : datagrams)
    ASSERT_EQ(sendto(sender, datagram.data(), datagram.size(), 0, reinterpret_cast<const sockaddr*>(&group), sizeof group),
              static_cast<ssize_t>(datagram.size()));
  close(sender);
  const bool ended = peer.wait_for({"ECHO_TEST_END"}, [] {});
  ASSERT_EQ(peer.stop(), 0) << peer.process.output();
  ASSERT_TRUE(ended) << peer.process.output();
  EXPECT_EQ(peer.answers["ECHO_TEST_END"], std::vector<std::string>{"end"});
  EXPECT_EQ(peer.answers["ECHO_TEST_A"], std::vector<std::string>{a});
  EXPECT_EQ(peer.answers["ECHO_TEST_C"], std::vector<std::string>{c});
  for (const std::string channel : {"ECHO_TEST_B", "ECHO_TEST_D", "ECHO_TEST_E"}) EXPECT_TRUE(peer.answers[channel].empty()) << channel;
}

// A missing piece or a server that does not answer: python_float.py says so in one line, no traceback.
TEST(BridgePython, PythonFloatReportsEachProblemInOneLine) {
  const std::string url = test::unique_lcm_url(7);
  const std::vector<std::pair<std::vector<std::string>, std::string>> cases = {
      {python(kTypes + ":" + kClient, {kExample, "--lcm-url", url, "--timeout", "0.2"}),
       "python_float: no robot state on CSP_STATE for 0.2 s (is csp serve running?)\n"},
      {python(kTypes, {kExample, "--lcm-url", url}),
       "python_float: no LCM client: add bridge/python to PYTHONPATH (CSP's csp_lcm) or install LCM's Python module\n"},
      {python(kClient, {kExample, "--lcm-url", url}),
       "python_float: no CSP message types: build them (cmake --build build --target csp_lcm_types) and add "
       "build/bridge/python to PYTHONPATH\n"},
      {python(kTypes + ":" + kClient, {kExample, "--lcm-url", "udpm://localhost:7667"}),
       "python_float: cannot open LCM at udpm://localhost:7667: LCM URL 'udpm://localhost:7667': expected "
       "udpm://MULTICAST_IPV4:PORT\n"},
  };
  for (const auto& [command, expected] : cases) {
    test::Process run(command, test::temp_path("python-error.out"));
    EXPECT_EQ(run.wait(30s), 1);
    EXPECT_EQ(run.output(), expected);
  }
}

}  // namespace
}  // namespace csp::bridge
