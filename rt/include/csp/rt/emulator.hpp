// The emulated robot: one Franka Control Interface cycle per step(), at 1 kHz. Stages run in a
// fixed order each cycle (DESIGN.md; MuJoCo's mj_step is the model): command intake (reception,
// refusals, the torque or the motion generator's setpoint) -> inner torque loop and plant
// integration (substeps) -> sensors and estimators -> limit and reflex checks -> end of motion ->
// publish the RobotState. docs/emulator.md describes each stage.
//
// Two models: the plant (what the arm really is: inertia, link-side friction, armature, load,
// external wrenches) and the robot's internal model (what its firmware believes: gravity
// compensation, external torque estimate, the Model API). Making them differ is how CSP emulates
// a real robot whose model is not perfect.
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "csp/dynamics/algorithms.hpp"
#include "csp/rt/contact.hpp"
#include "csp/rt/errors.hpp"
#include "csp/rt/robot_state.hpp"

namespace csp::rt {

inline constexpr double kDeltaT = 1e-3;   // FCI cycle [s] (libfranka kDeltaT)

// What a motion commands (libfranka's Robot::control overloads): joint-level torques, or one of
// the four external motion generators.
enum class ControlMode { kTorque, kJointPosition, kJointVelocity, kCartesianPose, kCartesianVelocity };
const char* control_mode_name(ControlMode mode);
bool is_cartesian(ControlMode mode);

// Which controller of the robot turns a motion generator's setpoint into torques (libfranka
// ControllerMode, and the research interface's kExternalController): the robot's joint impedance
// (Robot::setJointImpedance), its Cartesian impedance on the stiffness frame K
// (Robot::setCartesianImpedance), or the user's torques (Robot::control(torque_cb, motion_cb):
// the motion generator's setpoint is checked and published but the user's torque drives the arm).
enum class ControllerMode { kJointImpedance, kCartesianImpedance, kExternalController };
const char* controller_mode_name(ControllerMode mode);

// One cycle's command as it reaches the robot. Which fields count depends on the motion's mode:
//   kTorque             values: torques without gravity (tau_J_d) [N m]
//   kJointPosition      values: commanded joint positions q_c [rad]
//   kJointVelocity      values: commanded joint velocities dq_c [rad/s]
//   kCartesianPose      O_T_EE_c: commanded EE pose in the base frame, 4x4 column-major; elbow
//   kCartesianVelocity  O_dP_EE_c: commanded EE twist, base-frame axes about the EE origin,
//                       (m/s x3, rad/s x3); elbow
// elbow (Cartesian modes, optional as in franka::CartesianPose::hasElbow): joint 3's position
// [rad] and the sign of joint 4 relative to kElbowFlip (+1 or -1); without it the robot keeps
// joint 3 where its last commanded joint trajectory had it.
// torque: the user's torque without gravity [N m] when a motion generator runs with
// ControllerMode::kExternalController (libfranka's control(torque_cb, motion_cb)).
struct Command {
  Vector7 values = Vector7::Zero();
  bool motion_finished = false;
  std::array<double, 16> O_T_EE_c = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  std::array<double, 6> O_dP_EE_c{};
  std::optional<std::array<double, 2>> elbow = std::nullopt;
  Vector7 torque = Vector7::Zero();
};

// What reaches the robot in one cycle (the input of Emulator::step): a command; none, because it
// was lost on the network or came too late; or word that the controller failed (it threw, or
// returned a value libfranka refuses) and sends no more. The robot's command intake handles all three.
struct CycleInput {
  enum class Kind { kCommand, kLost, kControllerFailed };
  Kind kind = Kind::kLost;
  const Command* command = nullptr;   // kCommand: the command, valid during step()
  std::string_view failure;           // kControllerFailed: why (becomes reflex_reason())

