// A scene (configs/scenes/*.yaml, format in docs/planning.md): the operating room around the arm,
// the patient, the tool on the flange, named joint poses and the medical task. Shared by the
// planner (collision) and, later, the emulator (contact). Loading validates every field and throws
// ConfigError naming the file, the key and what was expected, as robot files do.
#pragma once

#include <map>
#include <string>
#include <variant>
#include <vector>

#include "csp/dynamics/collision_world.hpp"
#include "csp/dynamics/contact.hpp"
#include "csp/dynamics/model.hpp"

namespace csp {

// A periodic rigid motion of an obstacle (breathing): displacement amplitude sin(2 pi f t) [m].
struct ObstacleMotion {
  Vector3 amplitude = Vector3::Zero();   // base frame [m]
  double frequency_hz = 0.0;

  Vector3 displacement(double t) const;
  Vector3 velocity(double t) const;
};

struct Obstacle {
  std::string name;
  std::string obstacle_class;        // a key of Scene::clearance
  Shape shape;                       // base frame, at displacement 0
  std::vector<std::string> exempt;   // arm or tool capsules never checked against it (e.g. the cart under link 0)
  // Defaulted (= {}) so that the planner's four-field initialisers stay warning-free.
  std::string material = {};         // a key of Scene::materials; empty: no contact (a keep-out zone)
  ObstacleMotion motion = {};        // none by default (the planner plans against `shape`)
};

struct NamedCapsule {
  std::string name;
  Capsule capsule;
};

// The tool replacing the hand: its collision capsules and inertia in the flange frame, its TCP.
struct Tool {
  std::string name;
  std::vector<NamedCapsule> capsules;   // flange frame
  Transform F_T_EE;                     // flange -> TCP (libfranka F_T_EE)
  RigidBodyInertia inertia;             // flange frame
};

struct NamedPose {
  std::string name;
  Vector7 q = Vector7::Zero();
};

// The medical tasks (their paths are planned in a later phase; here they are validated data).
// Probe on the skin, moved along a straight line at constant speed, its axis along `tool_axis`.
struct UltrasoundScan {
  Vector3 start = Vector3::Zero(), end = Vector3::Zero();   // TCP on the skin [m]
  Vector3 tool_axis = -Vector3::UnitZ();                     // unit, TCP z axis during the scan
  double speed = 0.0;                                        // [m/s]
  double hover = 0.0;                                        // retract along the axis for excitation [m]
};
// A shaft through a trocar (remote centre of motion).
struct RcmPivot {
  Vector3 trocar = Vector3::Zero();
  double insertion_min = 0.0, insertion_max = 0.0;   // tip depth below the trocar [m]
  double max_pivot = 0.0;                            // from the port normal [rad]
  double hover = 0.0;                                // tip above the port for excitation [m]
};
// A drill advanced along the burr-hole axis into the skull.
struct BurrHole {
  Vector3 entry = Vector3::Zero();
  Vector3 axis = Vector3::UnitZ();   // unit, out of the skull; the drill points along -axis
  double standoff = 0.0;             // approach ends this far above the entry [m]
  double advance = 0.0;              // then advances this far [m]
  double speed = 0.0;                // [m/s]
};
using Task = std::variant<UltrasoundScan, RcmPivot, BurrHole>;

struct Scene {
  std::string path;
  std::string name;
  std::map<std::string, double> clearance;   // required distance per obstacle class, and "self" [m]
  std::vector<Obstacle> obstacles;
  std::map<std::string, Material> materials; // contact laws by name (docs/contact.md)
  Tool tool;
  std::vector<NamedPose> poses;
  std::string start;                         // the name of the pose the plans start from
  Task task;

  const NamedPose& pose(const std::string& name) const;   // throws ConfigError naming the scene
  int obstacle_index(const std::string& name) const;      // in `obstacles`; -1 if none has that name
};

Scene load_scene(const std::string& path);

// The capsules that move with the arm when it carries `tool`: the arm's (franka_arm_capsules, in
// link order), then the tool's on the flange.
std::vector<FrameCapsule> arm_and_tool_capsules(const Tool& tool);

// The scene's collision world: the arm's and the tool's capsules (arm_and_tool_capsules) against
// its obstacles at rest, each with its exempt capsules.
CollisionWorld collision_world(const Scene& scene);

// The tool's working end (the probe's face, the shaft's tip, the burr's bit): the index in
// tool.capsules of the capsule whose end cap is nearest to the TCP; -1 for a tool without capsules.
// The planner lets it touch the task's obstacle; the emulator's tissue laws take it over.
int tool_tip_capsule(const Tool& tool);

// The robot's parameters with the scene's tool as its end effector (mass, TCP).
ModelParameters with_tool(ModelParameters parameters, const Tool& tool);

}  // namespace csp
