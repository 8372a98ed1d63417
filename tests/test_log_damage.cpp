// Damaged LCM logs: every reader says where the damage is and how much it skipped, nothing
// crashes, and replay never calls a partial log identical (issue: a data length of 0x7FFFFFFF
// crashed liblcm's reader; a log cut short replayed "bit for bit" from 59 of 501 states).
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <filesystem>
#include <fstream>

#include "bridge_support.hpp"
#include "csp/bridge/csv_convert.hpp"
#include "csp/bridge/replay.hpp"
#include "csp/rt/controllers.hpp"
#include "csp/rt/csv_log.hpp"

namespace csp::bridge {
namespace {

// A CSP log of `seconds` of the default scenario (as `csp emulate --lcm-log` writes it).
std::string emulate_log(const std::string& name, double seconds) {
  const std::string path = test::temp_path(name);
  const rt::Scenario scenario = rt::load_scenario(rt::default_scenario_path());
  rt::Emulator emulator(scenario.emulator);
  const rt::BuiltinController builtin = rt::make_controller(scenario.controller, scenario.controller_faults, emulator);
  EmulateLogRecorder recorder(path, scenario, emulator, builtin.mode);
  rt::LoopOptions options;
  options.max_duration = seconds;
  options.observer = [&](const rt::RobotState& s, const rt::CycleInfo& c) { recorder.record(s, c); };
  rt::run_motion(emulator, builtin.mode, builtin.controller, options);
  return path;
}

void overwrite(const std::string& path, std::streamoff offset, const std::vector<uint8_t>& bytes) {
  std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
  file.seekp(offset);
  file.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

// Byte offsets of every event header, read independently of LogReader: lcm-logger's layout is
// 28 header bytes (sync, event number, timestamp, channel length, data length) + channel + data.
std::vector<uint64_t> event_offsets(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)), {});
  const auto be32 = [&](uint64_t at) { return (uint32_t{bytes[at]} << 24) | (uint32_t{bytes[at + 1]} << 16) | (uint32_t{bytes[at + 2]} << 8) | bytes[at + 3]; };
  std::vector<uint64_t> offsets;
  for (uint64_t at = 0; at + 28 <= bytes.size(); at += 28 + be32(at + 20) + be32(at + 24)) offsets.push_back(at);
  return offsets;
}

TEST(LogDamage, HugeDataLengthIsSkippedAndNamed) {
  const std::string path = emulate_log("huge-length.lcmlog", 0.01);
  const std::vector<uint64_t> offsets = event_offsets(path);
  overwrite(path, 24, {0x7f, 0xff, 0xff, 0xff});   // the first event's data length (the reproduction of the issue)
  LogReader log(path);
  uint64_t events = 0;
  while (log.next()) ++events;
  EXPECT_EQ(events, offsets.size() - 1);
  ASSERT_EQ(log.damage().size(), 1u);
  EXPECT_EQ(log.damage()[0].offset, 0u);
  EXPECT_EQ(log.damage()[0].bytes_skipped, offsets[1]);
  EXPECT_NE(log.damage()[0].what.find("2147483647"), std::string::npos) << log.damage()[0].what;
  // The scenario record was the damaged event: replay refuses the log and says why.
  try {
    resimulate(path);
    FAIL() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("damaged log"), std::string::npos) << e.what();
  }
  std::filesystem::remove(path);
}

TEST(LogDamage, ALogCutShortIsNeverIdentical) {
  const std::string path = emulate_log("cut.lcmlog", 0.5);
  const ResimulationReport whole = resimulate(path);
  ASSERT_TRUE(whole.identical());
  const auto size = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, size * 3 / 10);
  const ResimulationReport part = resimulate(path);
  EXPECT_LT(part.states, whole.states);
  EXPECT_EQ(part.differing_states, 0u);   // what was read replays bit for bit ...
  EXPECT_FALSE(part.identical());         // ... but the log is not whole
  EXPECT_NE(part.damage.find("run past the end of the file"), std::string::npos) << part.damage;
  std::filesystem::remove(path);
}

