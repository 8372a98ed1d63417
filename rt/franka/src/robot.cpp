#include "franka/robot.h"

#include <chrono>
#include <cmath>
#include <thread>

#include "csp/dynamics/arrays.hpp"
#include "franka/rate_limiting.h"

namespace franka {
namespace {

using csp::from_array;
using csp::to_array;
using csp::rt::ControlMode;

std::array<double, 7>& values_of(Torques& command) { return command.tau_J; }
std::array<double, 7>& values_of(JointPositions& command) { return command.q; }
std::array<double, 7>& values_of(JointVelocities& command) { return command.dq; }

bool all_finite(const std::array<double, 7>& values) {
  for (double v : values)
    if (!std::isfinite(v)) return false;
  return true;
}

csp::rt::LoopOptions loop_options(const csp::rt::Scenario& scenario, RealtimeConfig realtime_config) {
  csp::rt::LoopOptions options;
  options.clock = scenario.clock;
  options.realtime_config = realtime_config == RealtimeConfig::kEnforce ? csp::rt::RealtimeConfig::kEnforce
                                                                      : csp::rt::RealtimeConfig::kIgnore;
  options.faults = scenario.command_faults;
  return options;   // no max_duration: a user's controller decides when its motion ends
}

// Runs a configuration call of the emulator, with libfranka's exception for a call during a motion.
template <typename Call>
void configure(Call call) {
  try {
    call();
  } catch (const csp::rt::InvalidOperation& e) {
    throw InvalidOperationException(std::string("libfranka: ") + e.what());
  }
}

}  // namespace

Robot::Robot(const std::string& scenario_path, RealtimeConfig realtime_config)
    : Robot(csp::rt::load_scenario(scenario_path), realtime_config) {}

Robot::Robot(const csp::rt::Scenario& scenario, RealtimeConfig realtime_config)
    : emulator_(scenario.emulator), loop_options_(loop_options(scenario, realtime_config)) {
  loop_options_.observer = [this](const RobotState& state, const csp::rt::CycleInfo& cycle) { record(state, cycle); };
}

void Robot::control(std::function<Torques(const RobotState&, franka::Duration)> control_callback, bool limit_rate,
                    double cutoff_frequency) {
  run(ControlMode::kTorque, control_callback, ControllerMode::kJointImpedance, limit_rate, cutoff_frequency);
}

void Robot::control(std::function<JointPositions(const RobotState&, franka::Duration)> motion_generator_callback,
                    ControllerMode controller_mode, bool limit_rate, double cutoff_frequency) {
  run(ControlMode::kJointPosition, motion_generator_callback, controller_mode, limit_rate, cutoff_frequency);
}

void Robot::control(std::function<JointVelocities(const RobotState&, franka::Duration)> motion_generator_callback,
                    ControllerMode controller_mode, bool limit_rate, double cutoff_frequency) {
  run(ControlMode::kJointVelocity, motion_generator_callback, controller_mode, limit_rate, cutoff_frequency);
}

template <typename Command>
void Robot::run(ControlMode mode, const std::function<Command(const RobotState&, franka::Duration)>& callback,
                ControllerMode controller_mode, bool limit_rate, double cutoff_frequency) {
  if (!callback) throw std::invalid_argument("libfranka: control callback is empty");
  if (!(cutoff_frequency > 0.0) || !std::isfinite(cutoff_frequency))
    throw std::invalid_argument("libfranka: cutoff_frequency must be positive and finite");
  if (controller_mode != ControllerMode::kJointImpedance)
    throw InvalidOperationException(
        "libfranka: ControllerMode::kCartesianImpedance is not emulated; CSP's robot tracks motion generators with "
        "its joint impedance controller");
  if (emulator_.in_motion()) throw InvalidOperationException("libfranka: Attempted to start multiple motions!");
  if (emulator_.state().robot_mode == RobotMode::kReflex)
    throw ControlException("libfranka: Move command rejected: command not possible in the current mode (Reflex, " +
                           std::string(emulator_.state().current_errors) +
                           ")! Call automaticErrorRecovery() first.");
  const csp::rt::Controller controller = [&](const RobotState& state, franka::Duration period) {
    Command command = callback(state, period);
    std::array<double, 7>& values = values_of(command);
    // libfranka refuses the value before sending it; the loop then tells the robot that the
    // controller failed, and the robot stops the motion in a reflex.
    if (!all_finite(values)) throw CommandException("libfranka: Commanding value is infinite or NaN.");
    values = shape(mode, values, state, limit_rate, cutoff_frequency);
    return csp::rt::Command{from_array<csp::Vector7>(values), command.motion_finished};
  };
  log_count_ = 0;
  csp::rt::MotionResult result;
  try {
    result = csp::rt::run_motion(emulator_, mode, controller, loop_options_);
  } catch (const csp::rt::RealtimeError& e) {   // refused before the motion started: the robot stays Idle
    throw RealtimeException(std::string("libfranka: ") + e.what());
  }
  last_timing_ = result.timing;
  if (result.reflex) {
    const std::string reason = result.errors ? std::string(result.errors) : result.reason;
    throw ControlException("libfranka: Move command aborted: motion aborted by reflex! " + reason, recent_log());
  }
}

std::array<double, 7> Robot::shape(ControlMode mode, std::array<double, 7> values, const RobotState& state,
                                   bool limit_rate, double cutoff_frequency) const {
  // The previous command as the robot received it.
  const std::array<double, 7>& last =
      mode == ControlMode::kTorque ? state.tau_J_d : (mode == ControlMode::kJointPosition ? state.q_d : state.dq_d);
  if (cutoff_frequency < kMaxCutoffFrequency)
    for (std::size_t i = 0; i < 7; ++i) values[i] = lowpassFilter(kDeltaT, values[i], last[i], cutoff_frequency);
  if (!limit_rate) return values;

  // The emulated arm's limits, kept kLimitEps inside so that round-off does not trip them.
  const csp::JointLimits& limits = emulator_.plant_model().parameters().joint_limits;
  const csp::Vector7 eps = csp::Vector7::Constant(kLimitEps);
  if (mode == ControlMode::kTorque) return limitRate(to_array(limits.dtau_max - eps), values, last);
  const csp::Vector7 q_d = from_array<csp::Vector7>(state.q_d);
  const std::array<double, 7> upper = to_array(limits.dq_upper(q_d) - eps), lower = to_array(limits.dq_lower(q_d) + eps);
  const std::array<double, 7> acceleration = to_array(limits.ddq_max - eps), jerk = to_array(limits.dddq_max - eps);
  if (mode == ControlMode::kJointPosition)
    return limitRate(upper, lower, acceleration, jerk, values, state.q_d, state.dq_d, state.ddq_d);
  return limitRate(upper, lower, acceleration, jerk, values, state.dq_d, state.ddq_d);
}

void Robot::record(const RobotState& state, const csp::rt::CycleInfo& cycle) {
  Record& r = log_[log_next_];
  r.state = state;
  r.command = to_array(cycle.command.values);
  r.command_received = cycle.command_received;
  log_next_ = (log_next_ + 1) % kLogSize;
  log_count_ = std::min(log_count_ + 1, kLogSize);
  if (user_observer_) user_observer_(state, cycle);
}

std::vector<Record> Robot::recent_log() const {
  std::vector<Record> log;
  log.reserve(log_count_);
  for (std::size_t k = log_count_; k > 0; --k) log.push_back(log_[(log_next_ + kLogSize - k) % kLogSize]);
  return log;
}

void Robot::read(std::function<bool(const RobotState&)> read_callback) {
  while (read_callback(readOnce())) {
  }
}

// The real robot sends a state every 1 ms, also without a motion: each read returns the next one.
// So in lockstep a read advances the emulator by one cycle (time moves, a reflex's braking goes
// on); on the real-time clock it also waits that millisecond.
RobotState Robot::readOnce() {
  if (emulator_.in_motion()) throw InvalidOperationException("libfranka: readOnce is not allowed during a motion");
  if (loop_options_.clock == csp::rt::Clock::kRealtime) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  emulator_.step(nullptr);
  return emulator_.state();
}

void Robot::setCollisionBehavior(const std::array<double, 7>& lower_torque_thresholds,
                                 const std::array<double, 7>& upper_torque_thresholds,
                                 const std::array<double, 6>& lower_force_thresholds,
                                 const std::array<double, 6>& upper_force_thresholds) {
  setCollisionBehavior(lower_torque_thresholds, upper_torque_thresholds, lower_torque_thresholds,
                       upper_torque_thresholds, lower_force_thresholds, upper_force_thresholds, lower_force_thresholds,
                       upper_force_thresholds);
}

void Robot::setCollisionBehavior(const std::array<double, 7>& lower_torque_thresholds_acceleration,
                                 const std::array<double, 7>& upper_torque_thresholds_acceleration,
                                 const std::array<double, 7>& lower_torque_thresholds_nominal,
                                 const std::array<double, 7>& upper_torque_thresholds_nominal,
                                 const std::array<double, 6>& lower_force_thresholds_acceleration,
                                 const std::array<double, 6>& upper_force_thresholds_acceleration,
                                 const std::array<double, 6>& lower_force_thresholds_nominal,
                                 const std::array<double, 6>& upper_force_thresholds_nominal) {
  csp::rt::CollisionBehavior b;
  b.lower_torque_acceleration = from_array<csp::Vector7>(lower_torque_thresholds_acceleration);
  b.upper_torque_acceleration = from_array<csp::Vector7>(upper_torque_thresholds_acceleration);
  b.lower_torque_nominal = from_array<csp::Vector7>(lower_torque_thresholds_nominal);
  b.upper_torque_nominal = from_array<csp::Vector7>(upper_torque_thresholds_nominal);
  b.lower_force_acceleration = from_array<csp::Vector6>(lower_force_thresholds_acceleration);
  b.upper_force_acceleration = from_array<csp::Vector6>(upper_force_thresholds_acceleration);
  b.lower_force_nominal = from_array<csp::Vector6>(lower_force_thresholds_nominal);
  b.upper_force_nominal = from_array<csp::Vector6>(upper_force_thresholds_nominal);
  configure([&] { emulator_.set_collision_behavior(b); });
}

void Robot::setJointImpedance(const std::array<double, 7>& K_theta) {
  configure([&] { emulator_.set_joint_impedance(from_array<csp::Vector7>(K_theta)); });
}

void Robot::setLoad(double load_mass, const std::array<double, 3>& F_x_Cload, const std::array<double, 9>& load_inertia) {
  csp::RigidBodyInertia load;
  load.mass = load_mass;
  load.com = csp::Vector3(F_x_Cload.data());
  load.inertia = from_array<csp::Matrix3>(load_inertia);
  configure([&] { emulator_.set_load(load); });
}

void Robot::setEE(const std::array<double, 16>& NE_T_EE) {
  configure([&] { emulator_.set_EE(csp::transform_from_array(NE_T_EE)); });
}

void Robot::setK(const std::array<double, 16>& EE_T_K) {
  configure([&] { emulator_.set_K(csp::transform_from_array(EE_T_K)); });
}

void Robot::automaticErrorRecovery() {
  configure([&] { emulator_.automatic_error_recovery(); });
}

Model Robot::loadModel() { return Model(emulator_.internal_model()); }

}  // namespace franka
