#include "net/address_rate.h"

#include <algorithm>
#include <iterator>

namespace drivegate::net {

AddressRate::Key AddressRate::key_of(const boost::asio::ip::address& who) {
  Key k{};
  if (who.is_v4()) {
    const auto b = who.to_v4().to_bytes();
    std::copy(b.begin(), b.end(), k.begin());
    return k;
  }
  const auto v6 = who.to_v6();
  if (v6.is_v4_mapped())
    return key_of(boost::asio::ip::make_address_v4(boost::asio::ip::v4_mapped, v6));
  const auto b = v6.to_bytes();
  k[15] = 6;  // an IPv6 /64 never equals an IPv4 key (whose bytes 4..15 are 0)
  std::copy(b.begin(), b.begin() + 8, k.begin() + 4);
  return k;
}

double AddressRate::tokens_at(const Bucket& b, Clock::time_point now) const {
  const double elapsed = std::chrono::duration<double>(now - b.at).count();
  return std::min<double>(limit_.burst, b.tokens + std::max(0.0, elapsed) * limit_.per_second);
}

AddressRate::Bucket& AddressRate::bucket_for(const Key& key, Clock::time_point now) {
  if (const auto it = buckets_.find(key); it != buckets_.end()) return it->second;
  if (buckets_.size() >= max_addresses_) {
    std::erase_if(buckets_,
                  [&](const auto& kv) { return tokens_at(kv.second, now) >= limit_.burst; });
  }
  if (buckets_.size() >= max_addresses_) {
    if (!overflow_used_) overflow_ = {static_cast<double>(limit_.burst), now};
    overflow_used_ = true;
    return overflow_;
  }
  return buckets_.emplace(key, Bucket{static_cast<double>(limit_.burst), now}).first->second;
}

bool AddressRate::admit(const boost::asio::ip::address& who, Clock::time_point now) {
  if (limit_.per_second == 0) return true;
  Bucket& b = bucket_for(key_of(who), now);
  b.tokens = tokens_at(b, now);
  b.at = now;
  if (b.tokens < 1.0) return false;
  b.tokens -= 1.0;
  return true;
}

void AddressRate::charge(const boost::asio::ip::address& who, double tokens,
                         Clock::time_point now) {
  if (limit_.per_second == 0 || tokens <= 0) return;
  Bucket& b = bucket_for(key_of(who), now);
  b.tokens = tokens_at(b, now) - tokens;
  b.at = now;
}

AddressRate::Clock::time_point AddressRate::next_token(const boost::asio::ip::address& who,
                                                       Clock::time_point now) const {
  if (limit_.per_second == 0) return now;
  const auto it = buckets_.find(key_of(who));
  const Bucket* b = nullptr;
  if (it != buckets_.end()) {
    b = &it->second;
  } else if (buckets_.size() >= max_addresses_ && overflow_used_) {
    b = &overflow_;  // where admit() would put it (unless full buckets are forgotten first)
  }
  if (b == nullptr) return now;
  const double have = tokens_at(*b, now);
  if (have >= 1.0) return now;
  const double wait_s = (1.0 - have) / limit_.per_second;
  return now + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(wait_s));
}

}  // namespace drivegate::net
