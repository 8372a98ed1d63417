#include "gap_emulated.hpp"

#include <random>
#include <stdexcept>

#include "csp/gap/effects.hpp"
#include "franka/lowpass_filter.h"
#include "franka/rate_limiting.h"
#include "csp/rt/controllers.hpp"
#include "csp/rt/scenario.hpp"

namespace csp::test {

namespace {

// The arm the emulator integrates: the truth's model, with the injected friction and armature.
ModelParameters plant_parameters(const Model& model, const gap::InjectedEffects& truth) {
  ModelParameters plant = gap::truth_parameters(model, truth);
  if (truth.friction.type != FrictionModel::Type::kNone) {
    if (plant.friction.type != FrictionModel::Type::kNone)
      throw std::invalid_argument("the emulated plant has one sliding friction law: the model and the truth both have one");
    const Vector7 breakaway = plant.friction.breakaway, stribeck_velocity = plant.friction.stribeck_velocity;
    plant.friction = truth.friction;
    plant.friction.breakaway = breakaway, plant.friction.stribeck_velocity = stribeck_velocity;
  }
  plant.friction.breakaway += truth.breakaway_excess;
  if (!truth.breakaway_excess.isZero()) plant.friction.stribeck_velocity.setConstant(truth.stribeck_velocity);
  plant.armature += truth.armature;
  return plant;
}

// Linear interpolation of a series at a fractional index >= 0.
Vector7 interpolate(const std::vector<Vector7>& series, double index) {
  const auto k = std::min(static_cast<std::size_t>(index), series.size() - 2);
  const double w = index - static_cast<double>(k);
  return (1.0 - w) * series[k] + w * series[k + 1];
}

}  // namespace

JointLog generate_emulated_log(const Model& model, const gap::InjectedEffects& truth, unsigned trajectory_seed,
                               unsigned noise_seed, const gap::LogOptions& options) {
  const gap::FourierExcitation excitation(model.parameters().joint_limits, trajectory_seed);
  rt::EmulatorSettings settings;
  settings.plant = plant_parameters(model, truth);
  settings.internal = model.parameters();
  settings.q_initial = excitation.centre();
  settings.tau_J_noise = options.torque_noise;
  settings.tau_J_bias = truth.sensor_offset;
  settings.seed = noise_seed;
  // The injected effects are what the diagnosis is to find, not contacts: the robot's contact and
  // collision detection (its model's external torque estimate sees them) is set out of their way.
  rt::CollisionBehavior& c = settings.collision;
  c.lower_torque_acceleration = c.upper_torque_acceleration = c.lower_torque_nominal = c.upper_torque_nominal =
      Vector7::Constant(100.0);
  c.lower_force_acceleration = c.upper_force_acceleration = c.lower_force_nominal = c.upper_force_nominal =
      Vector6::Constant(100.0);
  if (gap::InjectedJointTorque::present(truth)) {
    settings.extra_joint_torque = [injected = gap::InjectedJointTorque(truth, model, gap::InjectedJointTorque::Dahl::kWhole)](
                                      double t, const Vector7& q, const Vector7& dq, const Vector7& tau_motor) mutable {
      return injected(t - kRampIn, q, dq, tau_motor);
    };
  }
  rt::Emulator emulator(settings);

  // The default scenario's controller (gains, feed-forward) tracking the ramped-in excitation
  // q_d = c + r(t) (x(t) - c), computed with the robot's model as a libfranka controller would.
  const rt::ControllerSpec spec = rt::load_scenario(rt::default_scenario_path()).controller;
  // The command passes libfranka's default low-pass filter (100 Hz) and its torque rate limiter, as
  // Robot::control with limit_rate applies them: the stick-slip of static friction and Dahl's stiff
  // presliding near rest make the damping term jump beyond the robot's torque rate limit.
  Data data;
  double time = 0.0;
  Vector7 last_command = Vector7::Zero();
  const rt::Controller controller = [&](const rt::RobotState& state, rt::Duration period) {
    time += period.toSec();
    Vector7 x, dx, ddx;
    double r, dr, ddr;
    excitation.state(time - kRampIn, x, dx, ddx);
    rt::quintic_ramp(time, kRampIn, r, dr, ddr);
    const Vector7 s = x - excitation.centre();
    Vector7 tau = rt::joint_impedance_torque(emulator.internal_model(), data, spec, excitation.centre() + r * s,
                                             dr * s + r * dx, ddr * s + 2.0 * dr * dx + r * ddx, state);
    if (time > 0.0) {
      std::array<double, kNumJoints> filtered, last;
      for (int j = 0; j < kNumJoints; ++j) {
        filtered[j] = franka::lowpassFilter(rt::kDeltaT, tau[j], last_command[j], franka::kDefaultCutoffFrequency);
        last[j] = last_command[j];
      }
      tau = Vector7(franka::limitRate(franka::kMaxTorqueRate, filtered, last).data());
    }
    last_command = tau;
    return rt::Command{tau};
  };
  std::vector<double> t;
  std::vector<Vector7> q, dq, tau_J;
  rt::LoopOptions loop;
  loop.max_duration = kRampIn + options.duration + rt::kDeltaT;
  loop.observer = [&](const rt::RobotState& state, const rt::CycleInfo&) {
    t.push_back(time);
    q.emplace_back(state.q.data()), dq.emplace_back(state.dq.data()), tau_J.emplace_back(state.tau_J.data());
  };
  const rt::MotionResult result = rt::run_motion(emulator, rt::ControlMode::kTorque, controller, loop);
  if (result.reflex) throw std::runtime_error("the emulated excitation ended in a reflex: " + result.reason);

  std::mt19937_64 engine(noise_seed + 1);  // the emulator's sensor noise uses noise_seed
  std::normal_distribution<double> normal;
  auto noise = [&](double sigma) {
    Vector7 n;
    for (int j = 0; j < kNumJoints; ++j) n[j] = sigma * normal(engine);
    return n;
  };
  JointLog log;
  log.source = "emulated (trajectory seed " + std::to_string(trajectory_seed) + ")";
  for (std::size_t k = 0; k < t.size(); ++k) {
    if (t[k] < kRampIn - 1e-9) continue;
    const double since = t[k] - kRampIn;  // the log's time: the drift begins with it
    log.t.push_back(since);
    log.q.push_back(q[k] + noise(options.position_noise));
    log.dq.push_back(dq[k] + gap::velocity_sensor_error(truth, since) + noise(options.velocity_noise));
    const Vector7 reading = interpolate(tau_J, (t[k] - truth.delay - t.front()) / rt::kDeltaT);
    log.tau_J.push_back(reading + truth.sensor_gain.cwiseProduct(reading) + truth.drift_rate * since);
  }
  return log;
}

}  // namespace csp::test
