// A plain HTTP/1.0 GET for the end-to-end tests that read drivegated's [http] documents.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "loopback.h"

namespace drivegate::test {

struct HttpReply {
  int status = 0;  // 0: no answer
  std::string headers;
  std::string body;
};

// GET `target` from 127.0.0.1:`port` as HTTP/1.0 (no chunked answers), read to the close.
inline HttpReply http_get(int port, const std::string& target) {
  HttpReply r;
  const int fd = connect_loopback(port);
  if (fd < 0) return r;
  const std::string request = "GET " + target + " HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n";
  if (::write(fd, request.data(), request.size()) != static_cast<ssize_t>(request.size())) {
    ::close(fd);
    return r;
  }
  std::string in;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    char buf[8192];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n <= 0) break;
    in.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  const auto end = in.find("\r\n\r\n");
  if (end == std::string::npos || in.size() < 12 || !in.starts_with("HTTP/1.")) return r;
  r.status = std::atoi(in.substr(9, 3).c_str());
  r.headers = in.substr(0, end);
  r.body = in.substr(end + 4);
  return r;
}

// One sample of an unlabelled metric in the daemon's /metrics on 127.0.0.1:`port`, or -1 when
// the scrape fails or the metric is not there.
inline double metric(int port, const std::string& name) {
  const auto r = http_get(port, "/metrics");
  const auto at = r.body.find("\n" + name + " ");
  if (r.status != 200 || at == std::string::npos) return -1;
  return std::atof(r.body.c_str() + at + name.size() + 2);
}

}  // namespace drivegate::test
