// Hostile YAML for every reader of it (robot files, scenarios, scenes, a scenario recorded in a log),
// issue 25: an alias bomb of 8 levels (about 400 bytes) took 104 s of CPU in the duplicate-key
// check, x10 per level; 3000 nested block maps were refused as "bad file"; a 10 MB list under an
// unknown key took 2.3 GB before the key was refused; masses, CoMs, frequencies and gains of 1e200
// were accepted and blamed on the plant later. Each is now refused at once with one clear message.
// The CTest TIMEOUT of this program turns a return of the slow paths into a failure, not a hang.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "csp/bridge/lcm_log.hpp"
#include "csp/bridge/replay.hpp"
#include "csp/io/scene.hpp"
#include "csp/rt/scenario.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

const std::string kScenarios = std::string(CSP_SOURCE_DIR) + "/configs/scenarios/";

std::string write_file(const std::string& name, const std::string& text) {
  const std::string path = (temp_dir() / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// The issue's alias bomb: `levels` lists of ten, each of ten aliases to the list before (10^levels nodes).
std::string alias_bomb(int levels) {
  std::ostringstream text;
  text << "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int l = 1; l <= levels; ++l) {
    text << 'a' << l << ": &a" << l << " [*a" << l - 1;
    for (int i = 1; i < 10; ++i) text << ", *a" << l - 1;
    text << "]\n";
  }
  return text.str();
}

// `levels` block mappings, each one key indented one more than the last.
std::string deep_block_maps(int levels) {
  std::string text = "deep:\n";
  for (int d = 1; d <= levels; ++d) text += std::string(static_cast<std::size_t>(d), ' ') + "k:\n";
  return text + std::string(static_cast<std::size_t>(levels) + 1, ' ') + "v: 1\n";
}

// The default scenario with its robot file named by absolute path, so that copies can live in temp_dir().
std::string default_scenario_text() {
  std::string text = read_text(kDefaultScenario);
  text.replace(text.find("../robots/panda.yaml"), 20, robot_file("panda"));
  return text;
}

// The message `load` throws as a ConfigError; one line that names `path`.
template <typename Load>
std::string config_error(const std::string& path, Load load) {
  try {
    load(path);
  } catch (const ConfigError& e) {
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    EXPECT_EQ(message.rfind(path + ": ", 0), 0u) << message;
    return message;
  }
  ADD_FAILURE() << path << " was accepted";
  return {};
}

std::string robot_error(const std::string& name, const std::string& text) {
  return config_error(write_file(name, text), [](const std::string& p) { load_robot_config(p); });
}
std::string scenario_error(const std::string& name, const std::string& text) {
  return config_error(write_file(name, text), [](const std::string& p) { rt::load_scenario(p); });
}

// The default scenario with `old` replaced by `replacement`.
std::string edited_scenario(const std::string& old, const std::string& replacement) {
  std::string text = default_scenario_text();
  const std::size_t at = text.find(old);
  if (at == std::string::npos) throw std::runtime_error("default.yaml no longer contains `" + old + "`");
  return text.replace(at, old.size(), replacement);
}

std::string edited_robot(const std::string& old, const std::string& replacement) {
  std::string text = read_text(robot_file("panda"));
  const std::size_t at = text.find(old);
  if (at == std::string::npos) throw std::runtime_error("panda.yaml no longer contains `" + old + "`");
  return text.replace(at, old.size(), replacement);
}

// ---------------------------------------------------------------------------------------------
// Item 1: aliases

TEST(YamlInput, AliasBombIsRefusedAtOnceInEveryFile) {
  const std::string expected = "expected at most 100000 nodes once aliases are expanded";
  const std::string robot = robot_error("bomb_robot.yaml", read_text(robot_file("panda")) + alias_bomb(8));
  EXPECT_NE(robot.find(expected), std::string::npos) << robot;
  const std::string scenario = scenario_error("bomb_scenario.yaml", default_scenario_text() + alias_bomb(8));
  EXPECT_NE(scenario.find(expected), std::string::npos) << scenario;
  // The issue's file on its own: at the top level, before any key is looked at.
  const std::string bare = scenario_error("bomb_bare.yaml", "name: bomb\n" + alias_bomb(8));
  EXPECT_NE(bare.find(expected), std::string::npos) << bare;
  const std::string scene = config_error(write_file("bomb_scene.yaml", read_text(std::string(CSP_SOURCE_DIR) + "/configs/scenes/mis_rcm.yaml") + alias_bomb(8)),
                                         [](const std::string& p) { load_scene(p); });
  EXPECT_NE(scene.find(expected), std::string::npos) << scene;
}

// A bomb inside a key the readers know is refused before they see it (a reader walking it would
// be as slow as the old duplicate-key check).
TEST(YamlInput, AliasBombUnderAKnownKeyIsRefusedBeforeTheReaders) {
  const std::string message = scenario_error(
      "bomb_in_controller.yaml",
      alias_bomb(6) + edited_scenario("  trajectory:\n", "  trajectory: *a6\n  unused:\n"));
  EXPECT_NE(message.find("once aliases are expanded"), std::string::npos) << message;
}

// A modest use of anchors is CSP's to accept: one value written once and used twice.
TEST(YamlInput, ModestAnchorsAreAccepted) {
  const std::string path = write_file(
      "anchors.yaml", edited_scenario("  damping: [50, 50, 50, 20, 20, 20, 10]",
                                      "  damping: &gains [50, 50, 50, 20, 20, 20, 10]")
                          .append("robot_settings: {tau_J_bias: *gains}\n"));
  const rt::Scenario scenario = rt::load_scenario(path);
  EXPECT_EQ(scenario.emulator.tau_J_bias, scenario.controller.damping);
  EXPECT_EQ(scenario.controller.damping[3], 20.0);
}

// yaml-cpp builds an alias inside the node it names as a cycle, which every reader would follow forever.
TEST(YamlInput, AliasCycleIsRefused) {
  for (const char* cycle : {"cycle: &c [*c]\n", "cycle: &c {a: *c}\n", "cycle: &c [[1, *c]]\n"}) {
    const std::string message = scenario_error("cycle.yaml", default_scenario_text() + cycle);
    EXPECT_NE(message.find("no alias inside the node its anchor names"), std::string::npos) << message;
  }
}

// A key given twice is found once inside an anchored node, and through an alias used as a key.
TEST(YamlInput, KeyGivenTwiceIsFoundInAnchoredNodes) {
  const std::string inside = scenario_error("twice_anchored.yaml",
                                            default_scenario_text() + "x: &m {a: 1, a: 2}\ny: *m\n");
  EXPECT_NE(inside.find("x.a: key given twice"), std::string::npos) << inside;
  const std::string aliased_key = scenario_error("twice_alias_key.yaml", "k: &k name\n*k : other\n" + default_scenario_text());
  EXPECT_NE(aliased_key.find("name: key given twice"), std::string::npos) << aliased_key;
}

// ---------------------------------------------------------------------------------------------
// Item 10: deep nesting and big files

TEST(YamlInput, DeepNestingSaysSoWithTheLine) {
  // 600 levels: beyond yaml-cpp's own guard ("bad file"), 180 kB. The issue's 3000 levels are 4.5 MB
  // of indentation, refused by their size.
  const std::string message = scenario_error("deep.yaml", "name: x\n" + deep_block_maps(600));
  EXPECT_NE(message.find("expected at most 50 levels of nesting"), std::string::npos) << message;
  EXPECT_NE(message.find(": line 52: "), std::string::npos) << message;   // where the 51st level opens
  EXPECT_EQ(message.find("bad file"), std::string::npos) << message;
  const std::string flow = scenario_error("deep_flow.yaml", "name: x\ndeep: " + std::string(3000, '[') + std::string(3000, ']') + "\n");
  EXPECT_NE(flow.find("expected at most 50 levels of nesting"), std::string::npos) << flow;
  EXPECT_NE(flow.find(": line 2: "), std::string::npos) << flow;
  // A nesting as deep as CSP's own files is fine (the reader then refuses the unknown key).
  const std::string shallow = scenario_error("shallow.yaml", default_scenario_text() + deep_block_maps(10));
  EXPECT_NE(shallow.find("deep: expected no such key"), std::string::npos) << shallow;
  const std::string issue = scenario_error("deep3000.yaml", "name: x\n" + deep_block_maps(3000));
  EXPECT_NE(issue.find("expected at most 1 MB for a scenario file"), std::string::npos) << issue;
}

// A list of 10 MB under an unknown key is refused by its size before it is read or parsed (it
// took 2.3 GB); a smaller file of more nodes than any of CSP's is refused before nodes are built.
TEST(YamlInput, BigFilesAreRefusedBeforeTheyAreParsed) {
  std::string big = default_scenario_text() + "unknown:\n";
  while (big.size() < 10'000'000) big += "- 1\n";
  const std::string message = scenario_error("big.yaml", big);
  EXPECT_NE(message.find("expected at most 1 MB for a scenario file"), std::string::npos) << message;

  std::string many = default_scenario_text() + "unknown: [";
  for (int i = 0; i < 120'000; ++i) many += "1,";
  const std::string nodes = scenario_error("many.yaml", many + "1]\n");
  EXPECT_NE(nodes.find("expected at most 100000 nodes"), std::string::npos) << nodes;
}

// ---------------------------------------------------------------------------------------------
// Items 1 and 10 in a log: `csp replay` rebuilds the scenario from the log's record.

std::string log_with_scenario_text(const std::string& name, const std::string& text) {
  const rt::Scenario scenario = rt::load_scenario(kDefaultScenario);
  scenario_t record = bridge::scenario_message(scenario, "");
  record.text = text;
  const std::string path = (temp_dir() / name).string();
  bridge::LogWriter log(path);
  log.write("CSP_SCENARIO", bridge::encode(record), record.utime);
  return path;
}

std::string replay_error(const std::string& log) {
  try {
    bridge::resimulate(log);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  ADD_FAILURE() << log << " was replayed";
  return {};
}

TEST(YamlInput, ReplayRefusesARecordedAliasBombOrDeepNesting) {
  const std::string recorded = read_text(kDefaultScenario);
  const std::string bomb = replay_error(log_with_scenario_text("bomb.lcmlog", recorded + alias_bomb(8)));
  EXPECT_NE(bomb.find("the recorded scenario " + kDefaultScenario + ": line "), std::string::npos) << bomb;
  EXPECT_NE(bomb.find("once aliases are expanded"), std::string::npos) << bomb;
  EXPECT_EQ(bomb.find('\n'), std::string::npos) << bomb;
  const std::string deep = replay_error(log_with_scenario_text("deep.lcmlog", recorded + deep_block_maps(600)));
  EXPECT_NE(deep.find("levels of nesting"), std::string::npos) << deep;
}

// `csp replay` of such a log: exit 2, one line on stderr.
TEST(YamlInput, ReplayCommandRefusesARecordedAliasBomb) {
  const std::string log = log_with_scenario_text("bomb_cli.lcmlog", read_text(kDefaultScenario) + alias_bomb(8));
  const ProgramRun run = run_program(CSP_EXECUTABLE, {"replay", log});
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_EQ(std::count(run.err.begin(), run.err.end(), '\n'), 1) << run.err;
  EXPECT_NE(run.err.find("once aliases are expanded"), std::string::npos) << run.err;
}

// ---------------------------------------------------------------------------------------------
// Item 5: what the flange carries is bounded where it is written

TEST(YamlInput, EndEffectorAndToolMassAndCentreOfMassAreBounded) {
  const std::string mass = robot_error("ee_mass.yaml", edited_robot("mass: 0.73", "mass: 1e6"));
  EXPECT_NE(mass.find("end_effectors.hand.mass: expected a mass of at most 1000 kg"), std::string::npos) << mass;
  const std::string com = robot_error("ee_com.yaml", edited_robot("com: [-0.01, 0.0, 0.03]", "com: [-0.01, 0.0, 1e300]"));
  EXPECT_NE(com.find("end_effectors.hand.com: expected a centre of mass within 10 m"), std::string::npos) << com;
  const std::string inertia = robot_error("ee_inertia.yaml", edited_robot("inertia: [0.001, 0.0, 0.0, 0.0025, 0.0, 0.0017]",
                                                                          "inertia: [1e200, 0.0, 0.0, 0.0025, 0.0, 0.0017]"));
  EXPECT_NE(inertia.find("end_effectors.hand.inertia: expected inertia entries within"), std::string::npos) << inertia;

  std::string scene = read_text(std::string(CSP_SOURCE_DIR) + "/configs/scenes/mis_rcm.yaml");
  const std::size_t tool = scene.find("\ntool:");
  ASSERT_NE(tool, std::string::npos);
  const std::size_t at = scene.find("  mass: ", tool);
  ASSERT_NE(at, std::string::npos);
  scene.replace(at, scene.find('\n', at) - at, "  mass: 1e6");
  const std::string tool_mass = config_error(write_file("tool_mass.yaml", scene), [](const std::string& p) { load_scene(p); });
  EXPECT_NE(tool_mass.find("tool.mass: expected a mass of at most 1000 kg"), std::string::npos) << tool_mass;

  // The scenario's loads on the flange.
  const std::string load = scenario_error("load_mass.yaml", edited_scenario("  friction: gaz2019\n",
                                                                            "  friction: gaz2019\n  load: {mass: 1e6}\n"));
  EXPECT_NE(load.find("plant.load.mass: expected a mass of at most 1000 kg"), std::string::npos) << load;
  const std::string model_load = scenario_error("model_load_com.yaml", edited_scenario("  inertia: libfranka_fit\n",
                                                                                       "  inertia: libfranka_fit\n  load: {mass: 1, com: [0, 0, 1e300]}\n"));
  EXPECT_NE(model_load.find("robot_model.load.com: expected a centre of mass within 10 m"), std::string::npos) << model_load;
}

// ---------------------------------------------------------------------------------------------
// Item 6: the scenario's rates, gains and magnitudes

TEST(YamlInput, ScenarioRatesGainsAndMagnitudesAreBounded) {
  const std::string frequencies = "frequency_hz: [0.12, 0.17, 0.21, 0.15, 0.25, 0.19, 0.3]";
  const std::string amplitudes = "amplitude: [0.4, 0.3, 0.4, 0.35, 0.5, 0.4, 0.6]";
  const std::string stiffness = "stiffness: [600, 600, 600, 600, 250, 150, 50]";
  const std::string damping = "damping: [50, 50, 50, 20, 20, 20, 10]";
  const std::string wrench = "force: [0.0, 0.0, -5.0]";
  const std::string end = "  part: {mass: 0.3}\n";
  const struct {
    std::string old, replacement, expected;
  } cases[] = {
      {frequencies, "frequency_hz: [1e200, 0.17, 0.21, 0.15, 0.25, 0.19, 0.3]",
       "controller.trajectory.frequency_hz: expected frequencies below 500 Hz (the 1 kHz loop's Nyquist frequency)"},
      {frequencies, "frequency_hz: [0.12, 0.17, 0.21, 0.15, 0.25, 0.19, 500]", "frequency_hz: expected frequencies below 500 Hz"},
      {amplitudes, "amplitude: [0.4, 0.3, 0.4, 0.35, 0.5, 0.4, 1e200]",
       "controller.trajectory.amplitude: expected amplitudes within each joint's range (joint 7: 5.79"},
      {"    ramp: 1.0", "    ramp: 1e300", "controller.trajectory.ramp: expected a number from 0 to 31536000 s"},
      {"    ramp: 1.0", "    ramp: 1.0\n    phase: [0, 0, 0, 0, 0, 0, 1e9]", "controller.trajectory.phase: expected angles within +-2 pi rad"},
      {stiffness, "stiffness: [1e200, 600, 600, 600, 250, 150, 50]", "controller.stiffness: expected 7 numbers from 0 to 10000 N m/rad"},
      {damping, "damping: [50, 50, 50, 20, 20, 20, 1e200]", "controller.damping: expected 7 numbers from 0 to 1000 N m s/rad"},
      {wrench, "force: [0.0, 0.0, -1e200]", "external_wrenches[0].force: expected 3 numbers of magnitude at most 10000 N"},
      {wrench, wrench + ", moment: [1e200, 0, 0]", "external_wrenches[0].moment: expected 3 numbers of magnitude at most 1000 N m"},
      {"point: [0.0, 0.0, 0.2]", "point: [0.0, 0.0, 1e200]", "external_wrenches[0].point: expected 3 numbers of magnitude at most 10 m"},
      {end, end + "robot_settings: {tau_J_noise: [1e200, 0, 0, 0, 0, 0, 0]}\n", "robot_settings.tau_J_noise: expected 7 numbers from 0 to 100 N m"},
      {end, end + "robot_settings: {tau_J_bias: [0, 0, 0, 0, 0, 0, -1e200]}\n", "robot_settings.tau_J_bias: expected 7 numbers within +-100 N m"},
      {end, end + "robot_settings: {tau_ext_cutoff_hz: 1e200}\n", "robot_settings.tau_ext_cutoff_hz: expected a cutoff below 500 Hz"},
      {end, end + "robot_settings: {substeps: 2, torque_loop_bandwidth_hz: 1000}\n",
       "robot_settings.torque_loop_bandwidth_hz: expected a bandwidth below 1000 Hz"},
      {end, end + "faults: {latency_us: {mean: 1e200}}\n", "faults.latency_us.mean: expected a number from 0 to 1000000 us"},
      {end, end + "faults: {latency_us: {mean: 1, budget: 1e200}}\n", "faults.latency_us.budget: expected a number from 0 to 1000000 us"},
      {"  friction: gaz2019\n", "  friction: gaz2019\n  link_scale: {4: {mass: 1e200}}\n",
       "plant.link_scale.4.mass: expected a factor that keeps the link's mass at most 1000 kg"},
  };
  for (const auto& c : cases) {
    const std::string message = scenario_error("bounds.yaml", edited_scenario(c.old, c.replacement));
    EXPECT_NE(message.find(c.expected), std::string::npos) << c.replacement << "\n" << message;
  }
  // The bounds leave room: a torque loop of 999 Hz at 2 substeps, a sine of 499 Hz are accepted.
  rt::load_scenario(write_file("room.yaml", edited_scenario(frequencies, "frequency_hz: [0.12, 0.17, 0.21, 0.15, 0.25, 0.19, 499]") +
                                                "robot_settings: {substeps: 2, torque_loop_bandwidth_hz: 999}\n"));
}

}  // namespace
}  // namespace csp::test
