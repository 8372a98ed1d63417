#include "franka/robot.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <thread>

#include "csp/dynamics/arrays.hpp"
#include "csp/rt/deadline_clock.hpp"
#include "franka/active_motion_generator.h"
#include "franka/active_torque_control.h"
#include "franka/control_tools.h"
#include "franka/logging/logger.hpp"
#include "franka/model.h"
#include "franka/rate_limiting.h"
#include "commands.hpp"
#include "model_impl.hpp"
#include "robot_address.hpp"
#include "robot_impl.hpp"
#include "robot_model_urdf.hpp"

namespace franka {
namespace {

using csp::from_array;
using csp::to_array;
using csp::rt::ControlMode;
using Move = research_interface::robot::Move;
using commands::check;
using commands::set;

csp::rt::Scenario scenario_of_address(const std::string& franka_address) {
  try {
    return csp::rt::load_scenario(
        csp::franka_address::scenario_for_address(franka_address, std::getenv("CSP_SCENARIO"),
                                                 csp::rt::shipped_config_dir() + "/scenarios"));
  } catch (const std::exception& e) {
    throw NetworkException(std::string("libfranka: Connection to ") + franka_address + " failed: " + e.what());
  }
}

csp::rt::ControllerMode controller_of(ControllerMode mode) {
  return mode == ControllerMode::kJointImpedance ? csp::rt::ControllerMode::kJointImpedance
                                                 : csp::rt::ControllerMode::kCartesianImpedance;
}

csp::rt::ControllerMode controller_of(Move::ControllerMode mode) {
  switch (mode) {
    case Move::ControllerMode::kJointImpedance: return csp::rt::ControllerMode::kJointImpedance;
    case Move::ControllerMode::kCartesianImpedance: return csp::rt::ControllerMode::kCartesianImpedance;
    case Move::ControllerMode::kExternalController: break;
  }
  return csp::rt::ControllerMode::kExternalController;
}

// Runs a configuration call of the emulator between motions, with libfranka's exceptions: a call
// during a motion, and a value the robot refuses (CommandException, as the robot's reply).
template <typename Call>
void configure(Robot::Impl& impl, Call call) {
  std::unique_lock<std::mutex> lock(impl.control_mutex, std::try_to_lock);
  if (!lock.owns_lock() || impl.session)
    throw InvalidOperationException(
        "libfranka robot: Cannot perform this operation while another control or read operation is running.");
  impl.catch_up_idle_time();
  try {
    call();
  } catch (const csp::rt::InvalidOperation& e) {
    throw InvalidOperationException(std::string("libfranka: ") + e.what());
  } catch (const std::invalid_argument& e) {
    throw CommandException(std::string("libfranka: command rejected: ") + e.what());
  }
  impl.mark_idle();
}

// ---------------------------------------------------------------------------------------------
// Commands: a franka command as the robot receives it, and libfranka's client-side shaping in
// control() (low-pass filter, then rate limiting), each from the robot's last command in `state`.

void lowpass(std::array<double, 7>& values, const std::array<double, 7>& last, double cutoff) {
  for (std::size_t i = 0; i < 7; ++i) values[i] = lowpassFilter(kDeltaT, values[i], last[i], cutoff);
}

// The emulated arm's joint limits, kept kLimitEps inside so that round-off does not trip them.
struct JointRateLimits {
  std::array<double, 7> upper, lower, acceleration, jerk, torque_rate;
  JointRateLimits(const csp::JointLimits& limits, const std::array<double, 7>& q_d) {
    const csp::Vector7 eps = csp::Vector7::Constant(kLimitEps);
    const csp::Vector7 q = from_array<csp::Vector7>(q_d);
    upper = to_array(limits.dq_upper(q) - eps);
    lower = to_array(limits.dq_lower(q) + eps);
    acceleration = to_array(limits.ddq_max - eps);
    jerk = to_array(limits.dddq_max - eps);
    torque_rate = to_array(limits.dtau_max - eps);
  }
};

void shape(Torques& t, const RobotState& s, const csp::JointLimits& limits, bool limit_rate, double cutoff) {
  if (cutoff < kMaxCutoffFrequency) lowpass(t.tau_J, s.tau_J_d, cutoff);
  if (limit_rate) t.tau_J = limitRate(JointRateLimits(limits, s.q_d).torque_rate, t.tau_J, s.tau_J_d);
}
void shape(JointPositions& p, const RobotState& s, const csp::JointLimits& limits, bool limit_rate, double cutoff) {
  if (cutoff < kMaxCutoffFrequency) lowpass(p.q, s.q_d, cutoff);
  if (!limit_rate) return;
  const JointRateLimits l(limits, s.q_d);
  p.q = limitRate(l.upper, l.lower, l.acceleration, l.jerk, p.q, s.q_d, s.dq_d, s.ddq_d);
}
void shape(JointVelocities& v, const RobotState& s, const csp::JointLimits& limits, bool limit_rate, double cutoff) {
  if (cutoff < kMaxCutoffFrequency) lowpass(v.dq, s.dq_d, cutoff);
  if (!limit_rate) return;
  const JointRateLimits l(limits, s.q_d);
  v.dq = limitRate(l.upper, l.lower, l.acceleration, l.jerk, v.dq, s.dq_d, s.ddq_d);
}
// The elbow's joint-3 position, filtered and limited like one joint.
void shape_elbow(std::array<double, 2>& elbow, const RobotState& s, bool limit_rate, double cutoff) {
  if (cutoff < kMaxCutoffFrequency) elbow[0] = lowpassFilter(kDeltaT, elbow[0], s.elbow_c[0], cutoff);
  if (limit_rate)
    elbow[0] = limitRate(kMaxElbowVelocity, -kMaxElbowVelocity, kMaxElbowAcceleration, kMaxElbowJerk, elbow[0],
                         s.elbow_c[0], s.delbow_c[0], s.ddelbow_c[0]);
}
void shape(CartesianPose& p, const RobotState& s, const csp::JointLimits&, bool limit_rate, double cutoff) {
  if (cutoff < kMaxCutoffFrequency) p.O_T_EE = cartesianLowpassFilter(kDeltaT, p.O_T_EE, s.O_T_EE_c, cutoff);
  if (limit_rate)
    p.O_T_EE = limitRate(kMaxTranslationalVelocity, kMaxTranslationalAcceleration, kMaxTranslationalJerk,
                         kMaxRotationalVelocity, kMaxRotationalAcceleration, kMaxRotationalJerk, p.O_T_EE, s.O_T_EE_c,
                         s.O_dP_EE_c, s.O_ddP_EE_c);
  if (p.hasElbow()) shape_elbow(p.elbow, s, limit_rate, cutoff);
}
void shape(CartesianVelocities& v, const RobotState& s, const csp::JointLimits&, bool limit_rate, double cutoff) {
  if (cutoff < kMaxCutoffFrequency)
    for (std::size_t i = 0; i < 6; ++i) v.O_dP_EE[i] = lowpassFilter(kDeltaT, v.O_dP_EE[i], s.O_dP_EE_c[i], cutoff);
  if (limit_rate)
    v.O_dP_EE = limitRate(kMaxTranslationalVelocity, kMaxTranslationalAcceleration, kMaxTranslationalJerk,
                          kMaxRotationalVelocity, kMaxRotationalAcceleration, kMaxRotationalJerk, v.O_dP_EE,
                          s.O_dP_EE_c, s.O_ddP_EE_c);
  if (v.hasElbow()) {
    // The elbow's velocity: limited as a joint velocity, then integrated.
    double velocity = (v.elbow[0] - s.elbow_c[0]) / kDeltaT;
    if (cutoff < kMaxCutoffFrequency) velocity = lowpassFilter(kDeltaT, velocity, s.delbow_c[0], cutoff);
    if (limit_rate)
      velocity = limitRate(kMaxElbowVelocity, -kMaxElbowVelocity, kMaxElbowAcceleration, kMaxElbowJerk, velocity,
                           s.delbow_c[0], s.ddelbow_c[0]);
    v.elbow[0] = s.elbow_c[0] + velocity * kDeltaT;
  }
}

template <typename T> constexpr ControlMode kModeOf = ControlMode::kTorque;
template <> constexpr ControlMode kModeOf<JointPositions> = ControlMode::kJointPosition;
template <> constexpr ControlMode kModeOf<JointVelocities> = ControlMode::kJointVelocity;
template <> constexpr ControlMode kModeOf<CartesianPose> = ControlMode::kCartesianPose;
template <> constexpr ControlMode kModeOf<CartesianVelocities> = ControlMode::kCartesianVelocity;

template <typename T>
using Callback = std::function<T(const RobotState&, franka::Duration)>;

void check_cutoff(double cutoff_frequency) {
  if (!(cutoff_frequency > 0.0) || !std::isfinite(cutoff_frequency))
    throw std::invalid_argument("libfranka: cutoff_frequency must be positive and finite");
}

// One control() call: the motion generator callback (or none: a torque motion), the torque
// callback (or none: the robot's controller tracks the motion generator), on one MotionSession.
template <typename Motion>
void run_control(Robot::Impl& impl, const Callback<Motion>* motion, const Callback<Torques>* torque,
                 csp::rt::ControllerMode controller, bool limit_rate, double cutoff_frequency) {
  if ((motion && !*motion) || (torque && !*torque)) throw std::invalid_argument("libfranka: Invalid control callback given.");
  check_cutoff(cutoff_frequency);
  std::unique_lock<std::mutex> lock(impl.control_mutex, std::try_to_lock);
  if (!lock.owns_lock() || impl.session)
    throw InvalidOperationException(
        "libfranka robot: Cannot perform this operation while another control or read operation is running.");
  csp::rt::MotionSession& session = impl.start_motion(kModeOf<Motion>, controller);
  const csp::JointLimits& limits = impl.emulator.plant_model().parameters().joint_limits;
  try {
    while (!session.done()) {
      const franka::Duration period = session.read();
      const RobotState& state = session.state();
      csp::rt::Command command;
      bool finished = false;
      if (motion) {
        Motion m = (*motion)(state, period);
        check(m);
        shape(m, state, limits, limit_rate, cutoff_frequency);
        set(command, m);
        finished = m.motion_finished;
      }
      if (torque) {
        Torques t = (*torque)(state, period);
        check(t);
        shape(t, state, limits, limit_rate, cutoff_frequency);
        if (motion) command.torque = from_array<csp::Vector7>(t.tau_J);
        else set(command, t);
        finished = finished || t.motion_finished;
      }
      command.motion_finished = finished;
      session.write(command);
    }
  } catch (const std::exception& e) {
    // The controller failed: the robot's command intake stops the motion; the error goes on.
    impl.fail_motion(std::string("the controller failed: ") + e.what());
    throw;
  }
  impl.end_motion();
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Robot::Impl

Robot::Impl::Impl(const csp::rt::Scenario& scenario, RealtimeConfig realtime_config, std::size_t log_size)
    : emulator(scenario.emulator),
      robot_name(scenario.robot_file.empty() ? "robot" : std::filesystem::path(scenario.robot_file).stem().string()),
      log_(log_size) {
  if (log_size == 0) throw std::invalid_argument("libfranka: log_size must be at least 1");
  loop_options.clock = scenario.clock;
  loop_options.realtime_config = realtime_config == RealtimeConfig::kEnforce ? csp::rt::RealtimeConfig::kEnforce
                                                                             : csp::rt::RealtimeConfig::kIgnore;
  loop_options.faults = scenario.command_faults;
  loop_options.stop = &stop_requested;
  loop_options.observer = [this](const RobotState& state, const csp::rt::CycleInfo& cycle) { record(state, cycle); };
  mark_idle();
}

void Robot::Impl::mark_idle() { idle_since_ns_ = csp::rt::monotonic_ns(); }

void Robot::Impl::catch_up_idle_time() {
  if (!idle_time_runs || session) return;
  const int64_t idle = (csp::rt::monotonic_ns() - idle_since_ns_) / csp::rt::DeadlineClock::kPeriodNs;
  for (int64_t k = 0; k < std::min(idle, kMaxIdleCycles); ++k) emulator.step(nullptr);
  idle_since_ns_ += idle * csp::rt::DeadlineClock::kPeriodNs;
}

csp::rt::MotionSession& Robot::Impl::start_motion(ControlMode mode, std::optional<csp::rt::ControllerMode> controller) {
  if (session) throw InvalidOperationException("libfranka robot: Attempted to start multiple motions!");
  catch_up_idle_time();
  if (emulator.state().robot_mode == RobotMode::kReflex) {
    std::ostringstream message;
    message << "libfranka: Move command rejected: command not possible in the current mode ("
            << emulator.state().robot_mode << ")! " << emulator.state().current_errors
            << " Call automaticErrorRecovery() first.";
    mark_idle();
    throw ControlException(message.str());
  }
  stop_requested = false;
  log_count_ = 0;
  mode_ = mode;
  try {
    session.emplace(emulator, mode, controller, loop_options);
  } catch (const csp::rt::RealtimeError& e) {   // refused before the motion started: the robot stays Idle
    mark_idle();
    throw RealtimeException(std::string("libfranka: ") + e.what());
  }
  ++motion_id;
  return *session;
}

void Robot::Impl::end_motion() {
  const csp::rt::MotionResult result = session->result();
  const bool preempted = stop_requested.exchange(false) && !result.reflex;
  last_timing = result.timing;
  session.reset();
  mode_.reset();
  mark_idle();
  if (result.reflex) {
    std::ostringstream message;
    message << "libfranka: Move command aborted: motion aborted by reflex! " << emulator.state().last_motion_errors;
    if (!result.errors) message << " (" << result.reason << ")";
    const std::vector<Record> log = recent_log();
    // The last state's rate is 0 (no motion any more): the one before it, as libfranka reports.
    if (log.size() >= 2) message << "\ncontrol_command_success_rate: " << log[log.size() - 2].state.control_command_success_rate;
    throw ControlException(message.str(), log);
  }
  if (preempted) throw ControlException("libfranka: Move command preempted!", recent_log());
}

void Robot::Impl::fail_motion(const std::string& reason) {
  session->fail(reason);
  last_timing = session->result().timing;
  session.reset();
  mode_.reset();
  mark_idle();
}

void Robot::Impl::cancel_motion() {
  if (!session) return;
  if (!session->done()) {
    stop_requested = true;   // the next command is the last
    if (!session->awaiting_answer()) session->read();
    csp::rt::Command hold;
    const RobotState& s = session->state();
    switch (*mode_) {
      case ControlMode::kTorque: hold.values = from_array<csp::Vector7>(s.tau_J_d); break;
      case ControlMode::kJointPosition: hold.values = from_array<csp::Vector7>(s.q_d); break;
      case ControlMode::kJointVelocity: hold.values = from_array<csp::Vector7>(s.dq_d); break;
      case ControlMode::kCartesianPose: hold.O_T_EE_c = s.O_T_EE_c; break;
      case ControlMode::kCartesianVelocity: hold.O_dP_EE_c = s.O_dP_EE_c; break;
    }
    hold.torque = from_array<csp::Vector7>(s.tau_J_d);
    if (!session->done()) session->write(hold);
  }
  last_timing = session->result().timing;
  stop_requested = false;
  session.reset();
  mode_.reset();
  mark_idle();
}

RobotState Robot::Impl::read_once() {
  // The real robot sends a state every 1 ms, also without a motion: each read returns the next one.
  if (loop_options.clock == csp::rt::Clock::kRealtime) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  const uint64_t before = emulator.state().time.toMSec();
  catch_up_idle_time();
  if (emulator.state().time.toMSec() == before) emulator.step(nullptr);
  mark_idle();
  return emulator.state();
}

void Robot::Impl::record(const RobotState& state, const csp::rt::CycleInfo& cycle) {
  Record& r = log_[log_next_];
  r.state = state;
  r.command = RobotCommand{};
  if (mode_ && cycle.command_sent) {
    const csp::rt::Command& c = cycle.command;
    switch (*mode_) {
      case ControlMode::kTorque: r.command.torques.tau_J = to_array(c.values); break;
      case ControlMode::kJointPosition: r.command.joint_positions.q = to_array(c.values); break;
      case ControlMode::kJointVelocity: r.command.joint_velocities.dq = to_array(c.values); break;
      case ControlMode::kCartesianPose: r.command.cartesian_pose.O_T_EE = c.O_T_EE_c; break;
      case ControlMode::kCartesianVelocity: r.command.cartesian_velocities.O_dP_EE = c.O_dP_EE_c; break;
    }
    if (*mode_ != ControlMode::kTorque) r.command.torques.tau_J = to_array(c.torque);
  }
  log_next_ = (log_next_ + 1) % log_.size();
  log_count_ = std::min(log_count_ + 1, log_.size());
  if (user_observer) user_observer(state, cycle);
}

std::vector<Record> Robot::Impl::recent_log() const {
  std::vector<Record> log;
  log.reserve(log_count_);
  for (std::size_t k = log_count_; k > 0; --k) log.push_back(log_[(log_next_ + log_.size() - k) % log_.size()]);
  return log;
}

// ---------------------------------------------------------------------------------------------
// Robot

Robot::Robot(const std::string& franka_address, RealtimeConfig realtime_config, size_t log_size)
    : impl_(std::make_shared<Impl>(scenario_of_address(franka_address), realtime_config, log_size)) {}
Robot::Robot(std::shared_ptr<Impl> robot_impl) : impl_(std::move(robot_impl)) {}
Robot::Robot(Robot&& other) noexcept = default;
Robot& Robot::operator=(Robot&& other) noexcept = default;
Robot::~Robot() noexcept = default;

void Robot::control(Callback<Torques> control_callback, bool limit_rate, double cutoff_frequency) {
  run_control<Torques>(*impl_, nullptr, &control_callback, csp::rt::ControllerMode::kExternalController, limit_rate,
                       cutoff_frequency);
}

#define CSP_FRANKA_CONTROL_OVERLOADS(Motion)                                                                    \
  void Robot::control(Callback<Torques> control_callback, Callback<Motion> motion_generator_callback,          \
                      bool limit_rate, double cutoff_frequency) {                                               \
    run_control<Motion>(*impl_, &motion_generator_callback, &control_callback,                                  \
                        csp::rt::ControllerMode::kExternalController, limit_rate, cutoff_frequency);            \
  }                                                                                                             \
  void Robot::control(Callback<Motion> motion_generator_callback, ControllerMode controller_mode,               \
                      bool limit_rate, double cutoff_frequency) {                                               \
    run_control<Motion>(*impl_, &motion_generator_callback, nullptr, controller_of(controller_mode), limit_rate, \
                        cutoff_frequency);                                                                      \
  }
CSP_FRANKA_CONTROL_OVERLOADS(JointPositions)
CSP_FRANKA_CONTROL_OVERLOADS(JointVelocities)
CSP_FRANKA_CONTROL_OVERLOADS(CartesianPose)
CSP_FRANKA_CONTROL_OVERLOADS(CartesianVelocities)
#undef CSP_FRANKA_CONTROL_OVERLOADS

void Robot::read(std::function<bool(const RobotState&)> read_callback) {
  while (read_callback(readOnce())) {
  }
}

RobotState Robot::readOnce() {
  std::unique_lock<std::mutex> lock(impl_->control_mutex, std::try_to_lock);
  if (!lock.owns_lock() || impl_->session)
    throw InvalidOperationException(
        "libfranka robot: Cannot perform this operation while another control or read operation is running.");
  return impl_->read_once();
}

void Robot::setCollisionBehavior(const std::array<double, 7>& lower_torque_thresholds_acceleration,
                                 const std::array<double, 7>& upper_torque_thresholds_acceleration,
                                 const std::array<double, 7>& lower_torque_thresholds_nominal,
                                 const std::array<double, 7>& upper_torque_thresholds_nominal,
                                 const std::array<double, 6>& lower_force_thresholds_acceleration,
                                 const std::array<double, 6>& upper_force_thresholds_acceleration,
                                 const std::array<double, 6>& lower_force_thresholds_nominal,
                                 const std::array<double, 6>& upper_force_thresholds_nominal) {
  const csp::rt::CollisionBehavior b = csp::rt::collision_behavior(
      lower_torque_thresholds_acceleration, upper_torque_thresholds_acceleration, lower_torque_thresholds_nominal,
      upper_torque_thresholds_nominal, lower_force_thresholds_acceleration, upper_force_thresholds_acceleration,
      lower_force_thresholds_nominal, upper_force_thresholds_nominal);
  configure(*impl_, [&] { impl_->emulator.set_collision_behavior(b); });
}

void Robot::setCollisionBehavior(const std::array<double, 7>& lower_torque_thresholds,
                                 const std::array<double, 7>& upper_torque_thresholds,
                                 const std::array<double, 6>& lower_force_thresholds,
                                 const std::array<double, 6>& upper_force_thresholds) {
  setCollisionBehavior(lower_torque_thresholds, upper_torque_thresholds, lower_torque_thresholds,
                       upper_torque_thresholds, lower_force_thresholds, upper_force_thresholds, lower_force_thresholds,
                       upper_force_thresholds);
}

void Robot::setJointImpedance(const std::array<double, 7>& K_theta) {
  configure(*impl_, [&] { impl_->emulator.set_joint_impedance(from_array<csp::Vector7>(K_theta)); });
}

void Robot::setCartesianImpedance(const std::array<double, 6>& K_x) {
  configure(*impl_, [&] { impl_->emulator.set_cartesian_impedance(from_array<csp::Vector6>(K_x)); });
}

void Robot::setGuidingMode(const std::array<bool, 6>& guiding_mode, bool elbow) {
  configure(*impl_, [&] {
    impl_->guiding_mode = guiding_mode;
    impl_->guiding_elbow = elbow;
  });
}

void Robot::setK(const std::array<double, 16>& EE_T_K) {
  configure(*impl_, [&] { impl_->emulator.set_K(csp::transform_from_array(EE_T_K)); });
}

void Robot::setEE(const std::array<double, 16>& NE_T_EE) {
  configure(*impl_, [&] { impl_->emulator.set_EE(csp::transform_from_array(NE_T_EE)); });
}

void Robot::setLoad(double load_mass, const std::array<double, 3>& F_x_Cload, const std::array<double, 9>& load_inertia) {
  csp::RigidBodyInertia load;
  load.mass = load_mass;
  load.com = from_array<csp::Vector3>(F_x_Cload);
  load.inertia = from_array<csp::Matrix3>(load_inertia);
  configure(*impl_, [&] { impl_->emulator.set_load(load); });
}

void Robot::automaticErrorRecovery() {
  configure(*impl_, [&] { impl_->emulator.automatic_error_recovery(); });
}

std::unique_ptr<ActiveControlBase> Robot::startTorqueControl() {
  std::unique_lock<std::mutex> lock(impl_->control_mutex, std::try_to_lock);
  if (!lock.owns_lock() || impl_->session)
    throw InvalidOperationException(
        "libfranka robot: Cannot perform this operation while another control or read operation is running.");
  impl_->start_motion(ControlMode::kTorque, csp::rt::ControllerMode::kExternalController);
  return std::unique_ptr<ActiveControlBase>(new ActiveTorqueControl(impl_, impl_->motion_id));
}

#define CSP_FRANKA_START_CONTROL(Name, Motion)                                                                \
  std::unique_ptr<ActiveControlBase> Robot::Name(const Move::ControllerMode& control_type) {                  \
    std::unique_lock<std::mutex> lock(impl_->control_mutex, std::try_to_lock);                                 \
    if (!lock.owns_lock() || impl_->session)                                                                   \
      throw InvalidOperationException(                                                                         \
          "libfranka robot: Cannot perform this operation while another control or read operation is running."); \
    impl_->start_motion(kModeOf<Motion>, controller_of(control_type));                                         \
    return std::unique_ptr<ActiveControlBase>(                                                                 \
        new ActiveMotionGenerator<Motion>(impl_, impl_->motion_id, control_type));                             \
  }
CSP_FRANKA_START_CONTROL(startJointPositionControl, JointPositions)
CSP_FRANKA_START_CONTROL(startJointVelocityControl, JointVelocities)
CSP_FRANKA_START_CONTROL(startCartesianPoseControl, CartesianPose)
CSP_FRANKA_START_CONTROL(startCartesianVelocityControl, CartesianVelocities)
#undef CSP_FRANKA_START_CONTROL

void Robot::stop() { impl_->stop_requested = true; }

Model Robot::loadModel() { return Model(std::make_unique<Model::Impl>(impl_->emulator.internal_model())); }

std::string Robot::getRobotModel() {
  return csp::robot_model_urdf(impl_->emulator.internal_model().parameters(), impl_->robot_name);
}

Robot::ServerVersion Robot::serverVersion() const noexcept { return 9; }

}  // namespace franka
