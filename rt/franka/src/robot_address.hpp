// The robot a libfranka program's address names (docs/franka_api.md, "The robot's address").
#pragma once

#include <string>

namespace csp::franka_address {

// The scenario file of `franka_address`:
//  - a path to an existing file, or one ending in .yaml / .yml: that scenario file;
//  - an IP address or hostname (what a libfranka program passes): the scenario $CSP_SCENARIO
//    names (a path, or the name of a shipped scenario such as `libfranka_fr3`), else the shipped
//    libfranka_panda.yaml.
// `scenario_env` is $CSP_SCENARIO's value (null: unset); `shipped_dir` the shipped scenarios' folder.
// Throws std::invalid_argument naming what is wrong (an empty address, a hostname with characters
// no hostname has, a shipped name that does not exist).
std::string scenario_for_address(const std::string& franka_address, const char* scenario_env,
                                 const std::string& shipped_dir);

}  // namespace csp::franka_address
