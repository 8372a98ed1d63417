// The Franka Hand and the Cobot Pump as transport-free models, stepped in time like the emulator:
// a command is received, acts after the device's reaction time, runs, and ends with one of the
// answers the real device's server gives (libfranka's research_interface statuses). franka::Gripper
// and franka::VacuumGripper run them against the wall clock; tests step them directly.
// docs/gripper.md describes the models, their figures and sources, and what is simplified.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

#include "csp/dynamics/spatial.hpp"

namespace csp {
class Field;
}

namespace csp::rt {

// The answer to a gripper command, as the hand's server sends it.
enum class CommandStatus {
  kRunning,        // no answer yet
  kSuccess,        // libfranka: true
  kUnsuccessful,   // libfranka: false (e.g. a grasp whose width is out of tolerance)
  kAborted,        // libfranka: CommandException "Command aborted!" (another command took over)
};

// The answers to the last few commands, by command number (a waiting caller may look after a
// newer command has already replaced its own).
class CommandAnswers {
 public:
  // A new command: the one still running is aborted. Returns the new command's number.
  uint64_t issue();
  void answer(CommandStatus status) { set(current_, status); }
  CommandStatus of(uint64_t id) const;
  CommandStatus current() const { return of(current_); }
  uint64_t current_id() const { return current_; }

 private:
  void set(uint64_t id, CommandStatus status) { ring_[id % ring_.size()] = {id, status}; }
  struct Entry {
    uint64_t id = 0;
    CommandStatus status = CommandStatus::kSuccess;
  };
  std::array<Entry, 16> ring_{};
  uint64_t current_ = 0;
};

// A command the device refuses (libfranka: CommandException "Command failed!"); what() says why.
class CommandRefused : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

// A rigid object standing between the fingers (or under the suction cup), set by the scenario.
struct HeldObject {
  double width = 0.0;      // [m] between the finger pads (Hand only)
  double mass = 0.0;       // [kg]
  double friction = 0.5;   // pad-object friction coefficient (assumed; docs/gripper.md)
};

struct HandSettings {
  // Franka Hand data sheet (Franka Emika, "Panda" / "Franka Research 3" product data sheets): stroke
  // 80 mm, grasping force 70 N continuous and 140 N maximum.
  double max_width = 0.08;              // [m] the width homing finds with the standard fingers
  double max_continuous_force = 70.0;   // [N]
  double max_force = 140.0;             // [N]
  // 0.1 m/s: frankx's Gripper::max_speed and the speed libfranka users open the hand with.
  double max_speed = 0.1;               // [m/s] of the opening width
  // The speed of franka_ros's Gazebo hand (franka_gazebo FrankaGripperSim: homing at 0.02 m/s).
  double homing_speed = 0.02;           // [m/s]
  double reaction_time = 0.1;           // [s] from a command to the fingers moving (assumed)
  double state_period = 0.1;            // [s] between two GripperState messages (~10 Hz, franky #35)
  bool homed = true;                    // false: max_width is 0 until homing, as after a finger change
  double initial_width = 0.08;          // [m]
  // First-order heating by the motor current (force squared): the rise above ambient the
  // continuous force reaches in steady state, and its time constant (both assumed).
  double ambient_temperature = 30.0;    // [degC]
  double temperature_rise_at_continuous_force = 20.0;   // [K]
  double thermal_time_constant = 600.0; // [s]
  // Where a grasped object's centre of mass sits, in the flange frame: between the fingertips, at
  // the hand's TCP (0.1034 m along z, libfranka's F_T_EE for the Franka Hand).
  Vector3 grasp_point = Vector3(0.0, 0.0, 0.1034);
  std::optional<HeldObject> object;     // what stands between the fingers, if anything
};

// The hand's state as GripperState reports it.
struct HandState {
  double width = 0.0;        // [m]
  double max_width = 0.0;    // [m]
  bool is_grasped = false;
  uint16_t temperature = 0;  // [degC]
  uint64_t message_id = 0;   // the state message's number (libfranka puts it in GripperState::time)
};

// The Franka Hand: two fingers moved together by one motor, opening width 0..max_width.
//  - homing: close fully, then open fully at homing_speed; max_width becomes the measured width.
//    The scenario's object is placed after homing: homing finds the fingers free.
//  - move(width, speed): the fingers go to width at speed; they stop at an object in the way
//    (the move then answers unsuccessful).
//  - grasp(width, speed, force, eps_inner, eps_outer): the fingers close (or open, if width is
//    above the opening) at speed until they meet the object or their end; the grasp succeeds iff
//    the width d they stop at satisfies width - eps_inner < d < width + eps_outer (libfranka's
//    Gripper::grasp). After a success the hand holds with `force`; is_grasped stays true while
//    the width stays in that band, i.e. until the object slips (2 mu F < m g) or another command.
//    A grasp while the hand already holds answers unsuccessful (libfranka issue #108).
//  - stop: ends the running command and releases the grip.
// A command acts after reaction_time; receiving it aborts the command still running.
class Hand {
 public:
  explicit Hand(const HandSettings& settings);

  // The commands. Each checks its arguments against the hand's limits and throws CommandRefused
  // naming the wrong one; otherwise it returns the command's number for answer().
  uint64_t homing();
  uint64_t move(double width, double speed);
  uint64_t grasp(double width, double speed, double force, double epsilon_inner, double epsilon_outer);
  uint64_t stop();
  CommandStatus answer(uint64_t command) const { return answers_.of(command); }

  // Advances the hand by dt >= 0 seconds. The fingers move at constant speed and the temperature
  // is a first-order lag, both integrated exactly; events (reaction over, fingers at their stop,
  // a state message) split the step.
  void step(double dt);

