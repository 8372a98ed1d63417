#include "csp/can/frame.hpp"

#include <cstdio>
#include <stdexcept>

namespace csp::can {

bool is_valid(const Frame& frame) { return frame.id <= 0x7FF && frame.dlc <= 8; }

std::string to_string(const Frame& frame) {
  char text[32];
  int n = std::snprintf(text, sizeof text, "%03X#", static_cast<unsigned>(frame.id));
  for (int i = 0; i < frame.dlc && i < 8; ++i) n += std::snprintf(text + n, sizeof text - n, "%02X", frame.data[i]);
  return std::string(text, n);
}

namespace {
int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}
}  // namespace

Frame parse_frame(const std::string& text) {
  const auto hash = text.find('#');
  if (hash == std::string::npos || hash == 0 || hash > 3)
    throw std::invalid_argument("CAN frame `" + text + "`: expected ID#DATA with a 1-3 digit hex ID");
  Frame frame;
  for (size_t i = 0; i < hash; ++i) {
    const int d = hex_digit(text[i]);
    if (d < 0) throw std::invalid_argument("CAN frame `" + text + "`: the ID is not hexadecimal");
    frame.id = frame.id * 16 + static_cast<uint32_t>(d);
  }
  const std::string data = text.substr(hash + 1);
  if (data.size() % 2 != 0 || data.size() > 16)
    throw std::invalid_argument("CAN frame `" + text + "`: expected 0 to 8 data bytes as pairs of hex digits");
  for (size_t i = 0; i < data.size(); i += 2) {
    const int high = hex_digit(data[i]), low = hex_digit(data[i + 1]);
    if (high < 0 || low < 0) throw std::invalid_argument("CAN frame `" + text + "`: the data is not hexadecimal");
    frame.data[i / 2] = static_cast<uint8_t>(high * 16 + low);
  }
  frame.dlc = static_cast<uint8_t>(data.size() / 2);
  if (!is_valid(frame)) throw std::invalid_argument("CAN frame `" + text + "`: the ID exceeds 11 bits (0x7FF)");
  return frame;
}

std::string hex(uint64_t value, int digits) {
  char text[24];
  std::snprintf(text, sizeof text, "0x%0*llX", digits, static_cast<unsigned long long>(value));
  return text;
}

}  // namespace csp::can
