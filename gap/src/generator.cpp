#include "csp/gap/generator.hpp"

#include <cmath>
#include <random>
#include <stdexcept>

#include "csp/dynamics/algorithms.hpp"
#include "csp/gap/effects.hpp"

namespace csp::gap {

namespace {

double uniform(std::mt19937_64& engine, double low, double high) {
  return std::uniform_real_distribution<double>(low, high)(engine);
}
double random_sign(std::mt19937_64& engine) { return uniform(engine, -1.0, 1.0) < 0.0 ? -1.0 : 1.0; }

Matrix3 rotation_x(double a) { return Eigen::AngleAxisd(a, Vector3::UnitX()).toRotationMatrix(); }
Matrix3 rotation_y(double a) { return Eigen::AngleAxisd(a, Vector3::UnitY()).toRotationMatrix(); }

}  // namespace

InjectedEffects realistic_effect(const std::string& name, const Model& model, unsigned seed) {
  std::mt19937_64 engine(seed);
  InjectedEffects truth;
  if (name == "none") return truth;
  if (name == "joint_friction") {  // the ranges of Gaz et al.'s identified Panda sigmoid friction
    truth.friction.type = FrictionModel::Type::kGazSigmoid;
    for (int j = 0; j < kNumJoints; ++j) {
      truth.friction.phi1[j] = uniform(engine, 0.3, 1.2);
      truth.friction.phi2[j] = uniform(engine, 5.0, 17.0);
      truth.friction.phi3[j] = uniform(engine, -0.05, 0.05);
    }
  } else if (name == "sensor_offset") {  // the seed paper's ~0.4 N m
    for (int j = 0; j < kNumJoints; ++j) truth.sensor_offset[j] = random_sign(engine) * uniform(engine, 0.2, 0.5);
  } else if (name == "payload") {  // a tool or object of 0.5-1.5 kg: a solid 8 cm cube off the flange
    truth.payload.mass = uniform(engine, 0.5, 1.5);
    truth.payload.com = Vector3(uniform(engine, -0.03, 0.03), uniform(engine, -0.03, 0.03), uniform(engine, 0.03, 0.1));
    truth.payload.inertia = truth.payload.mass * 0.08 * 0.08 / 6.0 * Matrix3::Identity();
  } else if (name == "armature") {  // reflected rotor inertia
    for (int j = 0; j < kNumJoints; ++j) truth.armature[j] = uniform(engine, 0.03, 0.1);
  } else if (name == "base_tilt") {  // a mounting plate off level by 0.3-1 degree per axis
    truth.tilt_x = random_sign(engine) * uniform(engine, 0.3, 1.0) * M_PI / 180.0;
    truth.tilt_y = random_sign(engine) * uniform(engine, 0.3, 1.0) * M_PI / 180.0;
  } else if (name == "time_delay") {  // a few 1 kHz cycles between torque sensing and motion
    truth.delay = uniform(engine, 0.002, 0.005);
  } else if (name == "inertial_parameters") {  // masses +-10 %, CoM +-1 cm, inertia +-20 %
    std::array<RigidBodyInertia, kNumJoints> links = model.parameters().links;
    for (RigidBodyInertia& link : links) {
      link.mass *= 1.0 + uniform(engine, -0.1, 0.1);
      for (int k = 0; k < 3; ++k) link.com[k] += uniform(engine, -0.01, 0.01);
      link.inertia *= 1.0 + uniform(engine, -0.2, 0.2);
    }
    truth.links = links;
  } else if (name == "sensor_gain") {  // torque-sensor calibration off by 3-8 %
    for (int j = 0; j < kNumJoints; ++j) truth.sensor_gain[j] = random_sign(engine) * uniform(engine, 0.03, 0.08);
  } else if (name == "position_ripple") {  // gear / cogging ripple, periods the 10 Hz filter passes
    for (int j = 0; j < kNumJoints; ++j) {
      truth.ripple_amplitude[j] = uniform(engine, 0.2, 0.5);
      truth.ripple_period[j] = uniform(engine, 0.15, 0.6);
      truth.ripple_phase[j] = uniform(engine, 0.0, 2.0 * M_PI);
    }
  } else if (name == "static_friction") {  // breakaway 0.5-1 N m above the sliding level
    for (int j = 0; j < kNumJoints; ++j) truth.breakaway_excess[j] = uniform(engine, 0.5, 1.0);
    truth.stribeck_velocity = uniform(engine, 0.03, 0.08);
  } else if (name == "friction_hysteresis") {  // presliding memory of 0.3-0.8 N m over 5-30 mrad
    for (int j = 0; j < kNumJoints; ++j) truth.hysteresis_amplitude[j] = uniform(engine, 0.3, 0.8);
    truth.presliding_distance = uniform(engine, 0.005, 0.03);
  } else if (name == "load_dependent_friction") {  // 2-5 % of the transmitted torque
    for (int j = 0; j < kNumJoints; ++j) truth.load_friction[j] = uniform(engine, 0.02, 0.05);
  } else if (name == "thermal_drift") {  // warm-up after power-on: 1-3 N m per minute
    for (int j = 0; j < kNumJoints; ++j) truth.drift_rate[j] = random_sign(engine) * uniform(engine, 1.0, 3.0) / 60.0;
  } else {
    throw std::invalid_argument("unknown effect `" + name + "`");
  }
  return truth;
}

InjectedEffects outside_library_effect(const std::string& kind, const Model& model, unsigned seed) {
  std::mt19937_64 engine(seed);
  InjectedEffects truth;
  // A vibration of joint 1 + (seed + shift) % 7, amplitude [N m] and frequency [Hz] drawn uniformly.
  auto vibration = [&](unsigned shift, double amplitude_low, double amplitude_high, double low, double high) {
    truth.vibration_joint = 1 + static_cast<int>((seed + shift) % kNumJoints);
    truth.vibration_amplitude = uniform(engine, amplitude_low, amplitude_high);
    truth.vibration_frequency = uniform(engine, low, high);
  };
  if (kind == "vibration") {
    vibration(0, 0.4, 0.7, 2.0, 3.0);
  } else if (kind == "configuration_vibration") {
    vibration(3, 0.4, 0.7, 3.0, 4.5);
    truth.vibration_configuration = 0.8;
  } else if (kind == "speed_rumble") {
    vibration(5, 0.5, 0.8, 6.0, 9.0);
    truth.vibration_speed = 1.0;
  } else if (kind == "velocity_sensor_ripple") {
    truth.velocity_ripple_joint = 1 + static_cast<int>(seed % 4);
    truth.velocity_ripple_amplitude = uniform(engine, 0.01, 0.02);
    truth.velocity_ripple_frequency = uniform(engine, 8.0, 12.0);
  } else if (kind == "reversal_ringing") {
    truth.ringing_joint = 1 + static_cast<int>((seed + 2) % kNumJoints);
    truth.ringing_amplitude = uniform(engine, 0.5, 1.0);
    truth.ringing_frequency = uniform(engine, 5.0, 8.0);
    truth.ringing_decay = uniform(engine, 0.2, 0.4);
  } else if (kind == "position_catch") {
    const JointLimits& limits = model.parameters().joint_limits;
    const int j = static_cast<int>((seed + 4) % kNumJoints);
    truth.catch_joint = j + 1;
    truth.catch_amplitude = uniform(engine, 1.0, 2.0);
    truth.catch_position = 0.5 * (limits.q_min[j] + limits.q_max[j]) + uniform(engine, -0.1, 0.1) * (limits.q_max[j] - limits.q_min[j]);
    truth.catch_width = uniform(engine, 0.06, 0.1);
  } else if (kind == "base_shake") {
    const double direction = uniform(engine, 0.0, 2.0 * M_PI);
    truth.base_shake = uniform(engine, 0.3, 0.5) * Vector3(std::cos(direction), std::sin(direction), 0.0);
    truth.base_shake_frequency = uniform(engine, 6.0, 9.0);
  } else {
    throw std::invalid_argument("unknown outside-library effect `" + kind + "`");
  }
  return truth;
}

Vector7 velocity_sensor_error(const InjectedEffects& truth, double t) {
  Vector7 error = Vector7::Zero();
  if (truth.velocity_ripple_joint)
    error[truth.velocity_ripple_joint - 1] =
        truth.velocity_ripple_amplitude * std::sin(2.0 * M_PI * truth.velocity_ripple_frequency * t);
  return error;
}

InjectedEffects merged(const InjectedEffects& a, const InjectedEffects& b) {
  InjectedEffects m = a;
  if (b.friction.type != FrictionModel::Type::kNone) m.friction = b.friction, m.friction_trend = b.friction_trend;
  m.sensor_offset += b.sensor_offset;
  if (b.payload.mass > 0.0) m.payload = b.payload;
  m.armature += b.armature;
  m.tilt_x += b.tilt_x, m.tilt_y += b.tilt_y, m.delay += b.delay;
  if (b.links) m.links = b.links;
  m.sensor_gain += b.sensor_gain;
  if (!b.base_shake.isZero()) m.base_shake = b.base_shake, m.base_shake_frequency = b.base_shake_frequency;
  if (!b.ripple_amplitude.isZero())
    m.ripple_amplitude = b.ripple_amplitude, m.ripple_period = b.ripple_period, m.ripple_phase = b.ripple_phase;
  if (!b.breakaway_excess.isZero()) m.breakaway_excess = b.breakaway_excess, m.stribeck_velocity = b.stribeck_velocity;
  if (!b.hysteresis_amplitude.isZero())
    m.hysteresis_amplitude = b.hysteresis_amplitude, m.presliding_distance = b.presliding_distance;
  m.load_friction += b.load_friction;
  m.drift_rate += b.drift_rate;
  if (b.vibration_joint)
    m.vibration_joint = b.vibration_joint, m.vibration_amplitude = b.vibration_amplitude,
    m.vibration_frequency = b.vibration_frequency, m.vibration_configuration = b.vibration_configuration,
    m.vibration_speed = b.vibration_speed;
  if (b.ringing_joint)
    m.ringing_joint = b.ringing_joint, m.ringing_amplitude = b.ringing_amplitude,
    m.ringing_frequency = b.ringing_frequency, m.ringing_decay = b.ringing_decay;
  if (b.catch_joint)
    m.catch_joint = b.catch_joint, m.catch_amplitude = b.catch_amplitude, m.catch_position = b.catch_position,
    m.catch_width = b.catch_width;
  if (b.velocity_ripple_joint)
    m.velocity_ripple_joint = b.velocity_ripple_joint, m.velocity_ripple_amplitude = b.velocity_ripple_amplitude,
    m.velocity_ripple_frequency = b.velocity_ripple_frequency;
  return m;
}

FourierExcitation::FourierExcitation(const JointLimits& limits, unsigned seed, double period)
    : omega_(2.0 * M_PI / period) {
  std::mt19937_64 engine(seed);
  std::normal_distribution<double> normal;
  centre_ = 0.5 * (limits.q_min + limits.q_max);
  for (int j = 0; j < kNumJoints; ++j)
    for (int l = 0; l < kHarmonics; ++l) a_(j, l) = normal(engine) / (l + 1), b_(j, l) = normal(engine) / (l + 1);
  // Peaks over one period on a fine grid, then one scale per joint.
  Vector7 q_peak = Vector7::Zero(), dq_peak = Vector7::Zero(), ddq_peak = Vector7::Zero();
  for (int k = 0; k < 2000; ++k) {
    Vector7 q, dq, ddq;
    state(period * k / 2000.0, q, dq, ddq);
    q_peak = q_peak.cwiseMax((q - centre_).cwiseAbs()), dq_peak = dq_peak.cwiseMax(dq.cwiseAbs());
    ddq_peak = ddq_peak.cwiseMax(ddq.cwiseAbs());
  }
  for (int j = 0; j < kNumJoints; ++j) {
    const double scale = std::min({0.4 * (limits.q_max[j] - limits.q_min[j]) / q_peak[j],
                                   0.7 * limits.dq_max[j] / dq_peak[j], 0.4 * limits.ddq_max[j] / ddq_peak[j]});
    a_.row(j) *= scale, b_.row(j) *= scale;
  }
}

void FourierExcitation::state(double t, Vector7& q, Vector7& dq, Vector7& ddq) const {
  q = centre_, dq.setZero(), ddq.setZero();
  for (int l = 0; l < kHarmonics; ++l) {
    const double w = (l + 1) * omega_, s = std::sin(w * t), c = std::cos(w * t);
    q += a_.col(l) * s + b_.col(l) * c;
    dq += w * (a_.col(l) * c - b_.col(l) * s);
    ddq -= w * w * (a_.col(l) * s + b_.col(l) * c);
  }
}

LogOptions noise_free(LogOptions options) {
  options.torque_noise.setZero();
  options.velocity_noise = options.position_noise = 0.0;
  return options;
}

ModelParameters truth_parameters(const Model& model, const InjectedEffects& truth) {
  ModelParameters p = model.parameters();
  if (truth.links) p.links = *truth.links;
  p.load = combine(p.load, truth.payload);
  p.gravity = rotation_x(truth.tilt_x) * rotation_y(truth.tilt_y) * p.gravity;
  return p;
}

InjectedJointTorque::InjectedJointTorque(const InjectedEffects& truth, const Model& model, Dahl dahl)
    : truth_(truth), dahl_(dahl) {
  if (truth.base_shake.isZero()) return;
  ModelParameters shaken = truth_parameters(model, truth);
  shaken.gravity = -truth.base_shake;
  shaken_.emplace(shaken);
}

bool InjectedJointTorque::present(const InjectedEffects& truth) {
  return !truth.ripple_amplitude.isZero() || !truth.hysteresis_amplitude.isZero() || !truth.load_friction.isZero() ||
         truth.vibration_joint != 0 || truth.ringing_joint != 0 || truth.catch_joint != 0 ||
         !truth.base_shake.isZero() || truth.friction_trend != 0.0;
}

Vector7 InjectedJointTorque::operator()(double t, const Vector7& q, const Vector7& dq, const Vector7& tau_transmitted) {
  Vector7 tau;
  for (int j = 0; j < kNumJoints; ++j) {
    z_[j] = started_ ? dahl_state(z_[j], q[j] - q_previous_[j], truth_.presliding_distance) : smooth_sign(dq[j]);
    tau[j] = position_ripple(truth_.ripple_amplitude[j] * std::cos(truth_.ripple_phase[j]),
                             truth_.ripple_amplitude[j] * std::sin(truth_.ripple_phase[j]), truth_.ripple_period[j], q[j]) +
             (dahl_ == Dahl::kWhole ? truth_.hysteresis_amplitude[j] * z_[j]
                                    : hysteresis_torque(truth_.hysteresis_amplitude[j], z_[j], dq[j])) +
             load_friction(truth_.load_friction[j], tau_transmitted[j], dq[j]);
  }
  if (truth_.ringing_joint) {
    const int j = truth_.ringing_joint - 1;
    if (started_ && dq[j] * dq_previous_ < 0.0) last_reversal_ = t;
    dq_previous_ = dq[j];
    const double since = t - last_reversal_;
    tau[j] += truth_.ringing_amplitude * std::exp(-since / truth_.ringing_decay) *
              std::sin(2.0 * M_PI * truth_.ringing_frequency * since);
  }
  if (truth_.catch_joint) {
    const int j = truth_.catch_joint - 1;
    const double from = (q[j] - truth_.catch_position) / truth_.catch_width;
    if (std::abs(from) < 0.5) tau[j] -= truth_.catch_amplitude * std::copysign(std::pow(std::cos(M_PI * from), 2), dq[j]);
  }
  // The added friction's change since the log began (on the emulated robot, its plant's friction is
  // the added one at t = 0).
  tau += truth_.friction_trend * t * friction_torque(truth_.friction, dq);
  started_ = true;
  q_previous_ = q;
  if (truth_.vibration_joint) {
    const int j = truth_.vibration_joint - 1;
    double amplitude = truth_.vibration_amplitude * (1.0 + truth_.vibration_configuration * std::cos(2.0 * q[1]));
    if (truth_.vibration_speed > 0.0) amplitude *= std::abs(dq[j]) / truth_.vibration_speed;
    tau[j] += amplitude * std::sin(2.0 * M_PI * truth_.vibration_frequency * t);
  }
  if (shaken_) {
    Vector7 g;
    gravity_torque(*shaken_, data_, q, g);
    tau += g * std::sin(2.0 * M_PI * truth_.base_shake_frequency * t);
  }
  return tau;
}

JointLog generate_log(const Model& model, const InjectedEffects& truth, unsigned trajectory_seed, unsigned noise_seed,
                      const LogOptions& options) {
  const ModelParameters p = truth_parameters(model, truth);
  const Model true_model(p);
  const FourierExcitation trajectory(p.joint_limits, trajectory_seed);

  std::mt19937_64 engine(noise_seed);
  std::normal_distribution<double> normal;
  auto noise = [&](const Vector7& sigma) {
    Vector7 n;
    for (int j = 0; j < kNumJoints; ++j) n[j] = sigma[j] * normal(engine);
    return n;
  };
  JointLog log;
  log.source = "generated (trajectory seed " + std::to_string(trajectory_seed) + ")";
  Data data;
  const double dt = 1.0 / options.rate;
  InjectedJointTorque injected(truth, model);
  for (double t = 0.0; t <= options.duration; t += dt * (1.0 + uniform(engine, -0.1, 0.1))) {
    Vector7 q, dq, ddq, rigid;
    trajectory.state(t, q, dq, ddq);
    log.t.push_back(t);
    log.q.push_back(q + noise(Vector7::Constant(options.position_noise)));
    log.dq.push_back(dq + velocity_sensor_error(truth, t) + noise(Vector7::Constant(options.velocity_noise)));
    trajectory.state(t - truth.delay, q, dq, ddq);  // the torque the sensor reports now
    rnea(true_model, data, q, dq, ddq, rigid);
    Vector7 tau = rigid + friction_torque(p.friction, dq) + friction_torque(truth.friction, dq) +
                  truth.armature.cwiseProduct(ddq) + injected(t - truth.delay, q, dq, rigid);
    for (int j = 0; j < kNumJoints; ++j)
      tau[j] += stribeck_excess(truth.breakaway_excess[j], truth.stribeck_velocity, dq[j]);
    // What the sensor reports: scaled, offset, drifting since the log began.
    tau = tau + truth.sensor_gain.cwiseProduct(tau) + truth.sensor_offset + truth.drift_rate * t;
    log.tau_J.push_back(tau + noise(options.torque_noise));
  }
  return log;
}

}  // namespace csp::gap
