// The URDF of an emulated arm (Robot::getRobotModel): CSP's model written as URDF, so that a
// program that loads the robot's URDF (Pinocchio, KDL, urdfdom, ROS) gets the arm CSP emulates.
#pragma once

#include <string>

#include "csp/dynamics/model.hpp"

namespace csp {

// `name` prefixes the links and joints as franka_description does: <name>_link0 (the base) to
// <name>_link7, the revolute <name>_joint1..7 (the MDH frames, axis z, the joint limits), the fixed
// <name>_joint8 to <name>_link8 (the flange). Links 1-7 carry the arm's inertials; the end effector
// and load are not in it (libfranka passes them to the model's functions).
std::string robot_model_urdf(const ModelParameters& model, const std::string& name);

}  // namespace csp