TEST(LogDamage, ADamagedHeaderInTheMiddleIsSkippedToTheNextEvent) {
  const std::string path = emulate_log("middle.lcmlog", 0.1);
  const std::vector<uint64_t> offsets = event_offsets(path);
  const std::size_t k = offsets.size() / 2;
  overwrite(path, static_cast<std::streamoff>(offsets[k]), {0, 0, 0, 0});   // its sync word
  LogReader log(path);
  uint64_t events = 0;
  while (log.next()) ++events;
  EXPECT_EQ(events, offsets.size() - 1);
  ASSERT_EQ(log.damage().size(), 1u);
  EXPECT_EQ(log.damage()[0].offset, offsets[k]);
  EXPECT_EQ(log.damage()[0].bytes_skipped, offsets[k + 1] - offsets[k]);
  EXPECT_NE(log.damage_summary().find("at byte " + std::to_string(offsets[k])), std::string::npos) << log.damage_summary();
  EXPECT_FALSE(resimulate(path).identical());
  std::filesystem::remove(path);
}

TEST(LogDamage, ExportReportsItAndGapRefusesIt) {
  const std::string path = emulate_log("export.lcmlog", 0.2), csv = test::temp_path("export.csv");
  std::filesystem::resize_file(path, std::filesystem::file_size(path) * 2 / 3);
  const ExportReport r = export_csv(path, csv, "CSP_STATE");
  EXPECT_GT(r.rows, 10u);
  EXPECT_NE(r.damage.find("damaged log"), std::string::npos) << r.damage;
  try {
    read_joint_log_lcm(path, "CSP_STATE");
    FAIL() << "expected an error";
  } catch (const JointLogError& e) {
    EXPECT_NE(std::string(e.what()).find("damaged log"), std::string::npos) << e.what();
  }
  for (const std::string& f : {path, csv}) std::filesystem::remove(f);
}