  static CycleInput received(const Command& command) { return {Kind::kCommand, &command, {}}; }
  static CycleInput lost() { return {}; }
  static CycleInput controller_failed(std::string_view why) { return {Kind::kControllerFailed, nullptr, why}; }
};

// Robot::setCollisionBehavior: contact (lower) and collision (upper) thresholds on the estimated
// external joint torques [N m] and Cartesian wrench on K [N, N m], for accelerating and nominal motion.
struct CollisionBehavior {
  Vector7 lower_torque_acceleration, upper_torque_acceleration, lower_torque_nominal, upper_torque_nominal;
  Vector6 lower_force_acceleration, upper_force_acceleration, lower_force_nominal, upper_force_nominal;
};
// The values of libfranka's examples (setDefaultBehavior): 20 during acceleration, 10 nominal.
CollisionBehavior default_collision_behavior();
// From libfranka's eight arrays, in Robot::setCollisionBehavior's order, as every front end
// receives them (the franka API, LCM, the FCI).
CollisionBehavior collision_behavior(const std::array<double, 7>& lower_torque_acceleration,
                                     const std::array<double, 7>& upper_torque_acceleration,
                                     const std::array<double, 7>& lower_torque_nominal,
                                     const std::array<double, 7>& upper_torque_nominal,
                                     const std::array<double, 6>& lower_force_acceleration,
                                     const std::array<double, 6>& upper_force_acceleration,
                                     const std::array<double, 6>& lower_force_nominal,
                                     const std::array<double, 6>& upper_force_nominal);

// Robot::setJointImpedance default of libfranka's examples [N m/rad].
Vector7 default_joint_stiffness();
// Robot::setCartesianImpedance default of libfranka's examples (examples_common.cpp
// setDefaultBehavior: {3000, 3000, 3000, 300, 300, 300}) [N/m x3, N m/rad x3].
Vector6 default_cartesian_stiffness();

// A push or a contact scripted by a scenario: `force` and `moment` (base frame) act on link `link`
// (1..7) at `point` (link frame) from `start` to `end` [s], ramped in and out over `ramp` [s].
struct ExternalWrench {
  int link = 7;
  Vector3 point = Vector3::Zero();
  Vector3 force = Vector3::Zero();
  Vector3 moment = Vector3::Zero();
  double start = 0.0, end = 0.0, ramp = 0.0;
};

// A joint torque the plant's rigid-body and friction models do not have, for tests of what the
// emulator does not model (tests/gap_emulated: a torque ripple periodic in position, a friction
// with memory, a structural vibration). It acts on the links as the friction does, so the torque
// sensor feels it; it is evaluated in every integration substep at the substep's time t [s] and state, and
// tau_motor is the torque the drive transmits. It runs inside the 1 kHz loop: no allocation, no
// blocking. Empty (the default): none.
using PlantTorque = std::function<Vector7(double t, const Vector7& q, const Vector7& dq, const Vector7& tau_motor)>;

struct EmulatorSettings {
  ModelParameters plant;                 // the arm (inertia, friction, armature, load, limits, gravity)
  ModelParameters internal;              // the robot's own model (may use another inertial set)
  Vector7 q_initial = Vector7::Zero();   // the arm starts at rest here, in Idle
  int substeps = 2;                      // plant integration steps per 1 ms cycle
  double torque_loop_bandwidth_hz = 300.0;   // first-order inner torque loop
  double tau_ext_cutoff_hz = 30.0;       // low-pass of tau_ext_hat_filtered
  bool gravity_compensation = true;      // always on for a real robot; off only to test the plant
  Vector7 tau_J_noise = Vector7::Zero(); // standard deviation of the torque-sensor noise [N m]
  Vector7 tau_J_bias = Vector7::Zero();  // torque-sensor offset [N m]
  uint64_t seed = 1;                     // sensor noise
  CollisionBehavior collision = default_collision_behavior();
  Vector7 joint_stiffness = default_joint_stiffness();
  Vector6 cartesian_stiffness = default_cartesian_stiffness();   // K-frame axes x y z R P Y
  std::vector<ExternalWrench> external_wrenches;
  PlantTorque extra_joint_torque;        // off by default; no scenario key sets it
  // The environment the arm touches (docs/contact.md): the scene's obstacles with a material push
  // on the arm's and the tool's capsules, every substep. Null (the default): nothing to touch. The
  // plant and internal models should carry the scene's tool (with_tool), as load_scenario does.
  std::shared_ptr<const Scene> scene;
  ContactOptions contact;
  // Tissue laws evaluated with the scene's obstacles (a scenario's `tissue:` section; rt/medical_plant.hpp).
  // Stateful (the bone removed): one emulator per set of elements.
  std::vector<TissueElement> tissue;
};

// Cumulative counts over the emulator's life.
struct EmulatorCounters {
  uint64_t cycles = 0;
  uint64_t motion_cycles = 0;
  uint64_t lost_commands = 0;
  int max_consecutive_lost = 0;
  uint64_t reflexes = 0;
};

// A control call that must not happen now (libfranka InvalidOperationException).
class InvalidOperation : public std::logic_error {
 public:
  using std::logic_error::logic_error;
};

class Emulator {
 public:
  explicit Emulator(const EmulatorSettings& settings);

