// libcsp_fci_model.so: the "model library" an FCI robot sends to libfranka (up to 0.13), which
// dlopens it and calls these 31 functions for franka::Model (libfranka's src/libfcimodels.h names
// and signatures; arrays column-major). The robot model comes from the parameter block the server
// wrote (model_parameter_block.hpp); the end effector, the total load and gravity come per call.
//
// A library whose block was never written (the file as built, not a copy csp fci sent) prints why
// on stderr and aborts at its first call: a model of no robot must not go unnoticed.
// A load no rigid body has (negative mass, non-symmetric inertia) gives NaN everywhere, as
// CSP's franka::Model does (a controller refuses non-finite torques).
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/arrays.hpp"
#include "csp/fci/model_parameter_block.hpp"

#define CSP_FCI_EXPORT extern "C" __attribute__((visibility("default")))

using csp::fci::kParameterCount;
using csp::fci::ParameterBlock;

// Not const: the server writes it in the file, so its values must be read at run time. Constant-
// initialized, so that the marker is in the file's data.
CSP_FCI_EXPORT ParameterBlock csp_fci_model_parameters;
constinit ParameterBlock csp_fci_model_parameters = csp::fci::unwritten_parameter_block();

namespace {

using csp::Frame;
using csp::from_data;

// The robot model of the block, decoded once (a function-local static: thread-safe).
const csp::ModelParameters& robot_model() {
  static const csp::ModelParameters parameters = [] {
    if (csp_fci_model_parameters.value_count != kParameterCount) {
      std::fprintf(stderr,
                   "libcsp_fci_model: the robot model was never written into this library's parameter block "
                   "(this is the file as built; csp fci sends libfranka a copy holding the robot's model)\n");
      std::abort();
    }
    return csp::fci::decode_parameters(csp_fci_model_parameters.values);
  }();
  return parameters;
}

// The robot model's parameters with the end-effector frame F_T_EE (column-major 4x4; none: identity).
csp::ModelParameters with_frame(const double* F_T_EE) {
  csp::ModelParameters p = robot_model();
  if (F_T_EE != nullptr) p.F_T_EE = csp::transform_from_matrix(from_data<Eigen::Matrix4d>(F_T_EE));
  return p;
}

// The robot model's parameters with libfranka's total load on the flange (end effector and load in
// one body; no inertia: zero). csp::Model throws std::invalid_argument for a load no body has.
csp::ModelParameters with_load(const double* I_total, double m_total, const double* F_x_Ctotal) {
  csp::ModelParameters p = robot_model();
  p.load = {m_total, from_data<csp::Vector3>(F_x_Ctotal),
            I_total != nullptr ? from_data<csp::Matrix3>(I_total) : csp::Matrix3::Zero()};
  return p;
}

template <typename Result>
void write(const Result& result, double* out) {
  Eigen::Map<Result>{out} = result;
}

template <typename Result, typename Compute>
void write_or_nan(double* out, Compute compute) {
  try {
    write<Result>(compute(), out);
  } catch (const std::exception&) {
    write<Result>(Result::Constant(std::numeric_limits<double>::quiet_NaN()), out);
  }
}

// Frames 1..7 and the flange do not depend on F_T_EE; joint 1's Jacobians not on q (q = 0 then).
void pose(Frame frame, const double* q, const double* F_T_EE, double* O_T_frame) {
  const csp::Model model(with_frame(F_T_EE));
  csp::Data data;
  csp::forward_kinematics(model, data, from_data<csp::Vector7>(q));
  write<Eigen::Matrix4d>(csp::frame_pose(data, frame).matrix(), O_T_frame);
}

void jacobian(Frame frame, bool body, const double* q, const double* F_T_EE, double* J) {
  const csp::Model model(with_frame(F_T_EE));
  csp::Data data;
  csp::forward_kinematics(model, data, q != nullptr ? from_data<csp::Vector7>(q) : csp::Vector7::Zero());
  csp::Matrix6x7 jacobian;
  if (body) csp::body_jacobian(data, frame, jacobian);
  else csp::zero_jacobian(data, frame, jacobian);
  write<csp::Matrix6x7>(jacobian, J);
}

}  // namespace

CSP_FCI_EXPORT void O_T_J1(const double q[7], double b_O_T_J1[16]) { pose(Frame::kJoint1, q, nullptr, b_O_T_J1); }
CSP_FCI_EXPORT void O_T_J2(const double q[7], double b_O_T_J2[16]) { pose(Frame::kJoint2, q, nullptr, b_O_T_J2); }
CSP_FCI_EXPORT void O_T_J3(const double q[7], double b_O_T_J3[16]) { pose(Frame::kJoint3, q, nullptr, b_O_T_J3); }
CSP_FCI_EXPORT void O_T_J4(const double q[7], double b_O_T_J4[16]) { pose(Frame::kJoint4, q, nullptr, b_O_T_J4); }
CSP_FCI_EXPORT void O_T_J5(const double q[7], double b_O_T_J5[16]) { pose(Frame::kJoint5, q, nullptr, b_O_T_J5); }
CSP_FCI_EXPORT void O_T_J6(const double q[7], double b_O_T_J6[16]) { pose(Frame::kJoint6, q, nullptr, b_O_T_J6); }
CSP_FCI_EXPORT void O_T_J7(const double q[7], double b_O_T_J7[16]) { pose(Frame::kJoint7, q, nullptr, b_O_T_J7); }
CSP_FCI_EXPORT void O_T_J8(const double q[7], double b_O_T_J8[16]) { pose(Frame::kFlange, q, nullptr, b_O_T_J8); }
CSP_FCI_EXPORT void O_T_J9(const double q[7], const double F_T_EE[16], double b_O_T_J9[16]) {
  pose(Frame::kEndEffector, q, F_T_EE, b_O_T_J9);
}

