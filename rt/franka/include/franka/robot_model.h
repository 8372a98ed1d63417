// franka::RobotModel (libfranka 0.15): the arm's dynamics built from its URDF, e.g.
// Robot::getRobotModel()'s. libfranka computes with Pinocchio; CSP with its own dynamics, so this
// header shows no Pinocchio type. The URDF's arm must be a chain of 7 revolute joints about z whose
// origins have the modified-DH form (Franka's own URDFs and getRobotModel()'s do); inertials of
// bodies beyond link 7 are not used (the end effector is part of the total load, as in libfranka).
#pragma once

#include <array>
#include <memory>
#include <string>

#include "franka/robot_model_base.h"

namespace franka {

class RobotModel : public RobotModelBase {
 public:
  // Throws std::invalid_argument naming what in `urdf` it cannot use.
  explicit RobotModel(const std::string& urdf);
  ~RobotModel() override;
  RobotModel(const RobotModel&) = delete;
  RobotModel& operator=(const RobotModel&) = delete;

  void coriolis(const std::array<double, 7>& q,
                const std::array<double, 7>& dq,
                const std::array<double, 9>& i_total,
                double m_total,
                const std::array<double, 3>& f_x_ctotal,
                std::array<double, 7>& c_ne) override;
  void gravity(const std::array<double, 7>& q,
               const std::array<double, 3>& g_earth,
               double m_total,
               const std::array<double, 3>& f_x_ctotal,
               std::array<double, 7>& g_ne) override;
  void mass(const std::array<double, 7>& q,
            const std::array<double, 9>& i_total,
            double m_total,
            const std::array<double, 3>& f_x_ctotal,
            std::array<double, 49>& m_ne) override;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace franka