  const RobotState& state() const { return state_; }
  const Model& internal_model() const { return internal_; }
  const Model& plant_model() const { return plant_; }
  const EmulatorSettings& settings() const { return settings_; }
  const EmulatorCounters& counters() const { return counters_; }
  bool in_motion() const { return mode_.has_value(); }
  // What the scene does to the arm (settings().scene): the true contact wrench on the tool, the
  // penetration, the contacts of the last substep. Nothing in contact without a scene.
  const ContactState& contact() const { return contact_state_; }
  // Why the last reflex happened: the error names, or what the controller did wrong. Kept after
  // automatic_error_recovery(), as RobotState::last_motion_errors is; empty before any reflex.
  const std::string& reflex_reason() const { return reflex_reason_; }

  // Motions, like the FCI: start (Idle -> Move), one step per 1 ms cycle, finish (-> Idle).
  // `controller` tracks a motion generator: kJointImpedance unless given; kTorque motions always
  // use kExternalController (the user's torque), and refuse another (std::invalid_argument).
  void start_motion(ControlMode mode, std::optional<ControllerMode> controller = std::nullopt);
  std::optional<ControllerMode> controller_mode() const { return mode_ ? std::optional(controller_) : std::nullopt; }
  // One cycle. A lost command reuses the last torque or extrapolates the motion generator; 20 in
  // a row end the motion in a reflex. A non-finite command or a failed controller end it at once.
  void step(const CycleInput& input);
  // The same with the command that arrived in time, or null when none did (lost).
  void step(const Command* command) { step(command ? CycleInput::received(*command) : CycleInput::lost()); }

  // The FCI's StopMove: the motion ends now, whatever its commands say; the robot holds where the
  // arm is, its idle joint impedance bringing it to rest. InvalidOperation without a motion.
  void stop_motion();

  // Configuration between motions (Robot::set...); InvalidOperation during a motion.
  void set_collision_behavior(const CollisionBehavior& behavior);
  void set_joint_impedance(const Vector7& stiffness);
  // Robot::setCartesianImpedance: K-frame stiffness, 10..3000 N/m and 1..300 N m/rad (robot.h).
  void set_cartesian_impedance(const Vector6& stiffness);
  // What the robot is told it carries (flange frame): its model only; what the arm really
  // carries is the plant's load, set by the scenario.
  void set_load(const RigidBodyInertia& load);
  // What the arm really carries beyond the scenario's load, e.g. the object in the hand's grasp
  // (flange frame): changes the plant only (the robot's model learns of it only through setLoad,
  // as on a real robot). Allowed between any two cycles, also during a motion.
  void set_carried_object(const RigidBodyInertia& object);
  void set_EE(const Transform& NE_T_EE);
  void set_K(const Transform& EE_T_K);
  // Clears current_errors and releases the brakes (Reflex -> Idle).
  void automatic_error_recovery();

 private:
  // Idle: the robot holds q_hold with its joint impedance. Move: a motion runs. Braking: a reflex
  // decelerates the arm. Braked: standstill on closed brakes until error recovery.
  enum class Phase { kIdle, kMove, kBraking, kBraked };

  // The arm as it really moves (the plant's state).
  struct PlantState {
    Vector7 q, dq, ddq;
    Vector7 tau_J;   // the true link-side torque, before the sensor's bias and noise
  };
  // The robot's inner torque loop and the joint controllers around it.
  struct TorqueLoop {
    Vector7 tau_motor;   // motor torque, a first-order lag behind its setpoint
    Vector7 gravity;     // gravity compensation by the robot's model, g(q)
    Vector7 q_hold;      // the position Idle holds (q_d)
  };
  // The external motion generator as the robot sees it: the commanded joint trajectory and, in
  // the Cartesian modes, the commanded EE pose and elbow with their rates, from which the robot's
  // inverse kinematics makes the joint trajectory.
  struct MotionGenerator {
    Vector7 q_c, dq_c, ddq_c;
    bool first_command = true;
    Transform O_T_EE_c;
    Vector6 O_dP_EE_c, O_ddP_EE_c;
    double elbow_c = 0.0, delbow_c = 0.0, ddelbow_c = 0.0;   // joint 3 [rad, rad/s, rad/s^2]
    double elbow_sign = 1.0;                                   // of joint 4, relative to kElbowFlip
  };
  // What a joint-level check found out of bounds, as a motion generator's own error flags.
  struct JointTrajectoryErrors {
    Error position, velocity, velocity_discontinuity, acceleration_discontinuity;
  };
  // What arrived from the controller, and the robot's memory of it.
  struct CommandReception {
    Vector7 last_user_torque;      // torque mode: the last torque received (tau_J_d)
    bool finish_requested = false; // this cycle's command ends the motion (motion_finished)
    int consecutive_lost = 0;
    std::array<bool, 100> received{};   // the last 100 cycles (control_command_success_rate)
    int index = 0, count = 0, in_window = 0;

