// Scenario files (configs/scenarios/*.yaml, format in docs/emulator.md): which robot, plant and
// internal model, where the arm starts, which built-in controller runs for how long on which
// clock, and what goes wrong (lost commands, a throwing controller, pushes on the links).
// Loading validates every field and throws ConfigError naming the file, the key and what was
// expected.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "csp/rt/control_loop.hpp"
#include "csp/rt/emulator.hpp"
#include "csp/rt/hand.hpp"
#include "csp/io/joint_log.hpp"
#include "csp/io/scene.hpp"
#include "csp/rt/medical_controllers.hpp"
#include "csp/rt/medical_plant.hpp"

namespace csp::rt {

// A quintic ramp from 0 to 1 over `duration` [s] (1 after it) with its first and second time
// derivatives, all smooth: r(x) = 10x^3 - 15x^4 + 6x^5, x = t / duration; r' and r'' vanish at both ends.
void quintic_ramp(double t, double duration, double& r, double& dr, double& ddr);

// The reference a scenario's joint controller tracks: desired position, velocity and
// acceleration at motion time t [s] (t = 0 when the motion starts, from the start pose q0).
class JointReference {
 public:
  virtual ~JointReference() = default;
  virtual void evaluate(const Vector7& q0, double t, Vector7& q, Vector7& dq, Vector7& ddq) const = 0;
};

// One sine per joint around the start pose, ramped in,
// q_d = q0 + r(t) A (sin(2 pi f t + phase) - sin(phase)), r a quintic ramp from 0 to 1 over
// `ramp` seconds, so q_d starts at q0 at rest. Zero amplitude holds the start pose.
struct RampedSineReference final : JointReference {
  Vector7 amplitude = Vector7::Zero();      // [rad]
  Vector7 frequency_hz = Vector7::Zero();   // [Hz]
  Vector7 phase = Vector7::Zero();          // [rad]
  double ramp = 1.0;                        // [s]

  void evaluate(const Vector7& q0, double t, Vector7& q, Vector7& dq, Vector7& ddq) const override;
};

// A trajectory file (a joint log, docs/joint-log.md: its t, q, dq and, if present, ddq) played
// from its first row at t = 0, linearly interpolated between rows, and held at its last position
// (at rest) after its end. Without a ddq column the acceleration is the central difference of dq.
class JointLogReference final : public JointReference {
 public:
  explicit JointLogReference(const JointLog& log);   // a log as read_joint_log_csv validates it

  void evaluate(const Vector7& q0, double t, Vector7& q, Vector7& dq, Vector7& ddq) const override;
  double duration() const { return t_.back() - t_.front(); }
  const Vector7& first_q() const { return q_.front(); }

 private:
  std::vector<double> t_;
  std::vector<Vector7> q_, dq_, ddq_;
};

struct ControllerSpec {
  // float (gravity-compensated, optional joint damping), joint_impedance (torque, tracks the
  // trajectory), joint_position / joint_velocity (the robot's motion generator interface),
  // cartesian_impedance (holds the start pose of K); the medical controllers
  // cartesian_impedance_force, rcm and drilling (docs/medical.md: they follow the scene's task).
  std::string type = "float";
  Vector7 stiffness = Vector7::Zero();   // joint_impedance [N m/rad]
  Vector7 damping = Vector7::Zero();     // float, joint_impedance [N m s/rad]
  bool feedforward = true;               // joint_impedance: add M(q) ddq_d + c(q, dq)
  double translational_stiffness = 150.0, rotational_stiffness = 10.0;   // cartesian_impedance
  // joint_impedance, joint_position, joint_velocity: the reference (default: hold the start pose).
  std::shared_ptr<const JointReference> trajectory = std::make_shared<RampedSineReference>();
  MedicalControllerSpec medical;   // cartesian_impedance_force, rcm, drilling
};

// Faults of the controller itself, at motion time [s].
struct ControllerFaults {
  std::optional<double> throw_at;   // the controller throws std::runtime_error
  std::optional<double> nan_at;     // the controller returns NaN
};

// The longest run a scenario or --duration may ask for [s]: a year of 1 kHz cycles still counts
// exactly in every integer and double the loop uses.
inline constexpr double kMaxDuration = 365.0 * 86400.0;

struct Scenario {
  std::string path;
  std::string name;
  std::string robot_file;
  std::string end_effector = "none";   // a key of the robot file's end_effectors (its `end_effector:`)
  EmulatorSettings emulator;
  ControllerSpec controller;
  ControllerFaults controller_faults;
  CommandFaults command_faults;
  double duration = 10.0;   // [s], at most kMaxDuration
  Clock clock = Clock::kLockstep;
  uint64_t seed = 1;
  HandSettings hand;                   // the Franka Hand (franka::Gripper) and what it may grasp
  bool has_hand = false;               // the arm wears the hand (end_effector: hand): csp fci serves its port
  VacuumSettings vacuum_gripper;       // the Cobot Pump (franka::VacuumGripper)
  bool has_vacuum_gripper = false;     // the scenario mounts a Cobot Pump (a `vacuum_gripper:` section)
  // `tissue:` the bone under the burr and the trocar ring (docs/medical.md), already among
  // emulator.tissue: one emulator per loaded scenario (the tissue keeps its state). Null if absent.
  std::shared_ptr<const BoneUnderBurr> bone;
  std::shared_ptr<const TrocarRing> trocar;
};

Scenario load_scenario(const std::string& path);

// Where CSP's shipped configs/ (robots/, scenarios/, scenes/) are: $CSP_CONFIG_DIR if set, else the
// source tree's, else the installed copy (share/csp/configs).
std::string shipped_config_dir();
// A shipped scenario by name, e.g. "libfranka_panda" -> <configs>/scenarios/libfranka_panda.yaml.
std::string shipped_scenario_path(const std::string& name);
// The scenario the README's main command runs (configs/scenarios/default.yaml).
std::string default_scenario_path();

}  // namespace csp::rt
