// The one part of libfranka's research interface that its public API shows: the controller a
// motion runs with (Robot::startJointPositionControl(research_interface::robot::Move::ControllerMode)).
// CSP speaks no network protocol, so this header holds only that enum, with libfranka's names.
#pragma once

#include <cstdint>

namespace research_interface {
namespace robot {

struct Move {
  // kJointImpedance / kCartesianImpedance: the robot's controller tracks the motion generator;
  // kExternalController: the program's torques drive the arm (writeOnce(motion, torques)).
  enum class ControllerMode : uint8_t { kJointImpedance, kCartesianImpedance, kExternalController };
};

}  // namespace robot
}  // namespace research_interface
