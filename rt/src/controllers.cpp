#include "csp/rt/controllers.hpp"

#include <Eigen/Geometry>
#include <limits>
#include <memory>
#include <stdexcept>

#include "csp/dynamics/arrays.hpp"

namespace csp::rt {
namespace {

// State shared by the built-ins: the robot's model, motion time, the start pose and the reference.
struct ControllerContext {
  explicit ControllerContext(const Emulator& emulator, const ControllerSpec& spec)
      : model(emulator.internal_model()), spec(spec), q0(from_array<Vector7>(emulator.state().q_d)) {}

  // Advances time and evaluates the reference trajectory.
  void advance(Duration cycle) {
    period = cycle.toSec();
    time += period;
    spec.trajectory->evaluate(q0, time, q_d, dq_d, ddq_d);
  }

  Model model;
  Data data;
  ControllerSpec spec;
  Vector7 q0;
  double time = 0.0, period = 0.0;
  Vector7 q_d, dq_d, ddq_d;
};

Command torque(const Vector7& tau) { return Command{tau, false}; }

Command joint_impedance(ControllerContext& c, const RobotState& state) {
  return torque(joint_impedance_torque(c.model, c.data, c.spec, c.q_d, c.dq_d, c.ddq_d, state));
}

// libfranka's cartesian_impedance_control example: a spring-damper on K's pose (quaternion
// orientation error), mapped by J^T, plus Coriolis.
class CartesianImpedance {
 public:
  explicit CartesianImpedance(ControllerContext& c) : c_(c) {
    forward_kinematics(c.model, c.data, c.q0);
    const Transform& pose = frame_pose(c.data, Frame::kStiffness);
    position_d_ = pose.translation;
    orientation_d_ = Eigen::Quaterniond(pose.rotation);
    stiffness_.setZero();
    stiffness_.topLeftCorner<3, 3>().diagonal().setConstant(c.spec.translational_stiffness);
    stiffness_.bottomRightCorner<3, 3>().diagonal().setConstant(c.spec.rotational_stiffness);
    damping_ = 2.0 * stiffness_.cwiseSqrt();
  }

  Command operator()(const RobotState& state) {
    const Vector7 q = from_array<Vector7>(state.q), dq = from_array<Vector7>(state.dq);
    forward_kinematics(c_.model, c_.data, q);
    const Transform& pose = frame_pose(c_.data, Frame::kStiffness);
    zero_jacobian(c_.data, Frame::kStiffness, jacobian_);
    const Vector6 error = pose_error(pose, position_d_, orientation_d_);
    Vector7 coriolis;
    coriolis_torque(c_.model, c_.data, q, dq, coriolis);
    return torque(jacobian_.transpose() * (-stiffness_ * error - damping_ * (jacobian_ * dq)) + coriolis);
  }

 private:
  ControllerContext& c_;
  Vector3 position_d_;
  Eigen::Quaterniond orientation_d_;
  Matrix6 stiffness_, damping_;
  Matrix6x7 jacobian_;
};

}  // namespace

// tau = K (q_d - q) + D (dq_d - dq) [+ M(q) ddq_d + c(q, dq)]
Vector7 joint_impedance_torque(const Model& model, Data& data, const ControllerSpec& spec, const Vector7& q_d,
                               const Vector7& dq_d, const Vector7& ddq_d, const RobotState& state) {
  const Vector7 q = from_array<Vector7>(state.q), dq = from_array<Vector7>(state.dq);
  Vector7 tau = spec.stiffness.cwiseProduct(q_d - q) + spec.damping.cwiseProduct(dq_d - dq);
  if (spec.feedforward) {
    Vector7 inverse_dynamics, gravity;
    rnea(model, data, q, dq, ddq_d, inverse_dynamics);
    gravity_torque(model, data, q, gravity);
    tau += inverse_dynamics - gravity;   // the robot adds gravity itself
  }
  return tau;
}

BuiltinController make_controller(const ControllerSpec& spec, const ControllerFaults& faults, const Emulator& emulator) {
  auto status = std::make_shared<MedicalStatus>();
  auto context = std::make_shared<ControllerContext>(emulator, spec);
  std::function<Command(const RobotState&)> law;
  ControlMode mode = ControlMode::kTorque;
  if (spec.type == "float") {
    law = [context](const RobotState& s) { return torque(-context->spec.damping.cwiseProduct(from_array<Vector7>(s.dq))); };
  } else if (spec.type == "joint_impedance") {
    law = [context](const RobotState& s) { return joint_impedance(*context, s); };
  } else if (spec.type == "joint_position") {
    mode = ControlMode::kJointPosition;
    law = [context](const RobotState&) { return Command{context->q_d, false}; };
  } else if (spec.type == "joint_velocity") {
    mode = ControlMode::kJointVelocity;
    law = [context](const RobotState&) { return Command{context->dq_d, false}; };
  } else if (spec.type == "cartesian_impedance") {
    auto impedance = std::make_shared<CartesianImpedance>(*context);
    law = [context, impedance](const RobotState& s) { return (*impedance)(s); };
  } else if (is_medical_controller(spec.type)) {
    // The motion time the law sees is the context's, advanced before the law runs.
    auto medical = make_medical_law(spec.type, spec.medical, spec.translational_stiffness, spec.rotational_stiffness,
                                    context->model, context->q0, status);
    law = [context, medical](const RobotState& s) { return torque(medical(s, context->time, context->period)); };
  } else {
    throw std::invalid_argument("unknown controller type `" + spec.type + "`");
  }

  Controller controller = [context, law, faults](const RobotState& state, Duration period) {
    context->advance(period);
    if (faults.throw_at && context->time >= *faults.throw_at - 1e-9)
      throw std::runtime_error("scripted controller failure at t = " + std::to_string(context->time) + " s");
    Command command = law(state);
    if (faults.nan_at && context->time >= *faults.nan_at - 1e-9)
      command.values[0] = std::numeric_limits<double>::quiet_NaN();
    return command;
  };
  return {mode, controller, status};
}

}  // namespace csp::rt
