// What the host part of a listening address means, for every listener (Modbus and HTTP) and for
// the configuration's check of it: a numeric IPv4 or IPv6 address ("[::1]" accepted),
// "localhost" (127.0.0.1), or "" / "*" for every interface. No DNS lookup: it would block the
// event loop at start-up and could change under a running daemon. And how the log names a listening
// address.
#pragma once

#include <boost/asio/ip/address.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace drivegate::net {

struct ListenHost {
  boost::asio::ip::address address;  // for `any`: the IPv6 any address (dual stack)
  bool any = false;                  // every interface
};

std::optional<ListenHost> parse_listen_host(std::string_view host);

// "host:port" (an IPv6 host in brackets), and " (TLS)" for a TLS listener: a Modbus TCP
// listener's name in the log, the status documents and the configuration's messages.
std::string listen_name(const std::string& host, std::uint16_t port, bool tls);

}  // namespace drivegate::net
