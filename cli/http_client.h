// The little of an HTTP/1.1 client `drivegate capture` needs to talk to the daemon's HTTP side
// (docs/http.md): a connection, a request, the response head, and a whole small response.
// Plain blocking sockets: the tool does one thing at a time.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace drivegate::cli {

// An open TCP connection to host:port; -1 and `error` if none.
int connect_to(const std::string& host, std::uint16_t port, std::string& error);

// Writes all of `data`; false when the connection failed.
bool send_all(int fd, std::string_view data);

// `v` escaped for a query string (RFC 3986 unreserved characters kept).
std::string escape_query(std::string_view v);

// "GET TARGET HTTP/1.1" with Host, User-Agent, Accept and Connection: close.
std::string get_request(const std::string& host, std::uint16_t port, std::string_view target,
                        std::string_view accept);

// The status line's code and reason, and whether the body is chunked.
struct ResponseHead {
  int status = 0;
  bool chunked = false;
  std::string reason;
};
// From the head (the status line and the headers, up to the blank line); nullopt unless HTTP.
std::optional<ResponseHead> parse_head(std::string_view head);

struct HttpResponse {
  ResponseHead head;
  std::string body;  // de-chunked
};
// GET `target` whole, in at most `timeout` and `max_bytes`; nullopt and `error` on failure.
std::optional<HttpResponse> http_get(const std::string& host, std::uint16_t port,
                                     std::string_view target, std::chrono::milliseconds timeout,
                                     std::size_t max_bytes, std::string& error);

}  // namespace drivegate::cli
