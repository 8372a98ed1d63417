// libfranka 0.15's interface of a robot model that computes with a given total load (end effector
// plus load, at the flange): what franka::RobotModel implements. Global namespace, as libfranka's.
#pragma once

#include <array>

class RobotModelBase {
 public:
  virtual ~RobotModelBase() = default;

  // c = C(q, dq) dq [Nm]. i_total: the load's inertia about its centre of mass (3x3, column-major)
  // [kg m^2]; m_total [kg]; f_x_ctotal: its centre of mass in the flange frame [m].
  virtual void coriolis(const std::array<double, 7>& q,
                        const std::array<double, 7>& dq,
                        const std::array<double, 9>& i_total,
                        double m_total,
                        const std::array<double, 3>& f_x_ctotal,
                        std::array<double, 7>& c_ne) = 0;

  // g(q) [Nm] under the gravity vector g_earth [m/s^2] (base frame).
  virtual void gravity(const std::array<double, 7>& q,
                       const std::array<double, 3>& g_earth,
                       double m_total,
                       const std::array<double, 3>& f_x_ctotal,
                       std::array<double, 7>& g_ne) = 0;

  // M(q), 7x7 column-major [kg m^2].
  virtual void mass(const std::array<double, 7>& q,
                    const std::array<double, 9>& i_total,
                    double m_total,
                    const std::array<double, 3>& f_x_ctotal,
                    std::array<double, 49>& m_ne) = 0;
};
