// What csp view draws (docs/view.md): the robot (Franka's meshes per link, or the collision capsules
// of a robot without them), its end effector or the scene's tool, the scene's obstacles and task, and
// for each frame where every link is, the external force, the clearance to the closest obstacle and
// the robot's mode and errors.
//
// The page does no kinematics: every pose comes from dynamics' forward kinematics here, so the view
// shows the arm where the emulator, the planner and the gap tool put it. A frame is made from a
// joint-log row, whether the row was read from a log or plan, or is the live robot's state
// (rt::append_state): one path for recordings and live runs.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "csp/dynamics/collision_world.hpp"
#include "csp/io/joint_log.hpp"
#include "csp/io/scene.hpp"

namespace csp::view {

// The robot a view shows: its parameters (with the end effector or the scene's tool, as the
// emulator's), the robot file's name (panda or fr3 choose Franka's meshes), and what it wears.
struct ViewRobot {
  ModelParameters parameters;
  std::string name;                       // RobotConfig::name: "panda", "fr3", or another robot's
  std::shared_ptr<const Scene> scene;     // null: no scene; with a scene the arm wears its tool
  bool hand = false;                      // the Franka Hand on the flange (no scene tool)
};

// The closest obstacle to the arm and tool in a frame.
struct Clearance {
  double distance = 0.0;   // signed [m]; negative in contact
  Vector3 on_arm = Vector3::Zero(), on_obstacle = Vector3::Zero();
  int capsule = -1, obstacle = -1;
};

class ViewModel {
 public:
  explicit ViewModel(ViewRobot robot);

  // The page's scene, once: the robot's links and their meshes, the end effector or tool, the
  // obstacles with their shapes and materials, the task's markers, the joint limits.
  nlohmann::json description() const;

  // The frame of row `row` of `log`: time, q, each link's pose (link 1..7, flange, EE), the external
  // wrench on the EE, the obstacles' displacement, the clearance, the robot's mode and errors.
  nlohmann::json frame(const JointLog& log, std::size_t row);

  // The closest obstacle at q and time t (moving obstacles displaced); none without obstacles.
  std::optional<Clearance> clearance(const Vector7& q, double t);

  const ViewRobot& robot() const { return robot_; }
  const Model& model() const { return model_; }

 private:
  // The closest obstacle with data_ at the frame's configuration (forward kinematics done).
  std::optional<Clearance> closest_obstacle(double t) const;

  ViewRobot robot_;
  Model model_;
  Data data_;
  std::optional<CollisionWorld> world_;
};

// The joint an error is about, for highlighting it: the joint nearest its position, velocity or
// torque limit for the joint-limit and torque errors, -1 for the others (Cartesian, communication).
// `row` of `log` is the state the error appeared in.
int joint_of_error(const std::string& error, const JointLog& log, std::size_t row, const JointLimits& limits);

}  // namespace csp::view
