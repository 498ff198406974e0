// What the HTTP side counts (HttpServer::stats()): shown in /metrics and /api/v1/status beside
// the Modbus listeners' counters, so the status page's own traffic is visible too.
#pragma once

#include <cstdint>

namespace drivegate::http {

struct HttpStats {
  std::uint64_t accepted = 0;
  std::uint64_t not_allowed = 0;  // closed at accept: address not in the allow list
  std::uint64_t refused = 0;      // closed at accept: max_clients
  std::uint64_t requests = 0;
  std::uint64_t bad_requests = 0;      // malformed, headers too large, a body: 400 / 431, closed
  std::uint64_t timeouts = 0;          // closed: no whole request within request_timeout
  std::uint64_t captures = 0;          // /api/v1/capture streams started
  std::uint64_t captures_refused = 0;  // 503: max_captures were streaming already
  std::uint64_t requests_paced = 0;    // held back by the per-address rate limit, then served
};

}  // namespace drivegate::http
