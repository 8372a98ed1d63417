// Robot::getRobotModel(): the arm's URDF, read back by Debian's urdfdom (the parser ROS and
// Pinocchio users load URDF with), has 7 revolute joints whose chain gives CSP's forward kinematics
// (csp::forward_kinematics, the independent computation here) at random configurations, and CSP's
// inertials and joint limits. franka::RobotModel built from it computes the arm's dynamics with a
// total load as CSP's model of the same arm does; a URDF it cannot use is refused by name.
#include <random>
#include <regex>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <urdf_parser/urdf_parser.h>

#include "csp/dynamics/algorithms.hpp"
#include "csp/dynamics/arrays.hpp"
#include "csp/franka_access.hpp"
#include "franka/robot_model.h"

namespace {

csp::Transform transform_of(const urdf::Pose& pose) {
  csp::Transform t;
  t.rotation = Eigen::Quaterniond(pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z).toRotationMatrix();
  t.translation = {pose.position.x, pose.position.y, pose.position.z};
  return t;
}

void expect_same_pose(const csp::Transform& urdf, const csp::Transform& csp, const std::string& what) {
  EXPECT_LT((urdf.rotation - csp.rotation).cwiseAbs().maxCoeff(), 1e-12) << what;
  EXPECT_LT((urdf.translation - csp.translation).cwiseAbs().maxCoeff(), 1e-12) << what;
}

class RobotModelUrdf : public testing::TestWithParam<std::string> {};

TEST_P(RobotModelUrdf, ParsesToCspsKinematicsInertialsAndLimits) {
  const std::string robot_name = GetParam();
  csp::franka_access::LockstepRobot robot(csp::rt::load_scenario(csp::rt::shipped_scenario_path("libfranka_" + robot_name)));
  const std::string xml = robot.getRobotModel();
  const urdf::ModelInterfaceSharedPtr urdf = urdf::parseURDF(xml);
  ASSERT_TRUE(urdf) << "urdfdom does not parse:\n" << xml;
  EXPECT_EQ(urdf->getName(), robot_name);
  ASSERT_TRUE(urdf->getRoot());
  EXPECT_EQ(urdf->getRoot()->name, robot_name + "_link0");

  const csp::Model& model = robot.emulator().internal_model();
  const csp::ModelParameters& parameters = model.parameters();
  int revolute = 0;
  for (const auto& [name, joint] : urdf->joints_) revolute += joint->type == urdf::Joint::REVOLUTE;
  EXPECT_EQ(revolute, csp::kNumJoints);

  // The chain from the base: joint i+1 joins link i to link i+1; joint 8 (fixed) is the flange.
  std::vector<urdf::JointConstSharedPtr> chain;
  for (int i = 1; i <= csp::kNumJoints + 1; ++i) {
    const auto joint = urdf->getJoint(robot_name + "_joint" + std::to_string(i));
    ASSERT_TRUE(joint) << "joint " << i;
    EXPECT_EQ(joint->parent_link_name, robot_name + "_link" + std::to_string(i - 1));
    EXPECT_EQ(joint->child_link_name, robot_name + "_link" + std::to_string(i));
    chain.push_back(joint);
  }
  EXPECT_EQ(chain.back()->type, urdf::Joint::FIXED);

  const csp::JointLimits& limits = parameters.joint_limits;
  for (int i = 0; i < csp::kNumJoints; ++i) {
    const auto& joint = chain[i];
    EXPECT_EQ(joint->type, urdf::Joint::REVOLUTE);
    EXPECT_EQ(joint->axis.x, 0.0);
    EXPECT_EQ(joint->axis.y, 0.0);
    EXPECT_EQ(joint->axis.z, 1.0);
    ASSERT_TRUE(joint->limits);
    EXPECT_EQ(joint->limits->lower, limits.q_min[i]);
    EXPECT_EQ(joint->limits->upper, limits.q_max[i]);
    EXPECT_EQ(joint->limits->velocity, limits.dq_max[i]);
    EXPECT_EQ(joint->limits->effort, limits.tau_max[i]);
    const auto link = urdf->getLink(joint->child_link_name);
    ASSERT_TRUE(link && link->inertial) << joint->child_link_name;
    const csp::RigidBodyInertia& body = parameters.links[i];
    const urdf::Inertial& inertial = *link->inertial;
    EXPECT_EQ(inertial.mass, body.mass);
    expect_same_pose(transform_of(inertial.origin), csp::Transform{csp::Matrix3::Identity(), body.com},
                     joint->child_link_name + " centre of mass");
    EXPECT_EQ(inertial.ixx, body.inertia(0, 0));
    EXPECT_EQ(inertial.ixy, body.inertia(0, 1));
    EXPECT_EQ(inertial.ixz, body.inertia(0, 2));
    EXPECT_EQ(inertial.iyy, body.inertia(1, 1));
    EXPECT_EQ(inertial.iyz, body.inertia(1, 2));
    EXPECT_EQ(inertial.izz, body.inertia(2, 2));
  }

  std::mt19937 random(7);
  csp::Data data;
  for (int sample = 0; sample < 100; ++sample) {
    csp::Vector7 q;
    for (int i = 0; i < csp::kNumJoints; ++i) {
      q[i] = std::uniform_real_distribution<double>(limits.q_min[i], limits.q_max[i])(random);
    }
    csp::forward_kinematics(model, data, q);
    csp::Transform pose;   // ^0T of the child link of each joint, from the URDF
    for (int i = 0; i < csp::kNumJoints; ++i) {
      const csp::Transform rotation{Eigen::AngleAxisd(q[i], csp::Vector3::UnitZ()).toRotationMatrix(),
                                    csp::Vector3::Zero()};
      pose = pose * transform_of(chain[i]->parent_to_joint_origin_transform) * rotation;
      expect_same_pose(pose, data.O_T_joint[i], "joint " + std::to_string(i + 1) + ", sample " + std::to_string(sample));
    }
    pose = pose * transform_of(chain.back()->parent_to_joint_origin_transform);
    expect_same_pose(pose, data.O_T_F, "flange, sample " + std::to_string(sample));
  }
}

TEST_P(RobotModelUrdf, RobotModelComputesCspsDynamicsWithTheTotalLoad) {
  const std::string robot_name = GetParam();
  csp::franka_access::LockstepRobot robot(csp::rt::load_scenario(csp::rt::shipped_scenario_path("libfranka_" + robot_name)));
  franka::RobotModel robot_model(robot.getRobotModel());
  // The reference: CSP's model of the arm with only the given load at the flange, and no rotor
  // inertia (a URDF has none).
  csp::ModelParameters parameters = robot.emulator().internal_model().parameters();
  parameters.end_effector = {};
  parameters.armature = csp::Vector7::Zero();
  std::mt19937 random(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  csp::Data data;
  for (int sample = 0; sample < 20; ++sample) {
    csp::Vector7 q, dq;
    for (int i = 0; i < csp::kNumJoints; ++i) {
      q[i] = std::uniform_real_distribution<double>(parameters.joint_limits.q_min[i], parameters.joint_limits.q_max[i])(random);
      dq[i] = unit(random);
    }
    csp::RigidBodyInertia load;
    load.mass = 0.5 + 0.5 * unit(random);
    load.com = csp::Vector3(0.02 * unit(random), 0.02 * unit(random), 0.05 + 0.02 * unit(random));
    load.inertia = csp::Vector3(2e-3, 3e-3, 4e-3).asDiagonal();
    const csp::Vector3 gravity(0.5 * unit(random), 0.5 * unit(random), -9.81);
    parameters.load = load;
    parameters.gravity = gravity;
    const csp::Model reference(parameters);

    std::array<double, 49> mass{};
    robot_model.mass(csp::to_array(q), csp::to_array(load.inertia), load.mass, csp::to_array(load.com), mass);
    csp::crba(reference, data, q);
    EXPECT_LT((csp::from_array<csp::Matrix7>(mass) - data.mass_matrix).cwiseAbs().maxCoeff(), 1e-12) << sample;

    std::array<double, 7> coriolis{};
    robot_model.coriolis(csp::to_array(q), csp::to_array(dq), csp::to_array(load.inertia), load.mass,
                         csp::to_array(load.com), coriolis);
    csp::Vector7 expected;
    csp::coriolis_torque(reference, data, q, dq, expected);
    EXPECT_LT((csp::from_array<csp::Vector7>(coriolis) - expected).cwiseAbs().maxCoeff(), 1e-12) << sample;

    std::array<double, 7> gravity_torque{};
    robot_model.gravity(csp::to_array(q), csp::to_array(gravity), load.mass, csp::to_array(load.com), gravity_torque);
    csp::gravity_torque(reference, data, q, expected);
    EXPECT_LT((csp::from_array<csp::Vector7>(gravity_torque) - expected).cwiseAbs().maxCoeff(), 1e-11) << sample;
  }
}

INSTANTIATE_TEST_SUITE_P(Robots, RobotModelUrdf, testing::Values("panda", "fr3"));

// The Panda's URDF with `from` replaced by `to` (a regular expression) must be refused naming `why`.
void expect_refused(const std::string& from, const std::string& to, const std::string& why) {
  csp::franka_access::LockstepRobot robot(csp::rt::load_scenario(csp::rt::shipped_scenario_path("libfranka_panda")));
  const std::string urdf = std::regex_replace(robot.getRobotModel(), std::regex(from), to);
  try {
    franka::RobotModel model(urdf);
    ADD_FAILURE() << "accepted after replacing " << from << " by " << to;
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find(why), std::string::npos) << error.what();
  }
}

TEST(RobotModel, RefusesWhatItCannotUseByName) {
  expect_refused("</robot>", "", "not well-formed XML");
  expect_refused("<(/?)robot([ >])", "<$1robots$2", "no <robot> element");
  expect_refused("type=\"revolute\">\n      <parent link=\"panda_link6\"", "type=\"prismatic\">\n      <parent link=\"panda_link6\"",
                 "joint panda_joint7: type \"prismatic\"");
  expect_refused("(<joint name=\"panda_joint3\"[^]*?)<axis xyz=\"0 0 1\"/>", "$1<axis xyz=\"1 0 0\"/>",
                 "joint panda_joint3: its axis is not z");
  expect_refused("(<joint name=\"panda_joint2\"[^]*?rpy=\")[^ ]+ [^ ]+ ", "$010.3 0.2 ",   // $01: group 1, then 0.3
                 "joint panda_joint2: its origin's rotation is not RotX(alpha) RotZ(theta)");
  expect_refused("(<joint name=\"panda_joint1\"[^]*?xyz=\")[^ ]+ [^ ]+ ", "$010 0.05 ",   // off joint 1's z axis
                 "joint panda_joint1: its origin's offset is not");
  expect_refused("<mass value=\"[^\"]*\"", "<mass value=\"heavy\"", "expected a finite number in value of <mass>");
}

}  // namespace
