// `csp can serve`: the arm's seven joint drives on SocketCAN (docs/can.md). The drives
// (DriveBus) sit in front of the RobotServer (ServerArm); frames come from and go to one raw
// socket per interface; the session is logged in the LCM log format (`csp replay`).
//
// Clocks: sync = one robot cycle per SYNC (the master's, or CSP's with sync_producer, then as fast
// as the frames flow), deterministic; realtime = rt::DeadlineClock, the 1 kHz clock of every
// front end: CSP sends SYNC at each deadline (sync_producer), or follows the master's SYNC and
// runs a cycle without a command at a deadline no SYNC came for.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "csp/bridge/server.hpp"
#include "csp/can/bus_load.hpp"
#include "csp/can/drive_bus.hpp"
#include "csp/can/server_arm.hpp"
#include "csp/can/socketcan.hpp"
#include "csp/rt/cycle_driver.hpp"

namespace csp::can {

struct CanServeOptions {
  std::string interface = "vcan0";   // with split > 1: the first of `split` numbered interfaces
  int split = 1;                     // spread the joints over this many interfaces (1..7)
  rt::Clock clock = rt::Clock::kLockstep;   // kLockstep = the sync clock
  bool sync_producer = false;        // CSP sends SYNC (realtime: at each deadline; sync: needs a master's pace, refused)
  double bitrate = 1e6;              // of the real bus the load is reported for [bit/s]
  std::string log_path;              // LCM log of the session; empty: none
  double duration = 10.0;            // robot time to serve [s]
  const std::atomic<bool>* stop = nullptr;
  bool quiet = false;
  rt::CycleObserver after_cycle;     // after each robot cycle, once its TPDOs are sent (may be empty)
};

struct InterfaceReport {
  std::string name;
  std::vector<int> joints;           // 1..7
  SocketCounters socket;
  BusLoad load;                      // every frame on the interface, both directions
  // The traffic from the first to the last SYNC at options.bitrate, as if each cycle took 1 ms
  // (what a real bus would carry at 1 kHz); 0 with fewer than two SYNCs.
  double load_percent = 0.0;
  uint64_t bits_at_first_sync = 0, bits_at_last_sync = 0;
};

struct CanServeReport {
  rt::TimingReport timing;   // cycles, round trip SYNC -> the enabled joints' RPDOs, deadlines; warnings (bus load too)
  std::vector<InterfaceReport> interfaces;
  BusCounters bus;
  ServerArmCounters arm;
  bridge::ServerCounters server;
  rt::EmulatorCounters emulator;
  std::string last_reflex;
  uint64_t log_events = 0;
};

// The interface names of a split: "vcan0", 3 -> vcan0, vcan1, vcan2; which joint goes where.
std::vector<std::string> split_interfaces(const std::string& first, int split);
int interface_of_joint(int joint, int split);   // joint 0..6 -> 0..split-1

// Serves `robot` (the run's emulated robot, of `scenario`); run::CanBusSource is the front end.
// Throws std::runtime_error when an interface cannot be opened or the log cannot be written,
// std::invalid_argument on bad options.
CanServeReport serve(rt::Emulator& robot, const rt::Scenario& scenario, const CanServeOptions& options);

}  // namespace csp::can