TEST(LogDamage, PlaybackDoesNotWaitForACorruptedTimestamp) {
  const std::string path = test::temp_path("timestamps.lcmlog");
  {
    LogWriter log(path);
    for (int64_t t : {int64_t{0}, int64_t{1000}, int64_t{3'600'000'000}, int64_t{2000}, INT64_MIN, int64_t{3000}})
      log.write("TEST_PLAY", "x", 1, t);
  }
  PlaybackOptions options;
  options.lcm_url = test::unique_lcm_url(5);
  const PlaybackReport r = play_back(path, options);   // an hour's wait would time the test out
  EXPECT_EQ(r.published, 6u);
  EXPECT_EQ(r.timestamp_jumps, 4u);   // +1 h, back, to INT64_MIN, up from it
  EXPECT_TRUE(r.damage.empty());
  options.speed = 1e-320;
  EXPECT_THROW(play_back(path, options), std::invalid_argument);
  std::filesystem::remove(path);
}

TEST(LogDamage, ReplayCommandExitsNonZeroOnADamagedLog) {
  const std::string path = emulate_log("cli.lcmlog", 0.2);
  std::filesystem::resize_file(path, std::filesystem::file_size(path) - 10);
  test::Process replay({CSP_EXECUTABLE, "replay", path}, test::temp_path("replay.out"));
  EXPECT_EQ(replay.wait(std::chrono::seconds(60)), 1);
  const std::string out = replay.output();
  EXPECT_EQ(out.find("identical"), std::string::npos) << out;
  EXPECT_NE(out.find("NOT a full replay"), std::string::npos) << out;
  EXPECT_NE(out.find("damaged log"), std::string::npos) << out;
  std::filesystem::remove(path);
}

// A log that cannot be written is named as such and stops the run cleanly (it was reported as a
// reflex with an empty reason), as every other error is: one line on stderr, exit 2 (it was a line
// on stdout and exit 1). A device is refused before the run; a write that fails during the run
// (here the file size limit, as a full disk would) ends it, and the log keeps every whole row.

// `csp args...` under a file size limit of 64 kB (a write past it fails with EFBIG, as on a full
// disk), stdout to `out` and stderr to `err`; returns the exit status.
int csp_with_file_limit(const std::vector<std::string>& args, const std::string& out, const std::string& err) {
  std::vector<std::string> argv = {"/bin/sh", "-c", "ulimit -f 128; trap '' XFSZ; exec \"$@\" 2>\"$ERR\"", "sh", CSP_EXECUTABLE};
  argv.insert(argv.end(), args.begin(), args.end());
  ::setenv("ERR", err.c_str(), 1);
  test::Process run(argv, out);
  const int status = run.wait(std::chrono::seconds(120));
  ::unsetenv("ERR");
  return status;
}

std::string text_of(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

TEST(LogDamage, EmulateRefusesADeviceBeforeTheRun) {
  test::Process emulate({CSP_EXECUTABLE, "emulate", "--duration", "1", "--log", "/dev/full"}, test::temp_path("full.out"));
  EXPECT_EQ(emulate.wait(std::chrono::seconds(60)), 2);
  const std::string out = emulate.output();
  EXPECT_EQ(out, "csp emulate: --log /dev/full: is not a regular file (a device, FIFO or socket); give a file on a disk\n");
}

TEST(LogDamage, EmulateNamesAWriteErrorOnStderrAndKeepsTheWholeRows) {
  const std::string csv = test::temp_path("limited.csv"), out = test::temp_path("limited.out"), err = test::temp_path("limited.err");
  EXPECT_EQ(csp_with_file_limit({"emulate", "--duration", "2", "--log", csv}, out, err), 2);
  const std::string stdout_text = text_of(out), stderr_text = text_of(err);
  EXPECT_NE(stdout_text.find("STOPPED at t = "), std::string::npos) << stdout_text;
  EXPECT_NE(stdout_text.find("ran "), std::string::npos) << stdout_text;   // the summary
  EXPECT_EQ(stdout_text.find("REFLEX"), std::string::npos) << stdout_text;
  EXPECT_EQ(stderr_text, "csp emulate: " + csv + ": writing the log failed (File too large); the file ends at its last complete row\n");
  // Nothing written is lost: the file is the rows before the failure, each whole.
  const std::string text = text_of(csv);
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  EXPECT_GT(text.size(), 32u * 1024);
  EXPECT_GT(read_joint_log_csv(csv).size(), 10u);

  const std::string lcm = test::temp_path("limited.lcmlog");
  EXPECT_EQ(csp_with_file_limit({"emulate", "--duration", "2", "--lcm-log", lcm}, out, err), 2);
  const std::string lcm_error = text_of(err);
  EXPECT_NE(lcm_error.find(lcm + ": writing the LCM log failed (File too large)"), std::string::npos) << lcm_error;
  EXPECT_EQ(std::count(lcm_error.begin(), lcm_error.end(), '\n'), 1) << lcm_error;
  LogReader log(lcm);
  uint64_t events = 0;
  while (log.next()) ++events;
  EXPECT_GT(events, 10u);
  EXPECT_TRUE(log.damage().empty()) << log.damage_summary();

  // The other commands with a per-cycle CSV log say it the same way.
  const std::string recording = emulate_log("to-replay.lcmlog", 2.0);
  EXPECT_EQ(csp_with_file_limit({"replay", recording, "--csv", csv}, out, err), 2);
  EXPECT_EQ(text_of(err), "csp replay: " + csv + ": writing the log failed (File too large); the file ends at its last complete row\n");
  EXPECT_EQ(text_of(out).find("identical"), std::string::npos) << text_of(out);
  for (const std::string& f : {csv, out, err, lcm, recording}) std::filesystem::remove(f);
}

// `csp replay --play` of an empty file said "published 0 events" and exited 0.
TEST(LogDamage, PlayingBackNothingIsAnError) {
  const std::string empty = test::temp_path("empty.lcmlog");
  std::ofstream(empty).close();
  test::Process play({CSP_EXECUTABLE, "replay", "--play", "--lcm-url", test::unique_lcm_url(6), empty}, test::temp_path("empty.out"));
  EXPECT_EQ(play.wait(std::chrono::seconds(60)), 2);
  EXPECT_EQ(play.output(), "csp replay: " + empty + ": no event to publish (an empty log)\n");
  std::filesystem::remove(empty);
}

// A re-simulation that compared no state is never "identical, bit for bit" (it was, exit 0).
TEST(LogDamage, NoStateComparedIsNeverIdentical) {
  const std::string path = emulate_log("stopped.lcmlog", 0.05);
  const Recording recording(path);
  rt::Emulator robot(recording.scenario.emulator);
  const std::atomic<bool> stop = true;
  ResimulationOptions options;
  options.stop = &stop;
  const ResimulationReport r = resimulate(recording, robot, options);
  EXPECT_EQ(r.states, 0u);
  EXPECT_FALSE(r.identical());
  EXPECT_FALSE(ResimulationReport{}.identical());
  std::filesystem::remove(path);
}

// One reader rule for a log's robot states (read_state_event): `csp log export` dropped a state
// with a bad fingerprint silently (exit 0) while `csp replay` refused the file. Both name the same
// event now, export exits 1 having written the other states, replay and gap refuse the log.
TEST(LogDamage, ExportReplayAndGapRefuseTheSameStateEvent) {
  const std::string path = emulate_log("fingerprint.lcmlog", 0.1);
  std::vector<std::pair<uint64_t, int64_t>> states;   // byte offset of each state event's data, its event number
  {
    LogReader log(path);
    uint64_t offset = 0;
    for (const LogEvent* e = log.next(); e; e = log.next()) {
      if (e->channel == "CSP_STATE") states.emplace_back(offset + 28 + e->channel.size(), e->eventnum);
      offset = log.offset();
    }
  }
  ASSERT_GT(states.size(), 10u);
  const auto [data_at, eventnum] = states[5];
  overwrite(path, static_cast<std::streamoff>(data_at), {0, 0, 0, 0, 0, 0, 0, 0});   // its fingerprint
  const std::string refused = "event " + std::to_string(eventnum) + " on CSP_STATE is not a robot_state_t (unknown type (fingerprint mismatch))";

  const std::string csv = test::temp_path("fingerprint.csv");
  test::Process exported({CSP_EXECUTABLE, "log", "export", path, "--out", csv}, test::temp_path("export.out"));
  EXPECT_EQ(exported.wait(std::chrono::seconds(60)), 1);
  EXPECT_NE(exported.output().find(path + ": " + refused + ": only the readable states were exported"), std::string::npos)
      << exported.output();
  EXPECT_EQ(read_joint_log_csv(csv).size(), states.size() - 1);

  test::Process replay({CSP_EXECUTABLE, "replay", path}, test::temp_path("replay.out"));
  EXPECT_EQ(replay.wait(std::chrono::seconds(60)), 2);
  EXPECT_NE(replay.output().find(path + ": " + refused), std::string::npos) << replay.output();

  try {
    read_joint_log_lcm(path, "CSP_STATE");
    FAIL() << "expected an error";
  } catch (const JointLogError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ": " + refused), std::string::npos) << e.what();
  }
  for (const std::string& f : {path, csv}) std::filesystem::remove(f);
}

// Ctrl-C ends `csp emulate` with its summary and whole logs: the LCM log reads without damage and
// replays bit for bit, the CSV ends with a complete row.
TEST(LogDamage, EmulateStopsCleanlyOnCtrlC) {
  const std::string lcm_log = test::temp_path("sigint.lcmlog"), csv = test::temp_path("sigint.csv");
  test::Process emulate({CSP_EXECUTABLE, "emulate", "--duration", "3600", "--clock", "lockstep", "--lcm-log", lcm_log, "--log", csv},
                        test::temp_path("sigint.out"));
  std::this_thread::sleep_for(std::chrono::milliseconds(700));
  emulate.signal(SIGINT);
  EXPECT_EQ(emulate.wait(std::chrono::seconds(60)), 130);
  const std::string out = emulate.output();
  EXPECT_NE(out.find("STOPPED at t = "), std::string::npos) << out;
  EXPECT_NE(out.find("ran "), std::string::npos) << out;   // the summary
  LogReader log(lcm_log);
  uint64_t events = 0;
  while (log.next()) ++events;
  EXPECT_GT(events, 10u);
  EXPECT_TRUE(log.damage().empty()) << log.damage_summary();
  EXPECT_TRUE(resimulate(lcm_log).identical());
  std::ifstream in(csv, std::ios::binary);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  ASSERT_FALSE(text.empty());
  EXPECT_EQ(text.back(), '\n');
  for (const std::string& f : {lcm_log, csv}) std::filesystem::remove(f);
}

}  // namespace
}  // namespace csp::bridge
