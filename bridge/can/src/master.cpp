#include "csp/can/master.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>

#include "csp/can/drive_node.hpp"
#include "csp/rt/deadline_clock.hpp"

namespace csp::can {
namespace {

// A target in the drive's units, saturated to the object's type.
int64_t raw(double value, double step, int64_t low, int64_t high) {
  if (!std::isfinite(value)) return 0;
  return static_cast<int64_t>(std::clamp(std::round(value / step), static_cast<double>(low), static_cast<double>(high)));
}

int16_t signed16(const uint8_t* bytes) { return static_cast<int16_t>(get_le(bytes, 2)); }
int32_t signed32(const uint8_t* bytes) { return static_cast<int32_t>(get_le(bytes, 4)); }

}  // namespace

Master::Master(const std::string& interface, std::array<uint8_t, 7> nodes, double timeout_s)
    : socket_(interface), nodes_(nodes), timeout_ns_(static_cast<int64_t>(timeout_s * 1e9)) {}

void Master::send(const Frame& frame) {
  if (!socket_.send(frame)) throw std::runtime_error("CAN interface " + socket_.interface() + ": cannot send " + to_string(frame));
}

void Master::send(uint32_t id, std::initializer_list<uint8_t> bytes) { send(make_frame(id, bytes)); }

void Master::handle(const Frame& f) {
  const uint32_t function = f.id & 0x780, node = f.id & 0x7F;
  for (int j = 0; j < 7; ++j) {
    if (node != nodes_[j]) continue;
    DriveFeedback& d = feedback_[j];
    if (function == kTpdo1 && f.dlc == 8) {
      d.statusword = static_cast<uint16_t>(get_le(f.data.data(), 2));
      d.q = signed32(&f.data[2]) * 1e-6;
      d.tau_J = signed16(&f.data[6]) * torque_step_[j];
      tpdos_seen_[j] |= 1;
    } else if (function == kTpdo2 && f.dlc == 7) {
      d.dq = signed32(&f.data[0]) * 1e-6;
      d.tau_ext_hat_filtered = signed16(&f.data[4]) * torque_step_[j];
      d.mode = static_cast<int8_t>(f.data[6]);
      tpdos_seen_[j] |= 2;
    } else if (function == kEmcy && f.dlc == 8) {
      emergencies_.push_back(Emergency{static_cast<uint8_t>(node), static_cast<uint16_t>(get_le(f.data.data(), 2)), f.data[2], f.data[3]});
    }
  }
}

bool Master::wait_for(uint32_t id, Frame& out) {
  const int64_t deadline = rt::monotonic_ns() + timeout_ns_;
  while (true) {
    while (const std::optional<Frame> f = socket_.receive()) {
      handle(*f);
      if (f->id == id) {
        out = *f;
        return true;
      }
    }
    const int64_t left = deadline - rt::monotonic_ns();
    if (left <= 0) return false;
    wait_readable({&socket_}, left);
  }
}

uint32_t Master::sdo_read(int joint, uint16_t index, uint8_t subindex) {
  const uint8_t node = nodes_[joint];
  send(kSdoRx + node, {0x40, static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8), subindex, 0, 0, 0, 0});
  Frame answer;
  const std::string what = "node " + std::to_string(node) + " SDO read " + hex(index, 4) + ":" + std::to_string(subindex);
  if (!wait_for(kSdoTx + node, answer)) throw std::runtime_error(what + ": no answer");
  if (answer.data[0] == 0x80) throw std::runtime_error(what + ": abort " + hex(static_cast<uint32_t>(get_le(&answer.data[4], 4)), 8));
  if ((answer.data[0] & 0xE3) != 0x43) throw std::runtime_error(what + ": not an expedited answer");
  const int bytes = 4 - ((answer.data[0] >> 2) & 3);
  return static_cast<uint32_t>(get_le(&answer.data[4], bytes));
}

void Master::sdo_write(int joint, uint16_t index, uint8_t subindex, uint32_t value, int bytes) {
  if (bytes < 1 || bytes > 4) throw std::invalid_argument("expedited SDO write: 1 to 4 bytes");
  const uint8_t node = nodes_[joint];
  Frame request;
  request.id = kSdoRx + node;
  request.dlc = 8;
  request.data = {static_cast<uint8_t>(0x23 | (4 - bytes) << 2), static_cast<uint8_t>(index), static_cast<uint8_t>(index >> 8), subindex};
  for (int i = 0; i < bytes; ++i) request.data[4 + i] = static_cast<uint8_t>(value >> (8 * i));
  send(request);
  Frame answer;
  const std::string what = "node " + std::to_string(node) + " SDO write " + hex(index, 4) + ":" + std::to_string(subindex);
  if (!wait_for(kSdoTx + node, answer)) throw std::runtime_error(what + ": no answer");
  if (answer.data[0] == 0x80) throw std::runtime_error(what + ": abort " + hex(static_cast<uint32_t>(get_le(&answer.data[4], 4)), 8));
}

