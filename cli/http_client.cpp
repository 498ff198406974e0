#include "http_client.h"

#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstring>

#include "dechunk.h"

namespace drivegate::cli {

int connect_to(const std::string& host, std::uint16_t port, std::string& error) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port);
  if (const int rc = ::getaddrinfo(host.c_str(), service.c_str(), &hints, &found); rc != 0) {
    error = ::gai_strerror(rc);
    return -1;
  }
  int fd = -1;
  for (addrinfo* a = found; a != nullptr && fd < 0; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd >= 0 && ::connect(fd, a->ai_addr, a->ai_addrlen) != 0) {
      error = std::strerror(errno);
      ::close(fd);
      fd = -1;
    }
  }
  ::freeaddrinfo(found);
  return fd;
}

bool send_all(int fd, std::string_view data) {
  while (!data.empty()) {
    const ssize_t n = ::send(fd, data.data(), data.size(), MSG_NOSIGNAL);
    if (n <= 0) return false;
    data.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

std::string escape_query(std::string_view v) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (const char c : v) {
    const auto u = static_cast<unsigned char>(c);
    if (std::isalnum(u) != 0 || c == '-' || c == '_' || c == '.' || c == '~') {
      out.push_back(c);
    } else {
      out += '%';
      out += kHex[u >> 4];
      out += kHex[u & 15];
    }
  }
  return out;
}

std::string get_request(const std::string& host, std::uint16_t port, std::string_view target,
                        std::string_view accept) {
  return "GET " + std::string(target) + " HTTP/1.1\r\nHost: " + host + ":" + std::to_string(port) +
         "\r\nUser-Agent: drivegate\r\nAccept: " + std::string(accept) +
         "\r\nConnection: close\r\n\r\n";
}

std::optional<ResponseHead> parse_head(std::string_view head) {
  ResponseHead h;
  const auto eol = head.find("\r\n");
  const std::string_view status_line = head.substr(0, eol);
  if (status_line.substr(0, 5) != "HTTP/" || status_line.size() < 12) return std::nullopt;
  const auto sp = status_line.find(' ');
  const auto code = status_line.substr(sp + 1, 3);
  if (std::from_chars(code.data(), code.data() + 3, h.status).ec != std::errc{}) {
    return std::nullopt;
  }
  h.reason = std::string(status_line.substr(std::min(status_line.size(), sp + 5)));
  std::string lower(head);
  for (char& c : lower) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  h.chunked = lower.find("\r\ntransfer-encoding: chunked") != std::string::npos;
  return h;
}

std::optional<HttpResponse> http_get(const std::string& host, std::uint16_t port,
                                     std::string_view target, std::chrono::milliseconds timeout,
                                     std::size_t max_bytes, std::string& error) {
  const int fd = connect_to(host, port, error);
  if (fd < 0) return std::nullopt;
  error.clear();  // an address tried before the one that answered
  if (!send_all(fd, get_request(host, port, target, "*/*"))) {
    error = std::strerror(errno);
    ::close(fd);
    return std::nullopt;
  }
  // Connection: close: the response ends where the connection does.
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::string raw;
  char buf[16384];
  while (true) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    pollfd p{fd, POLLIN, 0};
    if (left.count() <= 0 || ::poll(&p, 1, static_cast<int>(left.count())) == 0) {
      error = "no complete answer in " + std::to_string(timeout.count()) + " ms";
      break;
    }
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) error = std::strerror(errno);
    if (n <= 0) break;
    raw.append(buf, static_cast<std::size_t>(n));
    if (raw.size() > max_bytes) {
      error = "an answer of more than " + std::to_string(max_bytes) + " bytes";
      break;
    }
  }
  ::close(fd);
  if (!error.empty()) return std::nullopt;
  const auto end = raw.find("\r\n\r\n");
  auto head = end == std::string::npos ? std::nullopt : parse_head(raw.substr(0, end + 2));
  if (!head) {
    error = "not an HTTP response";
    return std::nullopt;
  }
  HttpResponse out{*head, {}};
  const std::string_view body = std::string_view(raw).substr(end + 4);
  if (!head->chunked) {
    out.body = body;
    return out;
  }
  Dechunker dechunk;
  if (!dechunk.feed(body, out.body) || !dechunk.done()) {
    error = "a bad or cut short chunked body";
    return std::nullopt;
  }
  return out;
}

}  // namespace drivegate::cli
