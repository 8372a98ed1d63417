// The in-process reference of the vcan test: the emulator of the default scenario given the
// quantized CST commands the Python master sent, printing what the drives' TPDOs must carry.
// Input (file): "start S" = the SYNC whose cycle started the motion (cycles 0..S-1 idle), then one
// line per cycle from S on with the seven target torques in per mille of 0x6076.
// Output: per cycle from S on, positions and velocities in urad and urad/s (the wire values).
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

#include "csp/rt/emulator.hpp"
#include "csp/rt/scenario.hpp"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: csp_can_reference COMMANDS_FILE\n";
    return 2;
  }
  std::ifstream in(argv[1]);
  std::string word;
  long start = -1;
  if (!(in >> word >> start) || word != "start" || start < 0) {
    std::cerr << argv[1] << ": expected `start S` first\n";
    return 2;
  }
  csp::rt::Emulator emulator(csp::rt::load_scenario(csp::rt::default_scenario_path()).emulator);
  for (long k = 0; k < start; ++k) emulator.step(nullptr);
  emulator.start_motion(csp::rt::ControlMode::kTorque);
  // 0x6076 rated torque: 3000 mN m (joints 1-4), 500 mN m (5-7); one step = 1 per mille.
  const double step[7] = {3e-3, 3e-3, 3e-3, 3e-3, 0.5e-3, 0.5e-3, 0.5e-3};
  std::string line;
  std::getline(in, line);
  while (std::getline(in, line)) {
    std::istringstream values(line);
    csp::rt::Command command;
    for (int j = 0; j < 7; ++j) {
      long raw = 0;
      if (!(values >> raw)) {
        std::cerr << argv[1] << ": expected 7 torques per line: `" << line << "`\n";
        return 2;
      }
      command.values[j] = static_cast<double>(raw) * step[j];
    }
    emulator.step(&command);
    const csp::rt::RobotState& s = emulator.state();
    for (int j = 0; j < 7; ++j) std::printf("%lld ", static_cast<long long>(std::round(s.q[j] / 1e-6)));
    for (int j = 0; j < 7; ++j) std::printf("%lld%c", static_cast<long long>(std::round(s.dq[j] / 1e-6)), j == 6 ? '\n' : ' ');
  }
  return 0;
}
