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
  // Fitted parameters with their standard deviations, in physical units.
  virtual nlohmann::json describe(const Eigen::VectorXd& theta, const Eigen::VectorXd& sigma) const = 0;
};

// An effect linear in its parameters: torque = regressor * theta.
class LinearEffect : public Effect {
 public:
  virtual Eigen::MatrixXd regressor(const Part& part) const = 0;
  Eigen::VectorXd torque(const Part& part, const Eigen::VectorXd& theta) const override;
  Eigen::MatrixXd jacobian(const Part& part, const Eigen::VectorXd& theta) const override;
  Eigen::VectorXd initial_guess(const Part& part, const Eigen::VectorXd& target) const override;
};

inline constexpr std::array<const char*, 7> kEffectNames = {
    "joint_friction", "sensor_offset", "payload", "armature", "base_tilt", "time_delay", "inertial_parameters"};

// joint_friction, sensor_offset, payload, armature, base_tilt, time_delay, inertial_parameters,
// in this order. The model is the diagnosing model (for the payload frame and the base parameters).
std::vector<std::unique_ptr<Effect>> effect_library(const Model& model);

// Gaz et al. sigmoid plus viscous friction of one joint: the joint_friction effect's law.
double friction_law(double phi1, double phi2, double phi3, double viscous, double dq);

}  // namespace csp::gap
