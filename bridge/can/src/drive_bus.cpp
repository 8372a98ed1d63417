#include "csp/can/drive_bus.hpp"

#include <stdexcept>
#include <string>

namespace csp::can {

DriveBus::DriveBus(const BusSettings& settings, Arm& arm) : arm_(arm) {
  joint_of_node_.fill(-1);
  out_.reserve(256);
  for (int j = 0; j < kJoints; ++j) {
    const uint8_t id = settings.node_ids[j];
    if (id < 1 || id > 127) throw std::invalid_argument("CAN bus: node id of joint " + std::to_string(j + 1) + " must be 1..127");
    if (joint_of_node_[id] >= 0) throw std::invalid_argument("CAN bus: node id " + std::to_string(id) + " is used twice");
    joint_of_node_[id] = j;
    nodes_.emplace_back(id, settings.drives[j], settings.identity, out_);
  }
  const ArmState initial = arm.measured();
  for (int j = 0; j < kJoints; ++j) nodes_[j].update(initial.joints[j], initial.errors, initial.mixed_modes, initial.motion);
}

void DriveBus::receive(const Frame& frame) {
  if (!is_valid(frame)) {
    ++counters_.ignored_frames;
    return;
  }
  const uint32_t function = frame.id & 0x780;
  const uint32_t node = frame.id & 0x7F;
  if (frame.id == kNmt) {
    if (frame.dlc != 2 || frame.data[1] > 127) {
      ++counters_.ignored_frames;
      return;
    }
    for (DriveNode& n : nodes_)
      if (frame.data[1] == 0 || frame.data[1] == n.node_id()) n.nmt_command(frame.data[0]);
    return;
  }
  if (frame.id == kSync) {
    for (DriveNode& n : nodes_) n.receive_sync(frame);
    on_sync();
    return;
  }
  if (function == kSdoRx && joint_of_node_[node] >= 0) {
    nodes_[joint_of_node_[node]].receive_sdo(frame);
    return;
  }
  if (function == kHeartbeat && frame.dlc == 1) {   // another node's heartbeat (the master's)
    for (DriveNode& n : nodes_) n.receive_heartbeat(static_cast<uint8_t>(node), frame.data[0]);
    return;
  }
  bool used = false;
  for (DriveNode& n : nodes_) used = n.receive_rpdo(frame) || used;
  if (!used) ++counters_.ignored_frames;
}

void DriveBus::on_sync() {
  ++counters_.syncs;
  int enabled = 0, received = 0;
  command_.error_recovery = false;
  for (int j = 0; j < kJoints; ++j) {
    DriveNode& n = nodes_[j];
    n.sync_transmit();
    n.sync_latch();
    command_.joints[j] = n.command();
    command_.error_recovery = n.take_recovery_request() || command_.error_recovery;
    if (command_.joints[j].operation_enabled) {
      ++enabled;
      received += command_.joints[j].received ? 1 : 0;
    }
  }
  command_.complete = enabled > 0 && received == enabled;
  if (enabled > 0 && !command_.complete) ++counters_.lost_cycles;
  if (received > 0 && received < enabled) ++counters_.torn_cycles;
  run_arm();
}

void DriveBus::cycle_without_sync() {
  ++counters_.missing_syncs;
  bool enabled = false;
  for (int j = 0; j < kJoints; ++j) {
    command_.joints[j] = nodes_[j].command();
    command_.joints[j].received = false;   // the RPDOs wait for the SYNC that latches them
    enabled = enabled || command_.joints[j].operation_enabled;
  }
  command_.complete = false;
  command_.error_recovery = false;
  if (enabled) ++counters_.lost_cycles;
  run_arm();
}

void DriveBus::run_arm() {
  const ArmState state = arm_.cycle(command_);
  for (int j = 0; j < kJoints; ++j) nodes_[j].update(state.joints[j], state.errors, state.mixed_modes, state.motion);
}

void DriveBus::elapse(uint32_t microseconds) {
  for (DriveNode& n : nodes_) n.elapse(microseconds);
}

}  // namespace csp::can
