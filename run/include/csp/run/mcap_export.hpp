// A CSP session as an MCAP file for Foxglove and Rerun users (`csp log export --format mcap`,
// docs/mcap.md): the joint log's rows as JSON messages with Foxglove's schemas, and back.
//
// Channels (message encoding "json", schema encoding "jsonschema"), every message at log_time =
// the row's t in ns:
//   /joint_states  csp.JointState: name, position, velocity, effort (as ROS sensor_msgs/JointState:
//                  q, dq, tau_J) and the row's other columns by their joint-log names (t, q_d, O_T_EE,
//                  robot_mode, x_..., docs/joint-log.md), numbers with full round-trip precision.
//   /tf            foxglove.FrameTransforms: <robot>_link0 -> _link1 .. _link7 -> _link8 (the flange)
//                  [-> <robot>_EE when the log has O_T_EE], CSP's forward kinematics at the row's q.
//   /scene         foxglove.SceneUpdate, once at the first row: the scene's obstacles.
//   /errors        foxglove.Log when current_errors or robot_mode changes.
// A Metadata record "csp.session" holds the robot (its file's path and text, the end effector) and
// the scenario, so that a reader finds the robot the log recorded (session_log.hpp).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "csp/bridge/lcm_log.hpp"
#include "csp/dynamics/model.hpp"
#include "csp/io/joint_log.hpp"
#include "csp/io/scene.hpp"
#include "csp/run/session_log.hpp"

namespace csp::run {

inline constexpr const char* kJointStatesTopic = "/joint_states";
inline constexpr const char* kTransformsTopic = "/tf";
inline constexpr const char* kSceneTopic = "/scene";
inline constexpr const char* kErrorsTopic = "/errors";
inline constexpr const char* kSessionMetadata = "csp.session";

// What the export needs of the session besides its rows.
struct McapSession {
  Model model;                          // the robot's model: /tf's forward kinematics (its end effector's F_T_EE)
  std::string robot_name;               // the robot file's `name` (panda, fr3): the frames' prefix, as franka_description
  std::shared_ptr<const Scene> scene;   // null: no /scene
  // The scenario record written as "csp.session" (a scenario_t's fields: path, text, robot_path,
  // robot_text): SessionRobot::record.
  scenario_t record;
};

// The session of a log, with the robot session_robot found for it and a scene (may be null). The
// tool of the recorded scenario's scene, when it mounts one, is the robot's end effector (the
// emulator's O_T_EE is its TCP). Throws ConfigError for a robot file that cannot be used.
McapSession mcap_session(const SessionRobot& robot, std::shared_ptr<const Scene> scene);

struct McapExportReport {
  uint64_t rows = 0;
  uint64_t error_messages = 0;   // on /errors
  uint64_t obstacles = 0;        // on /scene
};

// Writes `log` as an MCAP file at `path`. Throws JointLogError (a time before 0 cannot be an MCAP
// log_time) or mcap::McapError naming the file.
McapExportReport write_session_mcap(const std::string& path, const JointLog& log, const McapSession& session);

// The joint log on /joint_states of an MCAP file CSP wrote: the same rows, bit for bit, as the log
// it was written from. Throws JointLogError naming the file and the message for a file without the
// channel, a message that is no csp.JointState, and the joint log's own rules (check_joint_log).
JointLog read_joint_log_mcap(const std::string& path);

// The "csp.session" record of an MCAP file, if it has one.
std::optional<scenario_t> recorded_session(const std::string& path);

}  // namespace csp::run
