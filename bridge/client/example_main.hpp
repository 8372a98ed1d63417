// The command line shared by the example controller processes (csp_lcm_float,
// csp_lcm_joint_impedance): --lcm-url, --prefix, --duration, --timeout, then one torque control
// session.
#pragma once

#include <CLI/CLI.hpp>

#include <functional>

#include "csp/rt/control_loop.hpp"

namespace csp::bridge {

// Parses the options (the common ones and those `add_options` registers), runs one torque
// session of the controller `make(duration)` builds against `csp serve`, prints a one-line
// summary. Exit code: 0 finished, 1 the session ended in a reflex, 2 no robot or bad input.
int run_example_controller(int argc, char** argv, const char* name, const char* description,
                           const std::function<void(CLI::App&)>& add_options,
                           const std::function<rt::Controller(double duration)>& make);

}  // namespace csp::bridge
