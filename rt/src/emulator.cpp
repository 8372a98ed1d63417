#include "csp/rt/emulator.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "state_arrays.hpp"

namespace csp::rt {
namespace {

constexpr double kLimitTolerance = 1e-9;   // round-off allowance on every limit check
constexpr double kBrakingTimeConstant = 0.02;   // [s] reflex deceleration, then the brakes close
constexpr double kBrakesClosedVelocity = 5e-3;  // [rad/s] every joint slower: brakes engage
constexpr double kMaxBrakingTime = 0.5;         // [s] the brakes close at the latest after this
constexpr double kAccelerationThreshold = 0.5;  // [rad/s^2] desired |ddq| above: "acceleration" thresholds
constexpr double kWrenchDamping = 1e-2;         // damped pseudo-inverse of J^T (O_F_ext_hat_K)
constexpr int kMaxConsecutiveLost = 20;         // FCI: 20 lost commands in a row end the motion

// First-order low-pass factor for a step of dt at cutoff f (exact for a constant input).
double lowpass_factor(double cutoff_hz, double dt) { return 1.0 - std::exp(-2.0 * M_PI * cutoff_hz * dt); }

}  // namespace

const char* control_mode_name(ControlMode mode) {
  switch (mode) {
    case ControlMode::kTorque: return "torque";
    case ControlMode::kJointPosition: return "joint_position";
    case ControlMode::kJointVelocity: return "joint_velocity";
  }
  return "unknown";
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

Emulator::Emulator(const EmulatorSettings& settings)
    : settings_(settings),
      internal_parameters_(settings.internal),
      plant_(settings.plant),
      internal_(settings.internal),
      noise_rng_(settings.seed) {
  if (settings_.substeps < 1) throw std::invalid_argument("substeps: expected at least 1");
  F_T_NE_ = internal_parameters_.F_T_EE;
  q_ = settings_.q_initial;
  dq_.setZero();
  ddq_.setZero();
  q_hold_ = q_;
  gravity_compensation_torque();
  tau_motor_ = gravity_internal_;
  tau_J_true_ = tau_motor_;
  q_c_ = q_;
  dq_c_.setZero();
  ddq_c_.setZero();
  last_user_torque_.setZero();
  dq_previous_.setZero();
  tau_J_measured_previous_ = tau_J_true_ + settings_.tau_J_bias;   // dtau_J = 0 at rest
  tau_ext_filtered_.setZero();
  state_.robot_mode = RobotMode::kIdle;
  update_sensors_and_estimates();
  tau_ext_filtered_ = tau_ext_raw_;   // the arm has been standing: the filter has settled
  tau_J_measured_previous_ = tau_J_measured_;
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
  settings_.collision = behavior;
}

void Emulator::set_joint_impedance(const Vector7& stiffness) {
  require_no_motion("setJointImpedance");
  if (!stiffness.allFinite() || (stiffness.array() < 0.0).any())
    throw std::invalid_argument("setJointImpedance: expected 7 finite non-negative stiffnesses");
  settings_.joint_stiffness = stiffness;
}

void Emulator::set_load(const RigidBodyInertia& load) {
  require_no_motion("setLoad");
  if (!std::isfinite(load.mass) || load.mass < 0.0 || !load.com.allFinite() || !load.inertia.allFinite())
    throw std::invalid_argument("setLoad: expected a finite non-negative mass, finite CoM and inertia");
  internal_parameters_.load = load;
  rebuild_internal_model();
  publish();
}

void Emulator::set_EE(const Transform& NE_T_EE) {
  require_no_motion("setEE");
  NE_T_EE_ = NE_T_EE;
  rebuild_internal_model();
  publish();
}

void Emulator::set_K(const Transform& EE_T_K) {
  require_no_motion("setK");
  internal_parameters_.EE_T_K = EE_T_K;
  rebuild_internal_model();
  publish();
}

void Emulator::automatic_error_recovery() {
  require_no_motion("automaticErrorRecovery");
  state_.current_errors = Errors{};
  state_.joint_collision.fill(0.0);
  state_.cartesian_collision.fill(0.0);
  if (phase_ == Phase::kBraking || phase_ == Phase::kBraked) {
    // Brakes open; the robot holds where it stopped, its motors taking the load again.
    phase_ = Phase::kIdle;
    dq_.setZero();
    dq_previous_.setZero();   // no phantom deceleration in the next external-torque estimate
    q_hold_ = q_;
    gravity_compensation_torque();
    tau_motor_ = gravity_internal_;
  }
  state_.robot_mode = RobotMode::kIdle;
  reflex_reason_.clear();
}

void Emulator::start_motion(ControlMode mode) {
  if (mode_) throw InvalidOperation("a motion is already running");
  if (phase_ != Phase::kIdle)
    throw InvalidOperation("the robot is in Reflex mode " + std::string(state_.current_errors) +
                           ": call automaticErrorRecovery() first");
  mode_ = mode;
  phase_ = Phase::kMove;
  state_.robot_mode = RobotMode::kMove;
  first_command_ = true;
  q_c_ = q_hold_;   // a motion starts from the desired position the robot holds (q_d)
  dq_c_.setZero();
  ddq_c_.setZero();
  last_user_torque_.setZero();
  consecutive_lost_ = 0;
  received_count_ = 0;
  received_index_ = 0;
  received_in_window_ = 0;
}

void Emulator::abort_motion(const std::string& reason) {
  if (!mode_) return;
  enter_reflex(Errors{}, reason);
}

void Emulator::enter_reflex(const Errors& errors, const std::string& reason) {
  state_.current_errors.merge(errors);
  state_.last_motion_errors = errors;
  reflex_reason_ = reason.empty() ? std::string(errors) : reason;
  phase_ = Phase::kBraking;
  braking_since_ = state_.time.toSec();
  mode_.reset();
  state_.robot_mode = RobotMode::kReflex;
  ++counters_.reflexes;
}

// ---------------------------------------------------------------------------------------------
// One cycle

void Emulator::step(const Command* command) {
  ++counters_.cycles;
  state_.time += Duration(1);
  Errors errors;
  std::string reason;

  const bool moving = phase_ == Phase::kMove;
  bool received = false;
  if (moving) {
    ++counters_.motion_cycles;
    received = command != nullptr;
    if (received && !command->values.allFinite()) {
      std::ostringstream what;
      what << "the " << control_mode_name(*mode_) << " command is not finite ("
           << command->values.transpose() << ")";
      reason = what.str();
      received = false;
    }
    record_reception(received);
    if (!received && reason.empty()) {
      ++counters_.lost_commands;
      counters_.max_consecutive_lost = std::max(counters_.max_consecutive_lost, consecutive_lost_);
      if (consecutive_lost_ >= kMaxConsecutiveLost) errors.set(Error::communication_constraints_violation);
    }
  }

  // Stage 1: the user's torque (without gravity), or the motion generator driving the robot's
  // joint impedance controller.
  Vector7 user_torque = Vector7::Zero();
  if (moving && reason.empty()) {
    if (*mode_ == ControlMode::kTorque) {
      user_torque = received ? command->values : last_user_torque_;
      const Vector7 dtau_max = plant_.parameters().joint_limits.dtau_max;
      if (((user_torque - last_user_torque_).array().abs() > dtau_max.array() * kDeltaT + kLimitTolerance).any())
        errors.set(Error::controller_torque_discontinuity);
      last_user_torque_ = user_torque;
    } else {
      errors.merge(run_motion_generator(received ? command : nullptr));
    }
  }
  if (!reason.empty() || errors) {
    enter_reflex(errors, reason);
  }

  // Stage 2: inner torque loop and plant.
  integrate(user_torque);

  // Stage 3: sensors and estimators; then the robot's limit and collision checks.
  update_sensors_and_estimates();
  if (phase_ == Phase::kMove) {
    const Errors violations = check_limits_and_collisions();
    if (violations) enter_reflex(violations, "");
  }

  if (phase_ == Phase::kMove && received && command->motion_finished) {
    // The motion ends; the robot holds the last desired position (torque mode: where it is).
    q_hold_ = *mode_ == ControlMode::kTorque ? q_ : q_c_;
    mode_.reset();
    phase_ = Phase::kIdle;
    state_.robot_mode = RobotMode::kIdle;
  }
  publish();
}

void Emulator::record_reception(bool received) {
  consecutive_lost_ = received ? 0 : consecutive_lost_ + 1;
  // A running count over the window: the slot overwritten leaves it, the new cycle enters.
  const int window = static_cast<int>(received_.size());
  if (received_count_ == window && received_[received_index_]) --received_in_window_;
  received_[received_index_] = received;
  if (received) ++received_in_window_;
  received_index_ = (received_index_ + 1) % window;
  received_count_ = std::min(received_count_ + 1, window);
}

// The external joint motion generator: commanded q_c (or dq_c) of this cycle, its finite-difference
// derivatives and libfranka's joint_motion_generator_* checks. A lost command is extrapolated with
// constant acceleration.
Errors Emulator::run_motion_generator(const Command* command) {
  const JointLimits& limits = plant_.parameters().joint_limits;
  Errors errors;
  Vector7 q_c, dq_c;
  if (!command) {
    dq_c = dq_c_ + ddq_c_ * kDeltaT;
    q_c = q_c_ + dq_c * kDeltaT;
  } else if (*mode_ == ControlMode::kJointPosition) {
    q_c = command->values;
    if (first_command_ && ((q_c - q_c_).array().abs() > limits.dq_max.array() * kDeltaT).any()) {
      // The robot rejects the start pose itself; the jump is not also a velocity error.
      errors.set(Error::joint_position_motion_generator_start_pose_invalid);
      return errors;
    }
    dq_c = (q_c - q_c_) / kDeltaT;
  } else {
    dq_c = command->values;
    q_c = q_c_ + dq_c * kDeltaT;
  }
  if (command) first_command_ = false;
  const Vector7 ddq_c = (dq_c - dq_c_) / kDeltaT;
  const Vector7 dddq_c = (ddq_c - ddq_c_) / kDeltaT;

  const Vector7 upper = limits.dq_upper(q_c), lower = limits.dq_lower(q_c);
  for (int i = 0; i < kNumJoints; ++i) {
    if (q_c[i] > limits.q_max[i] + kLimitTolerance || q_c[i] < limits.q_min[i] - kLimitTolerance)
      errors.set(Error::joint_motion_generator_position_limits_violation);
    if (dq_c[i] > upper[i] + kLimitTolerance || dq_c[i] < lower[i] - kLimitTolerance)
      errors.set(Error::joint_motion_generator_velocity_limits_violation);
    if (std::abs(ddq_c[i]) > limits.ddq_max[i] + kLimitTolerance)
      errors.set(Error::joint_motion_generator_velocity_discontinuity);
    if (std::abs(dddq_c[i]) > limits.dddq_max[i] + kLimitTolerance)
      errors.set(Error::joint_motion_generator_acceleration_discontinuity);
  }
  q_c_ = q_c;
  dq_c_ = dq_c;
  ddq_c_ = ddq_c;
  return errors;
}

void Emulator::gravity_compensation_torque() {
  if (settings_.gravity_compensation) gravity_torque(internal_, internal_data_, q_, gravity_internal_);
  else gravity_internal_.setZero();
}

// External wrenches of the scenario at time t, as link-frame wrenches about each link origin.
LinkWrenches Emulator::external_link_wrenches(double t) {
  LinkWrenches wrenches = kNoLinkWrenches;
  bool any = false;
  for (const ExternalWrench& w : settings_.external_wrenches) {
    if (t < w.start || t >= w.end) continue;
    double scale = 1.0;   // linear ramp in and out
    if (w.ramp > 0.0) scale = std::clamp(std::min(t - w.start, w.end - t) / w.ramp, 0.0, 1.0);
    if (!any) forward_kinematics(plant_, plant_data_, q_);
    any = true;
    const Matrix3 R = plant_data_.O_T_joint[w.link - 1].rotation;   // base_R_link
    const Vector3 force = R.transpose() * (scale * w.force);
    const Vector3 moment = R.transpose() * (scale * w.moment) + w.point.cross(force);
    wrenches[w.link - 1].head<3>() += force;
    wrenches[w.link - 1].tail<3>() += moment;
  }
  return wrenches;
}

// The inner torque loop and the plant, integrated with `substeps` semi-implicit (symplectic)
// Euler steps: velocity first, then position with the new velocity. Its energy error stays
// bounded instead of drifting (tests/test_emulator.cpp measures it and a step response).
void Emulator::integrate(const Vector7& user_torque) {
  const LinkWrenches f_ext = external_link_wrenches(state_.time.toSec() - kDeltaT);
  if (phase_ == Phase::kBraked) {
    // Brakes closed: the links stand still and the sensors carry the static load.
    dq_.setZero();
    ddq_.setZero();
    rnea(plant_, plant_data_, q_, dq_, ddq_, f_ext, tau_J_true_);
    return;
  }
  gravity_compensation_torque();
  const bool impedance = phase_ == Phase::kIdle || (phase_ == Phase::kMove && *mode_ != ControlMode::kTorque);
  const bool braking = phase_ == Phase::kBraking;
  Vector7 mass_diagonal = Vector7::Zero();
  if (impedance || braking) {
    crba(internal_, internal_data_, q_);
    mass_diagonal = internal_data_.mass_matrix.diagonal();
  }
  const Vector7& stiffness = settings_.joint_stiffness;
  const Vector7 damping = 2.0 * (stiffness.cwiseProduct(mass_diagonal)).cwiseSqrt();   // critical
  const Vector7 q_target = phase_ == Phase::kIdle ? q_hold_ : q_c_;
  const Vector7 dq_target = phase_ == Phase::kIdle ? Vector7::Zero() : dq_c_;

  const double h = kDeltaT / settings_.substeps;
  const double alpha = lowpass_factor(settings_.torque_loop_bandwidth_hz, h);
  const Vector7& armature = settings_.armature;
  Vector7 bias;
  for (int s = 0; s < settings_.substeps; ++s) {
    // The robot's controllers run faster than the FCI: impedance and braking act every substep.
    Vector7 command = user_torque;
    if (impedance) command = stiffness.cwiseProduct(q_target - q_) + damping.cwiseProduct(dq_target - dq_);
    if (braking) command = -mass_diagonal.cwiseProduct(dq_) / kBrakingTimeConstant;
    tau_motor_ += alpha * (command + gravity_internal_ - tau_motor_);

    // (M + armature) ddq = tau_motor - c - g - tau_friction + J^T f_ext
    crba(plant_, plant_data_, q_);
    plant_data_.mass_matrix.diagonal() += armature;
    rnea(plant_, plant_data_, q_, dq_, Vector7::Zero(), f_ext, bias);
    plant_data_.mass_cholesky.compute(plant_data_.mass_matrix);
    ddq_ = plant_data_.mass_cholesky.solve(tau_motor_ - bias - friction_torque(plant_.parameters().friction, dq_));
    dq_ += h * ddq_;
    q_ += h * dq_;
  }
  // The sensor sits between rotor and link: the rotor's own inertia is not felt by it.
  tau_J_true_ = tau_motor_ - armature.cwiseProduct(ddq_);

  if (braking && ((dq_.array().abs() < kBrakesClosedVelocity).all() ||
                  state_.time.toSec() - braking_since_ >= kMaxBrakingTime - 1e-9)) {
    phase_ = Phase::kBraked;
    dq_.setZero();
  }
}

void Emulator::update_sensors_and_estimates() {
  tau_J_measured_ = tau_J_true_ + settings_.tau_J_bias;
  for (int i = 0; i < kNumJoints; ++i)
    if (settings_.tau_J_noise[i] > 0.0) tau_J_measured_[i] += settings_.tau_J_noise[i] * unit_normal_(noise_rng_);

  // Expected torque of the robot's model along the measured motion (acceleration by finite
  // difference of dq); what it cannot explain is attributed to external forces.
  const Vector7 ddq_estimate = (dq_ - dq_previous_) / kDeltaT;
  Vector7 expected;
  rnea(internal_, internal_data_, q_, dq_, ddq_estimate, expected);
  tau_ext_raw_ = tau_J_measured_ - expected;
  tau_ext_filtered_ += lowpass_factor(settings_.tau_ext_cutoff_hz, kDeltaT) * (tau_ext_raw_ - tau_ext_filtered_);
  dtau_J_ = (tau_J_measured_ - tau_J_measured_previous_) / kDeltaT;
  tau_J_measured_previous_ = tau_J_measured_;
  dq_previous_ = dq_;

  // External wrench on K: O_F = (J J^T + lambda^2 1)^-1 J tau_ext (damped pseudo-inverse of J^T).
  // Sign as libfranka's: the wrench the robot exerts on its environment (libfranka issue #26).
  forward_kinematics(internal_, internal_data_, q_);
  zero_jacobian(internal_data_, Frame::kStiffness, jacobian_);
  const Matrix6 JJt = jacobian_ * jacobian_.transpose() + kWrenchDamping * kWrenchDamping * Matrix6::Identity();
  O_F_ext_ = JJt.ldlt().solve(jacobian_ * tau_ext_filtered_);
  const Matrix3 R = internal_data_.O_T_K.rotation;
  K_F_ext_ << R.transpose() * O_F_ext_.head<3>(), R.transpose() * O_F_ext_.tail<3>();
}

Errors Emulator::check_limits_and_collisions() {
  const JointLimits& limits = plant_.parameters().joint_limits;
  Errors errors;
  const Vector7 upper = limits.dq_upper(q_), lower = limits.dq_lower(q_);
  double power = 0.0;
  for (int i = 0; i < kNumJoints; ++i) {
    if (q_[i] > limits.q_max[i] || q_[i] < limits.q_min[i]) errors.set(Error::joint_position_limits_violation);
    if (dq_[i] > upper[i] || dq_[i] < lower[i]) errors.set(Error::joint_velocity_violation);
    if (std::abs(tau_J_measured_[i]) > limits.tau_max[i]) errors.set(Error::tau_j_range_violation);
    power += std::max(0.0, tau_J_true_[i] * dq_[i]);
  }
  if (power > settings_.power_limit) errors.set(Error::power_limit_violation);

  // Contact and collision levels (setCollisionBehavior); collisions latch until recovery.
  const CollisionBehavior& c = settings_.collision;
  const bool accelerating = *mode_ != ControlMode::kTorque && (ddq_c_.array().abs() > kAccelerationThreshold).any();
  const Vector7& torque_lower = accelerating ? c.lower_torque_acceleration : c.lower_torque_nominal;
  const Vector7& torque_upper = accelerating ? c.upper_torque_acceleration : c.upper_torque_nominal;
  const Vector6& force_lower = accelerating ? c.lower_force_acceleration : c.lower_force_nominal;
  const Vector6& force_upper = accelerating ? c.upper_force_acceleration : c.upper_force_nominal;
  for (int i = 0; i < kNumJoints; ++i) {
    const double magnitude = std::abs(tau_ext_filtered_[i]);
    state_.joint_contact[i] = magnitude > torque_lower[i] ? 1.0 : 0.0;
    if (magnitude > torque_upper[i]) {
      state_.joint_collision[i] = 1.0;
      errors.set(Error::joint_reflex);
    }
  }
  for (int j = 0; j < 6; ++j) {
    const double magnitude = std::abs(K_F_ext_[j]);
    state_.cartesian_contact[j] = magnitude > force_lower[j] ? 1.0 : 0.0;
    if (magnitude > force_upper[j]) {
      state_.cartesian_collision[j] = 1.0;
      errors.set(Error::cartesian_reflex);
    }
  }
  return errors;
}

// ---------------------------------------------------------------------------------------------
// RobotState

void Emulator::publish() {
  RobotState& s = state_;
  const ModelParameters& p = internal_.parameters();
  const bool motion_generator = mode_ && *mode_ != ControlMode::kTorque;
  const Vector7 q_d = motion_generator ? q_c_ : (phase_ == Phase::kIdle ? q_hold_ : q_);

  assign(s.q, q_);
  assign(s.dq, dq_);
  assign(s.q_d, q_d);
  assign(s.dq_d, motion_generator ? dq_c_ : Vector7::Zero());
  assign(s.ddq_d, motion_generator ? ddq_c_ : Vector7::Zero());
  assign(s.theta, q_);   // rigid gears: motor position reported on the link side
  assign(s.dtheta, dq_);
  assign(s.tau_J, tau_J_measured_);
  assign(s.dtau_J, dtau_J_);
  assign(s.tau_J_d, mode_ == ControlMode::kTorque ? last_user_torque_ : Vector7::Zero());
  assign(s.tau_ext_hat_filtered, tau_ext_filtered_);
  assign(s.O_F_ext_hat_K, O_F_ext_);
  assign(s.K_F_ext_hat_K, K_F_ext_);
  s.elbow = {q_[2], q_[3] < 0.0 ? -1.0 : 1.0};
  s.elbow_d = s.elbow_c = {q_d[2], q_d[3] < 0.0 ? -1.0 : 1.0};

  // Kinematics of the robot's model (forward_kinematics at q ran in the estimator).
  assign(s.O_T_EE, internal_data_.O_T_EE);
  assign(s.F_T_EE, p.F_T_EE);
  assign(s.F_T_NE, F_T_NE_);
  assign(s.NE_T_EE, NE_T_EE_);
  assign(s.EE_T_K, p.EE_T_K);
  if (motion_generator) forward_kinematics(internal_, internal_data_, q_d);
  assign(s.O_T_EE_d, internal_data_.O_T_EE);
  s.O_T_EE_c = s.O_T_EE_d;
  assign(s.O_ddP_O, Vector3(-p.gravity));

  assign_inertia(p.end_effector, s.m_ee, s.F_x_Cee, s.I_ee);
  assign_inertia(p.load, s.m_load, s.F_x_Cload, s.I_load);
  assign_inertia(internal_.total_flange_load(), s.m_total, s.F_x_Ctotal, s.I_total);

  s.control_command_success_rate =
      mode_ && received_count_ > 0 ? static_cast<double>(received_in_window_) / received_count_ : 0.0;
}

}  // namespace csp::rt
