// How often one client address may do something that costs the event loop dearly: a TLS
// handshake (a private-key signature), an HTTP request (rendering a page). A token bucket per
// address: `per_second` tokens a second, up to `burst` saved. IPv6 clients count by their /64
// (one host can take any address in its prefix); IPv4 ones, and IPv4-mapped IPv6, by address.
// The table is bounded: past `max_addresses`, buckets already full again are forgotten first,
// and if none is, every address not in the table shares one bucket, so a flood from many
// addresses is limited as one. Pure: the caller says what time it is.
#pragma once

#include <array>
#include <boost/asio/ip/address.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <map>

namespace drivegate::net {

struct RateLimit {
  unsigned per_second = 0;  // 0: unlimited
  unsigned burst = 1;
  friend bool operator==(const RateLimit&, const RateLimit&) = default;

  // What a configured "so many a second" means (tls_handshakes_per_s, [http] requests_per_s):
  // bursts of twice the rate, so that a client's few at once (a PLC reconnecting, a page load's
  // requests) are never held back.
  static constexpr RateLimit per_second_in_bursts_of_two(unsigned n) {
    return {n, n > 0 ? 2 * n : 1};
  }
};

class AddressRate {
 public:
  using Clock = std::chrono::steady_clock;

  explicit AddressRate(RateLimit limit = {}, std::size_t max_addresses = 1024)
      : limit_(limit), max_addresses_(max_addresses) {}

  // New limits apply to the next admit(); saved tokens beyond the new burst are dropped then.
  void set_limit(RateLimit limit) { limit_ = limit; }
  [[nodiscard]] const RateLimit& limit() const { return limit_; }

  // Takes a token for `who` at `now`: false when it has none left (the caller refuses or waits).
  bool admit(const boost::asio::ip::address& who, Clock::time_point now);
  // Takes `tokens` more from `who` at `now`, for what turned out to cost more than one (a large
  // HTTP response): the balance may go below zero, and its next admit() waits until it is back.
  void charge(const boost::asio::ip::address& who, double tokens, Clock::time_point now);
  // When `who` has its next token: `now` if it has one (or no limit applies).
  [[nodiscard]] Clock::time_point next_token(const boost::asio::ip::address& who,
                                             Clock::time_point now) const;
  // Addresses with a bucket of their own (the bound's test).
  [[nodiscard]] std::size_t tracked() const { return buckets_.size(); }

 private:
  using Key = std::array<std::uint8_t, 16>;
  struct Bucket {
    double tokens = 0;
    Clock::time_point at{};
  };
  static Key key_of(const boost::asio::ip::address& who);
  [[nodiscard]] double tokens_at(const Bucket& b, Clock::time_point now) const;
  Bucket& bucket_for(const Key& key, Clock::time_point now);

  RateLimit limit_;
  std::size_t max_addresses_;
  std::map<Key, Bucket> buckets_;
  Bucket overflow_;  // every address that found the table full
  bool overflow_used_ = false;
};

}  // namespace drivegate::net
