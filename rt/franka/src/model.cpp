#include "franka/model.h"

#include "csp/dynamics/algorithms.hpp"

namespace franka {
namespace {

csp::Vector7 vector7(const std::array<double, 7>& a) { return csp::Vector7(a.data()); }

csp::Transform transform(const std::array<double, 16>& column_major) {
  const Eigen::Map<const Eigen::Matrix4d> m(column_major.data());
  csp::Transform t;
  t.rotation = m.topLeftCorner<3, 3>();
  t.translation = m.topRightCorner<3, 1>();
  return t;
}

template <std::size_t N, typename Derived>
std::array<double, N> column_major(const Eigen::MatrixBase<Derived>& matrix) {
  std::array<double, N> out{};
  Eigen::Map<Eigen::Matrix<double, Derived::RowsAtCompileTime, Derived::ColsAtCompileTime>>(out.data()) = matrix;
  return out;
}

std::array<double, 7> array7(const csp::Vector7& v) { return column_major<7>(v); }

}  // namespace

Frame operator++(Frame& frame, int /* dummy */) noexcept {
  const Frame before = frame;
  frame = static_cast<Frame>(static_cast<int>(frame) + 1);
  return before;
}

Model::Model(const csp::Model& robot_model) : parameters_(robot_model.parameters()), model_(robot_model) {
  const csp::ModelParameters& p = robot_model.parameters();
  const csp::RigidBodyInertia& total = robot_model.total_flange_load();
  configuration_.F_T_EE = column_major<16>(p.F_T_EE.matrix());
  configuration_.EE_T_K = column_major<16>(p.EE_T_K.matrix());
  configuration_.m_total = total.mass;
  configuration_.F_x_Ctotal = column_major<3>(total.com);
  configuration_.I_total = column_major<9>(total.inertia);
  configuration_.gravity_earth = column_major<3>(p.gravity);
  // The flange carries one body per call (libfranka's total load): end effector and load merged.
  parameters_.end_effector = {};
  parameters_.load = total;
}

Model::Configuration Model::of_state(const RobotState& state) const {
  Configuration c = configuration_;
  c.F_T_EE = state.F_T_EE;
  c.EE_T_K = state.EE_T_K;
  c.m_total = state.m_total;
  c.F_x_Ctotal = state.F_x_Ctotal;
  c.I_total = state.I_total;
  return c;
}

Model::Configuration Model::with_frames(const std::array<double, 16>& F_T_EE, const std::array<double, 16>& EE_T_K) const {
  Configuration c = configuration_;
  c.F_T_EE = F_T_EE;
  c.EE_T_K = EE_T_K;
  return c;
}

Model::Configuration Model::with_load(double m_total, const std::array<double, 3>& F_x_Ctotal,
                                      const std::array<double, 9>& I_total) const {
  Configuration c = configuration_;
  c.m_total = m_total;
  c.F_x_Ctotal = F_x_Ctotal;
  c.I_total = I_total;
  return c;
}

const csp::Model& Model::configured(const Configuration& configuration, const std::array<double, 7>& q) const {
  if (!(configuration == configuration_)) {
    csp::ModelParameters p = parameters_;
    p.F_T_EE = transform(configuration.F_T_EE);
    p.EE_T_K = transform(configuration.EE_T_K);
    p.load.mass = configuration.m_total;
    p.load.com = csp::Vector3(configuration.F_x_Ctotal.data());
    p.load.inertia = Eigen::Map<const csp::Matrix3>(configuration.I_total.data());
    p.gravity = csp::Vector3(configuration.gravity_earth.data());
    model_ = csp::Model(p);   // throws std::invalid_argument for an invalid load
    configuration_ = configuration;
  }
  csp::forward_kinematics(model_, data_, vector7(q));
  return model_;
}

std::array<double, 16> Model::pose(Frame frame, const RobotState& robot_state) const {
  configured(of_state(robot_state), robot_state.q);
  return column_major<16>(csp::frame_pose(data_, static_cast<csp::Frame>(frame)).matrix());
}

std::array<double, 16> Model::pose(Frame frame, const std::array<double, 7>& q, const std::array<double, 16>& F_T_EE,
                                   const std::array<double, 16>& EE_T_K) const {
  configured(with_frames(F_T_EE, EE_T_K), q);
  return column_major<16>(csp::frame_pose(data_, static_cast<csp::Frame>(frame)).matrix());
}

std::array<double, 42> Model::jacobian(Frame frame, bool body, const Configuration& configuration,
                                       const std::array<double, 7>& q) const {
  configured(configuration, q);
  csp::Matrix6x7 J;
  if (body) csp::body_jacobian(data_, static_cast<csp::Frame>(frame), J);
  else csp::zero_jacobian(data_, static_cast<csp::Frame>(frame), J);
  return column_major<42>(J);
}

std::array<double, 42> Model::bodyJacobian(Frame frame, const RobotState& robot_state) const {
  return jacobian(frame, true, of_state(robot_state), robot_state.q);
}

std::array<double, 42> Model::bodyJacobian(Frame frame, const std::array<double, 7>& q,
                                           const std::array<double, 16>& F_T_EE,
                                           const std::array<double, 16>& EE_T_K) const {
  return jacobian(frame, true, with_frames(F_T_EE, EE_T_K), q);
}

std::array<double, 42> Model::zeroJacobian(Frame frame, const RobotState& robot_state) const {
  return jacobian(frame, false, of_state(robot_state), robot_state.q);
}

std::array<double, 42> Model::zeroJacobian(Frame frame, const std::array<double, 7>& q,
                                           const std::array<double, 16>& F_T_EE,
                                           const std::array<double, 16>& EE_T_K) const {
  return jacobian(frame, false, with_frames(F_T_EE, EE_T_K), q);
}

std::array<double, 49> Model::mass(const RobotState& robot_state) const {
  return mass(robot_state.q, robot_state.I_total, robot_state.m_total, robot_state.F_x_Ctotal);
}

std::array<double, 49> Model::mass(const std::array<double, 7>& q, const std::array<double, 9>& I_total, double m_total,
                                   const std::array<double, 3>& F_x_Ctotal) const {
  csp::crba(configured(with_load(m_total, F_x_Ctotal, I_total), q), data_, vector7(q));
  return column_major<49>(data_.mass_matrix);
}

std::array<double, 7> Model::coriolis(const RobotState& robot_state) const {
  return coriolis(robot_state.q, robot_state.dq, robot_state.I_total, robot_state.m_total, robot_state.F_x_Ctotal);
}

std::array<double, 7> Model::coriolis(const std::array<double, 7>& q, const std::array<double, 7>& dq,
                                      const std::array<double, 9>& I_total, double m_total,
                                      const std::array<double, 3>& F_x_Ctotal) const {
  csp::Vector7 c;
  csp::coriolis_torque(configured(with_load(m_total, F_x_Ctotal, I_total), q), data_, vector7(q), vector7(dq), c);
  return array7(c);
}

std::array<double, 7> Model::gravity(const std::array<double, 7>& q, double m_total,
                                     const std::array<double, 3>& F_x_Ctotal,
                                     const std::array<double, 3>& gravity_earth) const {
  // Gravity does not depend on the load's inertia: keeping the cached one avoids a rebuild when
  // calls alternate with the state-based overloads.
  Configuration c = with_load(m_total, F_x_Ctotal, configuration_.I_total);
  c.gravity_earth = gravity_earth;
  csp::Vector7 g;
  csp::gravity_torque(configured(c, q), data_, vector7(q), g);
  return array7(g);
}

std::array<double, 7> Model::gravity(const RobotState& robot_state, const std::array<double, 3>& gravity_earth) const {
  return gravity(robot_state.q, robot_state.m_total, robot_state.F_x_Ctotal, gravity_earth);
}

}  // namespace franka
