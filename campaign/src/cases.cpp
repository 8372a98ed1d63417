#include "csp/campaign/cases.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace csp::campaign {
namespace {

// SplitMix64 (Steele, Lea, Flood 2014): well-spread seeds from consecutive indices.
uint64_t mix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// "j3" -> 2; std::invalid_argument otherwise.
int joint_index(const std::string& parameter, const std::string& suffix) {
  if (suffix.size() == 2 && suffix[0] == 'j' && suffix[1] >= '1' && suffix[1] <= '7') return suffix[1] - '1';
  throw std::invalid_argument("a joint j1 to j7 at the end of `" + parameter + "`");
}

void require(bool ok, const std::string& parameter, const std::string& expected) {
  if (!ok) throw std::invalid_argument("`" + parameter + "` to be " + expected);
}

// The scene's copy this campaign case changes: the plant's contact and the medical controller's
// task share it, as load_scenario made them.
Scene& own_scene(rt::Scenario& scenario, const std::string& parameter) {
  if (!scenario.emulator.scene) throw std::invalid_argument("a scenario with a scene for `" + parameter + "`");
  auto scene = std::make_shared<Scene>(*scenario.emulator.scene);
  scenario.emulator.scene = scene;
  if (scenario.controller.medical.scene) scenario.controller.medical.scene = scene;
  return *scene;
}

void apply_scene_parameter(rt::Scenario& scenario, const std::string& parameter, double value) {
  // scene.<material|obstacle>.<name>.<field>: the name may not contain a dot.
  const std::size_t first = parameter.find('.', 6), last = parameter.rfind('.');
  if (first == std::string::npos || last <= first)
    throw std::invalid_argument("scene.material.<name>.<field> or scene.obstacle.<name>.<field>, not `" + parameter + "`");
  const std::string kind = parameter.substr(6, first - 6), name = parameter.substr(first + 1, last - first - 1),
                    field = parameter.substr(last + 1);
  Scene& scene = own_scene(scenario, parameter);
  if (kind == "material") {
    const auto material = scene.materials.find(name);
    if (material == scene.materials.end()) throw std::invalid_argument("a material of the scene " + scene.name + ", not `" + name + "`");
    if (field == "stiffness") material->second.stiffness = value;
    else if (field == "damping") material->second.damping = value;
    else if (field == "friction") material->second.friction = value;
    else throw std::invalid_argument("stiffness, damping or friction of a material, not `" + field + "`");
    if (const auto problem = material_problem(material->second))
      throw std::invalid_argument("`" + parameter + "` to give a material's " + std::string(problem->key) + " " +
                                  std::string(problem->expected));
  } else if (kind == "obstacle") {
    const int index = scene.obstacle_index(name);
    if (index < 0) throw std::invalid_argument("an obstacle of the scene " + scene.name + ", not `" + name + "`");
    ObstacleMotion& motion = scene.obstacles[static_cast<std::size_t>(index)].motion;
    if (field == "breathing_amplitude") {
      // Along the motion's own direction; straight up for an obstacle that did not move.
      require(value >= 0.0, parameter, "a non-negative amplitude [m]");
      const Vector3 direction = motion.amplitude.norm() > 0.0 ? motion.amplitude.normalized() : Vector3::UnitZ();
      motion.amplitude = value * direction;
    } else if (field == "breathing_frequency_hz") {
      require(value >= 0.0, parameter, "a non-negative frequency [Hz]");
      motion.frequency_hz = value;
    } else {
      throw std::invalid_argument("breathing_amplitude or breathing_frequency_hz of an obstacle, not `" + field + "`");
    }
  } else {
    throw std::invalid_argument("scene.material.<name>.<field> or scene.obstacle.<name>.<field>, not `" + parameter + "`");
  }
}

void scale_link_inertia(ModelParameters& plant, double scale) {
  for (RigidBodyInertia& link : plant.links) {
    link.mass *= scale;
    link.inertia *= scale;
  }
}

void scale_friction(FrictionModel& friction, double scale) {
  for (Vector7* v : {&friction.phi1, &friction.viscous, &friction.coulomb, &friction.offset, &friction.breakaway}) *v *= scale;
}

}  // namespace

