// drivegate capture: a pcap of one bus, fetched from the running daemon's
// /api/v1/capture (docs/capture.md) over plain HTTP/1.1, de-chunked, written to a file or stdout
// as it comes (so it can feed `wireshark -k -i -`).
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>

#include "commands.h"
#include "config/config_loader.h"
#include "dechunk.h"

namespace drivegate::cli {

namespace {

constexpr const char* kUsage =
    "usage: drivegate capture --bus NAME [--seconds N] [-w FILE] [--http HOST:PORT]\n"
    "\n"
    "Captures every frame of bus NAME for N seconds (1..300, default 10) from the running\n"
    "daemon ([http] capture = true; --http: where its HTTP side listens, 127.0.0.1:8502 by\n"
    "default) and writes a pcap (link type USER0 = 147, docs/capture.md) to FILE, or to stdout.\n"
    "Open it with the dissectors of tools/wireshark/.\n";

// Extra time past the capture's own for the daemon to finish and the bytes to arrive.
constexpr std::chrono::seconds kSlack{15};

// An open TCP connection to host:port; -1 and `error` if none.
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

// The status code and whether the body is chunked, from the response head.
struct Head {
  int status = 0;
  bool chunked = false;
  std::string reason;
};

std::optional<Head> parse_head(std::string_view head) {
  Head h;
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

}  // namespace

int capture(std::span<const std::string_view> args) {
  ArgReader r("capture", args);
  std::string bus;
  int seconds = 10;
  std::string file;
  ListenAddress http{"127.0.0.1", 8502};
  while (!r.done()) {
    const auto arg = r.next();
    if (arg == "--help") {
      std::cout << kUsage;
      return 0;
    }
    auto v = r.value(arg);
    if (!v) return 2;
    if (arg == "--bus") {
      bus = *v;
    } else if (arg == "--seconds") {
      const auto [p, ec] = std::from_chars(v->data(), v->data() + v->size(), seconds);
      if (ec != std::errc{} || p != v->data() + v->size() || seconds < 1 || seconds > 300) {
        return r.usage("--seconds needs a number of seconds (1..300)", kUsage);
      }
    } else if (arg == "-w" || arg == "--write") {
      file = *v;
    } else if (arg == "--http") {
      auto at = parse_listen(*v);
      if (!at) return r.usage("--http needs HOST:PORT", kUsage);
      http = std::move(*at);
    } else {
      return r.usage("unknown argument '" + std::string(arg) + "'", kUsage);
    }
  }
  if (bus.empty()) return r.usage("--bus is required", kUsage);

  std::string error;
  const int fd = connect_to(http.host, http.port, error);
  if (fd < 0) {
    std::cerr << "drivegate capture: cannot connect to " << http.host << ":" << http.port << ": "
              << error << "\n";
    return 1;
  }
  const std::string request = "GET /api/v1/capture?bus=" + escape_query(bus) +
                              "&seconds=" + std::to_string(seconds) +
                              " HTTP/1.1\r\nHost: " + http.host + ":" + std::to_string(http.port) +
                              "\r\nUser-Agent: drivegate\r\nAccept: application/vnd.tcpdump.pcap"
                              "\r\nConnection: close\r\n\r\n";
  if (!send_all(fd, request)) {
    std::cerr << "drivegate capture: cannot send the request: " << std::strerror(errno) << "\n";
    ::close(fd);
    return 1;
  }

  std::ofstream out_file;
  if (!file.empty()) {
    out_file.open(file, std::ios::binary | std::ios::trunc);
    if (!out_file) {
      std::cerr << "drivegate capture: cannot write " << file << "\n";
      ::close(fd);
      return 1;
    }
  }
  std::ostream& out = file.empty() ? std::cout : out_file;

  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds) + kSlack;
  std::string head;
  std::optional<Head> h;
  Dechunker dechunk;
  std::string body;
  std::size_t written = 0;
  bool eof = false;
  char buf[16384];
  while (!eof && !dechunk.done()) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) {
      std::cerr << "drivegate capture: the daemon did not end the capture in time\n";
      break;
    }
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n < 0) {
      if (errno == EINTR) continue;
      std::cerr << "drivegate capture: " << std::strerror(errno) << "\n";
      break;
    }
    if (n == 0) eof = true;
    std::string_view in(buf, static_cast<std::size_t>(n));
    if (!h) {
      head.append(in);
      const auto end = head.find("\r\n\r\n");
      if (end == std::string::npos) {
        if (head.size() > 65536 || eof) {
          std::cerr << "drivegate capture: no HTTP response from the daemon\n";
          ::close(fd);
          return 1;
        }
        continue;
      }
      h = parse_head(std::string_view(head).substr(0, end + 2));
      if (!h) {
        std::cerr << "drivegate capture: bad HTTP response from the daemon\n";
        ::close(fd);
        return 1;
      }
      in = std::string_view(head).substr(end + 4);
      if (h->status != 200) {
        // The refusal's body is a line of text: read what is there and say it.
        std::string why(in);
        while (::poll(&p, 1, 2000) > 0) {
          const ssize_t k = ::recv(fd, buf, sizeof buf, 0);
          if (k <= 0) break;
          why.append(buf, static_cast<std::size_t>(k));
        }
        while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
        std::cerr << "drivegate capture: the daemon answered " << h->status << " " << h->reason
                  << (why.empty() ? "" : ": " + why) << "\n";
        ::close(fd);
        return 1;
      }
    }
    body.clear();
    if (h->chunked) {
      if (!dechunk.feed(in, body)) {
        std::cerr << "drivegate capture: bad chunked coding from the daemon\n";
        break;
      }
    } else {
      body.append(in);
    }
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
    out.flush();
    written += body.size();
  }
  ::close(fd);
  if (!out) {
    std::cerr << "drivegate capture: write failed\n";
    return 1;
  }
  const bool complete = h && (!h->chunked || dechunk.done());
  if (!file.empty()) {
    std::cerr << "drivegate capture: " << written << " bytes of pcap in " << file
              << (complete ? "" : " (cut short)") << "\n";
  }
  return complete ? 0 : 1;
}

}  // namespace drivegate::cli
