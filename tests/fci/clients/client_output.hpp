// What CSP's libfranka programs print: one JSON object a line, for tests/fci/run_client.py.
#pragma once

#include <array>
#include <cstdio>
#include <sstream>
#include <string>

#include <franka/robot_state.h>

namespace csp_fci_clients {

inline std::string json_string(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof(escaped), "\\u%04x", c);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// Every digit a double has (17 significant), so that the test compares what libfranka computed.
template <std::size_t N>
std::string json_array(const std::array<double, N>& values) {
  std::string out = "[";
  for (std::size_t i = 0; i < N; ++i) {
    char number[32];
    std::snprintf(number, sizeof(number), "%.17g", values[i]);
    out += (i ? "," : "") + std::string(number);
  }
  return out + "]";
}

// The whole state as libfranka prints it (a JSON object: q, dq, robot_mode by name, the error
// flags as lists of names).
inline std::string json_state(const franka::RobotState& state) {
  std::ostringstream text;
  text << state;
  return text.str();
}

}  // namespace csp_fci_clients
