// The files of a plan (`csp plan excite|transfer|task --out DIR`, docs/planning.md):
//
//   trajectory.csv  the motion at 1 kHz in the one joint-log format (t, q, dq, ddq, and as tau_J the
//                   torque it needs on the robot with the scene's tool)
//   scenario.yaml   what `csp emulate DIR/scenario.yaml` runs as it is: the robot (robot.yaml, a copy
//                   of the robot file) with the tool as its flange load, joint impedance with
//                   feed-forward tracking trajectory.csv
//   plan.yaml       the request (command, scene, robot, seed, options) from which `csp plan rebuild`
//                   makes the same files byte for byte, the versions, and what the engine made
//                   (coefficients, waypoints, segments) for the record
//
// Every number is written in its shortest exact form, so the same plan gives the same bytes.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "csp/io/joint_log.hpp"
#include "csp/io/scene.hpp"

namespace csp::planners {

// What was asked: enough to make the same plan again.
struct PlanRequest {
  std::string command;   // excite, transfer, task
  std::string scene;     // the scene file, as given
  std::string robot;     // panda, fr3 or a robot file, as given
  std::uint64_t seed = 1;
  std::vector<std::pair<std::string, std::string>> options;   // the command's own options (--name, value), as given
};

struct Versions {
  std::string csp;    // CSP's project version
  std::string ompl;   // MAJOR.MINOR.PATCH of the OMPL the plan was made with
};
Versions versions(const std::string& ompl_version);

// The gains of libfranka's examples/joint_impedance_control.cpp, as configs/scenarios/default.yaml.
inline constexpr double kScenarioStiffness[7] = {600, 600, 600, 600, 250, 150, 50};
inline constexpr double kScenarioDamping[7] = {50, 50, 50, 20, 20, 20, 10};
// The scenario runs this long after the trajectory ends (the robot holds its last pose) [s].
inline constexpr double kScenarioHold = 0.5;

// The shortest text that reads back as exactly `value`.
std::string exact_number(double value);

// The scenario text for a trajectory whose first row is `initial_q`, lasting `duration` [s].
std::string scenario_text(const std::string& title, const Vector7& initial_q, double duration, const Tool& tool);

// Writes trajectory.csv, robot.yaml (a copy of robot_file), scenario.yaml and plan.yaml into `dir`
// (created if needed). `made`: the engine's own record (written under `plan:`).
void write_plan_files(const std::string& dir, const PlanRequest& request, const Versions& versions,
                      const std::string& robot_file, const Scene& scene,
                      const JointLog& trajectory, const nlohmann::json& made);

// The request of a plan.yaml, validated (ConfigError naming the file and key).
PlanRequest read_plan_request(const std::string& plan_yaml);

}  // namespace csp::planners