CSP_FCI_EXPORT void O_J_J1(double b_O_J_J1[42]) { jacobian(Frame::kJoint1, false, nullptr, nullptr, b_O_J_J1); }
CSP_FCI_EXPORT void O_J_J2(const double q[7], double b_O_J_J2[42]) { jacobian(Frame::kJoint2, false, q, nullptr, b_O_J_J2); }
CSP_FCI_EXPORT void O_J_J3(const double q[7], double b_O_J_J3[42]) { jacobian(Frame::kJoint3, false, q, nullptr, b_O_J_J3); }
CSP_FCI_EXPORT void O_J_J4(const double q[7], double b_O_J_J4[42]) { jacobian(Frame::kJoint4, false, q, nullptr, b_O_J_J4); }
CSP_FCI_EXPORT void O_J_J5(const double q[7], double b_O_J_J5[42]) { jacobian(Frame::kJoint5, false, q, nullptr, b_O_J_J5); }
CSP_FCI_EXPORT void O_J_J6(const double q[7], double b_O_J_J6[42]) { jacobian(Frame::kJoint6, false, q, nullptr, b_O_J_J6); }
CSP_FCI_EXPORT void O_J_J7(const double q[7], double b_O_J_J7[42]) { jacobian(Frame::kJoint7, false, q, nullptr, b_O_J_J7); }
CSP_FCI_EXPORT void O_J_J8(const double q[7], double b_O_J_J8[42]) { jacobian(Frame::kFlange, false, q, nullptr, b_O_J_J8); }
CSP_FCI_EXPORT void O_J_J9(const double q[7], const double F_T_EE[16], double b_O_J_J9[42]) {
  jacobian(Frame::kEndEffector, false, q, F_T_EE, b_O_J_J9);
}

CSP_FCI_EXPORT void Ji_J_J1(double b_Ji_J_J1[42]) { jacobian(Frame::kJoint1, true, nullptr, nullptr, b_Ji_J_J1); }
CSP_FCI_EXPORT void Ji_J_J2(const double q[7], double b_Ji_J_J2[42]) { jacobian(Frame::kJoint2, true, q, nullptr, b_Ji_J_J2); }
CSP_FCI_EXPORT void Ji_J_J3(const double q[7], double b_Ji_J_J3[42]) { jacobian(Frame::kJoint3, true, q, nullptr, b_Ji_J_J3); }
CSP_FCI_EXPORT void Ji_J_J4(const double q[7], double b_Ji_J_J4[42]) { jacobian(Frame::kJoint4, true, q, nullptr, b_Ji_J_J4); }
CSP_FCI_EXPORT void Ji_J_J5(const double q[7], double b_Ji_J_J5[42]) { jacobian(Frame::kJoint5, true, q, nullptr, b_Ji_J_J5); }
CSP_FCI_EXPORT void Ji_J_J6(const double q[7], double b_Ji_J_J6[42]) { jacobian(Frame::kJoint6, true, q, nullptr, b_Ji_J_J6); }
CSP_FCI_EXPORT void Ji_J_J7(const double q[7], double b_Ji_J_J7[42]) { jacobian(Frame::kJoint7, true, q, nullptr, b_Ji_J_J7); }
CSP_FCI_EXPORT void Ji_J_J8(const double q[7], double b_Ji_J_J8[42]) { jacobian(Frame::kFlange, true, q, nullptr, b_Ji_J_J8); }
CSP_FCI_EXPORT void Ji_J_J9(const double q[7], const double F_T_EE[16], double b_Ji_J_J9[42]) {
  jacobian(Frame::kEndEffector, true, q, F_T_EE, b_Ji_J_J9);
}

// M, c and g of the arm carrying libfranka's total load (m_total, F_x_Ctotal, I_total about its CoM).
CSP_FCI_EXPORT void M_NE(const double q[7], const double I_load[9], double m_load, const double F_x_Cload[3],
                         double b_M_NE[49]) {
  write_or_nan<csp::Matrix7>(b_M_NE, [&] {
    const csp::Model model(with_load(I_load, m_load, F_x_Cload));
    csp::Data data;
    csp::crba(model, data, from_data<csp::Vector7>(q));
    return data.mass_matrix;
  });
}

CSP_FCI_EXPORT void c_NE(const double q[7], const double dq[7], const double I_load[9], double m_load,
                         const double F_x_Cload[3], double b_c_NE[7]) {
  write_or_nan<csp::Vector7>(b_c_NE, [&] {
    const csp::Model model(with_load(I_load, m_load, F_x_Cload));
    csp::Data data;
    csp::Vector7 c;
    csp::coriolis_torque(model, data, from_data<csp::Vector7>(q), from_data<csp::Vector7>(dq), c);
    return c;
  });
}

// g(q) does not depend on the load's inertia: libfranka passes none.
CSP_FCI_EXPORT void g_NE(const double q[7], const double g_earth[3], double m_load, const double F_x_Cload[3],
                         double b_g_NE[7]) {
  write_or_nan<csp::Vector7>(b_g_NE, [&] {
    csp::ModelParameters p = with_load(nullptr, m_load, F_x_Cload);
    p.gravity = from_data<csp::Vector3>(g_earth);
    const csp::Model model(p);
    csp::Data data;
    csp::Vector7 g;
    csp::gravity_torque(model, data, from_data<csp::Vector7>(q), g);
    return g;
  });
}
