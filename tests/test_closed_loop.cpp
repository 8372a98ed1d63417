// Issue 13's closed loop through the commands a user runs (docs/excitation.md, "Closed loop"):
// `csp plan excite` on a shipped scene, its written scenario with a known change of the plant,
// `csp emulate`, `csp gap` on the emulated log: the change is named and its parameters recovered.
// Then the medical claim on the emulated robot: the task-weighted excitation predicts a held-out
// emulated task's torques better than a whole-workspace one of equal length. The references are the
// changes planted in the plant (its payload, link 4, Gaz et al.'s friction law), not the planner's
// or the diagnosis's own figures.
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "csp/dynamics/friction.hpp"
#include "csp/gap/effects.hpp"
#include "csp/gap/signal.hpp"
#include "csp/io/scene.hpp"
#include "csp/planners/identifiability.hpp"
#include "csp/rt/scenario.hpp"
#include "support.hpp"

namespace csp::test {
namespace {

const std::string kScene = "ultrasound_abdomen";

ProgramRun csp(const std::vector<std::string>& args) { return run_program(CSP_EXECUTABLE, args); }

std::string text(double value) {
  std::ostringstream out;
  out << std::setprecision(17) << value;
  return out.str();
}

const Scene& scene() {
  static const Scene s = load_scene(std::string(CSP_SOURCE_DIR) + "/configs/scenes/" + kScene + ".yaml");
  return s;
}

// `csp plan excite` of the ultrasound scene, once per criterion (task or d): one period of 10 s at the
// task's anchor with the transfers there and back, a short optimiser budget (the loop, not the design,
// is tested here; csp_excitation_tests judges the design).
const std::string& plan(const std::string& criterion) {
  static std::map<std::string, std::string> dirs;
  if (!dirs.contains(criterion)) {
    const std::string dir = (temp_dir() / ("excite_" + criterion)).string();
    const ProgramRun run = csp({"plan", "excite", "--scene", kScene, "--criterion", criterion, "--periods", "1",
                                "--max-evaluations", "20", "--out", dir});
    if (run.exit_code != 0) throw std::runtime_error("csp plan excite failed: " + run.err + run.out);
    dirs[criterion] = dir;
  }
  return dirs.at(criterion);
}

// A known change of the plant: a payload on top of the probe, link masses scaled, another friction set.
struct PlantChange {
  std::optional<RigidBodyInertia> payload;
  double link4_scale = 1.0;
  std::string friction;   // the plant's friction set (empty: the robot file's default, Gaz et al.'s sigmoid)
  bool noise = true;      // the torque sensor's noise at the real log's levels
};

// +0.5 kg, CoM 0.12 m along the flange axis, a small inertia of its own (RoundTrip's payload).
RigidBodyInertia payload() { return {0.5, Vector3(0.0, 0.0, 0.12), Matrix3::Identity() * 2e-4}; }

YAML::Node load_node(const RigidBodyInertia& body) {
  const Matrix3& I = body.inertia;
  YAML::Node n;
  n["mass"] = body.mass;
  for (int k = 0; k < 3; ++k) n["com"].push_back(body.com[k]);
  for (const double v : {I(0, 0), I(0, 1), I(0, 2), I(1, 1), I(1, 2), I(2, 2)}) n["inertia"].push_back(v);
  return n;
}

// The plan's scenario with the changed plant, written next to it as `name` (its robot.yaml and
// trajectory.csv are relative). The robot's own model knows the probe only; the collision
// thresholds are raised to 100 N m / 100 N as for an identification run on a real arm (the model
// error would otherwise look like a contact: a cartesian_reflex with link 4 +10 %).
std::string changed_scenario(const std::string& dir, const std::string& name, const PlantChange& change) {
  YAML::Node s = YAML::LoadFile(dir + "/scenario.yaml");
  const RigidBodyInertia& probe = scene().tool.inertia;
  s["plant"]["load"] = load_node(change.payload ? combine(probe, *change.payload) : probe);
  if (change.link4_scale != 1.0) s["plant"]["link_scale"]["4"]["mass"] = change.link4_scale;
  if (!change.friction.empty()) s["plant"]["friction"] = change.friction;
  s["robot_model"]["load"] = load_node(probe);
  YAML::Node settings;
  const Vector7 sigma = planners::real_log_torque_noise();
  for (int j = 0; j < kNumJoints; ++j) settings["tau_J_noise"].push_back(change.noise ? sigma[j] : 0.0);
  for (const char* key : {"lower_torque", "upper_torque"})
    for (int j = 0; j < kNumJoints; ++j) settings["collision_behavior"][key].push_back(100.0);
  for (const char* key : {"lower_force", "upper_force"})
    for (int j = 0; j < 6; ++j) settings["collision_behavior"][key].push_back(100.0);
  s["robot_settings"] = settings;
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << s;
  const std::string path = dir + "/" + name;
  std::ofstream(path) << out.c_str() << "\n";
  return path;
}

// `csp emulate SCENARIO --log LOG`, which must finish without a reflex; the log's path.
std::string emulate(const std::string& scenario) {
  const std::string log = scenario + ".csv";
  const ProgramRun run = csp({"emulate", scenario, "--log", log});
  EXPECT_EQ(run.exit_code, 0) << run.err << run.out;
  EXPECT_NE(run.out.find("finished without reflex"), std::string::npos) << run.out;
  return log;
}

// `csp gap` on an emulated log with the model the plan was made for: the robot file's sets and the
// probe as the flange load (what the robot's model knows), `friction` the model's friction set.
nlohmann::json gap(const std::string& dir, const std::string& log, const std::string& friction = "") {
  const RigidBodyInertia& probe = scene().tool.inertia;
  const Matrix3& I = probe.inertia;
  const std::string json = log + ".gap.json";
  std::vector<std::string> args = {
      "gap", "--log", log, "--robot", dir + "/robot.yaml", "--load-mass", text(probe.mass), "--load-com",
      text(probe.com[0]) + "," + text(probe.com[1]) + "," + text(probe.com[2]), "--load-inertia",
      text(I(0, 0)) + "," + text(I(0, 1)) + "," + text(I(0, 2)) + "," + text(I(1, 1)) + "," + text(I(1, 2)) + "," +
          text(I(2, 2)),
      "--json", json};
  if (!friction.empty()) args.insert(args.end(), {"--friction", friction});
  const ProgramRun run = csp(args);
  EXPECT_EQ(run.exit_code, 0) << run.err << run.out;
  std::ifstream in(json);
  return nlohmann::json::parse(in);
}

std::vector<std::string> causes(const nlohmann::json& diagnosis) {
  return diagnosis.at("verdict").at("causes").get<std::vector<std::string>>();
}

// The emulated plant has static friction (the robot file's breakaway levels, docs/emulator.md), which
// gap's model (the sliding law alone) lacks: gap names it as static_friction and, for the lag it
// leaves at each reversal, friction_hysteresis, on an unchanged plant too. It is what the plant has.
bool plants_own(const std::string& cause) { return cause == "static_friction" || cause == "friction_hysteresis"; }

::testing::AssertionResult names_only(const nlohmann::json& diagnosis, const std::vector<std::string>& change) {
  const std::vector<std::string> named = causes(diagnosis);
  std::string list;
  for (const std::string& c : named) list += c + " ";
  for (const std::string& c : change)
    if (std::find(named.begin(), named.end(), c) == named.end())
      return ::testing::AssertionFailure() << c << " not named; named: " << list;
  for (const std::string& c : named)
    if (!plants_own(c) && std::find(change.begin(), change.end(), c) == change.end())
      return ::testing::AssertionFailure() << c << " named, which the plant does not have; named: " << list;
  return ::testing::AssertionSuccess() << list;
}

// --- the plant key -------------------------------------------------------------------------------

std::string scenario_with_plant(const std::string& name, const std::string& plant, const std::string& robot = "panda") {
  const std::string path = (temp_dir() / name).string();
  std::ofstream(path) << "name: plant\nrobot: " << robot_file(robot) << "\nplant:\n" << plant
                      << "initial_q: [0, -0.785, 0, -2.356, 0, 1.571, 0.785]\nduration: 1\n"
                         "controller: {type: float}\n";
  return path;
}

std::string scenario_error(const std::string& plant) {
  try {
    rt::load_scenario(scenario_with_plant("bad.yaml", plant));
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "no error";
}

TEST(ScenarioLinkScale, ScalesTheLinksMassAndInertiaAndKeepsItsCom) {
  const rt::Scenario s = rt::load_scenario(scenario_with_plant("scaled.yaml", "  link_scale: {4: {mass: 1.1}, 7: {mass: 0.5}}\n"));
  const ModelParameters nominal = model_parameters(load_robot_config(robot_file("panda")), {});
  for (int i = 0; i < kNumJoints; ++i) {
    const double scale = i == 3 ? 1.1 : (i == 6 ? 0.5 : 1.0);
    const RigidBodyInertia &plant = s.emulator.plant.links[i], &truth = nominal.links[i];
    EXPECT_DOUBLE_EQ(plant.mass, scale * truth.mass) << "link " << i + 1;
    EXPECT_TRUE(near(plant.com, truth.com, 0.0)) << "link " << i + 1;
    EXPECT_TRUE(near(plant.inertia, scale * truth.inertia, 1e-15)) << "link " << i + 1;
    // The robot's model does not know the change.
    EXPECT_DOUBLE_EQ(s.emulator.internal.links[i].mass, truth.mass) << "link " << i + 1;
  }
  // Gravity of the plant: the nominal arm's plus 0.1 of link 4's own and -0.5 of link 7's (the
  // torque is linear in each link's mass and first moment), from the potential energy by central
  // differences, V = -sum m_i g . c_i over the parameters.
  const Model plant(s.emulator.plant), arm(nominal);
  ModelParameters link4 = nominal, link7 = nominal;
  for (int i = 0; i < kNumJoints; ++i) {
    if (i != 3) link4.links[i].mass = 0.0;
    if (i != 6) link7.links[i].mass = 0.0;
  }
  const Vector7 q(0.3, -0.5, 0.2, -2.0, 0.4, 1.8, -0.6);
  Vector7 dV;
  for (int j = 0; j < kNumJoints; ++j) {
    const Vector7 step = Vector7::Unit(j) * 1e-6;
    auto V = [&](const ModelParameters& p, const Vector7& x) { return potential_energy(Model(p), x); };
    dV[j] = (0.1 * (V(link4, q + step) - V(link4, q - step)) - 0.5 * (V(link7, q + step) - V(link7, q - step))) / 2e-6;
  }
  EXPECT_TRUE(near(Vector7(gravity_of(plant, q) - gravity_of(arm, q)), dV, 1e-7));
}

TEST(ScenarioLinkScale, BadValuesNameTheKey) {
  for (const auto& [plant, expected] : std::vector<std::pair<std::string, std::string>>{
           {"  link_scale: {4: {mass: 0}}\n", "plant.link_scale.4.mass: expected a positive number"},
           {"  link_scale: {4: {mass: -1.1}}\n", "plant.link_scale.4.mass: expected a positive number"},
           {"  link_scale: {4: {mass: .nan}}\n", "plant.link_scale.4.mass: expected a finite number"},
           {"  link_scale: {4: {mass: .inf}}\n", "plant.link_scale.4.mass: expected a finite number"},
           {"  link_scale: {8: {mass: 1.1}}\n", "plant.link_scale.8: expected a link number from 1 to 7"},
           {"  link_scale: {0: {mass: 1.1}}\n", "plant.link_scale.0: expected a link number from 1 to 7"},
           {"  link_scale: {four: {mass: 1.1}}\n", "plant.link_scale.four: expected a link number from 1 to 7"},
           {"  link_scale: {4: {inertia: 1.1}}\n", "plant.link_scale.4.inertia: expected no such key (allowed: mass)"},
           {"  link_scale: {4: {}}\n", "plant.link_scale.4.mass: expected this key (missing)"},
           {"  link_scale: [1.1]\n", "plant.link_scale: expected a mapping"}}) {
    const std::string error = scenario_error(plant);
    EXPECT_NE(error.find(expected), std::string::npos) << plant << " -> " << error;
  }
}

// The plant carries the robot file's armature (an FR3's motors) unless the scenario names its own;
// the robot's own model has none. M of the plant is then the model's M plus diag(armature).
TEST(ScenarioArmature, TheRobotFilesUnlessTheScenarioNamesAnother) {
  const Vector7 fr3_armature =
      v7(franka_models().at("dynamics").at("fr3_mujoco_menagerie").at("joint_params").at("armature"));
  const rt::Scenario shipped = rt::load_scenario(rt::shipped_scenario_path("libfranka_fr3"));
  EXPECT_EQ(shipped.emulator.plant.armature, fr3_armature);
  EXPECT_EQ(shipped.emulator.internal.armature, Vector7::Zero());
  const Vector7 q(0.3, -0.5, 0.2, -2.0, 0.4, 1.8, -0.6);
  const Matrix7 added = mass_of(Model(shipped.emulator.plant), q) - mass_of(Model(shipped.emulator.internal), q);
  EXPECT_TRUE(near(added, Matrix7(fr3_armature.asDiagonal()), 1e-12)) << added;

  EXPECT_EQ(rt::load_scenario(scenario_with_plant("fr3.yaml", "  inertia: franka_description\n", "fr3")).emulator.plant.armature,
            fr3_armature);
  const std::string rigid = "  armature: {values: [0, 0, 0, 0, 0, 0, 0], source: \"no motors\"}\n";
  EXPECT_EQ(rt::load_scenario(scenario_with_plant("fr3_rigid.yaml", rigid, "fr3")).emulator.plant.armature, Vector7::Zero());
  EXPECT_EQ(rt::load_scenario(scenario_with_plant("panda.yaml", "  inertia: gaz2019\n")).emulator.plant.armature,
            Vector7::Zero());
  const std::string own = "  armature: {values: [0.4, 0.4, 0.3, 0.3, 0.1, 0.1, 0.05], source: \"a test\"}\n";
  EXPECT_EQ(rt::load_scenario(scenario_with_plant("panda_armature.yaml", own)).emulator.plant.armature,
            (Vector7() << 0.4, 0.4, 0.3, 0.3, 0.1, 0.1, 0.05).finished());
}

TEST(ScenarioArmature, BadValuesNameTheKey) {
  for (const auto& [plant, expected] : std::vector<std::pair<std::string, std::string>>{
           {"  armature: {values: [0, 0, 0, -1, 0, 0, 0], source: x}\n", "plant.armature.values: expected 7 non-negative numbers"},
           {"  armature: {values: [0, 0, 0], source: x}\n", "plant.armature.values: expected a list of 7 numbers"},
           {"  armature: {values: [0, 0, 0, 0, 0, 0, 0]}\n", "plant.armature.source: expected this key (missing)"},
           {"  armature: {values: [0, 0, 0, 1e9, 0, 0, 0], source: x}\n", "plant.armature.values: expected 7 rotor inertias of at most 1000 kg m^2"},
           {"  armature: [0, 0, 0, 0, 0, 0, 0]\n", "plant.armature: expected a mapping"}}) {
    const std::string error = scenario_error(plant);
    EXPECT_NE(error.find(expected), std::string::npos) << plant << " -> " << error;
  }
}

// --- the loop ----------------------------------------------------------------------------------

// The payload's tolerance. Seeds 1-5 of the torque noise (`csp emulate --seed`) gave 0.5029-0.5037 kg
// and the CoM within 3.3 mm of (0, 0, 0.12): a bias, not noise (their spread is 0.5 g and 0.5 mm, gap's
// own sigma 0.6 g and 0.5 mm), of what the point-mass law leaves out (the payload's own inertia,
// 2e-4 kg m^2) and of the plant's stiction left in the residual. Tracking does not enter: the fit uses
// the measured motion (4-5 mrad RMS behind the plan here), not the planned one. The tolerances are
// about 5x the bias.
constexpr double kPayloadMassTolerance = 0.02;   // [kg], 4 % of the payload
constexpr double kPayloadComTolerance = 0.01;    // [m]

// One plan, three changed plants, one change each: the payload and link 4 both move the link-7 and
// link-4 base parameters that one 10 s excitation at one anchor cannot tell apart from each other
// (with both in one plant gap names payload + sensor_gain, the payload at 0.39 kg: see docs/excitation.md).
TEST(ClosedLoop, PlanEmulateGapNamesEachChangeOfThePlant) {
  const std::string& dir = plan("task");

  PlantChange heavier;
  heavier.payload = payload();
  const nlohmann::json with_payload = gap(dir, emulate(changed_scenario(dir, "payload.yaml", heavier)));
  EXPECT_TRUE(names_only(with_payload, {"payload"})) << with_payload["verdict"]["params"].dump();
  const nlohmann::json& found = with_payload["verdict"]["params"]["payload"];
  EXPECT_NEAR(found["mass_kg"].get<double>(), payload().mass, kPayloadMassTolerance);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(found["com_m"][k].get<double>(), payload().com[k], kPayloadComTolerance) << "axis " << k;
  std::cout << "payload: " << found["mass_kg"] << " kg at " << found["com_m"] << " m (planted 0.5 kg at [0, 0, 0.12]); named "
            << with_payload["verdict"]["causes"] << "\n";

  PlantChange link4;
  link4.link4_scale = 1.1;
  const nlohmann::json with_link4 = gap(dir, emulate(changed_scenario(dir, "link4.yaml", link4)));
  EXPECT_TRUE(names_only(with_link4, {"inertial_parameters"}));
  std::cout << "link 4 +10 %: named " << with_link4["verdict"]["causes"] << "\n";

  // The friction change: the plant runs Gaz et al.'s sigmoid (the robot file's set), the model believes
  // their linear law (pi_hat_CLS). Its offset f_o, a constant per joint the sigmoid (zero at rest) lacks,
  // is named sensor_offset by its shape. Recovered: the fitted friction laws against the plant's minus the
  // model's along the emulated motion, where the joint slides (|dq| > 0.15 rad/s: the plant's static
  // friction has decayed below 1e-4 of its breakaway there).
  const std::string log = emulate(changed_scenario(dir, "friction.yaml", PlantChange{}));
  const nlohmann::json with_friction = gap(dir, log, "gaz2019_linear_cls");
  EXPECT_TRUE(names_only(with_friction, {"joint_friction"}) ||
              names_only(with_friction, {"joint_friction", "sensor_offset"}));
  const nlohmann::json& params = with_friction["verdict"]["params"];
  const RobotConfig robot = load_robot_config(dir + "/robot.yaml");
  const FrictionModel& plant = robot.friction_sets.at("gaz2019");
  const FrictionModel& model = robot.friction_sets.at("gaz2019_linear_cls");
  const JointLog motion = read_joint_log_csv(log);
  double change = 0.0, error = 0.0;   // sums of squares over the sliding samples of all joints
  for (std::size_t k = 0; k < motion.size(); k += 10) {
    const Vector7 truth = friction_torque(plant, motion.dq[k]) - friction_torque(model, motion.dq[k]);
    for (int j = 0; j < kNumJoints; ++j) {
      if (std::abs(motion.dq[k][j]) < 0.15) continue;
      const nlohmann::json& f = params["joint_friction"];
      // A sigmoid fitted as a step has an infinite phi2, which JSON writes as null.
      const double phi2 = f["phi2_s_per_rad"][j].is_null() ? std::numeric_limits<double>::infinity()
                                                           : f["phi2_s_per_rad"][j].get<double>();
      double fitted = gap::friction_law(f["phi1_Nm"][j], phi2, f["phi3_rad_per_s"][j], f["viscous_Nms_per_rad"][j],
                                        motion.dq[k][j]);
      if (params.contains("sensor_offset")) fitted += params["sensor_offset"]["offset_Nm"][j].get<double>();
      change += truth[j] * truth[j];
      error += (fitted - truth[j]) * (fitted - truth[j]);
    }
  }
  std::cout << "friction: named " << with_friction["verdict"]["causes"] << "; the fitted change misses the planted one by " << std::sqrt(error / change)
            << " of its RMS where the joints slide\n";
  EXPECT_LT(std::sqrt(error / change), 0.5);
}

// --- the medical claim on the emulated robot ----------------------------------------------------

// The identification model of the excitation design (planners/identifiability.hpp: the base inertial
// parameters and Gaz et al.'s linear friction columns), for the Panda with the probe.
const planners::IdentificationModel& identification() {
  static const planners::IdentificationModel id = [] {
    ModelOptions options;
    options.friction = "gaz2019_linear_cls";
    return planners::IdentificationModel(
        Model(with_tool(model_parameters(load_robot_config(robot_file("panda")), options), scene().tool)));
  }();
  return id;
}

// An emulated log as gap reads it (gap/signal.hpp: resampled, Savitzky-Golay smoothed and
// differentiated, one sample per 10 ms): its regressor rows, its filtered torques, and the plant's
// rigid-body torque along the same samples (RNEA of the plant's own parameters).
struct Rows {
  Eigen::MatrixXd R;       // physical rows, 7K x p
  Eigen::VectorXd tau;     // filtered measured torque (armature zero: the Panda's plant has none)
  Eigen::VectorXd rigid;   // the plant's M ddq + c + g
  Eigen::VectorXd dq;      // the filtered joint velocity of each row
};

Rows rows_of(const std::string& log, const Model& plant) {
  const gap::Samples samples = gap::filter_log(read_joint_log_csv(log), gap::FilterOptions{});
  const planners::IdentificationModel& id = identification();
  const Eigen::Index n = static_cast<Eigen::Index>(kNumJoints * samples.size());
  Rows r{Eigen::MatrixXd(n, id.parameters()), Eigen::VectorXd(n), Eigen::VectorXd(n), Eigen::VectorXd(n)};
  Data data;
  for (std::size_t k = 0; k < samples.size(); ++k) {
    const Eigen::Index row = static_cast<Eigen::Index>(kNumJoints * k);
    r.R.middleRows(row, kNumJoints) = id.rows(data, {samples.q[k], samples.dq[k], samples.ddq[k], Vector7::Zero()});
    r.tau.segment(row, kNumJoints) = samples.tau[k];
    Vector7 tau;
    rnea(plant, data, samples.q[k], samples.dq[k], samples.ddq[k], tau);
    r.rigid.segment(row, kNumJoints) = tau;
    r.dq.segment(row, kNumJoints) = samples.dq[k];
  }
  return r;
}

// Weighted least squares on the scaled rows (Sigma^-1/2 R S), theta = S z: what the design's
// predicted covariance is of (docs/excitation.md). Rows whose joint moves slower than `min_speed`
// [rad/s] are left out (RoundTrip's rule, tests/test_excitation.cpp).
Eigen::VectorXd identify(const Rows& r, double min_speed) {
  const planners::IdentificationModel& id = identification();
  Eigen::MatrixXd W(r.R.rows(), r.R.cols());
  Eigen::VectorXd tau(r.tau.size());
  std::vector<Eigen::Index> kept;
  for (Eigen::Index row = 0; row < r.R.rows(); row += kNumJoints) {
    W.middleRows(row, kNumJoints) = id.scale_rows(r.R.middleRows(row, kNumJoints));
    tau.segment(row, kNumJoints) = r.tau.segment(row, kNumJoints).cwiseQuotient(id.noise_sigma());
    for (Eigen::Index j = row; j < row + kNumJoints; ++j)
      if (std::abs(r.dq[j]) >= min_speed) kept.push_back(j);
  }
  return id.column_scale().cwiseProduct(W(kept, Eigen::all).colPivHouseholderQr().solve(tau(kept)));
}

double rms(const Eigen::VectorXd& v) { return std::sqrt(v.squaredNorm() / static_cast<double>(v.size())); }

// Two excitations of equal length (the same transfers, 10 s at the same anchor: task-weighted and
// whole-workspace D-optimal), each emulated on the changed plant (payload, link 4 +10 %, Gaz et al.'s
// sigmoid friction with the robot file's static friction) and identified; each predicts the scan
// (`csp plan task`, played on the emulator in free space on the same plant).
// - Judged on the rigid-body torque, against the plant's own (RNEA of its parameters along the scan's
//   filtered motion). The whole torque's prediction error, 0.13-0.15 N m for both, is mostly a bias
//   both share, of the model class's friction (a Coulomb level reached at 0.01 rad/s) against the
//   plant's sigmoid (zero at rest, shallow) at the scan's few 0.01 rad/s: printed, not compared, with
//   the error against a noisy record, whose noise (0.26 N m RMS) hides the rest.
// - Fitted on the rows where the joint moves at 0.1 rad/s or more (RoundTrip's rule): below it the
//   plant's stiction (breakaway up to 0.36 N m, decaying over 0.05 rad/s) and the sigmoid's knee are
//   outside the class, and their misfit leaks into the inertial estimate, the task-weighted design's
//   more (it reverses the order: printed).
TEST(ClosedLoop, TaskWeightedExcitationPredictsTheEmulatedScanBetterThanDOptimal) {
  PlantChange change;
  change.payload = payload();
  change.link4_scale = 1.1;
  ModelParameters truth = with_tool(model_parameters(load_robot_config(robot_file("panda")), {}), scene().tool);
  truth.load = payload();
  truth.links[3].mass *= 1.1;
  truth.links[3].inertia *= 1.1;
  const Model plant(truth);

  const std::string scan_dir = (temp_dir() / "scan").string();
  const ProgramRun task = csp({"plan", "task", "--scene", kScene, "--out", scan_dir});
  ASSERT_EQ(task.exit_code, 0) << task.err << task.out;
  PlantChange exact = change;
  exact.noise = false;
  const Rows scan = rows_of(emulate(changed_scenario(scan_dir, "scan_exact.yaml", exact)), plant);
  const Rows scan_noisy = rows_of(emulate(changed_scenario(scan_dir, "scan_noisy.yaml", change)), plant);
  const int base = identification().base_parameters();
  double rigid[2] = {0.0, 0.0}, whole[2] = {0.0, 0.0}, noisy[2] = {0.0, 0.0}, all_rows[2] = {0.0, 0.0};
  for (const bool weighted : {false, true}) {
    const std::string& dir = plan(weighted ? "task" : "d");
    const Rows excitation = rows_of(emulate(changed_scenario(dir, "identify.yaml", change)), plant);
    const Eigen::VectorXd theta = identify(excitation, 0.1);
    rigid[weighted] = rms(scan.R.leftCols(base) * theta.head(base) - scan.rigid);
    whole[weighted] = rms(scan.R * theta - scan.tau);
    noisy[weighted] = rms(scan_noisy.R * theta - scan_noisy.tau);
    all_rows[weighted] = rms(scan.R.leftCols(base) * identify(excitation, 0.0).head(base) - scan.rigid);
  }
  std::cout << "emulated scan, prediction RMS task-weighted vs D-optimal: rigid-body torque " << rigid[1] << " vs "
            << rigid[0] << " N m (fitted on every row: " << all_rows[1] << " vs " << all_rows[0] << "); whole torque "
            << whole[1] << " vs " << whole[0] << " N m; against a noisy record " << noisy[1] << " vs " << noisy[0]
            << " N m\n";
  EXPECT_LT(rigid[1], rigid[0]);
}

}  // namespace
}  // namespace csp::test
