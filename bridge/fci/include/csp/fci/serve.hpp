// `csp fci`: the emulated robot on the network as a Franka robot is (docs/fci.md): the command
// port 1337 (TCP) and the 1 kHz UDP exchange of states and commands, so that an unmodified
// libfranka connects to `address`; the Franka Hand on port 1338 and the Cobot Pump on 1339 where
// the robot has them. One
// client a port at a time; the robot outlives its clients.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>

#include "csp/fci/device_server.hpp"
#include "csp/fci/server.hpp"
#include "csp/rt/cycle_driver.hpp"

namespace csp::fci {

struct FciServeOptions {
  std::string address = "127.0.0.1";   // the robot's IPv4 address (any 127.x.y.z on one machine)
  Version version = kPandaVersion;      // the protocol the robot speaks
  rt::Clock clock = rt::Clock::kRealtime;   // lockstep: a motion's cycle waits for its command
  double lockstep_timeout = 1.0;        // lockstep: how long a motion's cycle waits [s]
  std::optional<double> duration;       // robot time to serve [s]; none: until `stop`
  FciServer::ModelLibrary model_library;
  rt::CommandFaults faults;              // the scenario's network faults (FciServer)
  std::optional<rt::HandSettings> hand;   // the Franka Hand on port 1338 (none: the port stays closed)
  std::optional<rt::VacuumSettings> vacuum_gripper;   // the Cobot Pump on port 1339 (none: closed)
  const std::atomic<bool>* stop = nullptr;   // set (e.g. by SIGINT) to end the run cleanly
  std::function<void()> listening;      // called once the command port accepts connections
  FciServer::Diagnostic diagnostic;     // one line per notable event (may be empty)
  rt::CycleObserver after_cycle;        // after each robot cycle (may be empty)
};

struct FciServeReport {
  rt::TimingReport timing;              // cycles, round trip state sent -> its command received
  FciCounters counters;
  rt::EmulatorCounters emulator;
  uint64_t foreign_packets = 0;         // UDP packets from another sender than the client
  std::optional<DeviceCounters> gripper, vacuum_gripper;
  std::string last_reflex;
};

// Serves `robot` (the run's emulated robot) until options.duration or options.stop. Throws
// std::runtime_error naming the address if the sockets cannot be opened (an address this machine
// does not have, port 1337 in use).
FciServeReport serve_fci(rt::Emulator& robot, const FciServeOptions& options);

}  // namespace csp::fci
