// Robot description files (configs/robots/*.yaml, format in docs/robot-config.md) and the
// Model they build. Loading validates every field and throws ConfigError naming the file, the
// key and what was expected.
#pragma once

#include <map>
#include <optional>
#include <stdexcept>
#include <string>

#include "csp/dynamics/model.hpp"

namespace csp {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct EndEffectorDescription {
  Transform F_T_EE;
  RigidBodyInertia inertia;   // flange frame
};

struct InertiaSet {
  std::array<RigidBodyInertia, kNumJoints> links{};
  bool physical = true;
};

// The motors' rotor inertia reflected to the links (Featherstone sec. 7.3), with its source: the
// plant an emulated arm integrates carries it; zero values: none given.
struct Armature {
  Vector7 values = Vector7::Zero();   // [kg m^2]
  std::string source;
};

struct RobotConfig {
  std::string path;
  std::string name;
  std::array<MdhParameters, kNumJoints> mdh{};
  Transform link7_T_flange;
  std::map<std::string, EndEffectorDescription> end_effectors;   // "none" is implicit
  std::string default_joint_limits;
  std::map<std::string, JointLimits> joint_limits;
  CartesianLimits cartesian_limits;
  std::string default_inertia;
  std::map<std::string, InertiaSet> inertia_sets;
  std::string default_friction;                                  // may be "none"
  std::map<std::string, FrictionModel> friction_sets;            // "none" is implicit
  Armature armature;                                             // optional in the file
};

RobotConfig load_robot_config(const std::string& path);

// Which named sets to use; an empty name means the config's default. The model has no armature:
// the robot file's (RobotConfig::armature) is the plant's, which a caller adds.
struct ModelOptions {
  std::string inertia;
  std::string friction;
  std::string joint_limits;
  std::string end_effector = "none";          // "none" or a key of end_effectors
  std::optional<RigidBodyInertia> load;       // extra load on the flange (libfranka set_load)
  std::optional<Vector3> gravity;             // default (0, 0, -9.81)
};

ModelParameters model_parameters(const RobotConfig& config, const ModelOptions& options);

}  // namespace csp
