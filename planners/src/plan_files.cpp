#include "csp/planners/plan_files.hpp"

#include <charconv>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "csp/io/svg_plot.hpp"
#include "csp/io/yaml_field.hpp"

namespace csp::planners {
namespace {

std::string vector_text(const double* values, int size) {
  std::string out = "[";
  for (int i = 0; i < size; ++i) out += (i ? ", " : "") + exact_number(values[i]);
  return out + "]";
}

bool is_scalar(const nlohmann::json& v) { return !v.is_object() && !v.is_array(); }

std::string scalar_text(const nlohmann::json& v) {
  if (v.is_number_float()) return exact_number(v.get<double>());
  return v.dump();   // integers, booleans, null, and strings JSON-quoted (YAML's double-quoted style)
}

// A JSON value as block YAML: mappings in key order, lists of scalars in flow style, so that a 7 x N
// coefficient matrix is N short lines.
void append_yaml(std::string& out, const nlohmann::json& value, int indent) {
  const std::string pad(static_cast<std::size_t>(indent), ' ');
  auto flow = [](const nlohmann::json& list) {
    std::string s = "[";
    for (std::size_t i = 0; i < list.size(); ++i) s += (i ? ", " : "") + scalar_text(list[i]);
    return s + "]";
  };
  auto all_scalars = [](const nlohmann::json& list) {
    for (const auto& item : list)
      if (!is_scalar(item)) return false;
    return true;
  };
  auto item = [&](const std::string& head, const nlohmann::json& v) {
    if (is_scalar(v)) out += head + " " + scalar_text(v) + "\n";
    else if (v.is_array() && all_scalars(v)) out += head + " " + flow(v) + "\n";
    else if (v.empty()) out += head + (v.is_array() ? " []\n" : " {}\n");
    else {
      out += head + "\n";
      append_yaml(out, v, indent + 2);
    }
  };
  if (value.is_object()) {
    for (const auto& [key, v] : value.items()) item(pad + nlohmann::json(key).dump() + ":", v);
  } else {
    for (const auto& v : value) item(pad + "-", v);
  }
}

}  // namespace

std::string exact_number(double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  return std::string(buffer, result.ptr);
}

Versions versions(const std::string& ompl_version) { return {CSP_VERSION, ompl_version}; }

std::string scenario_text(const std::string& title, const Vector7& initial_q, double duration, const Tool& tool) {
  const RigidBodyInertia& m = tool.inertia;
  const double inertia[6] = {m.inertia(0, 0), m.inertia(0, 1), m.inertia(0, 2),
                             m.inertia(1, 1), m.inertia(1, 2), m.inertia(2, 2)};
  std::string s;
  s += "# Written by csp plan (docs/planning.md): `csp emulate scenario.yaml` runs the plan's trajectory.csv\n";
  s += "# on the emulated robot (robot.yaml, the robot file's default sets and armature), the scene's tool as the flange load,\n";
  s += "# with joint impedance (libfranka's joint_impedance_control gains) and model feed-forward.\n";
  s += "name: " + nlohmann::json(title).dump() + "\n";
  s += "robot: robot.yaml\n";
  s += "end_effector: none\n";
  s += "plant:\n";
  s += "  load: {mass: " + exact_number(m.mass) + ", com: " + vector_text(m.com.data(), 3) +
       ", inertia: " + vector_text(inertia, 6) + "}   # " + nlohmann::json(tool.name).dump() + "\n";
  s += "initial_q: " + vector_text(initial_q.data(), kNumJoints) + "\n";
  s += "duration: " + exact_number(duration) + "\n";
  s += "clock: lockstep\n";
  s += "seed: 1\n";
  s += "controller:\n";
  s += "  type: joint_impedance\n";
  s += "  stiffness: " + vector_text(kScenarioStiffness, kNumJoints) + "\n";
  s += "  damping: " + vector_text(kScenarioDamping, kNumJoints) + "\n";
  s += "  feedforward: true\n";
  s += "  trajectory: {file: trajectory.csv}\n";
  return s;
}

void write_plan_files(const std::string& dir, const PlanRequest& request, const Versions& versions,
                      const std::string& robot_file, const Scene& scene,
                      const JointLog& trajectory, const nlohmann::json& made) {
  namespace fs = std::filesystem;
  std::error_code error;
  fs::create_directories(dir, error);
  if (error || !fs::is_directory(dir)) throw std::runtime_error("cannot create the plan directory " + dir);
  const fs::path folder(dir);
  check_joint_log(trajectory);

  write_joint_log_csv((folder / "trajectory.csv").string(), trajectory);
  std::ifstream robot(robot_file, std::ios::binary);
  std::ostringstream robot_text;
  robot_text << robot.rdbuf();
  if (!robot) throw std::runtime_error("cannot read the robot file " + robot_file);
  write_text_file((folder / "robot.yaml").string(), robot_text.str());
  const double duration = trajectory.t.back() - trajectory.t.front() + kScenarioHold;
  write_text_file((folder / "scenario.yaml").string(),
                  scenario_text("csp plan " + request.command + " " + scene.name, trajectory.q.front(), duration,
                                scene.tool));

  nlohmann::json options = nlohmann::json::object();
  std::string plan = "# Written by csp plan (docs/planning.md): `csp plan rebuild plan.yaml` makes the same files.\n";
  plan += "command: " + nlohmann::json(request.command).dump() + "\n";
  plan += "scene: " + nlohmann::json(request.scene).dump() + "\n";
  plan += "robot: " + nlohmann::json(request.robot).dump() + "\n";
  plan += "seed: " + std::to_string(request.seed) + "\n";
  plan += "options:" + std::string(request.options.empty() ? " {}" : "") + "\n";
  for (const auto& [name, value] : request.options)
    plan += "  " + nlohmann::json(name).dump() + ": " + nlohmann::json(value).dump() + "\n";
  plan += "versions: {csp: " + nlohmann::json(versions.csp).dump() + ", ompl: " + nlohmann::json(versions.ompl).dump() +
          "}\n";
  plan += "plan:\n";
  append_yaml(plan, made.is_object() ? made : nlohmann::json::object(), 2);
  write_text_file((folder / "plan.yaml").string(), plan);
}

PlanRequest read_plan_request(const std::string& plan_yaml) {
  const YAML::Node root = load_yaml_file(plan_yaml, "plan file");
  const Field top(root, plan_yaml, "");
  top.allow_only({"command", "scene", "robot", "seed", "options", "versions", "plan"});
  PlanRequest request;
  request.command = top["command"].text();
  if (request.command != "excite" && request.command != "transfer" && request.command != "task")
    top["command"].fail("excite, transfer or task");
  request.scene = top["scene"].text();
  request.robot = top["robot"].text();
  request.seed = static_cast<std::uint64_t>(top["seed"].whole_number(0, int64_t{1} << 53));
  const Field options = top["options"];
  for (const std::string& name : options.keys()) request.options.emplace_back(name, options[name].text());
  return request;
}

}  // namespace csp::planners
