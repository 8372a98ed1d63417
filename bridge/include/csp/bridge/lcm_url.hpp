// LCM provider URLs, checked before liblcm sees them: liblcm prints its own complaint on stderr
// and then fails (or, for a bad ttl, only warns and goes on), so a wrong URL gave two lines or
// none. One clear error instead.
#pragma once

#include <string>

namespace csp::bridge {

// Returns `url` if it is a URL CSP can open: udpm://ADDRESS:PORT[?ttl=N&recv_buf_size=N] with an
// IPv4 multicast address (224.0.0.0/4), a port from 1 to 65535 and ttl from 0 to 255, or
// memq:// (in-process). Throws std::invalid_argument naming what is wrong.
const std::string& checked_lcm_url(const std::string& url);

}  // namespace csp::bridge
