// The library of candidate unmodelled effects. Each is a parametric joint torque the simulator
// model lacks; the measured torque is modelled as predicted + sum of the selected effects' torques.
#pragma once

#include <array>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "csp/gap/part.hpp"

namespace csp::gap {

class Effect {
 public:
  virtual ~Effect() = default;
  virtual std::string name() const = 0;
  virtual int size() const = 0;  // number of fitted parameters
  // The effect's torque along a part for parameters theta, stacked (7 N).
  virtual Eigen::VectorXd torque(const Part& part, const Eigen::VectorXd& theta) const = 0;
  // d torque / d theta (7 N x size); by forward differences unless the effect knows better.
  virtual Eigen::MatrixXd jacobian(const Part& part, const Eigen::VectorXd& theta) const;
  // Where the fit to `target` (stacked torque) starts.
  virtual Eigen::VectorXd initial_guess(const Part& part, const Eigen::VectorXd& target) const = 0;
  // Fitted parameters in physical units, a number or a list of numbers per key (the diagnosis adds
  // each one's bootstrap interval as KEY_sigma and KEY_interval: docs/gap.md, "Uncertainty").
  virtual nlohmann::json describe(const Eigen::VectorXd& theta) const = 0;
  // What the fitted parameters mean physically beyond their values (whether a physical arm realises
  // fitted inertial parameters), for the point estimate only: none unless the effect knows better.
  virtual nlohmann::json consistency(const Eigen::VectorXd&) const { return nlohmann::json::object(); }
};

// An effect linear in its parameters: torque = regressor * theta.
class LinearEffect : public Effect {
 public:
  virtual Eigen::MatrixXd regressor(const Part& part) const = 0;
  Eigen::VectorXd torque(const Part& part, const Eigen::VectorXd& theta) const override;
  Eigen::MatrixXd jacobian(const Part& part, const Eigen::VectorXd& theta) const override;
  Eigen::VectorXd initial_guess(const Part& part, const Eigen::VectorXd& target) const override;
};

inline constexpr std::array<const char*, 13> kEffectNames = {
    "joint_friction", "sensor_offset",   "payload",         "armature",           "base_tilt",
    "time_delay",     "inertial_parameters", "sensor_gain", "position_ripple",    "static_friction",
    "friction_hysteresis", "load_dependent_friction", "thermal_drift"};

// The effects of kEffectNames, in that order. The model is the diagnosing model (for the payload
// frame and the base parameters).
std::vector<std::unique_ptr<Effect>> effect_library(const Model& model);

// joint_friction with each joint's viscous coefficient kept above viscous_floor[j] (f_v = floor +
// exp(v)): the diagnosis refits a verdict with floor = minus the model's own viscous friction when a
// fitted one makes the total negative, which no passive joint has.
std::unique_ptr<Effect> joint_friction_above(const Vector7& viscous_floor);

// inertial_parameters fitted over physical links (the log-Cholesky parametrisation of each link's
// 10 standard parameters; 70 parameters, nonlinear), or null when the model's own links are not
// physical. The diagnosis refits a verdict with it when its linear inertial fit is not physical.
std::unique_ptr<Effect> physical_inertial_parameters(const Model& model);

// The effects' laws, shared by the library (which fits them) and the generator (which injects them
// into "real" logs). Each is one joint's torque [N m].

// joint_friction: Gaz et al. sigmoid plus viscous friction.
double friction_law(double phi1, double phi2, double phi3, double viscous, double dq);

// The sign of a velocity, smoothed over kSignVelocity: sensors never report an exact zero and a
// hard sign would make a fitted law jump with the noise.
inline constexpr double kSignVelocity = 0.005;  // [rad/s]
double smooth_sign(double dq);

// static_friction: the breakaway excess above the Coulomb level near zero velocity (Stribeck),
// excess sgn(dq) exp(-(dq / stribeck_velocity)^2): the plant's law (csp::stribeck_level) with
// smooth_sign. The excess is positive: static friction is never below the sliding level.
double stribeck_excess(double excess, double stribeck_velocity, double dq);

// position_ripple: a torque periodic in the joint's position (harmonic-drive / cogging ripple),
// a sin(2 pi q / period) + b cos(2 pi q / period).
double position_ripple(double a, double b, double period, double q);

// friction_hysteresis: Dahl's friction state z in [-1, 1] (Dahl 1968; Armstrong-Helouvry et al.
// 1994): dz/dq = (1 - z sgn(dq)) / presliding_distance, so the friction force follows position
// with memory after each reversal instead of jumping with the velocity's sign. dahl_state advances z
// over a monotone position step exactly. The effect is the part of Dahl's force the sliding
// (Coulomb) law does not have, amplitude (z - sgn(dq)): zero once the joint has slid well past the
// presliding distance, a lag of the friction behind each reversal before that.
double dahl_state(double z, double position_step, double presliding_distance);
double hysteresis_torque(double amplitude, double z, double dq);

// load_dependent_friction: friction growing with the torque the gear transmits,
// coefficient |tau_transmitted| sgn(dq) (the mesh's normal force grows with the load).
double load_friction(double coefficient, double tau_transmitted, double dq);

}  // namespace csp::gap
