// franka::Model's implementation: the robot's internal model (csp::Model), rebuilt only when the
// end effector, load or gravity a call asks for changes.
#pragma once

#include <array>

#include "csp/dynamics/algorithms.hpp"
#include "franka/model.h"

namespace franka {

class Model::Impl {
 public:
  explicit Impl(const csp::Model& robot_model);

  // What a call may change in the robot's model.
  struct Configuration {
    std::array<double, 16> F_T_EE{}, EE_T_K{};
    double m_total = 0.0;
    std::array<double, 3> F_x_Ctotal{};
    std::array<double, 9> I_total{};
    std::array<double, 3> gravity_earth{};
    bool operator==(const Configuration&) const = default;
  };

  Configuration of_state(const RobotState& state) const;
  Configuration with_frames(const std::array<double, 16>& F_T_EE, const std::array<double, 16>& EE_T_K) const;
  Configuration with_load(double m_total, const std::array<double, 3>& F_x_Ctotal,
                          const std::array<double, 9>& I_total) const;
  const Configuration& configuration() const { return configuration_; }

  // The robot's model in `configuration`, with forward kinematics at q done. Throws
  // std::invalid_argument for a load no rigid body has.
  const csp::Model& configured(const Configuration& configuration, const std::array<double, 7>& q);
  csp::Data& data() { return data_; }

 private:
  csp::ModelParameters parameters_;   // the robot's parameters; end effector and load come per call
  Configuration configuration_;
  csp::Model model_;
  csp::Data data_;
};

}  // namespace franka
