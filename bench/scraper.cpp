// dg-scraper PORT RATE SECONDS OUT [--keep-alive] [--decoy] [--path P] [--from A]: the HTTP
// scraper of bench/http_load.sh and bench/flood.sh, in C++ so that its own CPU time (on the load
// generator's CPU: the bench machine has two) is as small as a client's can be. It replaced a
// Python scraper that took ~0.4 ms of CPU a request, enough to delay the load generator and show in
// its latencies.
//
// For SECONDS seconds, fetches /metrics and /api/v1/status of 127.0.0.1:PORT RATE times a second
// each, interleaved: one request every 1 / (2 x RATE) s on an absolute schedule (request i is due
// at start + i x period, so a slow answer does not shift the ones after it; a request started
// more than 2 ms after it was due counts as "late"). Each is GET over HTTP/1.1 on a new TCP
// connection (connect, send, read the whole body, close), or with --keep-alive on one connection
// per path kept open; latency is connect (or send) -> last body byte, CLOCK_MONOTONIC. --decoy:
// the same requests, connections and pacing to two paths the daemon does not serve (a 10-byte
// 404): the client's and the connections' cost without rendering anything. --path P: P in place
// of both paths (bench/flood.sh's history pull: /api/v1/events?limit=1000). --from A: connect from
// the local IPv4 address A (127.0.0.2 ...: one client address of many, as the daemon counts them).
// Appends one line to OUT:
//   scrape requests=N errors=E late=L p50_ms= p99_ms= max_ms= metrics_p50_ms= status_p50_ms=
//          metrics_bytes= status_bytes= cpu_ms= (this process's user + system CPU) seconds=
// Not a general HTTP client: the daemon's replies carry Content-Length and no chunked body.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <string_view>
#include <vector>

namespace {

constexpr long kLateNs = 2'000'000;
constexpr int kTimeoutS = 5;

long long now_ns() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec * 1'000'000'000LL + t.tv_nsec;
}

void sleep_until_ns(long long due) {
  timespec t{static_cast<time_t>(due / 1'000'000'000LL), static_cast<long>(due % 1'000'000'000LL)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
  }
}

double cpu_ms() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  const auto ms = [](const timeval& v) {
    return static_cast<double>(v.tv_sec) * 1e3 + static_cast<double>(v.tv_usec) / 1e3;
  };
  return ms(u.ru_utime) + ms(u.ru_stime);
}

int connect_to(int port, const in_addr& from) {
  const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return -1;
  if (from.s_addr != htonl(INADDR_ANY)) {
    sockaddr_in local{};
    local.sin_family = AF_INET;
    local.sin_addr = from;
    if (bind(fd, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
      close(fd);
      return -1;
    }
  }
  const timeval tv{kTimeoutS, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  const int one = 1;
  setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<const sockaddr*>(&a), sizeof a) != 0) {
    close(fd);
    return -1;
  }
  return fd;
}

