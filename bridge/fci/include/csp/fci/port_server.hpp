// What serves one TCP port of the robot for its one client, without a transport: the robot's
// FciServer (1337) and the hand's GripperServer (1338). `csp fci` moves the bytes (serve.cpp).
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <vector>

namespace csp::fci {

class PortServer {
 public:
  // Sends bytes on the client's TCP connection.
  using SendTcp = std::function<void(const std::vector<uint8_t>& bytes)>;

  virtual ~PortServer() = default;
  // A client's connection opened; its bytes go to receive_tcp(), replies to `send`.
  virtual void open_connection(SendTcp send) = 0;
  // Bytes received on the connection, in any split. Returns false if the connection must be
  // closed (a malformed message, a version the device does not serve); the reason is a diagnostic.
  virtual bool receive_tcp(const uint8_t* data, std::size_t size) = 0;
  // The connection closed.
  virtual void close_connection() = 0;
  // After a successful Connect: the client's UDP port for the state messages.
  virtual std::optional<uint16_t> client_udp_port() const = 0;
};

}  // namespace csp::fci