void apply_parameter(rt::Scenario& scenario, const std::string& parameter, double value) {
  if (!std::isfinite(value)) throw std::invalid_argument("`" + parameter + "` to be a finite number");
  ModelParameters& plant = scenario.emulator.plant;
  rt::ControllerSpec& controller = scenario.controller;
  rt::MedicalControllerSpec& medical = controller.medical;
  auto prefixed = [&](const std::string& prefix) { return parameter.rfind(prefix, 0) == 0; };
  auto non_negative = [&] { require(value >= 0.0, parameter, "non-negative"); return value; };

  // The plain numbers, each set as given (>= 0).
  const std::pair<const char*, double*> numbers[] = {
      {"plant.load_mass", &plant.load.mass},
      {"controller.translational_stiffness", &controller.translational_stiffness},
      {"controller.rotational_stiffness", &controller.rotational_stiffness},
      {"controller.desired_force", &medical.desired_force},
      {"controller.force_k_p", &medical.force_k_p},
      {"controller.force_k_i", &medical.force_k_i},
      {"controller.axis_damping", &medical.axis_damping},
      {"controller.null_space_stiffness", &medical.null_space_stiffness},
      {"faults.latency_mean_us", &scenario.command_faults.latency_mean_us},
      {"faults.latency_jitter_us", &scenario.command_faults.latency_jitter_us}};
  for (const auto& [name, field] : numbers) {
    if (parameter != name) continue;
    *field = non_negative();
    return;
  }

  if (parameter == "seed") {
    require(value >= 0.0 && value == std::floor(value) && value < 9007199254740992.0, parameter, "a whole number >= 0");
    scenario.seed = static_cast<uint64_t>(value);
    scenario.emulator.seed = scenario.seed;
    scenario.command_faults.seed = scenario.seed + 1;   // as csp emulate --seed
  } else if (parameter == "plant.mass_scale") {
    require(value > 0.0, parameter, "positive");
    scale_link_inertia(plant, value);
  } else if (parameter == "plant.armature_scale") {
    plant.armature *= non_negative();
  } else if (parameter == "plant.friction_scale") {
    scale_friction(plant.friction, non_negative());
  } else if (prefixed("plant.armature.")) {
    plant.armature[joint_index(parameter, parameter.substr(15))] = non_negative();
  } else if (prefixed("plant.friction.phi")) {
    // plant.friction.phi1.jN [N m], phi2.jN [s/rad], phi3.jN [rad/s]: the Gaz law's (gap's joint_friction).
    require(plant.friction.type == FrictionModel::Type::kGazSigmoid, parameter, "used with a plant whose friction is Gaz's law");
    const std::string rest = parameter.substr(18);   // "1.j4"
    require(rest.size() == 4 && rest[0] >= '1' && rest[0] <= '3' && rest[1] == '.', parameter, "plant.friction.phi1|phi2|phi3.jN");
    Vector7& phi = rest[0] == '1' ? plant.friction.phi1 : rest[0] == '2' ? plant.friction.phi2 : plant.friction.phi3;
    if (rest[0] == '1') require(value >= 0.0, parameter, "non-negative");
    if (rest[0] == '2') require(value > 0.0, parameter, "positive");
    phi[joint_index(parameter, rest.substr(2))] = value;
  } else if (prefixed("sensor.tau_J_bias.")) {
    scenario.emulator.tau_J_bias[joint_index(parameter, parameter.substr(18))] = value;
  } else if (parameter == "controller.stiffness_scale" || parameter == "controller.damping_scale") {
    require(controller.type == "joint_impedance" || (controller.type == "float" && parameter == "controller.damping_scale"),
            parameter, "used with a joint_impedance controller, not " + controller.type);
    (parameter == "controller.stiffness_scale" ? controller.stiffness : controller.damping) *= non_negative();
  } else if (parameter == "faults.loss_probability") {
    require(value >= 0.0 && value <= 1.0, parameter, "a probability from 0 to 1");
    scenario.command_faults.loss_probability = value;
  } else if (prefixed("scene.")) {
    apply_scene_parameter(scenario, parameter, value);
  } else {
    throw std::invalid_argument("a known parameter (docs/campaign.md: seed, plant.*, sensor.*, controller.*, faults.*, scene.*), not `" +
                                parameter + "`");
  }
}