    void restart();
    void record(bool arrived);
    double success_rate() const { return count > 0 ? static_cast<double>(in_window) / count : 0.0; }
  };
  // The robot's sensors and the estimates it derives from them.
  struct Estimator {
    Vector7 tau_J_measured, tau_J_measured_previous, dtau_J, dq_previous, tau_ext_raw, tau_ext_filtered;
    Matrix6x7 jacobian;   // K frame, robot's model
    Vector6 O_F_ext, K_F_ext;
    std::mt19937_64 noise_rng;
    std::normal_distribution<double> unit_normal{0.0, 1.0};
  };

  // The stages of one cycle, in order.
  void take_command(const CycleInput& input);
  void integrate();
  void update_sensors_and_estimates();
  void check_limits_and_collisions();
  void end_motion_if_finished();
  void publish();

  // Parts of the stages.
  ErrorSet accept_torque(const Vector7* torque);   // null: the command was lost
  ErrorSet run_motion_generator(const Command* command);
  ErrorSet joint_setpoint(const Command* command, Vector7& q_c, Vector7& dq_c);
  ErrorSet cartesian_setpoint(const Command* command, Vector7& q_c, Vector7& dq_c);
  // The robot's Cartesian impedance controller, in cartesian_motion.cpp: the desired stiffness
  // frame K at the commanded joints and its critical damping, once per cycle; its torque at the
  // arm's state, every substep.
  struct CartesianImpedance {
    Transform O_T_K_d;   // the robot's model at q_c
    Vector6 O_dP_K_d;    // J_K(q_c) dq_c
    Vector6 damping;     // K-frame axes
  };
  CartesianImpedance cartesian_impedance_target(const Vector7& q_c, const Vector7& dq_c);
  Vector7 cartesian_impedance_torque(const CartesianImpedance& target, const Vector7& q_c, const Vector7& dq_c,
                                     const Vector7& joint_damping);
  // The torque loop's setpoint law for one cycle: which of the robot's controllers acts, and its
  // terms that stay fixed over the cycle's substeps.
  struct TorqueLoopTarget {
    bool impedance = false, cartesian = false, braking = false;
    Vector7 mass_diagonal, damping;   // the robot's model's at the cycle's q; critical joint damping
    Vector7 q, dq;                    // the held pose (Idle) or the motion generator's setpoint
    CartesianImpedance cartesian_impedance;
  };
  // The parts of integrate(), in order.
  void hold_on_brakes(double t, const LinkWrenches& f_ext);
  TorqueLoopTarget torque_loop_target();
  Vector7 torque_loop_setpoint(const TorqueLoopTarget& target);
  void plant_substep(double t, double h, const LinkWrenches& f_ext);
  bool stop_if_diverged(const Vector7& q_before, const LinkWrenches& f_ext);
  void close_brakes_when_stopped(bool braking);
  void gravity_compensation_torque();
  LinkWrenches external_link_wrenches(double t);
  LinkWrenches with_contact_wrenches(const LinkWrenches& scripted) const;
  void enter_reflex(const ErrorSet& errors, const std::string& reason);
  void end_motion(const Vector7& q_hold);   // Move -> Idle, holding q_hold

  void rebuild_internal_model();
  void require_no_motion(const char* operation) const;

  // Configuration and models
  EmulatorSettings settings_;
  ModelParameters internal_parameters_;   // the robot's model before setEE (setLoad and setK change it)
  Model plant_, internal_;
  Data plant_data_, internal_data_;
  Transform F_T_NE_, NE_T_EE_;   // configured end effector, and setEE on top of it

  // The robot's state machine
  std::optional<ControlMode> mode_;
  ControllerMode controller_ = ControllerMode::kJointImpedance;
  Phase phase_ = Phase::kIdle;
  std::string reflex_reason_;
  std::string motion_generator_reason_;   // why this cycle's setpoint was refused, beyond its flags
  double braking_since_ = 0.0;   // [s] when the last reflex began

  // The stages' state
  PlantState plant_state_;
  TorqueLoop torque_loop_;
  MotionGenerator motion_generator_;
  CommandReception reception_;
  Estimator estimator_;

  // The environment
  std::optional<SceneContact> contact_;
  ContactState contact_state_;

  // Outputs
  RobotState state_;
  EmulatorCounters counters_;
};

}  // namespace csp::rt