// One request on `fd`; the body's size, or -1 (a status other than `want`, a short or broken
// reply: `why` says which).
long exchange(int fd, std::string_view path, bool keep_alive, int want, std::string& why) {
  std::string req = "GET ";
  req += path;
  req += " HTTP/1.1\r\nHost: 127.0.0.1\r\nUser-Agent: dg-scraper\r\n";
  if (!keep_alive) req += "Connection: close\r\n";
  req += "\r\n";
  if (send(fd, req.data(), req.size(), MSG_NOSIGNAL) != static_cast<ssize_t>(req.size())) {
    why = "send: " + std::string(std::strerror(errno));
    return -1;
  }
  std::string in;
  std::array<char, 16384> buf{};
  std::size_t head_end = std::string::npos;
  long length = -1;
  for (;;) {
    if (head_end == std::string::npos) {
      head_end = in.find("\r\n\r\n");
      if (head_end != std::string::npos) {
        int status = 0;
        std::sscanf(in.c_str(), "HTTP/1.%*d %d", &status);
        if (status != want) {
          why = std::string(path) + ": status " + std::to_string(status);
          return -1;
        }
        // Header names are case-insensitive; the daemon (Beast) writes "Content-Length".
        std::string head = in.substr(0, head_end);
        std::transform(head.begin(), head.end(), head.begin(),
                       [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
        const auto at = head.find("\r\ncontent-length:");
        if (at == std::string::npos) {
          why = std::string(path) + ": no Content-Length";
          return -1;
        }
        length = std::strtol(head.c_str() + at + 17, nullptr, 10);
      }
    }
    if (length >= 0 && in.size() >= head_end + 4 + static_cast<std::size_t>(length)) return length;
    const ssize_t n = recv(fd, buf.data(), buf.size(), 0);
    if (n <= 0) {
      why = std::string(path) +
            (n == 0 ? ": closed early" : ": recv: " + std::string(std::strerror(errno)));
      return -1;
    }
    in.append(buf.data(), static_cast<std::size_t>(n));
  }
}

double pct(std::vector<double> v, double q) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1,
                    static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5))];
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr,
                 "usage: dg-scraper PORT RATE SECONDS OUT [--keep-alive] [--decoy] [--path P] "
                 "[--from A]\n");
    return 2;
  }
  const int port = std::atoi(argv[1]);
  const double rate = std::atof(argv[2]);
  const double seconds = std::atof(argv[3]);
  const char* out = argv[4];
  bool keep_alive = false;
  bool decoy = false;
  std::string_view only_path;
  in_addr from{htonl(INADDR_ANY)};
  for (int i = 5; i < argc; ++i) {
    const std::string_view a = argv[i];
    if (a == "--keep-alive") {
      keep_alive = true;
    } else if (a == "--decoy") {
      decoy = true;
    } else if (a == "--path" && i + 1 < argc) {
      only_path = argv[++i];
    } else if (a == "--from" && i + 1 < argc && inet_pton(AF_INET, argv[i + 1], &from) == 1) {
      ++i;
    } else {
      std::fprintf(stderr, "dg-scraper: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  if (port <= 0 || port > 65535 || !(rate > 0) || !(seconds > 0)) {
    std::fprintf(stderr, "dg-scraper: PORT 1..65535, RATE and SECONDS above 0\n");
    return 2;
  }
  const std::array<std::string_view, 2> paths =
      only_path.empty() ? std::array<std::string_view, 2>{"/metrics", "/api/v1/status"}
                        : std::array<std::string_view, 2>{only_path, only_path};
  const std::array<std::string_view, 2> sent =
      decoy ? std::array<std::string_view, 2>{"/metrics-decoy", "/api/v1/status-decoy"} : paths;
  const int want = decoy ? 404 : 200;
  const auto period = static_cast<long long>(1e9 / (2 * rate));
  std::array<int, 2> conns{-1, -1};
  std::array<std::vector<double>, 2> lat;
  std::array<long, 2> size{0, 0};
  int errors = 0;
  int late = 0;

  const double cpu0 = cpu_ms();
  const long long start = now_ns();
  for (long long i = 0;; ++i) {
    const long long due = start + i * period;
    if (due - start >= static_cast<long long>(seconds * 1e9)) break;
    const long long now = now_ns();
    if (due > now) {
      sleep_until_ns(due);
    } else if (now - due > kLateNs) {
      ++late;
    }
    const std::size_t k = static_cast<std::size_t>(i % 2);
    const long long t0 = now_ns();
    int fd = keep_alive ? conns[k] : -1;
    if (fd < 0) fd = connect_to(port, from);
    std::string why = "connect: " + std::string(std::strerror(errno));
    const long n = fd < 0 ? -1 : exchange(fd, sent[k], keep_alive, want, why);
    if (n >= 0) {
      size[k] = n;
      lat[k].push_back(static_cast<double>(now_ns() - t0) / 1e6);
    } else {
      ++errors;
      std::fprintf(stderr, "scraper: %s\n", why.c_str());
    }
    if (keep_alive && n >= 0) {
      conns[k] = fd;
    } else {
      if (fd >= 0) close(fd);
      conns[k] = -1;
    }
  }
  const double cpu = cpu_ms() - cpu0;
  for (const int fd : conns) {
    if (fd >= 0) close(fd);
  }

  std::vector<double> every = lat[0];
  every.insert(every.end(), lat[1].begin(), lat[1].end());
  FILE* f = std::fopen(out, "a");
  if (f == nullptr) {
    std::fprintf(stderr, "dg-scraper: %s: %s\n", out, std::strerror(errno));
    return 1;
  }
  std::fprintf(f,
               "scrape requests=%zu errors=%d late=%d p50_ms=%.3f p99_ms=%.3f max_ms=%.3f "
               "metrics_p50_ms=%.3f status_p50_ms=%.3f metrics_bytes=%ld status_bytes=%ld "
               "cpu_ms=%.0f seconds=%g\n",
               every.size(), errors, late, pct(every, 0.5), pct(every, 0.99),
               every.empty() ? NAN : *std::max_element(every.begin(), every.end()),
               pct(lat[0], 0.5), pct(lat[1], 0.5), size[0], size[1], cpu, seconds);
  std::fclose(f);
  return 0;
}
