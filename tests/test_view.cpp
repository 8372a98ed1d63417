// csp view's data and server (view/): poses against Franka's MDH table, clearance against the
// emulator's contact, events where the robot's errors appear, plot series that keep every extreme,
// the web server's answers (and refusals) over real HTTP, and live frames over a real WebSocket
// during a run, with the run's cycles kept.
#include <civetweb.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "csp/rt/csv_log.hpp"
#include "csp/run/sources.hpp"
#include "csp/view/inputs.hpp"
#include "csp/view/live_view.hpp"
#include "csp/view/server.hpp"
#include "support.hpp"

namespace csp::view {
namespace {

using nlohmann::json;

rt::Scenario shipped(const std::string& name) { return rt::load_scenario(rt::shipped_scenario_path(name)); }

// ^0T_i of Franka's MDH rows in the data file (RotX(alpha) TransX(a) RotZ(q) TransZ(d)), written
// here from the table, not with dynamics/.
std::vector<Eigen::Matrix4d> mdh_frames(const Vector7& q) {
  std::vector<Eigen::Matrix4d> frames;
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  int i = 0;
  for (const json& row : test::franka_models()["kinematics"]["mdh_panda_fr3"]["rows"]) {
    const double alpha = row["alpha"], a = row["a"], d = row["d"];
    const double theta = (row.contains("fixed") ? 0.0 : q[i++]) + row["theta_offset"].get<double>();
    Eigen::Matrix4d step;
    step << std::cos(theta), -std::sin(theta), 0, a,                                                    //
        std::sin(theta) * std::cos(alpha), std::cos(theta) * std::cos(alpha), -std::sin(alpha), -d * std::sin(alpha),  //
        std::sin(theta) * std::sin(alpha), std::cos(theta) * std::sin(alpha), std::cos(alpha), d * std::cos(alpha),    //
        0, 0, 0, 1;
    T = T * step;
    frames.push_back(T);
  }
  return frames;   // links 1..7, then the flange
}

Eigen::Matrix4d matrix_of(const json& column_major) {
  Eigen::Matrix4d m;
  for (int k = 0; k < 16; ++k) m(k % 4, k / 4) = column_major[k];
  return m;
}

JointLog one_row(const Vector7& q) {
  JointLog log;
  log.t = {0.0};
  log.q = {q};
  log.dq = {Vector7::Zero()};
  log.tau_J = {Vector7::Zero()};
  return log;
}

TEST(ViewModel, EveryLinkIsWhereFrankasMdhTablePutsIt) {
  for (const char* robot : {"default", "libfranka_fr3"}) {
    ViewModel model(view_robot(shipped(robot)));
    std::mt19937 random(7);
    const JointLimits& limits = model.robot().parameters.joint_limits;
    for (int k = 0; k < 20; ++k) {
      Vector7 q;
      for (int j = 0; j < kNumJoints; ++j) q[j] = std::uniform_real_distribution<double>(limits.q_min[j], limits.q_max[j])(random);
      const json frame = model.frame(one_row(q), 0);
      const std::vector<Eigen::Matrix4d> expected = mdh_frames(q);
      for (int i = 0; i < kNumJoints; ++i)
        EXPECT_LT((matrix_of(frame["links"][i]) - expected[i]).cwiseAbs().maxCoeff(), 2e-6) << robot << " link " << i + 1;
      EXPECT_LT((matrix_of(frame["flange"]) - expected[7]).cwiseAbs().maxCoeff(), 2e-6) << robot << " flange";
    }
  }
}

TEST(ViewModel, ClearanceIsThePenetrationTheEmulatorsContactFeels) {
  // The ultrasound scan presses the probe into the abdomen: at each cycle in contact, the view's
  // clearance is minus the deepest penetration the emulator's contact engine computed.
  rt::Scenario scenario = shipped("medical/ultrasound_abdomen_scan");
  scenario.duration = 4.0;   // the probe touches the skin at about 2.2 s
  run::Run run(scenario);
  ViewModel model(view_robot(scenario));
  struct Compare : run::Observer {
    Compare(const run::Run& r, ViewModel& m) : run(r), model(m) {}
    void on_cycle(const rt::RobotState& state, const rt::CycleInfo&) override {
      const rt::ContactState& contact = run.emulator().contact();
      const std::optional<Clearance> c = model.clearance(Vector7(state.q.data()), state.time.toSec());
      ASSERT_TRUE(c.has_value());
      EXPECT_NEAR((c->on_arm - c->on_obstacle).norm(), std::abs(c->distance), 1e-9);
      if (contact.active_contacts == 0) return;
      ++in_contact;
      // The contact engine measures at its last substep's start, half a millisecond before the
      // published q (2 substeps): the probe presses in at up to 5.3 cm/s (27 um in 0.5 ms) and scans
      // at 2 cm/s, so the two agree to 50 um.
      EXPECT_NEAR(c->distance, -contact.max_penetration, 5e-5) << "t = " << state.time.toSec();
    }
    const run::Run& run;
    ViewModel& model;
    int in_contact = 0;
  } compare(run, model);
  run.observe(compare);
  run::ControllerSource controller(run);
  run.run(controller);
  EXPECT_GT(compare.in_contact, 100);   // the check ran on the scan itself
}

TEST(Recording, AReflexIsAnEventAtItsCycleWithItsLibfrankaName) {
  // fr3_float ends in cartesian_reflex when it is pushed (docs/emulator.md).
  rt::Scenario scenario = shipped("fr3_float");
  const JointLog log = run_scenario(scenario);
  ViewModel model(view_robot(scenario));
  const Recording recording = record(model, log);
  std::size_t first_error = 0;
  while (first_error < log.size() && log.current_errors[first_error] == "[]") ++first_error;
  ASSERT_LT(first_error, log.size()) << "the scenario no longer ends in a reflex";
  // The first event with errors (the run's start, Idle -> Move, is an event without).
  const auto with_errors = std::find_if(recording.events.begin(), recording.events.end(),
                                        [](const json& e) { return !e["errors"].empty(); });
  ASSERT_NE(with_errors, recording.events.end());
  const json& event = *with_errors;
  EXPECT_EQ(recording.events[0]["mode"], "Move");
  EXPECT_DOUBLE_EQ(event["t"].get<double>(), log.t[first_error]);
  EXPECT_EQ(event["errors"][0]["name"], "cartesian_reflex");
  EXPECT_EQ(event["errors"][0]["joint"], -1);   // a Cartesian error is about no one joint
  // The frame at the reflex is in the recording with the error.
  bool found = false;
  for (const json& frame : recording.frames) found |= frame["t"] == log.t[first_error] && frame.contains("errors");
  EXPECT_TRUE(found);
  // Frames are at most kFrameInterval apart.
  for (std::size_t k = 1; k < recording.frames.size(); ++k)
    EXPECT_LE(recording.frames[k]["t"].get<double>() - recording.frames[k - 1]["t"].get<double>(), kFrameInterval + 1e-9);
}

TEST(Recording, TheErrorsJointIsTheOneAtItsLimit) {
  const JointLimits limits = view_robot(shipped("default")).parameters.joint_limits;
  JointLog log = one_row(0.5 * (limits.q_min + limits.q_max));
  log.q[0][4] = limits.q_max[4] - 1e-3;   // joint 5 at its upper limit
  EXPECT_EQ(joint_of_error("joint_position_limits_violation", log, 0, limits), 4);
  log.dq[0][2] = 0.99 * limits.dq_max[2];   // joint 3 at its speed limit
  EXPECT_EQ(joint_of_error("joint_velocity_violation", log, 0, limits), 2);
  log.tau_J[0][6] = -0.95 * limits.tau_max[6];
  EXPECT_EQ(joint_of_error("tau_j_range_violation", log, 0, limits), 6);
  EXPECT_EQ(joint_of_error("communication_constraints_violation", log, 0, limits), -1);
}

TEST(Recording, ASeriesKeepsEverySpikeAndItsColumnsShareTheirSamples) {
  std::mt19937 random(3);
  std::vector<double> values(100000);
  for (double& v : values) v = std::normal_distribution<double>(0.0, 1.0)(random);
  values[31337] = 50.0;    // one sample of a spike
  values[77777] = -50.0;
  const std::vector<std::size_t> kept = decimate(values, kMaxSeriesPoints);
  EXPECT_LE(kept.size(), kMaxSeriesPoints);
  EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
  EXPECT_NE(std::find(kept.begin(), kept.end(), 31337u), kept.end());
  EXPECT_NE(std::find(kept.begin(), kept.end(), 77777u), kept.end());
  EXPECT_EQ(kept.front(), 0u);
  EXPECT_EQ(kept.back(), values.size() - 1);

  const JointLog log = run_scenario(shipped("default"));
  ViewModel model(view_robot(shipped("default")));
  const Recording recording = record(model, log);
  const json s = series(recording, {"tau_J1", "tracking_error3"});
  ASSERT_EQ(s["t"].size(), s["columns"]["tau_J1"].size());
  ASSERT_EQ(s["t"].size(), s["columns"]["tracking_error3"].size());
  for (std::size_t k = 0; k < s["t"].size(); k += 97) {
    const double t = s["t"][k];
    const std::size_t row = static_cast<std::size_t>(std::lower_bound(log.t.begin(), log.t.end(), t) - log.t.begin());
    EXPECT_EQ(s["columns"]["tau_J1"][k].get<double>(), log.tau_J[row][0]);
    EXPECT_EQ(s["columns"]["tracking_error3"][k].get<double>(), log.q_d[row][2] - log.q[row][2]);
  }
  EXPECT_THROW(series(recording, {"tau_J9"}), std::out_of_range);
}

// --- The server over real sockets (civetweb's own client).
struct Response {
  int status = 0;
  std::string type, body;
};

// The port of a server's url, http://127.0.0.1:PORT/.
int port_of(const std::string& url) { return std::stoi(url.substr(url.rfind(':') + 1)); }

Response get(const std::string& url, const std::string& path) {
  const int port = port_of(url);
  char error[256] = "";
  mg_connection* connection =
      mg_download("127.0.0.1", port, 0, error, sizeof error, "GET %s HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n", path.c_str());
  if (connection == nullptr) throw std::runtime_error(std::string("GET ") + path + ": " + error);
  Response response;
  const mg_response_info* info = mg_get_response_info(connection);
  response.status = info->status_code;
  for (int i = 0; i < info->num_headers; ++i)
    if (std::string(info->http_headers[i].name) == "Content-Type") response.type = info->http_headers[i].value;
  char buffer[65536];
  for (int n; (n = mg_read(connection, buffer, sizeof buffer)) > 0;) response.body.append(buffer, static_cast<std::size_t>(n));
  mg_close_connection(connection);
  return response;
}

TEST(ViewServer, AnswersThePageTheDataAndRefusesWhatItDoesNotHave) {
  const rt::Scenario scenario = shipped("default");
  ViewModel model(view_robot(scenario));
  json description = model.description();
  description["live"] = false;
  ViewServer server("127.0.0.1", 0, description);

  EXPECT_EQ(json::parse(get(server.url(), "/api/description").body), description);
  const Response none = get(server.url(), "/api/recording");
  EXPECT_EQ(none.status, 404);
  EXPECT_NE(json::parse(none.body)["error"].get<std::string>().find("no recorded run"), std::string::npos);

  const JointLog log = run_scenario(scenario);
  server.set_recording(std::make_shared<Recording>(record(model, log)));
  const json recording = json::parse(get(server.url(), "/api/recording").body);
  EXPECT_EQ(recording["frames"].size(), record(model, log).frames.size());
  EXPECT_EQ(recording["frames"][0]["t"], log.t[0]);
  const Response s = get(server.url(), "/api/series?names=q1,q2");
  EXPECT_EQ(s.status, 200);
  EXPECT_EQ(json::parse(s.body)["columns"]["q2"].size(), json::parse(s.body)["t"].size());
  const Response unknown = get(server.url(), "/api/series?names=q1,nope");
  EXPECT_EQ(unknown.status, 404);
  EXPECT_NE(unknown.body.find("nope"), std::string::npos);
  EXPECT_EQ(get(server.url(), "/api/series").status, 400);

  const Response page = get(server.url(), "/");
  EXPECT_EQ(page.status, 200);
  EXPECT_EQ(page.type.rfind("text/html", 0), 0u);
  EXPECT_NE(page.body.find("importmap"), std::string::npos);
  const Response three = get(server.url(), "/vendor/three/build/three.module.js");
  EXPECT_EQ(three.status, 200);
  EXPECT_EQ(three.type, "text/javascript");   // an ES module needs a JavaScript type
  const Response mesh = get(server.url(), "/meshes/robot_arms/fer/collision/link4.stl");
  EXPECT_EQ(mesh.status, 200);
  EXPECT_GT(mesh.body.size(), 1000u);
  for (const char* outside : {"/../CMakeLists.txt", "/meshes/../../../franka_models.json", "/%2e%2e/%2e%2e/etc/passwd", "/nothing.js"})
    EXPECT_EQ(get(server.url(), outside).status, 404) << outside;

  // A port that is taken: one error naming the address.
  const int port = port_of(server.url());
  try {
    ViewServer second("127.0.0.1", port, description);
    FAIL() << "a second server on a taken port";
  } catch (const std::runtime_error& error) {
    EXPECT_NE(std::string(error.what()).find("cannot listen on 127.0.0.1:" + std::to_string(port)), std::string::npos) << error.what();
  }
  EXPECT_THROW(ViewServer("127.0.0.1", 70000, description), std::runtime_error);
}

// A live page: civetweb's WebSocket client, collecting what the server sends.
struct LivePage {
  std::mutex mutex;
  std::vector<json> messages;
  std::atomic<bool> closed{false};

