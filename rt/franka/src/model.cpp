#include "franka/model.h"

#include <limits>
#include <stdexcept>

#include "csp/dynamics/arrays.hpp"
#include "model_impl.hpp"

namespace franka {
namespace {

using csp::from_array;
using csp::to_array;

// noexcept results for a load no rigid body has: NaN everywhere (control() refuses them).
template <std::size_t N, typename Compute>
std::array<double, N> or_nan(Compute compute) noexcept {
  try {
    return compute();
  } catch (const std::exception&) {
    std::array<double, N> nan;
    nan.fill(std::numeric_limits<double>::quiet_NaN());
    return nan;
  }
}

}  // namespace

Frame operator++(Frame& frame, int /* dummy */) noexcept {
  const Frame before = frame;
  frame = static_cast<Frame>(static_cast<int>(frame) + 1);
  return before;
}

Model::Impl::Impl(const csp::Model& robot_model) : parameters_(robot_model.parameters()), model_(robot_model) {
  const csp::ModelParameters& p = robot_model.parameters();
  const csp::RigidBodyInertia& total = robot_model.total_flange_load();
  configuration_.F_T_EE = to_array(p.F_T_EE);
  configuration_.EE_T_K = to_array(p.EE_T_K);
  configuration_.m_total = total.mass;
  configuration_.F_x_Ctotal = to_array(total.com);
  configuration_.I_total = to_array(total.inertia);
  configuration_.gravity_earth = to_array(p.gravity);
  // The flange carries one body per call (libfranka's total load): end effector and load merged.
  parameters_.end_effector = {};
  parameters_.load = total;
}

Model::Impl::Configuration Model::Impl::of_state(const RobotState& state) const {
  Configuration c = configuration_;
  c.F_T_EE = state.F_T_EE;
  c.EE_T_K = state.EE_T_K;
  c.m_total = state.m_total;
  c.F_x_Ctotal = state.F_x_Ctotal;
  c.I_total = state.I_total;
  return c;
}

Model::Impl::Configuration Model::Impl::with_frames(const std::array<double, 16>& F_T_EE,
                                                    const std::array<double, 16>& EE_T_K) const {
  Configuration c = configuration_;
  c.F_T_EE = F_T_EE;
  c.EE_T_K = EE_T_K;
  return c;
}

Model::Impl::Configuration Model::Impl::with_load(double m_total, const std::array<double, 3>& F_x_Ctotal,
                                                  const std::array<double, 9>& I_total) const {
  Configuration c = configuration_;
  c.m_total = m_total;
  c.F_x_Ctotal = F_x_Ctotal;
  c.I_total = I_total;
  return c;
}

const csp::Model& Model::Impl::configured(const Configuration& configuration, const std::array<double, 7>& q) {
  if (!(configuration == configuration_)) {
    csp::ModelParameters p = parameters_;
    p.F_T_EE = csp::transform_from_array(configuration.F_T_EE);
    p.EE_T_K = csp::transform_from_array(configuration.EE_T_K);
    p.load.mass = configuration.m_total;
    p.load.com = from_array<csp::Vector3>(configuration.F_x_Ctotal);
    p.load.inertia = from_array<csp::Matrix3>(configuration.I_total);
    p.gravity = from_array<csp::Vector3>(configuration.gravity_earth);
    model_ = csp::Model(p);   // throws std::invalid_argument for an invalid load
    configuration_ = configuration;
  }
  csp::forward_kinematics(model_, data_, from_array<csp::Vector7>(q));
  return model_;
}

Model::Model(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
Model::Model(Model&& model) noexcept = default;
Model& Model::operator=(Model&& model) noexcept = default;
Model::~Model() noexcept = default;

std::array<double, 16> Model::pose(Frame frame, const RobotState& robot_state) const {
  impl_->configured(impl_->of_state(robot_state), robot_state.q);
  return to_array(csp::frame_pose(impl_->data(), static_cast<csp::Frame>(frame)));
}

std::array<double, 16> Model::pose(Frame frame, const std::array<double, 7>& q, const std::array<double, 16>& F_T_EE,
                                   const std::array<double, 16>& EE_T_K) const {
  impl_->configured(impl_->with_frames(F_T_EE, EE_T_K), q);
  return to_array(csp::frame_pose(impl_->data(), static_cast<csp::Frame>(frame)));
}

namespace {
std::array<double, 42> jacobian(Model::Impl& impl, Frame frame, bool body, const Model::Impl::Configuration& c,
                                const std::array<double, 7>& q) {
  impl.configured(c, q);
  csp::Matrix6x7 J;
  if (body) csp::body_jacobian(impl.data(), static_cast<csp::Frame>(frame), J);
  else csp::zero_jacobian(impl.data(), static_cast<csp::Frame>(frame), J);
  return to_array(J);
}
}  // namespace

std::array<double, 42> Model::bodyJacobian(Frame frame, const RobotState& robot_state) const {
  return jacobian(*impl_, frame, true, impl_->of_state(robot_state), robot_state.q);
}

std::array<double, 42> Model::bodyJacobian(Frame frame, const std::array<double, 7>& q,
                                           const std::array<double, 16>& F_T_EE,
                                           const std::array<double, 16>& EE_T_K) const {
  return jacobian(*impl_, frame, true, impl_->with_frames(F_T_EE, EE_T_K), q);
}

std::array<double, 42> Model::zeroJacobian(Frame frame, const RobotState& robot_state) const {
  return jacobian(*impl_, frame, false, impl_->of_state(robot_state), robot_state.q);
}

std::array<double, 42> Model::zeroJacobian(Frame frame, const std::array<double, 7>& q,
                                           const std::array<double, 16>& F_T_EE,
                                           const std::array<double, 16>& EE_T_K) const {
  return jacobian(*impl_, frame, false, impl_->with_frames(F_T_EE, EE_T_K), q);
}

std::array<double, 49> Model::mass(const RobotState& robot_state) const noexcept {
  return mass(robot_state.q, robot_state.I_total, robot_state.m_total, robot_state.F_x_Ctotal);
}

std::array<double, 49> Model::mass(const std::array<double, 7>& q, const std::array<double, 9>& I_total, double m_total,
                                   const std::array<double, 3>& F_x_Ctotal) const noexcept {
  return or_nan<49>([&] {
    const csp::Model& model = impl_->configured(impl_->with_load(m_total, F_x_Ctotal, I_total), q);
    csp::crba(model, impl_->data(), from_array<csp::Vector7>(q));
    return to_array(impl_->data().mass_matrix);
  });
}

std::array<double, 7> Model::coriolis(const RobotState& robot_state) const noexcept {
  return coriolis(robot_state.q, robot_state.dq, robot_state.I_total, robot_state.m_total, robot_state.F_x_Ctotal);
}

std::array<double, 7> Model::coriolis(const std::array<double, 7>& q, const std::array<double, 7>& dq,
                                      const std::array<double, 9>& I_total, double m_total,
                                      const std::array<double, 3>& F_x_Ctotal) const noexcept {
  return or_nan<7>([&] {
    const csp::Model& model = impl_->configured(impl_->with_load(m_total, F_x_Ctotal, I_total), q);
    csp::Vector7 c;
    csp::coriolis_torque(model, impl_->data(), from_array<csp::Vector7>(q), from_array<csp::Vector7>(dq), c);
    return to_array(c);
  });
}

std::array<double, 7> Model::gravity(const std::array<double, 7>& q, double m_total,
                                     const std::array<double, 3>& F_x_Ctotal,
                                     const std::array<double, 3>& gravity_earth) const noexcept {
  return or_nan<7>([&] {
    // Gravity does not depend on the load's inertia: keeping the cached one avoids a rebuild when
    // calls alternate with the state-based overloads.
    Model::Impl::Configuration c = impl_->with_load(m_total, F_x_Ctotal, impl_->configuration().I_total);
    c.gravity_earth = gravity_earth;
    const csp::Model& model = impl_->configured(c, q);
    csp::Vector7 g;
    csp::gravity_torque(model, impl_->data(), from_array<csp::Vector7>(q), g);
    return to_array(g);
  });
}

std::array<double, 7> Model::gravity(const RobotState& robot_state, const std::array<double, 3>& gravity_earth) const noexcept {
  return gravity(robot_state.q, robot_state.m_total, robot_state.F_x_Ctotal, gravity_earth);
}

std::array<double, 7> Model::gravity(const RobotState& robot_state) const noexcept {
  return gravity(robot_state, {{0., 0., -9.81}});
}

}  // namespace franka
