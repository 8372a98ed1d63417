// A session log as the input of a reader that judges it by a model (csp gap): the robot a CSP
// session log recorded (the scenario record of csp emulate --lcm-log, csp serve --log or
// lcm-logger's recording; docs/gap.md, "The recorded robot"), and the joint log it holds. A CSV
// joint log, an LCM log or an MCAP file CSP wrote (mcap_export.hpp), told apart by content, not by name.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "csp/bridge/lcm_log.hpp"
#include "csp/io/joint_log.hpp"

namespace csp::run {

// The robot a reader was told to use: a robot file and an end effector, each given by the user (on
// the command line) or a default, which a session log's recorded robot replaces.
struct GivenRobot {
  std::string robot_file;
  std::string end_effector;
  bool robot_file_given = false;
  bool end_effector_given = false;
  // The reader mounts a recorded scene's tool itself (mcap_session: its TCP is the end effector of
  // /tf); csp gap does not (a note says so).
  bool takes_scene_tool = false;
};

// What to build the model of a log's robot from. Without a scenario record for the log's state
// channel (a CSV log, another channel's robot, a recording begun after the last record) the given
// robot file and end effector, and nothing to say.
struct SessionRobot {
  std::string robot_file;     // the given one, or a temporary copy of the recorded one (kept by `recorded`)
  std::string end_effector;   // the given one, or the recorded scenario's

  std::unique_ptr<bridge::RecordedRobot> recorded;   // the log's record of the robot; null without one
  std::string recorded_scenario;                     // the recorded scenario's path
  // The robot used as a scenario record names it: the log's record, else (no record) the given robot
  // file (its path and text) and `end_effector:` as the scenario text (what an MCAP export stores).
  scenario_t record;
  // With a record: one line naming what is used ("the robot's recorded scenario S: its robot file R,
  // its end effector hand"), and notes: where the given robot differs from the recording, what of the
  // recording is not taken (a scene's tool).
  std::string used;
  std::vector<std::string> notes;
  // The robot file is the recorded one (none given): an error in it is the recording's, not the user's.
  bool robot_file_recorded = false;
};

// The robot of the states on `state_channel` of the log at `log_path`: the recorded robot file and
// end effector of its scenario record (the one whose channel prefix `state_channel` has; an MCAP
// file's "csp.session") where not given. Throws std::runtime_error when the log or its record cannot be read.
SessionRobot session_robot(const std::string& log_path, const std::string& state_channel, const GivenRobot& given);

// The joint log at `path`: a CSV joint log (read_joint_log_csv), the robot states on
// `state_channel` of an LCM log (bridge::read_joint_log_lcm) or the /joint_states of an MCAP file
// (read_joint_log_mcap), told apart by content. Throws JointLogError naming the file.
JointLog read_joint_log(const std::string& path, const std::string& state_channel);

}  // namespace csp::run
