// The bridge over real LCM UDP multicast on loopback, with `csp serve`, the example controller
// processes and Debian's LCM tools (lcm-logger, lcm-logplayer) as independent peers.
#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <thread>

#include "bridge_support.hpp"
#include "csp/bridge/client.hpp"
#include "csp/bridge/controllers.hpp"
#include "csp/bridge/csv_convert.hpp"
#include "csp/bridge/replay.hpp"
#include "csp/rt/csv_log.hpp"
#include "support.hpp"

namespace csp::bridge {
namespace {

using namespace std::chrono_literals;


// status_t messages of a log, in order.
std::vector<status_t> statuses_in_log(const std::string& path) {
  LogReader log(path);
  std::vector<status_t> statuses;
  for (const LogEvent* e = log.next(); e; e = log.next()) {
    status_t s;
    if (e->channel == "CSP_STATUS" && decode_exact(e->data, e->datalen, s) == Rejection::kNone) statuses.push_back(s);
  }
  return statuses;
}

// csp serve (lockstep) + csp_lcm_joint_impedance in two processes for 2000+ cycles: no lost
// command, the states of the in-process run (the LCM log's states and the --csv log's rows), and a
// log that replays bit for bit. The controller
// starts 2 s after the server: the round trip (rt::TimingReport) times a session's states only,
// not the wait for a controller.
TEST(BridgeNet, LockstepExternalControllerMatchesInProcessRun) {
  const std::string url = test::unique_lcm_url(0), log = test::temp_path("lockstep.lcmlog");
  const std::string csv = test::temp_path("lockstep.csv"), reference_csv = test::temp_path("lockstep_reference.csv");
  const double motion = 2.0;
  test::Process server({CSP_EXECUTABLE, "serve", test::kDefaultScenario, "--clock", "lockstep", "--wait", "--duration", "2.1",
                        "--lockstep-timeout", "5", "--lcm-url", url, "--log", log, "--csv", csv},
                       test::temp_path("serve.out"));
  std::this_thread::sleep_for(2s);
  test::Process controller({CSP_LCM_JOINT_IMPEDANCE, "--lcm-url", url, "--duration", "2", "--amplitude", "0.2", "--timeout", "30"},
                           test::temp_path("controller.out"));
  ASSERT_EQ(controller.wait(60s), 0) << controller.output();
  ASSERT_EQ(server.wait(30s), 0) << server.output();

  const std::vector<robot_state_t> served = test::states_in_log(log);
  ASSERT_EQ(served.size(), 2101u);
  const status_t status = statuses_in_log(log).back();
  EXPECT_EQ(status.sessions, 1);
  EXPECT_EQ(status.motion_cycles, 2001);
  EXPECT_EQ(status.lost_commands, 0);
  EXPECT_EQ(status.rejected_stale + status.rejected_fingerprint + status.rejected_truncated + status.rejected_oversized, 0);
  EXPECT_GT(status.round_trip_max_us, 0.0);
  EXPECT_LT(status.round_trip_max_us, 1e6 * std::chrono::duration<double>(2s).count())
      << "the round trip counted the wait for the controller";

  // The same controller in-process from the same scenario, then the same idle cycles.
  const rt::Scenario scenario = rt::load_scenario(test::kDefaultScenario);
  rt::Emulator emulator(scenario.emulator);
  std::vector<robot_state_t> reference{to_message(emulator.state(), 0, false)};
  {
    rt::CsvLog reference_log(reference_csv);
    reference_log.write(emulator.state(), rt::CycleInfo{});
    rt::LoopOptions options;
    options.observer = [&](const rt::RobotState& s, const rt::CycleInfo& c) {
      reference.push_back(to_message(s, 0, c.command_received));
      reference_log.write(s, c);
    };
    rt::run_motion(emulator, rt::ControlMode::kTorque,
                   joint_impedance_controller(example_joint_stiffness(), example_joint_damping(), example_excitation(0.2), motion), options);
    while (reference.size() < served.size()) {
      emulator.step(nullptr);
      reference.push_back(to_message(emulator.state(), 0, false));
      reference_log.write(emulator.state(), rt::CycleInfo{});
    }
  }
  EXPECT_EQ(test::read_text(csv), test::read_text(reference_csv)) << "the --csv log of the served robot";
  for (std::size_t i = 0; i < served.size(); ++i) {
    std::string field;
    ASSERT_EQ(state_difference(served[i], reference[i], field), 0.0) << "state " << i << ": " << field;
  }

  const ResimulationReport replay = resimulate(log);
  EXPECT_EQ(replay.states, served.size());
  EXPECT_EQ(replay.differing_states, 0u) << replay.first_difference;
  std::filesystem::remove(log);
  std::filesystem::remove(csv);
  std::filesystem::remove(reference_csv);
}

// Real time, a controller that stops answering after 300 commands: the robot ends the session
// with communication_constraints_violation after 20 lost cycles and the server shuts down cleanly.
TEST(BridgeNet, RealtimeSilentControllerTriggersCommunicationConstraintsViolation) {
  const std::string url = test::unique_lcm_url(1), log = test::temp_path("realtime.lcmlog");
  test::Process server({CSP_EXECUTABLE, "serve", test::kDefaultScenario, "--clock", "realtime", "--duration", "1.5", "--lcm-url", url, "--log", log},
                       test::temp_path("serve-rt.out"));
  Client client(url, "", 30.0);   // generous: the server may start slowly on a loaded machine
  int commands = 0;
  const rt::Controller silent_after_300 = [&](const rt::RobotState& state, rt::Duration) {
    if (++commands == 300) std::this_thread::sleep_for(100ms);   // the controller hangs for 100 cycles
    return rt::Command{-Vector7::Constant(2.0).cwiseProduct(Vector7(state.dq.data())), false};
  };
  const SessionResult result = client.control(rt::ControlMode::kTorque, silent_after_300);
  EXPECT_TRUE(result.reflex);
  EXPECT_TRUE(result.state.last_motion_errors.communication_constraints_violation);
  ASSERT_EQ(server.wait(30s), 0) << server.output();

  const std::vector<robot_state_t> states = test::states_in_log(log);
  const status_t status = statuses_in_log(log).back();
  EXPECT_EQ(status.cycles, 1500);
  EXPECT_EQ(states.size(), static_cast<std::size_t>(status.cycles) + 1);   // every cycle's state, and the last one's result
  for (std::size_t i = 0; i < states.size(); ++i) ASSERT_EQ(states[i].message_id, static_cast<int64_t>(i));
  EXPECT_GE(status.max_consecutive_lost, 20);
  EXPECT_EQ(status.reflexes, 1);
  EXPECT_NE(status.last_reflex.find("communication_constraints_violation"), std::string::npos);
  EXPECT_EQ(resimulate(log).differing_states, 0u);   // real-time logs replay too
  std::filesystem::remove(log);
}

// lcm-logger records a csp serve session: csp log export reads it, and its rows are those of
// CSP's own log of the same session.
TEST(BridgeNet, LcmLoggerRecordingIsReadByCspLogExport) {
  const std::string url = test::unique_lcm_url(2), theirs = test::temp_path("lcm-logger.lcmlog"),
                    ours = test::temp_path("ours.lcmlog"), theirs_csv = test::temp_path("theirs.csv"),
                    ours_csv = test::temp_path("ours.csv");
  test::Process logger({"/usr/bin/lcm-logger", "--lcm-url=" + url, "-f", "--flush-interval=10", theirs}, test::temp_path("logger.out"));
  lcm::LCM probe(url);
  ASSERT_TRUE(probe.good());
  // Markers on a channel of their own: the logger records the session only once it has
  // recorded "ready", and has received all of it once it has recorded "end".
  ASSERT_TRUE(test::wait_until_logged(probe, theirs, "ready")) << logger.output();
  test::Process server({CSP_EXECUTABLE, "serve", test::kDefaultScenario, "--clock", "realtime", "--duration", "0.3", "--lcm-url", url, "--log", ours},
                       test::temp_path("serve-logger.out"));
  ASSERT_EQ(server.wait(30s), 0) << server.output();
  ASSERT_TRUE(test::wait_until_logged(probe, theirs, "end")) << logger.output();
  logger.signal(SIGINT);
  ASSERT_EQ(logger.wait(10s), 0) << logger.output();

  const ExportReport a = export_csv(theirs, theirs_csv, "CSP_STATE");
  const ExportReport b = export_csv(ours, ours_csv, "CSP_STATE");
  EXPECT_EQ(b.rows, 301u);
  EXPECT_EQ(a.rows, b.rows);   // loopback multicast loses nothing at this rate
  std::ifstream x(theirs_csv), y(ours_csv);
  EXPECT_EQ(std::string((std::istreambuf_iterator<char>(x)), {}), std::string((std::istreambuf_iterator<char>(y)), {}));
  for (const std::string& f : {theirs, ours, theirs_csv, ours_csv}) std::filesystem::remove(f);
}

// lcm-logplayer plays a CSP log; a CSP subscriber receives and decodes every state.
TEST(BridgeNet, LcmLogplayerPlaysACspLog) {
  const std::string url = test::unique_lcm_url(3), path = test::temp_path("played.lcmlog");
  rt::Emulator emulator(rt::load_scenario(test::kDefaultScenario).emulator);
  {
    LogWriter log(path);
    for (int i = 0; i < 200; ++i) {
      log.write("CSP_STATE", encode(to_message(emulator.state(), 1'000'000 + i * 1000, false)), 1'000'000 + i * 1000);
      emulator.step(nullptr);
    }
  }
  lcm::LCM lcm(url);
  ASSERT_TRUE(lcm.good());
  std::vector<int64_t> ids;
  lcm.subscribeFunction<robot_state_t, std::vector<int64_t>*>(
      "CSP_STATE",
      [](const lcm::ReceiveBuffer*, const std::string&, const robot_state_t* m, std::vector<int64_t>* received) {
        received->push_back(m->message_id);
      },
      &ids);
  test::Process player({"/usr/bin/lcm-logplayer", "--lcm-url=" + url, "--speed=1", path}, test::temp_path("player.out"));
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (ids.size() < 200 && std::chrono::steady_clock::now() < deadline) lcm.handleTimeout(100);
  EXPECT_EQ(player.wait(10s), 0) << player.output();
  ASSERT_EQ(ids.size(), 200u);
  for (int i = 0; i < 200; ++i) EXPECT_EQ(ids[i], i);
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace csp::bridge
