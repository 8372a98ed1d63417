// The external control loop (franka/active_control.h): readOnce/writeOnce on the motion's
// MotionSession, the same loop control() runs on.
#include "franka/active_control.h"

#include "csp/dynamics/arrays.hpp"
#include "franka/active_motion_generator.h"
#include "franka/active_torque_control.h"
#include "franka/control_tools.h"
#include "commands.hpp"
#include "robot_impl.hpp"

namespace franka {
namespace {

using Move = research_interface::robot::Move;

using commands::check;
using commands::set;

// The session of the handle's motion; ControlException once that motion is over.
csp::rt::MotionSession& session_of(Robot::Impl& impl, uint32_t motion_id, bool finished, const char* call) {
  if (finished || !impl.session || impl.motion_id != motion_id)
    throw ControlException(std::string(call) + " must not be called after the motion has finished.");
  return *impl.session;
}

// Sends `command` as the answer to the state read last; a command with motion_finished ends the
// motion (ControlException if it ended in a reflex). Returns whether the motion is over.
bool send(Robot::Impl& impl, csp::rt::MotionSession& session, const csp::rt::Command& command) {
  if (!session.awaiting_answer())
    throw InvalidOperationException("libfranka: writeOnce must answer a state: call readOnce first");
  session.write(command);
  if (!command.motion_finished) return false;
  impl.end_motion();   // throws for a reflex in the last cycle
  return true;
}

}  // namespace

ActiveControl::ActiveControl(std::shared_ptr<Robot::Impl> robot_impl, uint32_t motion_id)
    : robot_impl(std::move(robot_impl)), motion_id(motion_id) {}

ActiveControl::~ActiveControl() {
  // A handle that goes away before its motion finished stops it (libfranka's cancelMotion).
  if (!control_finished && robot_impl->session && robot_impl->motion_id == motion_id) robot_impl->cancel_motion();
}

void ActiveControl::wrongWriteOnce() {
  throw ControlException("Wrong writeOnce method called for currently active control!");
}

std::pair<RobotState, Duration> ActiveControl::readOnce() {
  csp::rt::MotionSession& session = session_of(*robot_impl, motion_id, control_finished, "readOnce");
  const Duration period = session.read();
  if (session.done()) {
    // A reflex, or Robot::stop: the motion is over and the robot says why.
    control_finished = true;
    robot_impl->end_motion();
    throw ControlException("libfranka: Move command aborted!");
  }
  last_read_access = session.state().time;
  return {session.state(), period};
}

void ActiveTorqueControl::writeOnce(const Torques& control_input) {
  csp::rt::MotionSession& session = session_of(*robot_impl, motion_id, control_finished, "writeOnce");
  checkFinite(control_input.tau_J);
  csp::rt::Command command;
  command.values = csp::from_array<csp::Vector7>(control_input.tau_J);
  command.motion_finished = control_input.motion_finished;
  control_finished = send(*robot_impl, session, command);
}

template <typename MotionGeneratorType>
void ActiveMotionGenerator<MotionGeneratorType>::writeOnce(const MotionGeneratorType& motion_generator_input,
                                                           const std::optional<const Torques>& control_input) {
  csp::rt::MotionSession& session = session_of(*robot_impl, motion_id, control_finished, "writeOnce");
  const bool external = controller_type_ == Move::ControllerMode::kExternalController;
  if (control_input && !external)
    throw ControlException("Torques can only be commanded in kExternalController mode.");
  if (!control_input && external)
    throw ControlException(
        "Torque command missing, please use writeOnce(const MotionGeneratorType& motion_generator_input, const "
        "Torques& control_input) for external controllers.");
  check(motion_generator_input);
  csp::rt::Command command;
  set(command, motion_generator_input);
  if (control_input) {
    checkFinite(control_input->tau_J);
    command.torque = csp::from_array<csp::Vector7>(control_input->tau_J);
  }
  command.motion_finished = motion_generator_input.motion_finished || (control_input && control_input->motion_finished);
  control_finished = send(*robot_impl, session, command);
}

template class ActiveMotionGenerator<JointPositions>;
template class ActiveMotionGenerator<JointVelocities>;
template class ActiveMotionGenerator<CartesianPose>;
template class ActiveMotionGenerator<CartesianVelocities>;

}  // namespace franka