void Master::start() {
  for (int j = 0; j < 7; ++j) {
    const uint32_t device_type = sdo_read(j, 0x1000, 0);
    if ((device_type & 0xFFFF) != 402)
      throw std::runtime_error("node " + std::to_string(nodes_[j]) + ": device type " + hex(device_type, 8) + " is not a CiA 402 drive");
    torque_step_[j] = sdo_read(j, 0x6076, 0) * 1e-6;   // per mille of mN m -> N m
  }
  send(kNmt, {kNmtStart, 0});
}

void Master::set_mode(int8_t mode) {
  for (int j = 0; j < 7; ++j) sdo_write(j, 0x6060, 0, static_cast<uint8_t>(mode), 1);
  mode_ = mode;
}

const std::array<DriveFeedback, 7>& Master::cycle(uint16_t controlword, const std::array<double, 7>& targets) {
  if (torque_step_[0] == 0.0) throw std::logic_error("csp::can::Master: start() reads the drives' scaling before the first cycle");
  for (int j = 0; j < 7; ++j) {
    const uint8_t n = nodes_[j];
    const int64_t torque = mode_ == kModeCst ? raw(targets[j], torque_step_[j], INT16_MIN, INT16_MAX) : 0;
    send(kRpdo1 + n, {static_cast<uint8_t>(controlword), static_cast<uint8_t>(controlword >> 8), static_cast<uint8_t>(torque),
                      static_cast<uint8_t>(torque >> 8)});
    if (mode_ == kModeCsp || mode_ == kModeCsv) {
      const auto value = static_cast<uint32_t>(raw(targets[j], 1e-6, INT32_MIN, INT32_MAX));
      send((mode_ == kModeCsp ? kRpdo2 : kRpdo3) + n, {static_cast<uint8_t>(value), static_cast<uint8_t>(value >> 8),
                                                       static_cast<uint8_t>(value >> 16), static_cast<uint8_t>(value >> 24), 0, 0});
    }
  }
  tpdos_seen_.fill(0);
  send(kSync, {});
  const int64_t deadline = rt::monotonic_ns() + timeout_ns_;
  const auto complete = [&] {
    for (uint8_t seen : tpdos_seen_)
      if (seen != 3) return false;
    return true;
  };
  while (!complete()) {
    while (const std::optional<Frame> f = socket_.receive()) handle(*f);
    if (complete()) break;
    const int64_t left = deadline - rt::monotonic_ns();
    if (left <= 0) {
      for (int j = 0; j < 7; ++j)
        if (tpdos_seen_[j] != 3) throw std::runtime_error("node " + std::to_string(nodes_[j]) + ": no TPDOs after SYNC");
    }
    wait_readable({&socket_}, left);
  }
  return feedback_;
}

int Master::enable(const std::array<double, 7>& targets) {
  int cycles = 0;
  const auto all = [&](uint16_t mask, uint16_t value) {
    for (const DriveFeedback& d : feedback_)
      if ((d.statusword & mask) != value) return false;
    return true;
  };
  cycle(0x00, targets);
  ++cycles;
  // (controlword, statusword mask and value it leads to): fault reset, shutdown, switch on, enable.
  const struct {
    uint16_t controlword, mask, value;
  } steps[] = {{0x80, 0x4F, 0x40}, {0x06, 0x6F, 0x21}, {0x07, 0x6F, 0x23}, {0x0F, 0x6F, 0x27}};
  for (const auto& s : steps) {
    if (s.controlword == 0x80 && !all(0x4F, 0x08) && all(0x4F, 0x40)) continue;   // no fault, already disabled
    int tries = 0;
    while (!all(s.mask, s.value)) {
      if (++tries > 10) throw std::runtime_error("the drives do not follow controlword " + hex(s.controlword, 2));
      cycle(s.controlword, targets);
      ++cycles;
    }
  }
  return cycles;
}

}  // namespace csp::can
