#include "net/allow_list.h"

#include <algorithm>
#include <array>
#include <charconv>

namespace drivegate::net {
namespace {

namespace ip = boost::asio::ip;

// The address as bytes, IPv4-mapped IPv6 addresses unmapped, so that one rule serves both.
ip::address canonical(const ip::address& a) {
  if (a.is_v6() && a.to_v6().is_v4_mapped()) {
    return ip::make_address_v4(ip::v4_mapped, a.to_v6());
  }
  return a;
}

template <std::size_t N>
bool prefix_equal(const std::array<unsigned char, N>& a, const std::array<unsigned char, N>& b,
                  unsigned prefix) {
  for (std::size_t i = 0; i < N && prefix > 0; ++i) {
    const unsigned bits = std::min(prefix, 8u);
    const auto mask = static_cast<unsigned char>(0xFFu << (8 - bits));
    if (((a[i] ^ b[i]) & mask) != 0) return false;
    prefix -= bits;
  }
  return true;
}

template <std::size_t N>
bool host_bits_zero(const std::array<unsigned char, N>& a, unsigned prefix) {
  for (std::size_t i = 0; i < N; ++i) {
    const unsigned keep = std::min(prefix, 8u);  // network bits in this byte
    prefix -= keep;
    if ((a[i] & (0xFFu >> keep)) != 0) return false;
  }
  return true;
}

}  // namespace

bool AddressRange::contains(const ip::address& peer) const {
  const ip::address p = canonical(peer);
  if (p.is_v4() != network.is_v4()) return false;
  if (p.is_v4()) return prefix_equal(p.to_v4().to_bytes(), network.to_v4().to_bytes(), prefix);
  return prefix_equal(p.to_v6().to_bytes(), network.to_v6().to_bytes(), prefix);
}

std::string AddressRange::to_string() const {
  const unsigned full = network.is_v4() ? 32 : 128;
  return prefix == full ? network.to_string() : network.to_string() + "/" + std::to_string(prefix);
}

std::optional<AddressRange> parse_address_range(std::string_view text, std::string& error) {
  const auto slash = text.find('/');
  const std::string host(text.substr(0, slash));
  boost::system::error_code ec;
  AddressRange r;
  r.network = canonical(ip::make_address(host, ec));
  if (ec) {
    error = "\"" + std::string(text) + "\" is not an IPv4 or IPv6 address or CIDR range";
    return std::nullopt;
  }
  const unsigned full = r.network.is_v4() ? 32 : 128;
  r.prefix = full;
  if (slash != std::string_view::npos) {
    const std::string_view bits = text.substr(slash + 1);
    unsigned value = 0;
    const auto [end, perr] = std::from_chars(bits.data(), bits.data() + bits.size(), value);
    if (bits.empty() || perr != std::errc() || end != bits.data() + bits.size() || value > full) {
      error = "\"" + std::string(text) + "\": the prefix length must be 0.." + std::to_string(full);
      return std::nullopt;
    }
    r.prefix = value;
  }
  const bool clean = r.network.is_v4() ? host_bits_zero(r.network.to_v4().to_bytes(), r.prefix)
                                       : host_bits_zero(r.network.to_v6().to_bytes(), r.prefix);
  if (!clean) {
    error = "\"" + std::string(text) + "\" has address bits set beyond /" +
            std::to_string(r.prefix) + " (a range is written with its first address)";
    return std::nullopt;
  }
  return r;
}

bool allowed(const AllowList& allow, const ip::address& peer) {
  return allow.empty() || std::any_of(allow.begin(), allow.end(),
                                      [&](const AddressRange& r) { return r.contains(peer); });
}

bool allows_everyone(const AllowList& allow) {
  return allow.empty() || std::any_of(allow.begin(), allow.end(),
                                      [](const AddressRange& r) { return r.prefix == 0; });
}

}  // namespace drivegate::net