std::vector<Case> expand_cases(const Campaign& campaign) {
  std::size_t grid = 1;
  for (const Axis& axis : campaign.axes)
    if (axis.kind == Axis::Kind::kValues) grid *= axis.values.size();
  const std::size_t count = grid * static_cast<std::size_t>(campaign.runs);
  const std::size_t width = std::max<std::size_t>(4, std::to_string(count - 1).size());
  std::vector<Case> cases;
  cases.reserve(count);
  for (std::size_t i = 0; i < count; ++i) {
    Case c;
    c.index = static_cast<int>(i);
    const std::string number = std::to_string(i);
    c.id = std::string(1, 'c').append(width - number.size(), '0').append(number);
    c.seed = mix(mix(campaign.seed) ^ i) >> 11;   // 53 bits: exact in a double and in JSON readers
    std::mt19937_64 draw(mix(c.seed));
    std::size_t point = i / static_cast<std::size_t>(campaign.runs), stride = grid;   // the grid point, first axis slowest
    for (const Axis& axis : campaign.axes) {
      double value = 0.0;
      if (axis.kind == Axis::Kind::kValues) {
        stride /= axis.values.size();
        value = axis.values[(point / stride) % axis.values.size()];
      } else if (axis.kind == Axis::Kind::kUniform) {
        value = std::uniform_real_distribution<double>(axis.low, axis.high)(draw);
      } else {
        value = std::clamp(std::normal_distribution<double>(axis.mean, axis.sd)(draw), axis.low, axis.high);
      }
      c.parameters.emplace_back(axis.parameter, value);
    }
    cases.push_back(std::move(c));
  }
  return cases;
}

rt::Scenario case_scenario(const Campaign& campaign, const Case& c) {
  std::size_t base = 0;
  for (const auto& [parameter, value] : c.parameters)
    if (parameter == "scenario") base = static_cast<std::size_t>(value);
  rt::Scenario scenario = rt::load_scenario(campaign.scenarios.at(base));
  if (campaign.duration) scenario.duration = *campaign.duration;
  apply_parameter(scenario, "seed", static_cast<double>(c.seed));
  for (const auto& [parameter, value] : c.parameters)
    if (parameter != "scenario") apply_parameter(scenario, parameter, value);
  return scenario;
}

std::string scenario_name(const Campaign& campaign, double index) {
  return campaign.scenario_names.at(static_cast<std::size_t>(index));
}

std::string cases_json(const Campaign& campaign, const std::vector<Case>& cases) {
  nlohmann::ordered_json j;
  j["campaign_file"] = campaign.path;
  j["scenarios"] = campaign.scenarios;
  j["scenario_names"] = campaign.scenario_names;
  j["duration"] = campaign.duration ? nlohmann::ordered_json(*campaign.duration) : nlohmann::ordered_json(nullptr);
  j["seed"] = campaign.seed;
  j["runs"] = campaign.runs;
  j["axes"] = nlohmann::ordered_json::array();
  for (const Axis& axis : campaign.axes) j["axes"].push_back(axis.parameter);
  j["fail_if"] = campaign.limits;
  j["worst_by"] = campaign.worst_by;
  j["metrics"] = campaign.kept;
  j["gap_verdict"] = campaign.gap_verdict;
  j["cases"] = nlohmann::ordered_json::array();
  for (const Case& c : cases) {
    nlohmann::ordered_json parameters = nlohmann::ordered_json::object();
    for (const auto& [name, value] : c.parameters) parameters[name] = value;
    j["cases"].push_back({{"id", c.id}, {"seed", c.seed}, {"parameters", parameters}});
  }
  return j.dump(1) + "\n";
}

void read_cases_json(const std::string& path, Campaign& campaign, std::vector<Case>& cases) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot be read (not a campaign folder: `csp campaign FILE --out DIR` writes it)");
  try {
    const nlohmann::ordered_json j = nlohmann::ordered_json::parse(in);
    campaign = Campaign{};
    campaign.path = j.at("campaign_file").get<std::string>();
    campaign.scenarios = j.at("scenarios").get<std::vector<std::string>>();
    campaign.scenario_names = j.at("scenario_names").get<std::vector<std::string>>();
    if (!j.at("duration").is_null()) campaign.duration = j.at("duration").get<double>();
    campaign.seed = j.at("seed").get<uint64_t>();
    campaign.runs = j.at("runs").get<int>();
    for (const auto& name : j.at("axes")) {
      Axis axis;   // its parameter's name: the values are in the cases
      axis.parameter = name.get<std::string>();
      campaign.axes.push_back(axis);
    }
    campaign.limits = j.at("fail_if").get<std::map<std::string, double>>();
    campaign.worst_by = j.at("worst_by").get<std::string>();
    campaign.kept = j.at("metrics").get<std::vector<std::string>>();
    campaign.gap_verdict = j.at("gap_verdict").get<bool>();
    cases.clear();
    for (const auto& item : j.at("cases")) {
      Case c;
      c.index = static_cast<int>(cases.size());
      c.id = item.at("id").get<std::string>();
      c.seed = item.at("seed").get<uint64_t>();
      for (const auto& [name, value] : item.at("parameters").items()) c.parameters.emplace_back(name, value.get<double>());
      cases.push_back(std::move(c));
    }
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error(path + ": not a campaign's cases (" + e.what() + ")");
  }
}

}  // namespace csp::campaign