  static int on_data(mg_connection*, int flags, char* data, std::size_t length, void* self) {
    auto* page = static_cast<LivePage*>(self);
    if ((flags & 0xf) == MG_WEBSOCKET_OPCODE_TEXT) {
      const std::lock_guard lock(page->mutex);
      page->messages.push_back(json::parse(std::string(data, length)));
    }
    return 1;
  }
  static void on_close(const mg_connection*, void* self) { static_cast<LivePage*>(self)->closed = true; }
};

// The run without a view: its last state, to compare the viewed run with.
rt::RobotState unviewed_end(const rt::Scenario& scenario) {
  run::Run run(scenario);
  run::ControllerSource controller(run);
  run.run(controller);
  return run.emulator().state();
}

TEST(LiveView, APageSeesTheRunsStatesAsTheyHappenAndTheRunIsUnchanged) {
  rt::Scenario scenario = shipped("default");
  scenario.clock = rt::Clock::kLockstep;   // deterministic: the viewed run must equal the unviewed one
  scenario.duration = 3.0;
  run::Run run(scenario);
  ViewServer server("127.0.0.1", 0, json::object());
  LiveView live(server, view_robot(scenario), 1000.0);   // a frame wanted every millisecond: the most a page can ask
  JointLog states;   // every state of the run, to compare the frames with
  struct Record : run::Observer {
    explicit Record(JointLog& l) : log(l) {}
    void on_cycle(const rt::RobotState& state, const rt::CycleInfo& cycle) override { rt::append_state(log, state, cycle.command_received); }
    JointLog& log;
  } recorder(states);
  run.observe(recorder);
  run.observe(live);

  LivePage page;
  char error[256] = "";
  const int port = port_of(server.url());
  mg_connection* socket = mg_connect_websocket_client("127.0.0.1", port, 0, error, sizeof error, "/api/live", nullptr,
                                                      LivePage::on_data, LivePage::on_close, &page);
  ASSERT_NE(socket, nullptr) << error;
  while (server.pages() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(5));

  run::ControllerSource controller(run);
  run.run(controller);
  live.finish(run.emulator().state(), "finished");
  for (int wait = 0; wait < 200; ++wait) {   // the end message on its way
    {
      const std::lock_guard lock(page.mutex);
      if (!page.messages.empty() && page.messages.back()["type"] == "end") break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  mg_close_connection(socket);

  EXPECT_EQ(run.emulator().counters().motion_cycles, 3000u);
  EXPECT_EQ(run.emulator().counters().lost_commands, 0u);
  const rt::RobotState unviewed = unviewed_end(scenario);
  EXPECT_EQ(run.emulator().state().q, unviewed.q);   // bit for bit: the view only watches
  EXPECT_EQ(run.emulator().state().tau_J, unviewed.tau_J);
  const std::lock_guard lock(page.mutex);
  ASSERT_GE(page.messages.size(), 3u);   // at least a frame during the run, the last state's, the end
  EXPECT_EQ(page.messages.back()["type"], "end");
  EXPECT_EQ(page.messages.back()["text"], "finished");
  double last_t = -1.0;
  for (std::size_t k = 0; k + 1 < page.messages.size(); ++k) {
    const json& frame = page.messages[k];
    ASSERT_EQ(frame["type"], "frame");
    const double t = frame["t"];
    EXPECT_GT(t, last_t);
    last_t = t;
    // The frame is the state of its time: its q (and the link poses from it).
    const std::size_t row = static_cast<std::size_t>(std::lower_bound(states.t.begin(), states.t.end(), t) - states.t.begin());
    ASSERT_LT(row, states.size());
    ASSERT_EQ(states.t[row], t);
    const ColumnGroup& q = kJointLogSchema[1];
    for (int j = 0; j < kNumJoints; ++j) EXPECT_EQ(frame["values"][column_name(q, j)].get<double>(), states.q[row][j]);
    const std::vector<Eigen::Matrix4d> expected = mdh_frames(states.q[row]);
    EXPECT_LT((matrix_of(frame["flange"]) - expected[7]).cwiseAbs().maxCoeff(), 2e-6);
  }
  EXPECT_EQ(live.frames_sent() + 1, page.messages.size());   // the last state's frame counts in frames_sent
}

}  // namespace
}  // namespace csp::view
