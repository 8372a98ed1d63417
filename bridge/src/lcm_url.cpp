#include "csp/bridge/lcm_url.hpp"

#include <arpa/inet.h>

#include <charconv>
#include <stdexcept>

namespace csp::bridge {
namespace {

// A whole number from min to max written in full, or nothing.
bool whole_number(const std::string& text, long min, long max) {
  long value = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc() && end == text.data() + text.size() && value >= min && value <= max;
}

}  // namespace

const std::string& checked_lcm_url(const std::string& url) {
  const auto fail = [&](const std::string& what) -> void {
    throw std::invalid_argument("LCM URL `" + url + "`: " + what);
  };
  if (url == "memq://" || url.rfind("memq://", 0) == 0) return url;
  const std::string scheme = "udpm://";
  if (url.rfind(scheme, 0) != 0) fail("expected udpm://ADDRESS:PORT[?ttl=N] or memq://");
  const std::string rest = url.substr(scheme.size());
  const std::size_t query = rest.find('?');
  const std::string address_port = rest.substr(0, query);
  const std::size_t colon = address_port.rfind(':');
  if (colon == std::string::npos) fail("expected ADDRESS:PORT after udpm://");
  const std::string address = address_port.substr(0, colon), port = address_port.substr(colon + 1);
  in_addr parsed{};
  if (inet_pton(AF_INET, address.c_str(), &parsed) != 1) fail("`" + address + "` is not an IPv4 address");
  if ((ntohl(parsed.s_addr) >> 28) != 0xE) fail("`" + address + "` is not a multicast address (224.0.0.0 to 239.255.255.255)");
  if (!whole_number(port, 1, 65535)) fail("port `" + port + "`: expected a number from 1 to 65535");
  if (query == std::string::npos) return url;
  std::string options = rest.substr(query + 1);
  while (!options.empty()) {
    const std::size_t amp = options.find('&');
    const std::string option = options.substr(0, amp);
    options = amp == std::string::npos ? "" : options.substr(amp + 1);
    const std::size_t equals = option.find('=');
    const std::string key = option.substr(0, equals), value = equals == std::string::npos ? "" : option.substr(equals + 1);
    if (key == "ttl") {
      if (!whole_number(value, 0, 255)) fail("ttl `" + value + "`: expected a number from 0 to 255");
    } else if (key == "recv_buf_size") {
      if (!whole_number(value, 1, 1L << 30)) fail("recv_buf_size `" + value + "`: expected a positive number of bytes");
    } else {
      fail("unknown option `" + key + "` (known: ttl, recv_buf_size)");
    }
  }
  return url;
}

}  // namespace csp::bridge
