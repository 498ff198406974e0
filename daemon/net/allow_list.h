// Which client addresses a listener serves: IPv4 / IPv6 addresses and CIDR ranges, checked when a
// connection is accepted (before a byte of it is read). Pure: parsing and matching, no I/O.
#pragma once

#include <boost/asio/ip/address.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace drivegate::net {

// One address ("10.1.3.7", "::1": the whole length) or range ("10.1.2.0/24", "fd00::/8").
struct AddressRange {
  boost::asio::ip::address network;
  unsigned prefix = 0;  // leading bits that must match: 0..32 (IPv4), 0..128 (IPv6)

  // An IPv4 client reaching a dual-stack IPv6 socket appears as ::ffff:a.b.c.d; it matches the
  // IPv4 ranges as a.b.c.d.
  [[nodiscard]] bool contains(const boost::asio::ip::address& peer) const;
  [[nodiscard]] std::string to_string() const;
  friend bool operator==(const AddressRange&, const AddressRange&) = default;
};

// Parses one entry; nullopt with `error` saying why (not an address, prefix out of range, bits
// set beyond the prefix: "10.1.2.5/24" is refused, as it most likely means a mistyped range).
std::optional<AddressRange> parse_address_range(std::string_view text, std::string& error);

// Empty: every address.
using AllowList = std::vector<AddressRange>;
[[nodiscard]] bool allowed(const AllowList& allow, const boost::asio::ip::address& peer);
// True when the list admits every address of a family (empty, or a /0 range in it).
[[nodiscard]] bool allows_everyone(const AllowList& allow);

}  // namespace drivegate::net
