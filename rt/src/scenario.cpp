#include "csp/rt/scenario.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <system_error>

#include "csp/io/yaml_field.hpp"

namespace csp::rt {
namespace {

// A trajectory file's first row may differ from initial_q by the rounding of a printed pose [rad].
constexpr double kTrajectoryStartTolerance = 1e-6;
// A scan path's first TCP must be the scan's start [m] with the tool axis [rad]: the planner's task
// paths are on the task within 1e-8 (docs/planning-task-paths.md), its tests hold them to 1e-4 and 1e-3.
constexpr double kScanPathStartTolerance = 1e-4, kScanPathAxisTolerance = 1e-3;

// Bounds on the scenario's rates, gains and magnitudes, so that a typo such as 1e200 is named where
// it is written instead of ending the run in a reflex or "plant diverged" that blames the plant.
// A frequency the 1 kHz loop can represent: below its Nyquist frequency [Hz].
constexpr double kLoopNyquistHz = 500.0;
// setJointImpedance's bound [N m/rad], for every joint stiffness.
constexpr double kMaxJointStiffness = 10000.0;
// [N m s/rad]: critical damping of that stiffness on a joint inertia of 10 kg m^2 (more than an
// arm's shoulder sees) is 630.
constexpr double kMaxJointDamping = 1000.0;
// setCartesianImpedance's upper bounds (libfranka robot.h: 10..3000 N/m, 1..300 N m/rad).
constexpr double kMaxTranslationalStiffness = 3000.0, kMaxRotationalStiffness = 300.0;
// [N m]: above any joint's torque limit (87 N m); a sensor noise or bias beyond it is no sensor's.
constexpr double kMaxSensorTorque = 100.0;
// A push of a tonne-force, a moment of a tonne at 10 cm: far beyond what the arm can take [N, N m].
constexpr double kMaxWrenchForce = 10000.0, kMaxWrenchMoment = 1000.0;
// [kg]: a scaled link's mass, as a robot file's masses.
constexpr double kMaxLinkMass = 1000.0;
// [m]: a wrench's point of application in its link's frame, as a robot file's lengths.
constexpr double kMaxWrenchPoint = 10.0;
// [us]: a second of latency is a thousand cycles, every command late.
constexpr double kMaxLatencyUs = 1e6;

std::string number_text(double value) {
  std::string text = std::to_string(value);
  text.erase(text.find_last_not_of('0') + 1);
  if (text.back() == '.') text.pop_back();
  return text;
}

// A non-negative number, or each of 7, of at most `max`; `why` says where the bound comes from.
double at_most(const Field& f, double max, const std::string& unit, const std::string& why) {
  const double v = non_negative(f);
  if (v > max) f.fail("a number from 0 to " + number_text(max) + " " + unit + " (" + why + ")");
  return v;
}
Vector7 at_most7(const Field& f, double max, const std::string& unit, const std::string& why) {
  const Vector7 v = non_negative7(f);
  if ((v.array() > max).any()) f.fail("7 numbers from 0 to " + number_text(max) + " " + unit + " (" + why + ")");
  return v;
}

// A vector of at most `max` in magnitude.
Vector3 bounded3(const Field& f, double max, const std::string& unit) {
  const Vector3 v = f.vector<3>();
  if (v.norm() > max) f.fail("3 numbers of magnitude at most " + number_text(max) + " " + unit);
  return v;
}

Vector6 non_negative6(const Field& f) {
  const Vector6 v = f.vector<6>();
  if ((v.array() < 0.0).any()) f.fail("6 non-negative numbers");
  return v;
}

// plant / robot_model: which named sets of the robot file, and the load.
ModelOptions model_options(const Field& f, const std::string& end_effector, const std::string& joint_limits) {
  ModelOptions options;
  options.end_effector = end_effector;
  options.joint_limits = joint_limits;
  if (f.has("inertia")) options.inertia = f["inertia"].text();
  if (f.has("friction")) options.friction = f["friction"].text();
  if (f.has("load")) options.load = flange_load(f["load"]);
  return options;
}

// plant.link_scale: {LINK: {mass: s}}, links 1..7: link LINK's mass and its rotational inertia about
// the CoM times s, the CoM kept (the same shape, s times as dense: physically consistent for any s > 0).
// A change of the arm the robot's model does not know (a heavier link, issue 13's closed loop).
void scale_links(const Field& f, ModelParameters& plant) {
  for (const std::string& key : f.keys()) {
    const Field link = f[key];
    int number = 0;
    const auto [end, error] = std::from_chars(key.data(), key.data() + key.size(), number);
    if (error != std::errc() || end != key.data() + key.size() || number < 1 || number > kNumJoints)
      link.fail("a link number from 1 to 7 as the key");
    link.allow_only({"mass"});
    const double s = positive(link["mass"]);
    RigidBodyInertia& body = plant.links[static_cast<std::size_t>(number - 1)];
    if (body.mass * s > kMaxLinkMass)
      link["mass"].fail("a factor that keeps the link's mass at most 1000 kg (a robot file's bound; the link has " +
                        number_text(body.mass) + " kg)");
    body.mass *= s;
    body.inertia *= s;
  }
}

ModelParameters build_model(const RobotConfig& robot, const ModelOptions& options, const Field& where) {
  try {
    return model_parameters(robot, options);
  } catch (const ConfigError& e) {
    where.fail(std::string("set names the robot file has; ") + e.what());
  }
}

// A joint log file named by `f`, found relative to the scenario, as the reference it plays.
std::shared_ptr<const JointLogReference> read_joint_log_reference(const Field& f) {
  const std::filesystem::path file = f.text();
  const std::string path = (file.is_absolute() ? file : std::filesystem::path(f.file()).parent_path() / file).string();
  try {
    return std::make_shared<JointLogReference>(read_joint_log_csv(path));
  } catch (const JointLogError& e) {
    f.fail("a joint log (docs/joint-log.md), relative to this scenario: " + std::string(e.what()));
  }
}

// controller.trajectory: a ramped sine, or {file: F}, a joint log found relative to the scenario
// that must start at initial_q.
std::shared_ptr<const JointReference> read_trajectory(const Field& f, const Vector7& q_initial, const JointLimits& limits) {
  if (f.has("file")) {
    f.allow_only({"file"});
    auto reference = read_joint_log_reference(f["file"]);
    // Where the robot starts is where the file starts: a first row elsewhere is a position step.
    const Vector7 offset = (reference->first_q() - q_initial).cwiseAbs();
    Eigen::Index joint = 0;
    if (offset.maxCoeff(&joint) > kTrajectoryStartTolerance)
      f["file"].fail("a trajectory whose first row is initial_q (joint " + std::to_string(joint + 1) + " starts " +
                     std::to_string(offset[joint]) + " rad away)");
    return reference;
  }
  f.allow_only({"amplitude", "frequency_hz", "phase", "ramp", "file"});
  auto trajectory = std::make_shared<RampedSineReference>();
  // A sine wider than its joint's range can only run into the limit; one at or above the loop's
  // Nyquist frequency is not the sine the 1 kHz loop samples.
  trajectory->amplitude = non_negative7(f["amplitude"]);
  for (int i = 0; i < kNumJoints; ++i)
    if (trajectory->amplitude[i] > limits.q_max[i] - limits.q_min[i])
      f["amplitude"].fail("amplitudes within each joint's range (joint " + std::to_string(i + 1) + ": " +
                          number_text(limits.q_max[i] - limits.q_min[i]) + " rad)");
  trajectory->frequency_hz = non_negative7(f["frequency_hz"]);
  if ((trajectory->frequency_hz.array() >= kLoopNyquistHz).any())
    f["frequency_hz"].fail("frequencies below 500 Hz (the 1 kHz loop's Nyquist frequency)");
  if (f.has("phase")) {
    trajectory->phase = f["phase"].vector<7>();
    if ((trajectory->phase.array().abs() > 2.0 * M_PI).any()) f["phase"].fail("angles within +-2 pi rad");
  }
  if (f.has("ramp")) trajectory->ramp = at_most(f["ramp"], kMaxDuration, "s", "a year");
  return trajectory;
}

// controller.path: the planned scan path must start where the scan does, at the scene task's start
// with the probe along its tool axis (the robot model's forward kinematics of the first row).
void check_scan_path(const Field& f, const JointLogReference& path, const ModelParameters& robot, const Scene& scene) {
  const auto* scan = std::get_if<UltrasoundScan>(&scene.task);
  if (!scan) f.fail("no `path` on the scene " + scene.path + ": its task is not an ultrasound_scan");
  const Model model(robot);
  Data data;
  forward_kinematics(model, data, path.first_q());
  const Transform& tcp = frame_pose(data, Frame::kEndEffector);
  const double offset = (tcp.translation - scan->start).norm();
  const double angle = std::acos(std::clamp(tcp.rotation.col(2).dot(scan->tool_axis.normalized()), -1.0, 1.0));
  if (offset > kScanPathStartTolerance || angle > kScanPathAxisTolerance)
    f.fail("a path whose first pose is the scan's start of " + scene.path + " (within " +
           std::to_string(kScanPathStartTolerance) + " m, tool axis within " + std::to_string(kScanPathAxisTolerance) +
           " rad; its TCP is " + std::to_string(offset) + " m and " + std::to_string(angle) + " rad away)");
}

// The medical controllers' keys (docs/medical.md); each only for the controller that uses it.
void read_medical_controller(const Field& f, const std::string& type, MedicalControllerSpec& m) {
  const auto only = [&](const char* key, const char* owner) {
    if (f.has(key) && type != owner) f[key].fail(std::string("no `") + key + "` for a " + type + " controller (" + owner + " has it)");
    return f.has(key);
  };
  if (only("desired_force", "cartesian_impedance_force")) m.desired_force = non_negative(f["desired_force"]);
  if (only("force_k_p", "cartesian_impedance_force")) m.force_k_p = non_negative(f["force_k_p"]);
  if (only("force_k_i", "cartesian_impedance_force")) m.force_k_i = non_negative(f["force_k_i"]);
  if (only("force_integral_limit", "cartesian_impedance_force")) m.force_integral_limit = non_negative(f["force_integral_limit"]);
  if (only("force_ramp", "cartesian_impedance_force")) m.force_ramp = positive(f["force_ramp"]);
  if (only("axis_damping", "cartesian_impedance_force")) m.axis_damping = non_negative(f["axis_damping"]);
  if (only("settle", "cartesian_impedance_force")) m.settle = non_negative(f["settle"]);
  if (only("path", "cartesian_impedance_force")) m.path = read_joint_log_reference(f["path"]);
  if (only("null_space_stiffness", "cartesian_impedance_force")) {
    if (!m.path) f["null_space_stiffness"].fail("a `path` too (its joints are the null space's posture)");
    m.null_space_stiffness = non_negative(f["null_space_stiffness"]);
  }
  if (only("insertion", "rcm")) m.insertion = positive(f["insertion"]);
  if (only("insertion_time", "rcm")) m.insertion_time = positive(f["insertion_time"]);
  if (only("pivot_amplitude", "rcm")) m.pivot_amplitude = non_negative(f["pivot_amplitude"]);
  if (only("pivot_frequency_hz", "rcm")) m.pivot_frequency_hz = non_negative(f["pivot_frequency_hz"]);
  if (only("rcm_stiffness", "rcm")) m.rcm_stiffness = non_negative(f["rcm_stiffness"]);
  if (only("feed_rate", "drilling")) m.feed_rate = positive(f["feed_rate"]);
  if (only("approach_speed", "drilling")) m.approach_speed = positive(f["approach_speed"]);
  if (only("axial_stiffness", "drilling")) m.axial_stiffness = positive(f["axial_stiffness"]);
  if (only("max_thrust", "drilling")) m.max_thrust = positive(f["max_thrust"]);
  if (only("breakthrough_detection", "drilling")) m.breakthrough_detection = f["breakthrough_detection"].boolean();
  if (only("breakthrough", "drilling")) {
    const Field b = f["breakthrough"];
    b.allow_only({"engaged_thrust", "drop_ratio", "jump_ratio"});
    if (b.has("engaged_thrust")) m.breakthrough.engaged_thrust = positive(b["engaged_thrust"]);
    if (b.has("drop_ratio")) m.breakthrough.drop_ratio = positive(b["drop_ratio"]);
    if (b.has("jump_ratio")) m.breakthrough.jump_ratio = positive(b["jump_ratio"]);
    if (m.breakthrough.drop_ratio >= 1.0) b["drop_ratio"].fail("a ratio below 1 (of the peak thrust)");
  }
}

// The obstacle a tissue law takes over from the scene contact (with the tool's working end).
std::string tissue_obstacle(const Field& name, const Scene& scene) {
  const std::string obstacle = name.text();
  if (scene.obstacle_index(obstacle) < 0) name.fail("the name of an obstacle of the scene " + scene.path);
  if (tool_tip_capsule(scene.tool) < 0) name.fail("a scene whose tool has capsules (its working end)");
  return obstacle;
}

// A tissue law's construction error (the scene's task does not fit it) as the section's error.
template <typename Law, typename Settings>
std::shared_ptr<Law> make_tissue(const Field& f, const Scene& scene, const Settings& settings) {
  try {
    return std::make_shared<Law>(scene, settings);
  } catch (const std::invalid_argument& e) {
    f.fail(e.what());
  }
}

// tissue: the bone layer under the scene's burr hole and the trocar ring at its port, contact
// elements of the scene's contact engine, each replacing the scene contact of its `obstacle` with
// the tool's working end.
void read_tissue(const Field& top, Scenario& s) {
  const Field f = top["tissue"];
  if (!s.emulator.scene) f.fail("a scene (`scene:`): the tissue sits at the scene's task");
  const Scene& scene = *s.emulator.scene;
  f.allow_only({"bone", "trocar"});
  if (f.has("bone")) {
    const Field b = f["bone"];
    b.allow_only({"obstacle", "thickness", "stiffness", "dissipation", "threshold_thrust", "removal_rate",
                  "point_height", "soft_stiffness"});
    BoneLayerSettings bone;
    if (b.has("thickness")) bone.thickness = positive(b["thickness"]);
    if (b.has("stiffness")) bone.stiffness = positive(b["stiffness"]);
    if (b.has("dissipation")) bone.dissipation = non_negative(b["dissipation"]);
    if (b.has("threshold_thrust")) bone.threshold_thrust = non_negative(b["threshold_thrust"]);
    if (b.has("removal_rate")) bone.removal_rate = positive(b["removal_rate"]);
    if (b.has("point_height")) bone.point_height = positive(b["point_height"]);
    if (b.has("soft_stiffness")) bone.soft_stiffness = non_negative(b["soft_stiffness"]);
    const std::string obstacle = tissue_obstacle(b["obstacle"], scene);
    auto law = make_tissue<BoneUnderBurr>(b, scene, bone);
    s.bone = law;
    s.emulator.tissue.push_back({law, obstacle});
  }
  if (f.has("trocar")) {
    const Field t = f["trocar"];
    t.allow_only({"obstacle", "stiffness", "damping", "port_axis"});
    TrocarSettings trocar;
    const std::string obstacle = tissue_obstacle(t["obstacle"], scene);
    if (t.has("stiffness")) trocar.stiffness = positive(t["stiffness"]);
    if (t.has("damping")) trocar.damping = non_negative(t["damping"]);
    if (t.has("port_axis")) {
      trocar.port_axis = t["port_axis"].vector<3>();
      if (trocar.port_axis.norm() < 1e-9) t["port_axis"].fail("a non-zero vector");
    }
    auto law = make_tissue<TrocarRing>(t, scene, trocar);
    s.trocar = law;
    s.emulator.tissue.push_back({law, obstacle});
  }
}

void read_controller(const Field& f, const Vector7& q_initial, const JointLimits& limits, ControllerSpec& c) {
  f.allow_only({"type", "stiffness", "damping", "feedforward", "translational_stiffness", "rotational_stiffness",
                "trajectory", "desired_force", "force_k_p", "force_k_i", "force_integral_limit", "force_ramp",
                "axis_damping", "settle", "path", "null_space_stiffness", "insertion", "insertion_time",
                "pivot_amplitude", "pivot_frequency_hz", "rcm_stiffness", "feed_rate", "approach_speed",
                "axial_stiffness", "max_thrust", "breakthrough_detection", "breakthrough"});
  c.type = f["type"].text();
  if (c.type != "float" && c.type != "joint_impedance" && c.type != "joint_position" &&
      c.type != "joint_velocity" && c.type != "cartesian_impedance" && !is_medical_controller(c.type))
    f["type"].fail("float, joint_impedance, joint_position, joint_velocity, cartesian_impedance, "
                   "cartesian_impedance_force, rcm or drilling");
  read_medical_controller(f, c.type, c.medical);
  if (f.has("stiffness")) c.stiffness = at_most7(f["stiffness"], kMaxJointStiffness, "N m/rad", "setJointImpedance's bound");
  if (f.has("damping")) c.damping = at_most7(f["damping"], kMaxJointDamping, "N m s/rad", "above critical damping of the stiffest joint");
  if (f.has("feedforward")) c.feedforward = f["feedforward"].boolean();
  if (f.has("translational_stiffness"))
    c.translational_stiffness = at_most(f["translational_stiffness"], kMaxTranslationalStiffness, "N/m", "setCartesianImpedance's bound");
  if (f.has("rotational_stiffness"))
    c.rotational_stiffness = at_most(f["rotational_stiffness"], kMaxRotationalStiffness, "N m/rad", "setCartesianImpedance's bound");
  if (f.has("trajectory")) {
    if (c.type == "float" || c.type == "cartesian_impedance" || is_medical_controller(c.type))
      f["trajectory"].fail("no trajectory for a " + c.type + " controller (joint_impedance, joint_position and "
                           "joint_velocity track one)");
    c.trajectory = read_trajectory(f["trajectory"], q_initial, limits);
  }
  if (c.type == "joint_impedance" && !f.has("stiffness")) f.fail("`stiffness` for a joint_impedance controller");
}

void read_robot_settings(const Field& f, EmulatorSettings& s) {
  f.allow_only({"substeps", "torque_loop_bandwidth_hz", "tau_ext_cutoff_hz", "power_limit", "gravity_compensation",
                "tau_J_noise", "tau_J_bias", "joint_impedance", "collision_behavior"});
  if (f.has("substeps")) {
    s.substeps = static_cast<int>(f["substeps"].whole_number(1, 100));
  }
  // The torque loop runs once per substep, the external torque's filter once per cycle: each below its Nyquist frequency.
  if (f.has("torque_loop_bandwidth_hz")) {
    s.torque_loop_bandwidth_hz = positive(f["torque_loop_bandwidth_hz"]);
    if (s.torque_loop_bandwidth_hz >= kLoopNyquistHz * s.substeps)
      f["torque_loop_bandwidth_hz"].fail("a bandwidth below " + number_text(kLoopNyquistHz * s.substeps) +
                                         " Hz (the Nyquist frequency of `substeps` steps per 1 ms cycle)");
  }
  if (f.has("tau_ext_cutoff_hz")) {
    s.tau_ext_cutoff_hz = positive(f["tau_ext_cutoff_hz"]);
    if (s.tau_ext_cutoff_hz >= kLoopNyquistHz) f["tau_ext_cutoff_hz"].fail("a cutoff below 500 Hz (the 1 kHz loop's Nyquist frequency)");
  }
  if (f.has("power_limit")) s.plant.joint_limits.power_max = positive(f["power_limit"]);
  if (f.has("gravity_compensation")) s.gravity_compensation = f["gravity_compensation"].boolean();
  if (f.has("tau_J_noise")) s.tau_J_noise = at_most7(f["tau_J_noise"], kMaxSensorTorque, "N m", "above every joint's torque limit");
  if (f.has("tau_J_bias")) {
    s.tau_J_bias = f["tau_J_bias"].vector<7>();
    if ((s.tau_J_bias.array().abs() > kMaxSensorTorque).any())
      f["tau_J_bias"].fail("7 numbers within +-100 N m (above every joint's torque limit)");
  }
  if (f.has("joint_impedance")) {
    s.joint_stiffness = non_negative7(f["joint_impedance"]);
    if ((s.joint_stiffness.array() > 10000.0).any()) f["joint_impedance"].fail("stiffnesses of at most 10000 N m/rad (setJointImpedance's bound)");
  }
  if (f.has("collision_behavior")) {
    // libfranka's four-argument setCollisionBehavior: the same thresholds while accelerating and nominal.
    const Field c = f["collision_behavior"];
    c.allow_only({"lower_torque", "upper_torque", "lower_force", "upper_force"});
    CollisionBehavior& b = s.collision;
    b.lower_torque_acceleration = b.lower_torque_nominal = non_negative7(c["lower_torque"]);
    b.upper_torque_acceleration = b.upper_torque_nominal = non_negative7(c["upper_torque"]);
    b.lower_force_acceleration = b.lower_force_nominal = non_negative6(c["lower_force"]);
    b.upper_force_acceleration = b.upper_force_nominal = non_negative6(c["upper_force"]);
    if ((b.lower_torque_nominal.array() > b.upper_torque_nominal.array()).any())
      c["lower_torque"].fail("thresholds at most upper_torque's (contact below collision)");
    if ((b.lower_force_nominal.array() > b.upper_force_nominal.array()).any())
      c["lower_force"].fail("thresholds at most upper_force's (contact below collision)");
  }
}

void read_faults(const Field& f, Scenario& scenario) {
  f.allow_only({"command_loss_probability", "latency_us", "lost_command_bursts", "controller_throws_at",
                "controller_nan_at"});
  CommandFaults& faults = scenario.command_faults;
  if (f.has("command_loss_probability")) {
    faults.loss_probability = f["command_loss_probability"].number();
    if (faults.loss_probability < 0.0 || faults.loss_probability > 1.0)
      f["command_loss_probability"].fail("a probability from 0 to 1");
  }
  if (f.has("latency_us")) {
    const Field l = f["latency_us"];
    l.allow_only({"mean", "jitter", "budget"});
    const std::string second = "a second: a thousand cycles";
    faults.latency_mean_us = at_most(l["mean"], kMaxLatencyUs, "us", second);
    if (l.has("jitter")) faults.latency_jitter_us = at_most(l["jitter"], kMaxLatencyUs, "us", second);
    if (l.has("budget")) {
      faults.budget_us = positive(l["budget"]);
      at_most(l["budget"], kMaxLatencyUs, "us", second);
    }
  }
  if (f.has("lost_command_bursts")) {
    const Field bursts = f["lost_command_bursts"];
    for (std::size_t i = 0; i < bursts.sequence_size(); ++i) {
      const Field b = bursts[i];
      b.allow_only({"at", "count"});
      // At most a day of lost commands: a longer burst is an outage, not a fault to emulate.
      faults.bursts.push_back({non_negative(b["at"]), static_cast<int>(b["count"].whole_number(1, 86'400'000))});
    }
  }
  if (f.has("controller_throws_at")) scenario.controller_faults.throw_at = non_negative(f["controller_throws_at"]);
  if (f.has("controller_nan_at")) scenario.controller_faults.nan_at = non_negative(f["controller_nan_at"]);
}

ExternalWrench read_wrench(const Field& f) {
  f.allow_only({"link", "point", "force", "moment", "start", "end", "ramp"});
  ExternalWrench w;
  w.link = static_cast<int>(f["link"].whole_number(1, kNumJoints));
  if (f.has("point")) w.point = bounded3(f["point"], kMaxWrenchPoint, "m");
  if (f.has("force")) w.force = bounded3(f["force"], kMaxWrenchForce, "N");
  if (f.has("moment")) w.moment = bounded3(f["moment"], kMaxWrenchMoment, "N m");
  w.start = non_negative(f["start"]);
  w.end = f["end"].number();
  if (w.end <= w.start) f["end"].fail("a time after `start`");
  if (f.has("ramp")) w.ramp = at_most(f["ramp"], kMaxDuration, "s", "a year");
  return w;
}

// scene: a scene file (configs/scenes, relative to this scenario) whose tool the arm carries and
// whose obstacles it touches (docs/contact.md); contact: the options of the contact engine.
void read_scene(const Field& top, EmulatorSettings& s) {
  if (top.has("end_effector") && top["end_effector"].text() != "none")
    top["end_effector"].fail("none (or no end_effector) with a `scene`: the scene's tool is the end effector");
  const std::filesystem::path file = top["scene"].text();
  const std::string path = (file.is_absolute() ? file : std::filesystem::path(top.file()).parent_path() / file).string();
  if (!std::filesystem::is_regular_file(path))
    top["scene"].fail("the path of a scene file, relative to this scenario (`" + path + "` is not a readable file)");
  auto scene = std::make_shared<Scene>(load_scene(path));
  s.plant = with_tool(s.plant, scene->tool);
  s.internal = with_tool(s.internal, scene->tool);
  if (top.has("contact")) {
    const Field c = top["contact"];
    c.allow_only({"friction_velocity", "max_substeps"});
    if (c.has("friction_velocity")) s.contact.friction_velocity = positive(c["friction_velocity"]);
    if (c.has("max_substeps")) s.contact.max_substeps = static_cast<int>(c["max_substeps"].whole_number(1, 1000));
  }
  s.scene = std::move(scene);
}

}  // namespace

void quintic_ramp(double t, double duration, double& r, double& dr, double& ddr) {
  // r(x) = 10x^3 - 15x^4 + 6x^5, x = t / duration: r, r', r'' vanish at both ends but r(1) = 1.
  r = 1.0, dr = 0.0, ddr = 0.0;
  if (duration > 0.0 && t < duration) {
    const double x = t / duration;
    r = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
    dr = 30.0 * x * x * (1.0 - 2.0 * x + x * x) / duration;
    ddr = 60.0 * x * (1.0 - 3.0 * x + 2.0 * x * x) / (duration * duration);
  }
}

void RampedSineReference::evaluate(const Vector7& q0, double t, Vector7& q, Vector7& dq, Vector7& ddq) const {
  double r, dr, ddr;
  quintic_ramp(t, ramp, r, dr, ddr);
  for (int i = 0; i < kNumJoints; ++i) {
    const double w = 2.0 * M_PI * frequency_hz[i];
    const double s = amplitude[i] * (std::sin(w * t + phase[i]) - std::sin(phase[i]));
    const double ds = amplitude[i] * w * std::cos(w * t + phase[i]);
    const double dds = -amplitude[i] * w * w * std::sin(w * t + phase[i]);
    q[i] = q0[i] + r * s;
    dq[i] = dr * s + r * ds;
    ddq[i] = ddr * s + 2.0 * dr * ds + r * dds;
  }
}

JointLogReference::JointLogReference(const JointLog& log) : t_(log.t), q_(log.q), dq_(log.dq), ddq_(log.ddq) {
  if (ddq_.size() != t_.size()) {
    ddq_.assign(t_.size(), Vector7::Zero());
    for (std::size_t k = 0; k < t_.size(); ++k) {
      const std::size_t a = k == 0 ? 0 : k - 1, b = std::min(k + 1, t_.size() - 1);
      ddq_[k] = (dq_[b] - dq_[a]) / (t_[b] - t_[a]);
    }
  }
}

void JointLogReference::evaluate(const Vector7&, double t, Vector7& q, Vector7& dq, Vector7& ddq) const {
  const double time = t_.front() + t;
  if (time >= t_.back()) {   // held at the last position, at rest
    q = q_.back();
    dq.setZero();
    ddq.setZero();
    return;
  }
  // The row k with t_k <= time < t_k+1 (before the first row: the first).
  const auto next = std::upper_bound(t_.begin(), t_.end(), time);
  const std::size_t k = next == t_.begin() ? 0 : static_cast<std::size_t>(next - t_.begin()) - 1;
  const double s = std::clamp((time - t_[k]) / (t_[k + 1] - t_[k]), 0.0, 1.0);
  q = q_[k] + s * (q_[k + 1] - q_[k]);
  dq = dq_[k] + s * (dq_[k + 1] - dq_[k]);
  ddq = ddq_[k] + s * (ddq_[k + 1] - ddq_[k]);
}

Scenario load_scenario(const std::string& path) {
  const YAML::Node root = load_yaml_file(path, "scenario file");
  const Field top(root, path, "");
  top.allow_only({"name", "robot", "end_effector", "joint_limits", "plant", "robot_model", "initial_q", "duration",
                  "clock", "seed", "robot_settings", "controller", "faults", "external_wrenches",
                  "hand", "vacuum_gripper", "scene", "contact", "tissue"});
  Scenario s;
  s.path = path;
  s.name = top["name"].text();

  // The robot file is found relative to the scenario file.
  const std::filesystem::path robot = top["robot"].text();
  s.robot_file = (robot.is_absolute() ? robot : std::filesystem::path(path).parent_path() / robot).string();
  // A robot file that is not there is this file's error; errors inside it name the robot file.
  if (!std::filesystem::is_regular_file(s.robot_file))
    top["robot"].fail("the path of a robot file, relative to this scenario (`" + s.robot_file + "` is not a readable file)");
  const RobotConfig config = load_robot_config(s.robot_file);
  const std::string end_effector = top.has("end_effector") ? top["end_effector"].text() : "none";
  s.end_effector = end_effector;
  s.has_hand = end_effector == "hand";
  const std::string joint_limits = top.has("joint_limits") ? top["joint_limits"].text() : "";

  const Field plant = top["plant"];
  plant.allow_only({"inertia", "friction", "load", "armature", "link_scale"});
  const ModelOptions plant_options = model_options(plant, end_effector, joint_limits);
  s.emulator.plant = build_model(config, plant_options, plant);
  if (!s.emulator.plant.physically_consistent) plant["inertia"].fail("a physically consistent inertial set for the plant");
  if (plant.has("link_scale")) scale_links(plant["link_scale"], s.emulator.plant);
  // The robot file's armature unless the scenario names another (every number carries its source).
  s.emulator.plant.armature = (plant.has("armature") ? read_armature(plant["armature"]) : config.armature).values;

  // The robot's own model: the plant's sets unless named; it is told the plant's load unless told otherwise.
  ModelOptions internal_options = plant_options;
  internal_options.friction = "none";
  if (top.has("robot_model")) {
    const Field internal = top["robot_model"];
    internal.allow_only({"inertia", "load"});
    if (internal.has("inertia")) internal_options.inertia = internal["inertia"].text();
    if (internal.has("load")) internal_options.load = flange_load(internal["load"]);
    s.emulator.internal = build_model(config, internal_options, internal);
  } else {
    s.emulator.internal = build_model(config, internal_options, top);
  }

  if (top.has("scene")) read_scene(top, s.emulator);
  else if (top.has("contact")) top["contact"].fail("no contact options without a `scene` to touch");

  s.emulator.q_initial = top["initial_q"].vector<7>();
  const JointLimits& limits = s.emulator.plant.joint_limits;
  for (int i = 0; i < kNumJoints; ++i)
    if (s.emulator.q_initial[i] <= limits.q_min[i] || s.emulator.q_initial[i] >= limits.q_max[i])
      top["initial_q"].fail("a pose inside the joint limits (joint " + std::to_string(i + 1) + " is not)");

  s.duration = positive(top["duration"]);
  if (s.duration > kMaxDuration) top["duration"].fail("at most " + std::to_string(static_cast<int64_t>(kMaxDuration)) + " s (a year)");
  if (top.has("clock")) {
    const std::string clock = top["clock"].text();
    if (clock != "lockstep" && clock != "realtime") top["clock"].fail("lockstep or realtime");
    s.clock = clock == "lockstep" ? Clock::kLockstep : Clock::kRealtime;
  }
  if (top.has("seed")) {
    // Up to 2^53: every such seed is exact in a YAML number read as double.
    s.seed = static_cast<uint64_t>(top["seed"].whole_number(0, int64_t{1} << 53));
  }
  if (top.has("robot_settings")) read_robot_settings(top["robot_settings"], s.emulator);
  read_controller(top["controller"], s.emulator.q_initial, limits, s.controller);
  const std::shared_ptr<const Scene>& scene = s.emulator.scene;
  s.controller.medical.scene = scene;
  if (is_medical_controller(s.controller.type) && !scene)
    top["controller"]["type"].fail("a scene (`scene:`) for a " + s.controller.type + " controller: it follows the scene's task");
  if (s.controller.medical.path)
    check_scan_path(top["controller"]["path"], *s.controller.medical.path, s.emulator.internal, *scene);
  if (s.controller.type == "drilling" && !top["controller"].has("feed_rate"))
    if (const auto* hole = std::get_if<BurrHole>(&scene->task)) s.controller.medical.feed_rate = hole->speed;
  if (top.has("tissue")) read_tissue(top, s);
  if (top.has("faults")) read_faults(top["faults"], s);
  if (top.has("external_wrenches")) {
    const Field wrenches = top["external_wrenches"];
    for (std::size_t i = 0; i < wrenches.sequence_size(); ++i) s.emulator.external_wrenches.push_back(read_wrench(wrenches[i]));
  }
  if (top.has("hand")) s.hand = read_hand_settings(top["hand"]);
  if (top.has("vacuum_gripper")) {
    s.vacuum_gripper = read_vacuum_settings(top["vacuum_gripper"]);
    s.has_vacuum_gripper = true;
  }
  s.emulator.seed = s.seed;
  s.command_faults.seed = s.seed + 1;   // a stream of its own: noise settings do not shift command losses
  return s;
}

// The source tree's configs/ while it exists (the build tree's programs and tests), else the copy
// installed next to the binary holding this code (<prefix>/lib/libcsp_franka.so or <prefix>/bin/csp
// -> <prefix>/share/csp/configs), so that an installed CSP, or a Debian package installed under
// another prefix than the build's, finds its scenarios without the sources.
std::string shipped_config_dir() {
  if (const char* dir = std::getenv("CSP_CONFIG_DIR"); dir != nullptr && *dir != '\0') return dir;
  std::error_code error;
  const std::filesystem::path source = std::filesystem::path(CSP_SOURCE_DIR) / "configs";
  if (std::filesystem::is_directory(source, error)) return source.string();
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&shipped_config_dir), &info) != 0 && info.dli_fname != nullptr) {
    const std::filesystem::path installed =
        std::filesystem::path(info.dli_fname).parent_path().parent_path() / "share" / "csp" / "configs";
    if (std::filesystem::is_directory(installed, error)) return installed.string();
  }
  return CSP_INSTALLED_CONFIG_DIR;
}

std::string shipped_scenario_path(const std::string& name) {
  return shipped_config_dir() + "/scenarios/" + name + ".yaml";
}

std::string default_scenario_path() { return shipped_scenario_path("default"); }

}  // namespace csp::rt
