// "Real" logs for checking the diagnosis on data whose effect is known: a truth model = the
// diagnosing model plus injected effects, driven along a Fourier excitation trajectory within the
// joint limits, with sensor noise like the real Panda log's. Built on the dynamics core only (the
// same check with the emulated robot in the way is tests/gap_emulated.hpp: gap does not link rt).
#pragma once

#include <optional>
#include <string>

#include "csp/dynamics/model.hpp"
#include "csp/io/joint_log.hpp"

namespace csp::gap {

// What the truth has that the diagnosing model lacks. Zero / empty = absent.
struct InjectedEffects {
  FrictionModel friction;                                         // added to the model's own friction
  Vector7 sensor_offset = Vector7::Zero();                        // [N m]
  RigidBodyInertia payload;                                       // on the flange, combined with the model's load
  Vector7 armature = Vector7::Zero();                             // [kg m^2]
  double tilt_x = 0.0, tilt_y = 0.0;                              // base rotation about base x, then y [rad]
  double delay = 0.0;                                             // the torque sensor reads tau(t - delay) [s]
  std::optional<std::array<RigidBodyInertia, kNumJoints>> links;  // the true inertial parameters
  Vector7 sensor_gain = Vector7::Zero();                          // the sensor reads (1 + g) tau
  Vector7 ripple_amplitude = Vector7::Zero();                     // [N m], periodic in q
  Vector7 ripple_period = Vector7::Ones();                        // [rad]
  Vector7 ripple_phase = Vector7::Zero();                         // [rad]
  Vector7 breakaway_excess = Vector7::Zero();                     // static friction above Coulomb [N m]
  double stribeck_velocity = 0.05;                                // [rad/s]
  Vector7 hysteresis_amplitude = Vector7::Zero();                 // Dahl friction's memory [N m]
  double presliding_distance = 0.02;                              // [rad]
  Vector7 load_friction = Vector7::Zero();                        // friction per N m transmitted
  Vector7 drift_rate = Vector7::Zero();                           // sensor offset drift [N m/s]
  double friction_trend = 0.0;  // the added friction scales by 1 + friction_trend t [1/s] (warming grease)
  // Outside every library effect on purpose (the check that the diagnosis names no false cause and
  // localises what it cannot name): a structural vibration of one joint, its amplitude constant, or
  // following the configuration (times 1 + vibration_configuration cos(2 q2): the arm's stiffness
  // changes with the shoulder's angle), or the joint's speed (times |dq_j| / vibration_speed: a
  // rumble growing with speed);
  int vibration_joint = 0;                                        // 1..7; 0 = none
  double vibration_amplitude = 0.0, vibration_frequency = 0.0;    // [N m], [Hz]
  double vibration_configuration = 0.0, vibration_speed = 0.0;    // [-], [rad/s]; 0 = not
  // a ringing of one joint after each of its velocity reversals (its elasticity: a decaying sinusoid,
  // amplitude [N m] at the reversal, frequency [Hz], decay time [s]);
  int ringing_joint = 0;                                          // 1..7; 0 = none
  double ringing_amplitude = 0.0, ringing_frequency = 0.0, ringing_decay = 0.0;
  // a catch of one joint at one position (a cable or hose that snags there, a damaged tooth): a
  // bump against the motion, -catch_amplitude sgn(dq) cos^2(pi (q - catch_position) / catch_width)
  // within catch_width / 2 of the position;
  int catch_joint = 0;                                            // 1..7; 0 = none
  double catch_amplitude = 0.0, catch_position = 0.0, catch_width = 0.0;  // [N m], [rad], [rad]
  // the base shaken along a horizontal direction (the table or cart a machine beside it sets
  // vibrating): its acceleration a(t) = base_shake sin(2 pi base_shake_frequency t) acts on every link
  // as a gravity of -a(t) (the base frame is not inertial), so each joint's sensor reads the gravity
  // torque of that field: one mode on several joints, its amplitude following the configuration;
  Vector3 base_shake = Vector3::Zero();                           // [m/s^2] amplitude per base axis
  double base_shake_frequency = 0.0;                              // [Hz]
  // and a ripple of a velocity sensor: the logged dq of one joint reads a sinusoid the motion has not.
  int velocity_ripple_joint = 0;                                  // 1..7; 0 = none
  double velocity_ripple_amplitude = 0.0, velocity_ripple_frequency = 0.0;  // [rad/s], [Hz]
};

// One effect of the library (docs/gap.md lists the sizes), or "none", drawn with `seed`.
InjectedEffects realistic_effect(const std::string& name, const Model& model, unsigned seed);
// An effect kept out of the library, drawn with `seed`:
// - "vibration": 0.4-0.7 N m at 2-3 Hz on joint 1 + seed % 7;
// - "configuration_vibration": 0.4-0.7 N m at 3-4.5 Hz following the configuration (depth 0.8) on
//   joint 1 + (seed + 3) % 7;
// - "speed_rumble": 0.5-0.8 N m per rad/s at 6-9 Hz on joint 1 + (seed + 5) % 7;
// - "velocity_sensor_ripple": 0.01-0.02 rad/s at 8-12 Hz in the velocity of joint 1 + seed % 4;
// - "reversal_ringing": 0.5-1 N m at 5-8 Hz decaying over 0.2-0.4 s after each velocity reversal of
//   joint 1 + (seed + 2) % 7;
// - "position_catch": 1-2 N m over 0.06-0.1 rad at a position within 10 % of the range of the middle
//   of joint 1 + (seed + 4) % 7's limits (the excitation's centre, which it crosses again and again);
// - "base_shake": the base shaken at 6-9 Hz with 0.3-0.5 m/s^2 along a horizontal direction drawn
//   uniformly.
InjectedEffects outside_library_effect(const std::string& kind, const Model& model, unsigned seed);
// What the velocity sensors read beyond the motion's dq at time t.
Vector7 velocity_sensor_error(const InjectedEffects& truth, double t);
// Both injections (each sets different fields).
InjectedEffects merged(const InjectedEffects& a, const InjectedEffects& b);

// The truth's model: the diagnosing model with the injected links, payload and base tilt (its
// friction stays the model's: the injected friction is added by each generator).
ModelParameters truth_parameters(const Model& model, const InjectedEffects& truth);

// The injected effects that are physical joint torques beyond a rigid-body model with sliding and
// static friction: position ripple, Dahl hysteresis, load-dependent friction, the added friction's
// trend and the outside-library vibration, ringing, catch and base shake. Both generators use it: the
// dynamics core's adds it to the truth's inverse dynamics, the emulated robot's plant takes it as its
// extra joint torque (csp::rt::PlantTorque). Allocation-free.
class InjectedJointTorque {
 public:
  // Dahl's friction as the library's friction_hysteresis effect has it (the part beyond the sliding
  // law, amplitude (z - sgn(dq))), or whole (amplitude z: the physical friction, passive, which a
  // plant integrated in closed loop needs; the excess alone is an anti-friction near rest).
  enum class Dahl { kBeyondSliding, kWhole };
  // `model` is the diagnosing model (the truth's rigid body, for the base shake).
  InjectedJointTorque(const InjectedEffects& truth, const Model& model, Dahl dahl = Dahl::kBeyondSliding);
  // At time t [s] and joint state (q, dq), tau_transmitted the torque the gears transmit. Calls
  // follow the motion in time: each advances Dahl's friction state from the last call's position.
  Vector7 operator()(double t, const Vector7& q, const Vector7& dq, const Vector7& tau_transmitted);
  // Whether the truth has any of these effects.
  static bool present(const InjectedEffects& truth);

