#include "csp/rt/emulator.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "csp/rt/cartesian_motion.hpp"
#include "state_arrays.hpp"

namespace csp::rt {
namespace {

constexpr double kBrakingTimeConstant = 0.02;   // [s] reflex deceleration, then the brakes close
constexpr double kBrakesClosedVelocity = 5e-3;  // [rad/s] every joint slower: brakes engage
constexpr double kMaxBrakingTime = 0.5;         // [s] the brakes close at the latest after this
constexpr double kAccelerationThreshold = 0.5;  // [rad/s^2] desired |ddq| above: "acceleration" thresholds
constexpr double kWrenchDamping = 1e-2;         // damped pseudo-inverse of J^T (O_F_ext_hat_K)
constexpr int kMaxConsecutiveLost = 20;         // FCI: 20 lost commands in a row end the motion
// Configuration the robot refuses (a real Panda refuses loads and gains outside its limits and
// never integrates a NaN; these bounds are CSP's, stated in docs/emulator.md):
constexpr double kMaxPayload = 3.0;              // [kg] Franka's datasheet payload (Panda and FR3)
constexpr double kMaxLoadDistance = 1.0;         // [m] load CoM from the flange: beyond the arm's own size
constexpr double kMaxJointStiffness = 10000.0;   // [N m/rad] the joint impedance stays stable at 0.5 ms substeps
// Robot::setCartesianImpedance's ranges (libfranka robot.h): translation [10, 3000] N/m, rotation [1, 300] N m/rad.
constexpr double kMinTranslationalStiffness = 10.0, kMaxTranslationalStiffness = 3000.0;
constexpr double kMinRotationalStiffness = 1.0, kMaxRotationalStiffness = 300.0;

template <typename Vector>
bool within(const Vector& v, double low, double high) {
  return v.allFinite() && (v.array() >= low).all() && (v.array() <= high).all();
}

// Why `behavior` cannot be set, or empty: every threshold a non-negative number (infinity: never
// trips) and each lower (contact) threshold at most its upper (collision) one.
std::string collision_behavior_problem(const CollisionBehavior& b) {
  const auto pair = [](const auto& lower, const auto& upper, const char* name) -> std::string {
    if (!(lower.array() >= 0.0).all() || !(upper.array() >= 0.0).all())   // NaN fails too
      return std::string(name) + ": expected non-negative thresholds";
    if ((lower.array() > upper.array()).any()) return std::string(name) + ": expected each lower threshold <= its upper one";
    return {};
  };
  for (const std::string& problem :
       {pair(b.lower_torque_acceleration, b.upper_torque_acceleration, "torque thresholds (acceleration)"),
        pair(b.lower_torque_nominal, b.upper_torque_nominal, "torque thresholds (nominal)"),
        pair(b.lower_force_acceleration, b.upper_force_acceleration, "force thresholds (acceleration)"),
        pair(b.lower_force_nominal, b.upper_force_nominal, "force thresholds (nominal)")})
    if (!problem.empty()) return problem;
  return {};
}

std::string joint_stiffness_problem(const Vector7& stiffness) {
  return within(stiffness, 0.0, kMaxJointStiffness) ? "" : "expected 7 finite stiffnesses from 0 to 10000 N m/rad";
}

std::string cartesian_stiffness_problem(const Vector6& stiffness) {
  if (!within(stiffness.head<3>(), kMinTranslationalStiffness, kMaxTranslationalStiffness))
    return "expected translational stiffnesses (x, y, z) from 10 to 3000 N/m";
  if (!within(stiffness.tail<3>(), kMinRotationalStiffness, kMaxRotationalStiffness))
    return "expected rotational stiffnesses (R, P, Y) from 1 to 300 N m/rad";
  return {};
}

std::string load_problem(const RigidBodyInertia& load) {
  if (!(load.mass >= 0.0 && load.mass <= kMaxPayload)) return "expected a mass from 0 to 3 kg (the robot's payload)";
  if (!load.com.allFinite() || load.com.norm() > kMaxLoadDistance) return "expected a centre of mass within 1 m of the flange";
  if (!load.inertia.allFinite()) return "expected a finite inertia";
  if (load.inertia.isZero() || load.mass == 0.0) return {};   // a point mass, or nothing
  if (!is_physical_inertia(load.inertia) ||
      Eigen::SelfAdjointEigenSolver<Matrix3>(load.inertia, Eigen::EigenvaluesOnly).eigenvalues().maxCoeff() >
          load.mass * kMaxLoadDistance * kMaxLoadDistance)
    return "expected a physical inertia about the CoM (positive definite, triangle inequality, at most mass x 1 m^2)";
  return {};
}

std::string transform_problem(const Transform& t) {
  if (!t.rotation.allFinite() || !t.translation.allFinite()) return "expected a finite transform";
  if (!(t.rotation.transpose() * t.rotation).isApprox(Matrix3::Identity(), 1e-6) || t.rotation.determinant() < 0.0)
    return "expected a rotation (orthonormal, determinant 1)";
  if (t.translation.norm() > kMaxLoadDistance) return "expected a translation within 1 m";
  return {};
}

void require(const std::string& problem, const char* operation) {
  if (!problem.empty()) throw std::invalid_argument(std::string(operation) + ": " + problem);
}

// First-order low-pass factor for a step of dt at cutoff f (exact for a constant input).
double lowpass_factor(double cutoff_hz, double dt) { return 1.0 - std::exp(-2.0 * M_PI * cutoff_hz * dt); }

}  // namespace

const char* control_mode_name(ControlMode mode) {
  switch (mode) {
    case ControlMode::kTorque: return "torque";
    case ControlMode::kJointPosition: return "joint_position";
    case ControlMode::kJointVelocity: return "joint_velocity";
    case ControlMode::kCartesianPose: return "cartesian_pose";
    case ControlMode::kCartesianVelocity: return "cartesian_velocity";
  }
  return "unknown";
}

bool is_cartesian(ControlMode mode) { return mode == ControlMode::kCartesianPose || mode == ControlMode::kCartesianVelocity; }

const char* controller_mode_name(ControllerMode mode) {
  switch (mode) {
    case ControllerMode::kJointImpedance: return "joint_impedance";
    case ControllerMode::kCartesianImpedance: return "cartesian_impedance";
    case ControllerMode::kExternalController: return "external_controller";
  }
  return "unknown";
}

CollisionBehavior collision_behavior(const std::array<double, 7>& lower_torque_acceleration,
                                     const std::array<double, 7>& upper_torque_acceleration,
                                     const std::array<double, 7>& lower_torque_nominal,
                                     const std::array<double, 7>& upper_torque_nominal,
                                     const std::array<double, 6>& lower_force_acceleration,
                                     const std::array<double, 6>& upper_force_acceleration,
                                     const std::array<double, 6>& lower_force_nominal,
                                     const std::array<double, 6>& upper_force_nominal) {
  CollisionBehavior b;
  b.lower_torque_acceleration = from_array<Vector7>(lower_torque_acceleration);
  b.upper_torque_acceleration = from_array<Vector7>(upper_torque_acceleration);
  b.lower_torque_nominal = from_array<Vector7>(lower_torque_nominal);
  b.upper_torque_nominal = from_array<Vector7>(upper_torque_nominal);
  b.lower_force_acceleration = from_array<Vector6>(lower_force_acceleration);
  b.upper_force_acceleration = from_array<Vector6>(upper_force_acceleration);
  b.lower_force_nominal = from_array<Vector6>(lower_force_nominal);
  b.upper_force_nominal = from_array<Vector6>(upper_force_nominal);
  return b;
}

CollisionBehavior default_collision_behavior() {
  CollisionBehavior b;
  b.lower_torque_acceleration = b.upper_torque_acceleration = Vector7::Constant(20.0);
  b.lower_torque_nominal = b.upper_torque_nominal = Vector7::Constant(10.0);
  b.lower_force_acceleration = b.upper_force_acceleration = Vector6::Constant(20.0);
  b.lower_force_nominal = b.upper_force_nominal = Vector6::Constant(10.0);
  return b;
}

Vector7 default_joint_stiffness() { return (Vector7() << 3000, 3000, 3000, 2500, 2500, 2000, 2000).finished(); }

Vector6 default_cartesian_stiffness() { return (Vector6() << 3000, 3000, 3000, 300, 300, 300).finished(); }

namespace {
template <typename Values>
bool all_finite(const Values& values) {
  return std::all_of(std::begin(values), std::end(values), [](double v) { return std::isfinite(v); });
}

// Why the robot refuses a command that is not finite (reflex_reason()), or empty: every value the
// motion's mode and controller read must be a number. (Only a refusal builds a message: no
// allocation in a normal cycle.)
std::string not_finite_reason(ControlMode mode, ControllerMode controller, const Command& command) {
  const bool pose = mode == ControlMode::kCartesianPose && !all_finite(command.O_T_EE_c);
  const bool twist = mode == ControlMode::kCartesianVelocity && !all_finite(command.O_dP_EE_c);
  const bool elbow = is_cartesian(mode) && command.elbow && !all_finite(*command.elbow);
  const bool values = !is_cartesian(mode) && !command.values.allFinite();
  const bool torque =
      mode != ControlMode::kTorque && controller == ControllerMode::kExternalController && !command.torque.allFinite();
  if (!pose && !twist && !elbow && !values && !torque) return {};
  std::ostringstream what;
  what << "the " << control_mode_name(mode) << " command is not finite (";
  if (pose) what << "O_T_EE_c " << from_array<Eigen::Matrix4d>(command.O_T_EE_c).reshaped().transpose();
  else if (twist) what << "O_dP_EE_c " << from_array<Vector6>(command.O_dP_EE_c).transpose();
  else if (elbow) what << "elbow " << (*command.elbow)[0] << " " << (*command.elbow)[1];
  else if (values) what << command.values.transpose();
  else what << "torque " << command.torque.transpose();
  what << ")";
  return what.str();
}
}  // namespace

Emulator::Emulator(const EmulatorSettings& settings)
    : settings_(settings),
      internal_parameters_(settings.internal),
      plant_(settings.plant),
      internal_(settings.internal) {
  if (settings_.substeps < 1) throw std::invalid_argument("substeps: expected at least 1");
  require(collision_behavior_problem(settings_.collision), "collision behavior");
  require(joint_stiffness_problem(settings_.joint_stiffness), "joint impedance");
  require(cartesian_stiffness_problem(settings_.cartesian_stiffness), "Cartesian impedance");
  F_T_NE_ = internal_parameters_.F_T_EE;
  PlantState& arm = plant_state_;
  arm.q = settings_.q_initial;
  if (settings_.scene) {
    contact_.emplace(settings_.scene, settings_.contact, settings_.tissue);
    contact_state_ = contact_->initial_state();
    contact_->require_clear(plant_, plant_data_, arm.q);
  }
  contact_state_.substeps = settings_.substeps;
  arm.dq.setZero();
  arm.ddq.setZero();
  torque_loop_.q_hold = arm.q;
  gravity_compensation_torque();
  torque_loop_.tau_motor = torque_loop_.gravity;
  arm.tau_J = torque_loop_.tau_motor;
  motion_generator_.q_c = arm.q;
  motion_generator_.dq_c.setZero();
  motion_generator_.ddq_c.setZero();
  reception_.restart();
  Estimator& e = estimator_;
  e.noise_rng.seed(settings_.seed);
  e.dq_previous.setZero();
  e.tau_J_measured_previous = arm.tau_J + settings_.tau_J_bias;   // dtau_J = 0 at rest
  e.tau_ext_filtered.setZero();
  state_.robot_mode = RobotMode::kIdle;
  update_sensors_and_estimates();
  e.tau_ext_filtered = e.tau_ext_raw;   // the arm has been standing: the filter has settled
  e.tau_J_measured_previous = e.tau_J_measured;
  publish();
}

void Emulator::rebuild_internal_model() {
  ModelParameters p = internal_parameters_;
  p.F_T_EE = F_T_NE_ * NE_T_EE_;
  internal_ = Model(p);
}

void Emulator::require_no_motion(const char* operation) const {
  if (mode_) throw InvalidOperation(std::string(operation) + ": not allowed while a motion is running");
}

void Emulator::set_collision_behavior(const CollisionBehavior& behavior) {
  require_no_motion("setCollisionBehavior");
  require(collision_behavior_problem(behavior), "setCollisionBehavior");
  settings_.collision = behavior;
}

void Emulator::set_joint_impedance(const Vector7& stiffness) {
  require_no_motion("setJointImpedance");
  require(joint_stiffness_problem(stiffness), "setJointImpedance");
  settings_.joint_stiffness = stiffness;
}

void Emulator::set_cartesian_impedance(const Vector6& stiffness) {
  require_no_motion("setCartesianImpedance");
  require(cartesian_stiffness_problem(stiffness), "setCartesianImpedance");
  settings_.cartesian_stiffness = stiffness;
}

void Emulator::set_load(const RigidBodyInertia& load) {
  require_no_motion("setLoad");
  require(load_problem(load), "setLoad");
  internal_parameters_.load = load;
  rebuild_internal_model();
  publish();
}

void Emulator::set_carried_object(const RigidBodyInertia& object) {
  require(load_problem(object), "carried object");
  plant_ = with_load(plant_, combine(settings_.plant.load, object));
}

void Emulator::set_EE(const Transform& NE_T_EE) {
  require_no_motion("setEE");
  require(transform_problem(NE_T_EE), "setEE");
  NE_T_EE_ = NE_T_EE;
  rebuild_internal_model();
  publish();
}

void Emulator::set_K(const Transform& EE_T_K) {
  require_no_motion("setK");
  require(transform_problem(EE_T_K), "setK");
  internal_parameters_.EE_T_K = EE_T_K;
  rebuild_internal_model();
  publish();
}

void Emulator::automatic_error_recovery() {
  require_no_motion("automaticErrorRecovery");
  state_.current_errors = franka::Errors{};
  state_.joint_collision.fill(0.0);
  state_.cartesian_collision.fill(0.0);
  if (phase_ == Phase::kBraking || phase_ == Phase::kBraked) {
    // Brakes open; the robot holds where it stopped, its motors taking the load again.
    phase_ = Phase::kIdle;
    plant_state_.dq.setZero();
    estimator_.dq_previous.setZero();   // no phantom deceleration in the next external-torque estimate
    torque_loop_.q_hold = plant_state_.q;
    gravity_compensation_torque();
    torque_loop_.tau_motor = torque_loop_.gravity;
  }
  state_.robot_mode = RobotMode::kIdle;   // reflex_reason() stays: CSP_STATUS reports the last reflex
}

void Emulator::start_motion(ControlMode mode, std::optional<ControllerMode> controller) {
  if (mode == ControlMode::kTorque && controller && *controller != ControllerMode::kExternalController)
    throw std::invalid_argument(std::string("a torque motion is its own controller, not ") + controller_mode_name(*controller));
  if (mode_) throw InvalidOperation("a motion is already running");
  if (phase_ != Phase::kIdle)
    throw InvalidOperation("the robot is in Reflex mode " + std::string(state_.current_errors) +
                           ": call automaticErrorRecovery() first");
  mode_ = mode;
  controller_ = mode == ControlMode::kTorque ? ControllerMode::kExternalController
                                             : controller.value_or(ControllerMode::kJointImpedance);
  phase_ = Phase::kMove;
  state_.robot_mode = RobotMode::kMove;
  // A motion starts at rest where the arm is (what Idle publishes as q_d; libfranka 0.15's examples
  // start from q, 0.9's from q_d, libfranka's filter from q_d): its EE pose and elbow are where a
  // Cartesian motion generator starts.
  MotionGenerator& g = motion_generator_;
  g.q_c = plant_state_.q;
  g.dq_c.setZero();
  g.ddq_c.setZero();
  g.first_command = true;
  forward_kinematics(internal_, internal_data_, g.q_c);
  g.O_T_EE_c = internal_data_.O_T_EE;
  g.O_dP_EE_c.setZero();
  g.O_ddP_EE_c.setZero();
  g.elbow_c = g.q_c[2];
  g.delbow_c = g.ddelbow_c = 0.0;
  g.elbow_sign = elbow_sign(g.q_c[3]);
  reception_.restart();
}

void Emulator::enter_reflex(const ErrorSet& errors, const std::string& reason) {
  ErrorSet current(state_.current_errors);
  current.merge(errors);
  state_.current_errors = current.errors();
  state_.last_motion_errors = errors.errors();
  reflex_reason_ = reason.empty() ? std::string(errors) : reason;
  phase_ = Phase::kBraking;
  braking_since_ = state_.time.toSec();
  mode_.reset();
  state_.robot_mode = RobotMode::kReflex;
  ++counters_.reflexes;
}

// ---------------------------------------------------------------------------------------------
// One cycle

// The stages in the robot's order: each reads what the ones before it wrote this cycle.
void Emulator::step(const CycleInput& input) {
  ++counters_.cycles;
  state_.time += Duration(1);
  take_command(input);              // reception, refusals, torque or motion-generator setpoint
  integrate();                      // inner torque loop and plant, `substeps` times
  update_sensors_and_estimates();   // tau_J, dtau_J, tau_ext_hat_filtered, O_F_ext_hat_K
  check_limits_and_collisions();    // reflexes of a running motion
  end_motion_if_finished();         // motion_finished -> Idle
  publish();                        // the RobotState
}

// Command intake: what arrived, whether the robot accepts it, and what it makes of it (the user's
// torque, or the motion generator's next setpoint). A refused command, a failed controller or the
// 20th lost command in a row end the motion here, before the torque loop runs: the arm brakes in
// this very cycle, as the FCI does when a cycle's command is missing or invalid.
void Emulator::take_command(const CycleInput& input) {
  reception_.finish_requested = false;
  if (phase_ != Phase::kMove) return;   // no motion runs: nothing is commanded
  ++counters_.motion_cycles;

  const Command* command = input.kind == CycleInput::Kind::kCommand ? input.command : nullptr;
  std::string refusal;
  motion_generator_reason_.clear();
  if (input.kind == CycleInput::Kind::kControllerFailed) refusal = input.failure;
  else if (command) refusal = not_finite_reason(*mode_, controller_, *command);
  const bool received = command && refusal.empty();
  reception_.record(received);

  ErrorSet errors;
  if (!received && refusal.empty()) {   // lost: bridged by the last torque or an extrapolation
    ++counters_.lost_commands;
    counters_.max_consecutive_lost = std::max(counters_.max_consecutive_lost, reception_.consecutive_lost);
    if (reception_.consecutive_lost >= kMaxConsecutiveLost) errors.set(Error::communication_constraints_violation);
  }
  if (refusal.empty()) {
    const Command* accepted = received ? command : nullptr;
    // The user's torque: alone (kTorque), or next to a motion generator (kExternalController).
    if (controller_ == ControllerMode::kExternalController)
      errors.merge(accept_torque(!accepted ? nullptr : *mode_ == ControlMode::kTorque ? &accepted->values : &accepted->torque));
    if (*mode_ != ControlMode::kTorque) errors.merge(run_motion_generator(accepted));
  }
  if (!refusal.empty() || errors) enter_reflex(errors, refusal.empty() ? motion_generator_reason_ : refusal);
  reception_.finish_requested = received && command->motion_finished;
}

void Emulator::CommandReception::restart() {
  last_user_torque.setZero();
  finish_requested = false;
  consecutive_lost = 0;
  index = count = in_window = 0;
}

void Emulator::CommandReception::record(bool arrived) {
  consecutive_lost = arrived ? 0 : consecutive_lost + 1;
  // A running count over the window: the slot overwritten leaves it, the new cycle enters.
  const int window = static_cast<int>(received.size());
  if (count == window && received[index]) --in_window;
  received[index] = arrived;
  if (arrived) ++in_window;
  index = (index + 1) % window;
  count = std::min(count + 1, window);
}

// Torque mode: the user's torque without gravity (tau_J_d); a lost command reuses the last one.
// Its change per cycle is bounded by dtau_max.
ErrorSet Emulator::accept_torque(const Vector7* torque) {
  ErrorSet errors;
  Vector7& last = reception_.last_user_torque;
  const Vector7 user_torque = torque ? *torque : last;
  const Vector7 dtau_max = plant_.parameters().joint_limits.dtau_max;
  if (((user_torque - last).array().abs() > dtau_max.array() * kDeltaT + kLimitTolerance).any())
    errors.set(Error::controller_torque_discontinuity);
  last = user_torque;
  return errors;
}

// The external motion generator: this cycle's commanded joint trajectory point q_c, dq_c (from
// the joint command, or from the Cartesian command through the robot's inverse kinematics), its
// finite-difference derivatives and the joint-level checks with the motion generator's own error
// names (libfranka: joint_motion_generator_* or cartesian_motion_generator_joint_*).
ErrorSet Emulator::run_motion_generator(const Command* command) {
  const JointLimits& limits = plant_.parameters().joint_limits;
  MotionGenerator& g = motion_generator_;
  const bool cartesian = is_cartesian(*mode_);
  Vector7 q_c, dq_c;
  ErrorSet errors = cartesian ? cartesian_setpoint(command, q_c, dq_c) : joint_setpoint(command, q_c, dq_c);
  if (errors) return errors;
  if (command) g.first_command = false;
  const Vector7 ddq_c = (dq_c - g.dq_c) / kDeltaT;
  const Vector7 dddq_c = (ddq_c - g.ddq_c) / kDeltaT;

  const JointTrajectoryErrors flags =
      cartesian ? JointTrajectoryErrors{Error::cartesian_motion_generator_joint_position_limits_violation,
                                        Error::cartesian_motion_generator_joint_velocity_limits_violation,
                                        Error::cartesian_motion_generator_joint_velocity_discontinuity,
                                        Error::cartesian_motion_generator_joint_acceleration_discontinuity}
                : JointTrajectoryErrors{Error::joint_motion_generator_position_limits_violation,
                                        Error::joint_motion_generator_velocity_limits_violation,
                                        Error::joint_motion_generator_velocity_discontinuity,
                                        Error::joint_motion_generator_acceleration_discontinuity};
  const Vector7 upper = limits.dq_upper(q_c), lower = limits.dq_lower(q_c);
  for (int i = 0; i < kNumJoints; ++i) {
    if (q_c[i] > limits.q_max[i] + kLimitTolerance || q_c[i] < limits.q_min[i] - kLimitTolerance)
      errors.set(flags.position);
    if (dq_c[i] > upper[i] + kLimitTolerance || dq_c[i] < lower[i] - kLimitTolerance) errors.set(flags.velocity);
    if (std::abs(ddq_c[i]) > limits.ddq_max[i] + kLimitTolerance) errors.set(flags.velocity_discontinuity);
    if (std::abs(dddq_c[i]) > limits.dddq_max[i] + kLimitTolerance) errors.set(flags.acceleration_discontinuity);
  }
  g.q_c = q_c;
  g.dq_c = dq_c;
  g.ddq_c = ddq_c;
  return errors;
}

// A joint position or velocity command; a lost one is extrapolated with constant acceleration.
ErrorSet Emulator::joint_setpoint(const Command* command, Vector7& q_c, Vector7& dq_c) {
  const MotionGenerator& g = motion_generator_;
  ErrorSet errors;
  if (!command) {
    dq_c = g.dq_c + g.ddq_c * kDeltaT;
    q_c = g.q_c + dq_c * kDeltaT;
  } else if (*mode_ == ControlMode::kJointPosition) {
    q_c = command->values;
    // The robot rejects the start pose itself; the jump is not also a velocity error. A first
    // command within the tolerance starts the trajectory at rest where it says (libfranka's
    // examples start from the measured q, 0.9's from q_d: both a little off the held pose).
    if (g.first_command &&
        ((q_c - g.q_c).array().abs() > plant_.parameters().joint_limits.dq_max.array() * kDeltaT).any())
      errors.set(Error::joint_position_motion_generator_start_pose_invalid);
    dq_c = g.first_command ? Vector7::Zero().eval() : ((q_c - g.q_c) / kDeltaT).eval();
  } else {
    dq_c = command->values;
    q_c = g.q_c + dq_c * kDeltaT;
  }
  return errors;
}

void Emulator::gravity_compensation_torque() {
  if (settings_.gravity_compensation) gravity_torque(internal_, internal_data_, plant_state_.q, torque_loop_.gravity);
  else torque_loop_.gravity.setZero();
}

// External wrenches of the scenario at time t, as link-frame wrenches about each link origin.
LinkWrenches Emulator::external_link_wrenches(double t) {
  LinkWrenches wrenches = kNoLinkWrenches;
  bool any = false;
  for (const ExternalWrench& w : settings_.external_wrenches) {
    if (t < w.start || t >= w.end) continue;
    double scale = 1.0;   // linear ramp in and out
    if (w.ramp > 0.0) scale = std::clamp(std::min(t - w.start, w.end - t) / w.ramp, 0.0, 1.0);
    if (!any) forward_kinematics(plant_, plant_data_, plant_state_.q);
    any = true;
    const Matrix3 R = plant_data_.O_T_joint[w.link - 1].rotation;   // base_R_link
    const Vector3 force = R.transpose() * (scale * w.force);
    const Vector3 moment = R.transpose() * (scale * w.moment) + w.point.cross(force);
    wrenches[w.link - 1].head<3>() += force;
    wrenches[w.link - 1].tail<3>() += moment;
  }
  return wrenches;
}

// The scripted wrenches plus the scene's contact forces of the substep (contact_state_).
LinkWrenches Emulator::with_contact_wrenches(const LinkWrenches& scripted) const {
  LinkWrenches total;
  for (int i = 0; i < kNumJoints; ++i) total[i] = scripted[i] + contact_state_.link_wrenches[i];
  return total;
}

// The inner torque loop and the plant, integrated with `substeps` semi-implicit (symplectic)
// Euler steps: velocity first, then position with the new velocity. Its energy error stays
// bounded instead of drifting (tests/test_emulator.cpp measures it and a step response). Static
// friction enters implicitly on the new velocity (tests/test_friction.cpp).
void Emulator::integrate() {
  TorqueLoop& loop = torque_loop_;
  const double cycle_start = state_.time.toSec() - kDeltaT;
  const LinkWrenches f_ext = external_link_wrenches(cycle_start);
  if (phase_ == Phase::kBraked) {
    hold_on_brakes(cycle_start, f_ext);
    return;
  }
  gravity_compensation_torque();
  const TorqueLoopTarget target = torque_loop_target();

  // Stiff contact needs shorter steps (docs/contact.md); without one the configured substeps.
  const int substeps =
      contact_ ? contact_->required_substeps(plant_, plant_data_, plant_state_.q, contact_state_, settings_.substeps)
               : settings_.substeps;
  contact_state_.substeps = substeps;
  const double h = kDeltaT / substeps;
  const double alpha = lowpass_factor(settings_.torque_loop_bandwidth_hz, h);
  const Vector7 q_before = plant_state_.q;
  for (int s = 0; s < substeps; ++s) {
    // The robot's controllers run faster than the FCI: impedance and braking act every substep.
    loop.tau_motor += alpha * (torque_loop_setpoint(target) + loop.gravity - loop.tau_motor);
    plant_substep(cycle_start + s * h, h, f_ext);
  }
  // The sensor sits between rotor and link: the rotor's own inertia is not felt by it.
  plant_state_.tau_J = loop.tau_motor - plant_.armature().cwiseProduct(plant_state_.ddq);

  if (stop_if_diverged(q_before, f_ext)) return;
  close_brakes_when_stopped(target.braking);
}

// Brakes closed: the links stand still and the sensors carry the static load (the scripted
// wrenches and the scene's contact forces at rest).
void Emulator::hold_on_brakes(double t, const LinkWrenches& f_ext) {
  PlantState& arm = plant_state_;
  arm.dq.setZero();
  arm.ddq.setZero();
  if (contact_) {
    contact_->evaluate(plant_, plant_data_, t, arm.q, arm.dq, contact_state_);
    contact_->add_dissipative_forces(plant_data_, arm.dq, contact_state_);
  }
  rnea(plant_, plant_data_, arm.q, arm.dq, arm.ddq, contact_ ? with_contact_wrenches(f_ext) : f_ext, arm.tau_J);
}

// The torque loop's setpoint: the user's torque (kExternalController), the robot's joint
// impedance (Idle, motion generators), its Cartesian impedance, or a reflex's braking. Its parts
// that depend on the cycle only (the targets, the mass matrix's diagonal) are computed once here.
Emulator::TorqueLoopTarget Emulator::torque_loop_target() {
  TorqueLoopTarget target;
  const bool moving = phase_ == Phase::kMove;
  target.impedance = phase_ == Phase::kIdle || (moving && controller_ == ControllerMode::kJointImpedance);
  target.cartesian = moving && controller_ == ControllerMode::kCartesianImpedance;
  target.braking = phase_ == Phase::kBraking;
  target.mass_diagonal = Vector7::Zero();
  if (target.impedance || target.cartesian || target.braking) {
    crba(internal_, internal_data_, plant_state_.q);
    target.mass_diagonal = internal_data_.mass_matrix.diagonal();
  }
  const Vector7& stiffness = settings_.joint_stiffness;
  target.damping = 2.0 * (stiffness.cwiseProduct(target.mass_diagonal)).cwiseSqrt();   // critical
  target.q = phase_ == Phase::kIdle ? torque_loop_.q_hold : motion_generator_.q_c;
  target.dq = phase_ == Phase::kIdle ? Vector7::Zero() : motion_generator_.dq_c;
  // Uses the mass matrix at q.
  if (target.cartesian) target.cartesian_impedance = cartesian_impedance_target(target.q, target.dq);
  return target;
}

// The setpoint at the arm's state of this substep.
Vector7 Emulator::torque_loop_setpoint(const TorqueLoopTarget& target) {
  const PlantState& arm = plant_state_;
  Vector7 setpoint = reception_.last_user_torque;
  if (target.impedance)
    setpoint = settings_.joint_stiffness.cwiseProduct(target.q - arm.q) + target.damping.cwiseProduct(target.dq - arm.dq);
  if (target.cartesian)
    setpoint = cartesian_impedance_torque(target.cartesian_impedance, target.q, target.dq, target.damping);
  if (target.braking) setpoint = -target.mass_diagonal.cwiseProduct(arm.dq) / kBrakingTimeConstant;
  return setpoint;
}

// One semi-implicit Euler step of length h of the plant under the torque loop's motor torque, at
// time t [s].
void Emulator::plant_substep(double t, double h, const LinkWrenches& f_ext) {
  PlantState& arm = plant_state_;
  // (M + armature) ddq = tau_motor - tau_friction(dq) - tau_extra - c - g + J^T f_ext
  const FrictionModel& friction = plant_.parameters().friction;
  const bool static_friction = (friction.breakaway.array() > 0.0).any();
  Vector7 tau_link = torque_loop_.tau_motor - friction_torque(friction, arm.dq);
  if (settings_.extra_joint_torque) tau_link -= settings_.extra_joint_torque(t, arm.q, arm.dq, torque_loop_.tau_motor);
  if (contact_) contact_->evaluate(plant_, plant_data_, t, arm.q, arm.dq, contact_state_);
  forward_dynamics_cholesky(plant_, plant_data_, arm.q, arm.dq, tau_link, contact_ ? with_contact_wrenches(f_ext) : f_ext);
  if (contact_ || static_friction) {
    Vector7 dq_next = arm.dq + h * plant_data_.ddq;
    // The contacts' damping and friction act on the new velocity (implicit, docs/contact.md): a
    // friction slope mu F_n / v_s of thousands of N s/m needs no shorter step.
    if (contact_) dq_next = contact_->dissipate(plant_data_, plant_data_.mass_matrix, arm.dq, dq_next, h, contact_state_);
    // Static friction too: a joint at rest stays exactly at rest while the torque on it is below
    // its breakaway level; its sliding level follows dq.
    if (static_friction) {
      Vector7 bound;
      for (int i = 0; i < kNumJoints; ++i)
        bound[i] = h * stribeck_level(friction.breakaway[i], friction.stribeck_velocity[i], arm.dq[i]);
      dq_next = static_friction_velocity(plant_data_.mass_matrix, dq_next, bound);
    }
    arm.ddq = (dq_next - arm.dq) / h;
    arm.dq = dq_next;
  } else {
    arm.ddq = plant_data_.ddq;
    arm.dq += h * arm.ddq;
  }
  arm.q += h * arm.dq;
}

// The integration diverged (a setting the checks let through): a real robot never reports a
// NaN. Keep the last finite pose, stop the arm on its brakes, and say why; recoverable.
bool Emulator::stop_if_diverged(const Vector7& q_before, const LinkWrenches& f_ext) {
  PlantState& arm = plant_state_;
  if (arm.q.allFinite() && arm.dq.allFinite() && arm.tau_J.allFinite()) return false;
  arm.q = q_before;
  arm.dq.setZero();
  arm.ddq.setZero();
  gravity_compensation_torque();
  torque_loop_.tau_motor = torque_loop_.gravity;
  rnea(plant_, plant_data_, arm.q, arm.dq, arm.ddq, f_ext, arm.tau_J);
  enter_reflex(ErrorSet{}, "the emulated plant diverged (non-finite joint state); the arm was stopped at its last finite pose");
  phase_ = Phase::kBraked;
  return true;
}

// A reflex's braking ends with the brakes closed once the arm has (nearly) stopped, or after the
// longest braking time whatever its speed.
void Emulator::close_brakes_when_stopped(bool braking) {
  PlantState& arm = plant_state_;
  if (braking && ((arm.dq.array().abs() < kBrakesClosedVelocity).all() ||
                  state_.time.toSec() - braking_since_ >= kMaxBrakingTime - 1e-9)) {
    phase_ = Phase::kBraked;
    arm.dq.setZero();
  }
}

// Sensors and estimates: the torque sensor (bias, seeded noise), and what the robot's model makes
// of it: the external torque and the external wrench on K.
void Emulator::update_sensors_and_estimates() {
  Estimator& e = estimator_;
  const PlantState& arm = plant_state_;
  e.tau_J_measured = arm.tau_J + settings_.tau_J_bias;
  for (int i = 0; i < kNumJoints; ++i)
    if (settings_.tau_J_noise[i] > 0.0) e.tau_J_measured[i] += settings_.tau_J_noise[i] * e.unit_normal(e.noise_rng);

  // Expected torque of the robot's model along the measured motion (acceleration by finite
  // difference of dq); what it cannot explain is attributed to external forces.
  const Vector7 ddq_estimate = (arm.dq - e.dq_previous) / kDeltaT;
  Vector7 expected;
  rnea(internal_, internal_data_, arm.q, arm.dq, ddq_estimate, expected);
  e.tau_ext_raw = e.tau_J_measured - expected;
  e.tau_ext_filtered += lowpass_factor(settings_.tau_ext_cutoff_hz, kDeltaT) * (e.tau_ext_raw - e.tau_ext_filtered);
  e.dtau_J = (e.tau_J_measured - e.tau_J_measured_previous) / kDeltaT;
  e.tau_J_measured_previous = e.tau_J_measured;
  e.dq_previous = arm.dq;

  // External wrench on K: O_F = (J J^T + lambda^2 1)^-1 J tau_ext (damped pseudo-inverse of J^T).
  // Sign as libfranka's: the wrench the robot exerts on its environment (libfranka issue #26).
  forward_kinematics(internal_, internal_data_, arm.q);
  zero_jacobian(internal_data_, Frame::kStiffness, e.jacobian);
  const Matrix6 JJt = e.jacobian * e.jacobian.transpose() + kWrenchDamping * kWrenchDamping * Matrix6::Identity();
  e.O_F_ext = JJt.ldlt().solve(e.jacobian * e.tau_ext_filtered);
  const Matrix3 R = internal_data_.O_T_K.rotation;
  e.K_F_ext << R.transpose() * e.O_F_ext.head<3>(), R.transpose() * e.O_F_ext.tail<3>();
}

// The robot's limit and collision checks of a running motion; a violation ends it in a reflex.
void Emulator::check_limits_and_collisions() {
  if (phase_ != Phase::kMove) return;
  const JointLimits& limits = plant_.parameters().joint_limits;
  const PlantState& arm = plant_state_;
  const Estimator& e = estimator_;
  ErrorSet errors;
  // The robot's own state, compared exactly: the sensed torque's range, the true torque's power.
  const LimitViolations violated =
      limit_violations(limits, arm.q, arm.dq, e.tau_J_measured, joint_power(arm.tau_J, arm.dq), 0.0);
  if (violated.position.any()) errors.set(Error::joint_position_limits_violation);
  if (violated.velocity.any()) errors.set(Error::joint_velocity_violation);
  if (violated.torque.any()) errors.set(Error::tau_j_range_violation);
  if (violated.power) errors.set(Error::power_limit_violation);

  // Contact and collision levels (setCollisionBehavior); collisions latch until recovery.
  const CollisionBehavior& c = settings_.collision;
  const bool accelerating =
      *mode_ != ControlMode::kTorque && (motion_generator_.ddq_c.array().abs() > kAccelerationThreshold).any();
  const Vector7& torque_lower = accelerating ? c.lower_torque_acceleration : c.lower_torque_nominal;
  const Vector7& torque_upper = accelerating ? c.upper_torque_acceleration : c.upper_torque_nominal;
  const Vector6& force_lower = accelerating ? c.lower_force_acceleration : c.lower_force_nominal;
  const Vector6& force_upper = accelerating ? c.upper_force_acceleration : c.upper_force_nominal;
  for (int i = 0; i < kNumJoints; ++i) {
    const double magnitude = std::abs(e.tau_ext_filtered[i]);
    state_.joint_contact[i] = magnitude > torque_lower[i] ? 1.0 : 0.0;
    if (magnitude > torque_upper[i]) {
      state_.joint_collision[i] = 1.0;
      errors.set(Error::joint_reflex);
    }
  }
  for (int j = 0; j < 6; ++j) {
    const double magnitude = std::abs(e.K_F_ext[j]);
    state_.cartesian_contact[j] = magnitude > force_lower[j] ? 1.0 : 0.0;
    if (magnitude > force_upper[j]) {
      state_.cartesian_collision[j] = 1.0;
      errors.set(Error::cartesian_reflex);
    }
  }
  if (errors) enter_reflex(errors, "");
}

// A command with motion_finished ends the motion; the robot then holds the last desired position
// (the user's torque drove the arm: where the arm is).
void Emulator::end_motion_if_finished() {
  if (phase_ != Phase::kMove || !reception_.finish_requested) return;
  end_motion(controller_ == ControllerMode::kExternalController ? plant_state_.q : motion_generator_.q_c);
}

void Emulator::stop_motion() {
  if (!mode_) throw InvalidOperation("StopMove: no motion is running");
  end_motion(plant_state_.q);
}

void Emulator::end_motion(const Vector7& q_hold) {
  torque_loop_.q_hold = q_hold;
  mode_.reset();
  phase_ = Phase::kIdle;
  state_.robot_mode = RobotMode::kIdle;
}

// ---------------------------------------------------------------------------------------------
// RobotState

void Emulator::publish() {
  RobotState& s = state_;
  const ModelParameters& p = internal_.parameters();
  const PlantState& arm = plant_state_;
  const MotionGenerator& g = motion_generator_;
  const Estimator& e = estimator_;
  const bool motion_generator = mode_ && *mode_ != ControlMode::kTorque;
  const Vector7 q_d = motion_generator ? g.q_c : arm.q;   // no motion: the robot desires where it is

  assign(s.q, arm.q);
  assign(s.dq, arm.dq);
  assign(s.q_d, q_d);
  assign(s.dq_d, motion_generator ? g.dq_c : Vector7::Zero());
  assign(s.ddq_d, motion_generator ? g.ddq_c : Vector7::Zero());
  assign(s.theta, arm.q);   // rigid gears: motor position reported on the link side
  assign(s.dtheta, arm.dq);
  assign(s.tau_J, e.tau_J_measured);
  assign(s.dtau_J, e.dtau_J);
  const bool user_torque = mode_ && controller_ == ControllerMode::kExternalController;
  assign(s.tau_J_d, user_torque ? reception_.last_user_torque : Vector7::Zero());
  assign(s.tau_ext_hat_filtered, e.tau_ext_filtered);
  assign(s.O_F_ext_hat_K, e.O_F_ext);
  assign(s.K_F_ext_hat_K, e.K_F_ext);
  s.elbow = {arm.q[2], elbow_sign(arm.q[3])};
  s.elbow_d = {q_d[2], elbow_sign(q_d[3])};

  // Kinematics of the robot's model (forward_kinematics at q ran in the estimator).
  assign(s.O_T_EE, internal_data_.O_T_EE);
  assign(s.F_T_EE, p.F_T_EE);
  assign(s.F_T_NE, F_T_NE_);
  assign(s.NE_T_EE, NE_T_EE_);
  assign(s.EE_T_K, p.EE_T_K);
  forward_kinematics(internal_, internal_data_, q_d);   // the desired pose, also the one Idle holds
  assign(s.O_T_EE_d, internal_data_.O_T_EE);
  // libfranka: "If the base is resting this shows the gravity vector. It is hardcoded for now to
  // {0, 0, -9.81}" (robot_state.h); franka::Model::gravity(state) passes it as gravity_earth.
  assign(s.O_ddP_O, p.gravity);

  // The motion generator's rates as the robot reports them (zero in torque mode, as libfranka's):
  // the EE twist J(q_c) dq_c, the EE acceleration J ddq_c + dJ/dt dq_c, the elbow's joint-3 rates.
  // A Cartesian motion generator's commanded pose, twist, acceleration and elbow are its own:
  // what the user sent (O_T_EE_c, elbow_c) and their finite differences, as libfranka's
  // limitRate reads them back; O_T_EE_d and elbow_d are where the inverse kinematics went.
  Vector6 O_dP_EE = Vector6::Zero(), O_ddP_EE = Vector6::Zero();
  if (motion_generator) {
    Matrix6x7 J, dJ;
    zero_jacobian(internal_data_, Frame::kEndEffector, J);
    zero_jacobian_time_derivative(internal_data_, Frame::kEndEffector, g.dq_c, dJ);
    O_dP_EE = J * g.dq_c;
    O_ddP_EE = J * g.ddq_c + dJ * g.dq_c;
  }
  assign(s.O_dP_EE_d, O_dP_EE);
  if (mode_ && is_cartesian(*mode_)) {
    assign(s.O_T_EE_c, g.O_T_EE_c);
    assign(s.O_dP_EE_c, g.O_dP_EE_c);
    assign(s.O_ddP_EE_c, g.O_ddP_EE_c);
    s.elbow_c = {g.elbow_c, g.elbow_sign};
    s.delbow_c = {g.delbow_c, 0.0};
    s.ddelbow_c = {g.ddelbow_c, 0.0};
  } else {
    s.O_T_EE_c = s.O_T_EE_d;
    s.O_dP_EE_c = s.O_dP_EE_d;
    assign(s.O_ddP_EE_c, O_ddP_EE);
    s.elbow_c = s.elbow_d;
    s.delbow_c = {motion_generator ? g.dq_c[2] : 0.0, 0.0};
    s.ddelbow_c = {motion_generator ? g.ddq_c[2] : 0.0, 0.0};
  }

  assign_inertia(p.end_effector, s.m_ee, s.F_x_Cee, s.I_ee);
  assign_inertia(p.load, s.m_load, s.F_x_Cload, s.I_load);
  assign_inertia(internal_.total_flange_load(), s.m_total, s.F_x_Ctotal, s.I_total);

  s.control_command_success_rate = mode_ ? reception_.success_rate() : 0.0;
}

}  // namespace csp::rt
