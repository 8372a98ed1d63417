// Damaged LCM logs: every reader says where the damage is and how much it skipped, nothing
// crashes, and replay never calls a partial log identical (issue: a data length of 0x7FFFFFFF
// crashed liblcm's reader; a log cut short replayed "bit for bit" from 59 of 501 states).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "bridge_support.hpp"
#include "csp/bridge/csv_convert.hpp"
#include "csp/bridge/replay.hpp"
#include "csp/rt/controllers.hpp"

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
// reflex with an empty reason).
TEST(LogDamage, EmulateNamesAWriteErrorAndStops) {
  test::Process emulate({CSP_EXECUTABLE, "emulate", "--duration", "1", "--log", "/dev/full"}, test::temp_path("full.out"));
  EXPECT_EQ(emulate.wait(std::chrono::seconds(60)), 1);
  const std::string out = emulate.output();
  EXPECT_NE(out.find("STOPPED at t = "), std::string::npos) << out;
  EXPECT_NE(out.find("writing the log failed"), std::string::npos) << out;
  EXPECT_EQ(out.find("REFLEX"), std::string::npos) << out;
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