 private:
  InjectedEffects truth_;
  Dahl dahl_;
  std::optional<Model> shaken_;  // the truth's arm under a gravity of -base_shake (its torque per unit sin)
  Data data_;
  bool started_ = false;
  Vector7 z_ = Vector7::Zero(), q_previous_ = Vector7::Zero();  // Dahl's state and where it was
  double last_reversal_ = -1e9, dq_previous_ = 0.0;             // of the ringing joint [s], [rad/s]
};

// The generator's excitation: a finite Fourier series per joint (as Gaz et al.'s real trajectories),
// q(t) = centre + sum_l a_l sin(l w t) + b_l cos(l w t), l = 1..5, scaled per joint to stay within
// 80 % of the position range, 70 % of the velocity limit and 40 % of the acceleration limit.
// The planner (planners/) will own excitation trajectories; this one then moves there.
class FourierExcitation {
 public:
  FourierExcitation(const JointLimits& limits, unsigned seed, double period = 10.0);
  void state(double t, Vector7& q, Vector7& dq, Vector7& ddq) const;
  const Vector7& centre() const { return centre_; }  // the series oscillates about it

 private:
  static constexpr int kHarmonics = 5;
  Vector7 centre_;
  Eigen::Matrix<double, kNumJoints, kHarmonics> a_, b_;
  double omega_;
};

struct LogOptions {
  double duration = 10.0;  // [s]
  double rate = 1000.0;    // [Hz], time stamps jittered by +-10 %
  // Noise standard deviations, as estimated on the real log (Savitzky-Golay residual).
  Vector7 torque_noise = (Vector7() << 0.26, 0.37, 0.22, 0.35, 0.094, 0.11, 0.034).finished();
  double velocity_noise = 0.006;  // [rad/s]
  double position_noise = 1e-4;   // [rad]
};

// The same options without any noise (for checks against the truth).
LogOptions noise_free(LogOptions options);

JointLog generate_log(const Model& model, const InjectedEffects& truth, unsigned trajectory_seed, unsigned noise_seed,
                      const LogOptions& options = {});

}  // namespace csp::gap
