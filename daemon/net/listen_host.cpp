#include "net/listen_host.h"

#include <string>

namespace drivegate::net {

std::optional<ListenHost> parse_listen_host(std::string_view host) {
  if (host.empty() || host == "*") return ListenHost{boost::asio::ip::address_v6::any(), true};
  if (host == "localhost") host = "127.0.0.1";
  if (host.size() > 2 && host.front() == '[' && host.back() == ']') {
    host = host.substr(1, host.size() - 2);
  }
  boost::system::error_code ec;
  const auto address = boost::asio::ip::make_address(std::string(host), ec);
  if (ec) return std::nullopt;
  return ListenHost{address, false};
}

std::string listen_name(const std::string& host, std::uint16_t port, bool tls) {
  return (host.find(':') != std::string::npos && host.front() != '[' ? "[" + host + "]" : host) +
         ":" + std::to_string(port) + (tls ? " (TLS)" : "");
}

}  // namespace drivegate::net
