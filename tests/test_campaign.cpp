// `csp campaign` (docs/campaign.md): the campaign's table against the same cases run one by one in
// this process (bit-identical metrics), a killed campaign resumed (nothing lost, nothing run
// twice), a task's slice and the collection of a partial campaign, a case that fails (marked with
// why, run again on resume), and bad campaign files.
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "csp/campaign/pool.hpp"
#include "csp/campaign/runner.hpp"
#include "csp/io/robot_config.hpp"
#include "csp/run/observers.hpp"
#include "csp/run/sources.hpp"

namespace {

namespace fs = std::filesystem;
using csp::campaign::Case;

std::string scratch_dir(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("csp_campaign_test_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

std::string write_file(const std::string& path, const std::string& text) {
  std::ofstream(path) << text;
  return path;
}

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The small campaign (tests/campaign/small.yaml: 24 cases of 1 s of the default scenario), copied
// into `dir`.
std::string small_campaign(const std::string& dir) {
  return write_file(dir + "/campaign.yaml", read_file(CSP_SOURCE_DIR "/tests/campaign/small.yaml"));
}

int run_csp(const std::string& arguments) {
  const int status = std::system((std::string(CSP_EXECUTABLE) + " " + arguments + " > /dev/null").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// results.csv's rows by id, split at commas (the test's cases have no quoted text fields but the
// failure text, which comes after every number).
std::map<std::string, std::vector<std::string>> table_rows(const std::string& dir, std::vector<std::string>& header) {
  std::ifstream in(dir + "/results.csv");
  std::map<std::string, std::vector<std::string>> rows;
  std::string line;
  auto split = [](const std::string& text) {
    std::vector<std::string> fields;
    std::stringstream stream(text);
    for (std::string field; std::getline(stream, field, ',');) fields.push_back(field);
    return fields;
  };
  std::getline(in, line);
  header = split(line);
  while (std::getline(in, line)) rows[line.substr(0, line.find(','))] = split(line);
  return rows;
}

// results.csv without its last three columns (the controller's time and the wall time of each run,
// the numbers that are not deterministic).
std::string deterministic_table(const std::string& dir) {
  std::istringstream in(read_file(dir + "/results.csv"));
  std::string out;
  for (std::string line; std::getline(in, line);) {
    for (int column = 0; column < 3; ++column) line.erase(line.rfind(','));
    out += line + "\n";
  }
  return out;
}

double number_or_nan(const std::string& field) { return field.empty() ? NAN : std::strtod(field.c_str(), nullptr); }

}  // namespace

TEST(Campaign, TwoWorkersGiveTheRowsOfTheCasesRunOneByOne) {
  const std::string dir = scratch_dir("local");
  const std::string file = small_campaign(dir);
  ASSERT_EQ(run_csp("campaign " + file + " --out " + dir + "/out --jobs 2"), 0);

  // The cases as the campaign expanded them (cases.json: what its workers ran; the draws are made
  // once, so that workers built with other flags run the same values), run here one by one.
  const csp::campaign::CampaignDir prepared = csp::campaign::open_campaign(dir + "/out");
  const csp::campaign::Campaign& campaign = prepared.campaign;
  const std::vector<Case>& cases = prepared.cases;
  ASSERT_EQ(cases.size(), 24u);
  EXPECT_EQ(cases.size(), csp::campaign::expand_cases(csp::campaign::load_campaign(file)).size());
  std::vector<std::string> header;
  const auto rows = table_rows(dir + "/out", header);
  ASSERT_EQ(rows.size(), cases.size());
  int failures = 0;
  for (const Case& c : cases) {
    const csp::campaign::Outcome expected = csp::campaign::run_case(campaign, c);
    const std::vector<std::string>& row = rows.at(c.id);
    ASSERT_GE(row.size(), 4 + c.parameters.size() + expected.metrics.size()) << c.id;
    EXPECT_EQ(row[1], std::to_string(c.seed));
    for (std::size_t i = 0; i < c.parameters.size(); ++i) {
      EXPECT_EQ(header[2 + i], c.parameters[i].first);
      EXPECT_EQ(std::strtod(row[2 + i].c_str(), nullptr), c.parameters[i].second) << c.id << " " << header[2 + i];
    }
    const std::size_t reflex_column = 2 + c.parameters.size();
    EXPECT_EQ(row[reflex_column], expected.reflex ? "1" : "0") << c.id;
    EXPECT_EQ(row[reflex_column + 1], expected.failed ? "1" : "0") << c.id;
    for (std::size_t i = 0; i < expected.metrics.size(); ++i) {
      EXPECT_EQ(header[reflex_column + 2 + i], expected.metrics[i].first);
      const double value = number_or_nan(row[reflex_column + 2 + i]);
      if (std::isnan(expected.metrics[i].second)) EXPECT_TRUE(std::isnan(value)) << c.id;
      else EXPECT_EQ(value, expected.metrics[i].second) << c.id << " " << expected.metrics[i].first;   // bit-identical
    }
    failures += expected.failed ? 1 : 0;
  }
  // The sweep reaches both sides: soft gains track worse than 20 mrad, stiff ones hold.
  EXPECT_GT(failures, 0);
  EXPECT_LT(failures, static_cast<int>(cases.size()));
  EXPECT_TRUE(fs::exists(dir + "/out/report/summary.md"));
  EXPECT_TRUE(fs::exists(dir + "/out/report/failure_rate_plant_mass_scale.svg"));
  EXPECT_TRUE(fs::exists(dir + "/out/report/region.svg"));
  fs::remove_all(dir);
}

TEST(Campaign, AKilledCampaignResumedLosesNothingAndRepeatsNothing) {
  const std::string dir = scratch_dir("resume");
  const std::string file = small_campaign(dir);
  ASSERT_EQ(run_csp("campaign " + file + " --out " + dir + "/whole --jobs 2"), 0);

  // The same campaign in its own process group, killed (every worker too) after a few cases.
  const std::string out = dir + "/killed";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    setpgid(0, 0);
    const int null = open("/dev/null", O_WRONLY);
    dup2(null, STDOUT_FILENO);
    execl(CSP_EXECUTABLE, CSP_EXECUTABLE, "campaign", file.c_str(), "--out", out.c_str(), "--jobs", "1", nullptr);
    _exit(127);
  }
  setpgid(pid, pid);
  auto done_files = [&] {
    std::map<std::string, std::pair<ino_t, std::string>> done;
    if (!fs::exists(out + "/runs")) return done;
    for (const auto& entry : fs::directory_iterator(out + "/runs")) {
      const std::string path = entry.path().string();
      if (entry.path().extension() != ".json") continue;
      struct stat info {};
      stat(path.c_str(), &info);
      done[entry.path().filename().string()] = {info.st_ino, read_file(path)};
    }
    return done;
  };
  int status = 0;
  while (done_files().size() < 3) {
    ASSERT_EQ(waitpid(pid, &status, WNOHANG), 0) << "the campaign ended before it was killed";
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  kill(-pid, SIGKILL);
  waitpid(pid, &status, 0);
  const auto before = done_files();
  ASSERT_LT(before.size(), 24u) << "the campaign ended before it was killed";

  ASSERT_EQ(run_csp("campaign " + file + " --out " + out + " --jobs 2"), 0);
  const auto after = done_files();
  ASSERT_EQ(after.size(), 24u);
  for (const auto& [name, file_before] : before) EXPECT_EQ(after.at(name), file_before) << name << " was run again";
  // runs.log: one line per case run, never two.
  std::map<std::string, int> executions;
  std::istringstream log(read_file(out + "/runs.log"));
  for (std::string line; std::getline(log, line);) ++executions[line.substr(0, line.find(' '))];
  for (const auto& [id, count] : executions) EXPECT_EQ(count, 1) << id;
  EXPECT_EQ(deterministic_table(out), deterministic_table(dir + "/whole"));
  fs::remove_all(dir);
}

TEST(Campaign, ATaskRunsItsSliceAndACollectionSaysWhatIsMissing) {
  const std::string dir = scratch_dir("slice");
  const std::string file = small_campaign(dir);
  const csp::campaign::CampaignDir prepared = csp::campaign::prepare_campaign(file, dir + "/out");
  EXPECT_EQ(csp::campaign::run_cases(prepared, 1, 1, 4, {}).ran, 6);   // indices 1, 5, 9, ...
  const csp::campaign::Status status = csp::campaign::campaign_status(prepared);
  EXPECT_EQ(status.total, 24);
  EXPECT_EQ(status.done, 6);
  for (const Case& c : prepared.cases) EXPECT_EQ(fs::exists(dir + "/out/runs/" + c.id + ".json"), c.index % 4 == 1) << c.id;
  EXPECT_EQ(run_csp("campaign status " + dir + "/out"), 1);    // not done
  EXPECT_EQ(run_csp("campaign collect " + dir + "/out"), 1);   // 18 missing
  std::vector<std::string> header;
  EXPECT_EQ(table_rows(dir + "/out", header).size(), 6u);
  // The rest, and the same folder refuses another campaign.
  EXPECT_EQ(csp::campaign::run_cases(prepared, 2, 0, 1, {}).ran, 18);
  EXPECT_EQ(run_csp("campaign status " + dir + "/out"), 0);
  write_file(file, read_file(file) + "worst_by: max_tau_ext\n");
  EXPECT_THROW(csp::campaign::prepare_campaign(file, dir + "/out"), std::runtime_error);
  fs::remove_all(dir);
}

TEST(Campaign, ACaseThatFailsIsMarkedWithWhyAndRunAgainOnResume) {
  // The base scenario is a copy that disappears after the cases are prepared: every worker fails.
  const std::string dir = scratch_dir("failing");
  std::string scenario = read_file(CSP_SOURCE_DIR "/configs/scenarios/default.yaml");
  scenario.replace(scenario.find("../robots/panda.yaml"), 20, CSP_SOURCE_DIR "/configs/robots/panda.yaml");
  write_file(dir + "/base.yaml", scenario);
  const std::string file = write_file(dir + "/campaign.yaml", "base: base.yaml\nduration: 0.5\nruns: 3\naxes: []\n");
  const csp::campaign::CampaignDir prepared = csp::campaign::prepare_campaign(file, dir + "/out");
  fs::rename(dir + "/base.yaml", dir + "/moved.yaml");
  const csp::campaign::CasesRun failing = csp::campaign::run_cases(prepared, 2, 0, 1, {});
  EXPECT_EQ(failing.ran, 3);
  EXPECT_EQ(failing.failed, 3);
  const csp::campaign::Status status = csp::campaign::campaign_status(prepared);
  EXPECT_EQ(status.done, 0);
  ASSERT_EQ(status.failures.size(), 3u);
  EXPECT_NE(status.failures[0].find("c0000: "), std::string::npos);
  EXPECT_NE(status.failures[0].find("base.yaml"), std::string::npos) << status.failures[0];   // the loader's error
  // Back in place: the failed cases run again, and pass.
  fs::rename(dir + "/moved.yaml", dir + "/base.yaml");
  const csp::campaign::CasesRun resumed = csp::campaign::run_cases(prepared, 2, 0, 1, {});
  EXPECT_EQ(resumed.ran, 3);
  EXPECT_EQ(resumed.failed, 0);
  EXPECT_EQ(csp::campaign::campaign_status(prepared).done, 3);
  EXPECT_EQ(csp::campaign::campaign_status(prepared).failed, 0);
  fs::remove_all(dir);
}

// ... and the table keeps the metrics the file chose.
TEST(Campaign, AScenarioAxisRunsEachBaseScenario) {
  const std::string dir = scratch_dir("scenarios");
  const std::string file = write_file(dir + "/campaign.yaml",
                                      "duration: 0.5\naxes:\n"
                                      "  - {parameter: scenario, values: [default, libfranka_panda]}\n"
                                      "  - {parameter: plant.load_mass, values: [0, 1]}\n"
                                      "metrics: [tracking_error_max, lost_commands]\n");
  const csp::campaign::CampaignDir prepared = csp::campaign::prepare_campaign(file, dir + "/out");
  ASSERT_EQ(prepared.cases.size(), 4u);
  const std::string names[] = {"default", "default", "libfranka_panda", "libfranka_panda"};
  for (const Case& c : prepared.cases) {
    const std::string& name = names[c.index];
    EXPECT_EQ(csp::campaign::case_scenario(prepared.campaign, c).name,
              csp::rt::load_scenario(csp::rt::shipped_scenario_path(name)).name) << c.id;
  }
  EXPECT_EQ(csp::campaign::run_cases(prepared, 2, 0, 1, {}).ran, 4);
  EXPECT_EQ(run_csp("campaign collect " + dir + "/out"), 0);
  std::vector<std::string> header;
  const auto rows = table_rows(dir + "/out", header);
  EXPECT_EQ(header, (std::vector<std::string>{"id", "case_seed", "scenario", "plant.load_mass", "reflex", "failed",
                                              "tracking_error_max", "lost_commands", "reflex_errors", "failure",
                                              "controller_time_p99_us", "controller_time_max_us", "wall_time_s"}));
  for (const Case& c : prepared.cases) EXPECT_EQ(rows.at(c.id)[2], names[c.index]) << c.id;
  fs::remove_all(dir);
}

TEST(Campaign, TheShippedCampaignsLoad) {
  // The excitation campaign reads designs made first (its comment): not here.
  const std::pair<const char*, std::size_t> shipped[] = {{"joint_impedance_real_gap.yaml", 64}, {"ultrasound_tissue.yaml", 20},
                                                                {"gap_tool_check.yaml", 8}};
  for (const auto& [name, cases] : shipped) {
    const csp::campaign::Campaign campaign = csp::campaign::load_campaign(std::string(CSP_SOURCE_DIR "/configs/campaigns/") + name);
    const std::vector<Case> expanded = csp::campaign::expand_cases(campaign);
    EXPECT_EQ(expanded.size(), cases) << name;
    // The gap axes draw inside the verdict's intervals (joint 4's phi1: [0.905, 1.506] N m).
    for (const Case& c : expanded) {
      for (const auto& [parameter, value] : c.parameters) {
        if (parameter != "plant.friction.phi1.j4") continue;
        EXPECT_TRUE(value >= 0.905 && value <= 1.506) << value;
      }
    }
  }
}

TEST(Campaign, ABadCampaignFileIsOneErrorNamingItsKey) {
  const std::string dir = scratch_dir("bad");
  const std::string base = "base: " CSP_SOURCE_DIR "/configs/scenarios/default.yaml\n";
  auto error_of = [&](const std::string& text) {
    const std::string path = write_file(dir + "/bad.yaml", text);
    try {
      csp::campaign::load_campaign(path);
    } catch (const csp::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(error_of(base + "axes:\n  - {parameter: plant.wingspan, values: [1]}\n"),
            dir + "/bad.yaml: axes[0].parameter: expected a known parameter (docs/campaign.md: seed, plant.*, sensor.*, "
                  "controller.*, faults.*, scene.*), not `plant.wingspan`");
  EXPECT_EQ(error_of(base + "axes:\n  - {parameter: plant.mass_scale, uniform: [1.2, 0.8]}\n"),
            dir + "/bad.yaml: axes[0].uniform: expected [low, high] with low < high");
  EXPECT_EQ(error_of("axes:\n  - {parameter: plant.mass_scale, values: [1]}\n"),
            dir + "/bad.yaml: base: expected this key (missing)");
  EXPECT_NE(error_of("base: no_such_dir/nothing.yaml\naxes: []\n").find("bad.yaml: base: expected a scenario file"), std::string::npos);
  EXPECT_EQ(error_of(base + "axes:\n  - {parameter: faults.loss_probability, values: [1.5]}\n"),
            dir + "/bad.yaml: axes[0].parameter: expected `faults.loss_probability` to be a probability from 0 to 1");
  EXPECT_EQ(error_of(base + "axes:\n  - {parameter: scene.material.skin.stiffness, values: [1000]}\n"),
            dir + "/bad.yaml: axes[0].parameter: expected a scenario with a scene for `scene.material.skin.stiffness`");
  EXPECT_EQ(error_of(base + "axes: []\ngap_verdict: yes please\n"), dir + "/bad.yaml: gap_verdict: expected true or false");
  // csp gap's metrics are the campaign's only when it asks for the verdict.
  EXPECT_EQ(error_of(base + "axes: []\nfail_if: {gap_unexplained_fraction: 0.5}\n")
                .rfind(dir + "/bad.yaml: fail_if.gap_unexplained_fraction: expected a metric of this scenario (", 0), 0u);
  EXPECT_EQ(error_of(base + "axes: []\nfail_if: {force_error: 1}\n").rfind(dir + "/bad.yaml: fail_if.force_error: expected a metric of this scenario (tracking_error_rms, ", 0), 0u);
  EXPECT_EQ(error_of(base + "axes:\n  - {parameter: scenario, values: [default]}\n"),
            dir + "/bad.yaml: base: expected no base with a `scenario` axis (its values are the base scenarios)");
  EXPECT_EQ(error_of("axes:\n  - {parameter: scenario, values: [default, medical/ultrasound_abdomen_scan]}\n"),
            dir + "/bad.yaml: axes[0].values[1]: expected a scenario whose runs have the metrics of the first (the same kind of task, or none)");
  EXPECT_EQ(error_of(base + "axes: []\nmetrics: [tracking_error_max, clearance]\n").rfind(dir + "/bad.yaml: metrics[1]: expected a metric of this scenario (", 0), 0u);
  EXPECT_EQ(error_of(base + "axes: []\nrepeats: 3\n").rfind(dir + "/bad.yaml: repeats: expected no such key", 0), 0u);
  // The command says it in one line and exits with 2.
  EXPECT_EQ(run_csp("campaign " + dir + "/bad.yaml --out " + dir + "/out 2> /dev/null"), 2);
  EXPECT_FALSE(fs::exists(dir + "/out/cases.json"));
  fs::remove_all(dir);
}

// gap_verdict: each run's log diagnosed as `csp gap --log` diagnoses the LCM log of the same run (an
// independent path: the log written and read back, the model built from the recording by the csp
// program): the same causes and the same numbers. The plant's unmodelled payload is named in the run
// that has it, in none other (the default scenario's plant is its robot file's model otherwise).
TEST(Campaign, EachRunsGapVerdictIsCspGapsOnTheRunsLog) {
  const std::string dir = scratch_dir("gap");
  const std::string file = write_file(dir + "/campaign.yaml",
                                      "base: default\ngap_verdict: true\naxes:\n"
                                      "  - {parameter: plant.load_mass, values: [0, 0.3]}\n"
                                      "fail_if: {gap_unexplained_fraction: 0.5}\n");
  ASSERT_EQ(run_csp("campaign " + file + " --out " + dir + "/out --jobs 2"), 0);
  const csp::campaign::CampaignDir prepared = csp::campaign::open_campaign(dir + "/out");
  std::vector<std::string> header;
  const auto rows = table_rows(dir + "/out", header);
  ASSERT_EQ(rows.size(), 2u);
  auto column = [&](const std::string& name) {
    const auto it = std::find(header.begin(), header.end(), name);
    EXPECT_NE(it, header.end()) << name;
    return static_cast<std::size_t>(it - header.begin());
  };
  const std::size_t verdict = column("gap_verdict"), unexplained = column("gap_unexplained_fraction"),
                    heldout_rms = column("gap_heldout_rms"), failed = column("failed"), p99 = column("controller_time_p99_us"),
                    max = column("controller_time_max_us");
  for (const Case& c : prepared.cases) {
    const std::vector<std::string>& row = rows.at(c.id);
    ASSERT_GT(row.size(), max) << c.id;
    // The same run as an LCM log, diagnosed by the csp program.
    const std::string log = dir + "/" + c.id + ".lcmlog", json = dir + "/" + c.id + ".json";
    {
      csp::run::Run run(csp::campaign::case_scenario(prepared.campaign, c));
      csp::run::ControllerSource controller(run);
      csp::run::LcmLogObserver recorder(log, run, controller.controller().mode);
      run.observe(recorder);
      run.run(controller);
      recorder.flush();
    }
    ASSERT_EQ(run_csp("gap --log " + log + " --json " + json + " 2> /dev/null"), 0) << c.id;
    const nlohmann::json diagnosis = nlohmann::json::parse(read_file(json));
    std::string causes;
    for (const auto& cause : diagnosis["verdict"]["causes"]) causes += (causes.empty() ? "" : "; ") + cause.get<std::string>();
    EXPECT_EQ(row[verdict], causes.empty() ? "none" : causes) << c.id;
    EXPECT_NEAR(std::strtod(row[unexplained].c_str(), nullptr), diagnosis["verdict"]["unexplained_fraction"].get<double>(), 1e-6) << c.id;
    double mean_square = 0.0;
    for (const auto& rms : diagnosis["baseline"]["heldout_rms"]) mean_square += rms.get<double>() * rms.get<double>() / 7.0;
    EXPECT_NEAR(std::strtod(row[heldout_rms].c_str(), nullptr), std::sqrt(mean_square), 1e-6) << c.id;
    const bool loaded = std::strtod(row[2].c_str(), nullptr) > 0.0;
    EXPECT_EQ(row[verdict].find("payload") != std::string::npos, loaded) << c.id << ": " << row[verdict];
    // The limit on what is left unexplained: the payload's run is explained, the other is not.
    EXPECT_EQ(row[failed], loaded ? "0" : "1") << c.id;
    const double controller_p99 = std::strtod(row[p99].c_str(), nullptr);
    EXPECT_GT(controller_p99, 0.0) << c.id;
    EXPECT_LE(controller_p99, std::strtod(row[max].c_str(), nullptr)) << c.id;
  }
  const std::string summary = read_file(dir + "/out/report/summary.md");
  EXPECT_NE(summary.find("the causes csp gap's verdicts name (docs/gap.md), in how many runs: none 1, payload 1"), std::string::npos)
      << summary;
  fs::remove_all(dir);
}

// A run too short for csp gap's filters (a reflex at once) keeps its other metrics; its verdict says why.
TEST(Campaign, ARunTooShortForTheGapToolSaysWhy) {
  const std::string dir = scratch_dir("gap_short");
  const std::string file = write_file(dir + "/campaign.yaml", "base: default\nduration: 0.1\ngap_verdict: true\naxes: []\n");
  const csp::campaign::CampaignDir prepared = csp::campaign::prepare_campaign(file, dir + "/out");
  const csp::campaign::Outcome outcome = csp::campaign::run_case(prepared.campaign, prepared.cases.at(0));
  EXPECT_EQ(outcome.gap_verdict.rfind("not diagnosed: case c0000's run: too short", 0), 0u) << outcome.gap_verdict;
  ASSERT_GE(outcome.metrics.size(), 2u);
  EXPECT_EQ(outcome.metrics.end()[-2].first, "gap_heldout_rms");
  EXPECT_TRUE(std::isnan(outcome.metrics.back().second));
  EXPECT_EQ(outcome.metrics.front().first, "tracking_error_rms");
  EXPECT_FALSE(std::isnan(outcome.metrics.front().second));
  fs::remove_all(dir);
}
