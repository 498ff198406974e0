#include "config/port_address.h"

#include <charconv>

namespace drivegate {

std::optional<PortAddress> parse_port_address(std::string_view text, std::string& error) {
  PortAddress a;
  std::string_view rest;
  if (text.starts_with("tcp://")) {
    a.kind = PortAddress::Kind::tcp;
    rest = text.substr(6);
  } else if (text.starts_with("rfc2217://")) {
    a.kind = PortAddress::Kind::rfc2217;
    rest = text.substr(10);
  } else if (text.find("://") != std::string_view::npos) {
    error = "\"" + std::string(text) +
            "\": unknown scheme (a device path, tcp://host:port or rfc2217://host:port)";
    return std::nullopt;
  } else {
    if (text.empty()) {
      error = "is empty (a device path, tcp://host:port or rfc2217://host:port)";
      return std::nullopt;
    }
    a.path = std::string(text);
    return a;
  }
  std::string_view host;
  std::string_view port;
  if (rest.starts_with("[")) {
    const auto close = rest.find("]:");
    if (close != std::string_view::npos) {
      host = rest.substr(1, close - 1);
      port = rest.substr(close + 2);
    }
  } else if (const auto colon = rest.rfind(':'); colon != std::string_view::npos) {
    host = rest.substr(0, colon);
    port = rest.substr(colon + 1);
  }
  unsigned value = 0;
  const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
  if (host.empty() || port.empty() || ec != std::errc() || end != port.data() + port.size() ||
      value == 0 || value > 65535) {
    error = "\"" + std::string(text) + "\": must be " +
            (a.kind == PortAddress::Kind::tcp ? "tcp" : "rfc2217") +
            "://host:port with a port 1..65535 (IPv6 as [addr]:port)";
    return std::nullopt;
  }
  a.host = std::string(host);
  a.port = static_cast<std::uint16_t>(value);
  return a;
}

}  // namespace drivegate
