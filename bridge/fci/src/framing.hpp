// The command ports' framing, the same for the robot's server (1337) and the hand's (1338): a
// request has a fixed size for its command, so a message is judged by its header before it is
// whole (a header announcing 4 GB is refused at once, not waited for); bytes wait in `buffer`
// until the message is complete. Private to bridge/fci.
#pragma once

#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "csp/fci/protocol.hpp"

namespace csp::fci {

// A request's fixed-size payload (packed, possibly unaligned in the buffer). Callers that read its
// arrays hold it as `alignas(8)`: every request's doubles lie at multiples of 8 in it.
template <typename T>
T read_payload(const uint8_t* payload) {
  return unaligned_field<T>(payload, 0);
}

// Appends `data` to `buffer` and hands over every complete message. `problem(header)` names what
// is wrong with a header (empty: nothing, and header.size is the message's size); `handle(header,
// payload)` returns false when the message ends the connection; `refuse(problem)` reports one.
// Returns false when the connection must close.
template <typename Header, typename Problem, typename Handle, typename Refuse>
bool take_messages(std::vector<uint8_t>& buffer, const uint8_t* data, std::size_t size, const Problem& problem,
                   const Handle& handle, const Refuse& refuse) {
  buffer.insert(buffer.end(), data, data + size);
  while (buffer.size() >= sizeof(Header)) {
    Header header;
    std::memcpy(&header, buffer.data(), sizeof(header));
    const std::string wrong = problem(header);
    if (!wrong.empty()) {
      buffer.clear();
      refuse(wrong);
      return false;
    }
    if (buffer.size() < header.size) return true;   // the rest is on its way
    const bool keep = handle(header, buffer.data() + sizeof(Header));
    buffer.erase(buffer.begin(), buffer.begin() + header.size);
    if (!keep) return false;
  }
  return true;
}

}  // namespace csp::fci
