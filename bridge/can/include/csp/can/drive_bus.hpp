// The arm's seven joint drives on one CANopen bus, without a transport: frames in (receive),
// frames out (sent), one robot cycle per SYNC. The robot behind the drives is an `Arm`: the bus
// hands it the seven latched commands and takes back its measured state. The bus holds no
// emulator; bridge's RobotServer is the Arm in `csp can serve` (docs/can.md, "The seam").
#pragma once

#include <array>
#include <cstdint>
#include <deque>
#include <vector>

#include "csp/can/drive_node.hpp"

namespace csp::can {

inline constexpr int kJoints = 7;

// One cycle's command for the whole arm, as latched at a SYNC.
struct ArmCommand {
  std::array<JointCommand, kJoints> joints;
  // Every joint in operation enabled got its synchronous RPDO since the previous SYNC. A cycle
  // where some did and some did not ("torn") counts as lost, like a late FCI command.
  bool complete = false;
  bool error_recovery = false;   // a fault reset (402 bit 7) or 0x2003 arrived: automatic error recovery
};

// The robot's state after a cycle.
struct ArmState {
  std::array<JointMeasurement, kJoints> joints;
  rt::ErrorSet errors;             // current_errors: non-empty = a reflex stopped the robot
  // The joints in operation enabled are not all in one mode of operation: the robot runs none of
  // them (one control mode per motion, as Franka's); each such drive sends EMCY 0x6320 once.
  bool mixed_modes = false;
  // The robot runs a motion on the drives' targets (every drive in operation enabled in one mode
  // and the motion started): the enabled drives set statusword bit 12 ("drive follows the
  // target"); when it ends while some stay enabled, those send EMCY 0xFF00.
  bool motion = false;
};

// The robot behind the drives: one cycle per SYNC.
class Arm {
 public:
  virtual ~Arm() = default;
  virtual ArmState cycle(const ArmCommand& command) = 0;
  // The state before the first cycle: what the drives report before the first SYNC (an SDO read
  // of 0x6064, the first TPDOs), so that a master reading its start pose early gets the true one.
  virtual ArmState measured() const = 0;
};

struct BusSettings {
  std::array<uint8_t, kJoints> node_ids{1, 2, 3, 4, 5, 6, 7};   // joint i = node_ids[i]
  std::array<JointDrive, kJoints> drives{panda_joint_drive(1), panda_joint_drive(2), panda_joint_drive(3),
                                         panda_joint_drive(4), panda_joint_drive(5), panda_joint_drive(6),
                                         panda_joint_drive(7)};
  Identity identity;
};

struct BusCounters {
  uint64_t syncs = 0;
  uint64_t lost_cycles = 0;      // an enabled arm without a complete set of RPDOs
  uint64_t torn_cycles = 0;      // some enabled joints' RPDOs arrived, others not
  uint64_t ignored_frames = 0;   // COB-IDs no node uses, malformed NMT frames
  uint64_t missing_syncs = 0;    // cycles run without the master's SYNC (real-time clock)
};

class DriveBus {
 public:
  // Powers the seven nodes on (their boot-up messages are the first frames sent) with the arm's
  // measured state in their objects.
  DriveBus(const BusSettings& settings, Arm& arm);
  DriveBus(const DriveBus&) = delete;   // the nodes send into this object's outbox
  DriveBus& operator=(const DriveBus&) = delete;

  // One frame from the bus; a SYNC runs one cycle.
  void receive(const Frame& frame);
  // One cycle: TPDOs out (the state at this SYNC), RPDOs latched, the arm steps once.
  void on_sync();
  // A cycle the master's SYNC did not come for (real-time clock following the master): the robot
  // runs it without a command, as the FCI runs a cycle whose command is late; no PDO moves.
  void cycle_without_sync();
  // Time for heartbeats (producer 0x1017, consumer 0x1016).
  void elapse(uint32_t microseconds);

  // Frames the nodes sent since the last clear_sent().
  const std::vector<Frame>& sent() const { return out_; }
  void clear_sent() { out_.clear(); }

  const DriveNode& node(int joint) const { return nodes_[joint]; }   // joint 0..6
  const BusCounters& counters() const { return counters_; }

 private:
  Arm& arm_;
  std::vector<Frame> out_;
  std::deque<DriveNode> nodes_;   // a deque: nodes are built in place and never move
  std::array<int, 128> joint_of_node_{};   // -1: no node of ours
  void run_arm();

  ArmCommand command_;
  BusCounters counters_;
};

}  // namespace csp::can