  // The last published state message (what readOnce returns), and the hand as it is now.
  const HandState& published_state() const { return published_; }
  HandState state() const;
  // Time until the next state message [s].
  double time_to_next_state() const { return next_state_in_; }
  double time() const { return time_; }
  // The grasping force applied now [N].
  double force() const { return holding_ ? force_ : 0.0; }
  // What the grasp makes the arm carry (flange frame): the object while it is held, else nothing.
  RigidBodyInertia carried_object() const;

 private:
  enum class Kind { kHoming, kMove, kGrasp, kStop };
  struct Command {
    Kind kind = Kind::kStop;
    double width = 0.0, speed = 0.0, force = 0.0, epsilon_inner = 0.0, epsilon_outer = 0.0;
  };

  uint64_t issue(const Command& command);
  void start();                       // the pending command takes effect
  void arrive();                      // the fingers reached where they were heading
  double heading_to() const;          // where the fingers stop: the target, or the object in the way
  bool object_between() const;
  bool object_in_fingers() const;

  HandSettings settings_;
  double time_ = 0.0;
  double width_, max_width_, temperature_;
  std::optional<HeldObject> object_;

  CommandAnswers answers_;
  Command command_;
  bool pending_ = false;          // received, waiting for reaction_left_
  double reaction_left_ = 0.0;
  int homing_leg_ = 0;            // 1 closing, 2 opening

  bool moving_ = false;           // fingers heading for target_ at speed_
  double target_ = 0.0, speed_ = 0.0;

  bool holding_ = false;          // the grip of a successful grasp
  double force_ = 0.0;
  double band_low_ = 0.0, band_high_ = 0.0;   // the grasp's tolerance band (width - eps_inner, width + eps_outer)

  double next_state_in_;
  HandState published_;
};

// The Cobot Pump's production setup profiles (libfranka VacuumGripper::ProductionSetupProfile).
enum class VacuumProfile { kP0, kP1, kP2, kP3 };

struct VacuumSettings {
  // The vacuum the pump reaches on a sealed part, and its thresholds (all assumed, docs/gripper.md).
  double max_vacuum = 750.0;            // [mbar] below ambient
  double open_vacuum = 20.0;            // [mbar] reached with no part on the cup (it leaks)
  double evacuation_time_constant = 0.1;   // [s]
  double release_time_constant = 0.05;     // [s] blow-off at dropOff
  double leak_time_constant = 30.0;        // [s] decay on a sealed part with the pump off
  double control_hysteresis = 50.0;     // [mbar] h1: in control range while vacuum >= H1 - h1
  double part_present_threshold = 200.0;   // [mbar] H2
  double part_present_hysteresis = 50.0;   // [mbar] h2: absent again below H2 - h2
  double reaction_time = 0.05;          // [s] (assumed)
  double state_period = 0.1;            // [s] between two VacuumGripperState messages (assumed)
  Vector3 suction_point = Vector3(0.0, 0.0, 0.1);   // [m] the part's CoM in the flange frame (assumed)
  std::optional<HeldObject> part;       // the part under the cup, if any (its width is unused)
};

struct VacuumState {
  bool in_control_range = false;
  bool part_detached = false;
  bool part_present = false;
  uint16_t actual_power = 0;   // [%]
  uint16_t vacuum = 0;         // [mbar]
  uint64_t message_id = 0;
};

// The Cobot Pump: a first-order pressure model. vacuum(setpoint) runs the pump towards the
// setpoint (capped by what it reaches: max_vacuum on a part, open_vacuum without one) and answers
// success once the vacuum is in the control range, unsuccessful at the timeout. dropOff blows the
// part off and answers success once it is detached; stop switches the pump off.
class VacuumPump {
 public:
  explicit VacuumPump(const VacuumSettings& settings);

  // setpoint in libfranka's unit (10 mbar), timeout [s]; CommandRefused on bad arguments.
  uint64_t vacuum(unsigned setpoint, double timeout, VacuumProfile profile);
  uint64_t drop_off(double timeout);
  uint64_t stop();
  CommandStatus answer(uint64_t command) const { return answers_.of(command); }

  void step(double dt);

  const VacuumState& published_state() const { return published_; }
  VacuumState state() const;
  double time_to_next_state() const { return next_state_in_; }
  double vacuum_level() const { return vacuum_; }   // [mbar]
  // The profile of the last vacuum command (the same pressure model for all four: docs/gripper.md).
  VacuumProfile profile() const { return profile_; }
  RigidBodyInertia carried_object() const;

 private:
  enum class Kind { kVacuum, kDropOff, kStop };
  enum class Pump { kOff, kSuction, kBlowOff };

  uint64_t issue(Kind kind, double setpoint, double timeout);
  void start();
  void check_answer();
  double heading_to() const;      // the vacuum the pump drives towards now [mbar]
  double time_constant() const;   // ... and how fast [s]
  bool in_control_range() const;

  VacuumSettings settings_;
  double vacuum_ = 0.0;           // [mbar] below ambient
  double setpoint_ = 0.0;         // [mbar]
  Pump pump_ = Pump::kOff;
  VacuumProfile profile_ = VacuumProfile::kP0;
  bool part_on_cup_;              // false once dropOff detached it
  bool part_present_ = false, part_detached_ = false;

  CommandAnswers answers_;
  Kind kind_ = Kind::kStop;
  bool pending_ = false, running_ = false;
  double reaction_left_ = 0.0, timeout_left_ = 0.0, pending_setpoint_ = 0.0;

  double next_state_in_;
  VacuumState published_;
};

// Scenario sections `hand:` and `vacuum_gripper:` (docs/gripper.md); errors name file and key.
HandSettings read_hand_settings(const Field& field);
VacuumSettings read_vacuum_settings(const Field& field);

}  // namespace csp::rt
