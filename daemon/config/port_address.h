// Where a bus's bytes go: a local serial device, or a serial device server on the network
// (README, "Buses behind serial device servers"). Parsed from [[bus]] port; one definition for
// the configuration's checks and the line's transports.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace drivegate {

struct PortAddress {
  enum class Kind : std::uint8_t {
    tty,      // "/dev/ttyUSB0": the line settings are set here, with termios
    tcp,      // "tcp://host:port": raw TCP; the server's line settings are set on the server
    rfc2217,  // "rfc2217://host:port": Telnet COM-PORT-OPTION; drivegate sets the line settings
  };
  Kind kind = Kind::tty;
  std::string path;  // tty
  std::string host;  // tcp, rfc2217: a name or a numeric IPv4 / IPv6 address ("[::1]" form)
  std::uint16_t port = 0;

  [[nodiscard]] bool network() const { return kind != Kind::tty; }
};

// nullopt and `error` saying what is wrong ("tcp://host" without a port, port 0, ...).
std::optional<PortAddress> parse_port_address(std::string_view text, std::string& error);

}  // namespace drivegate
