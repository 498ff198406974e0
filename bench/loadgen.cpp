// dg-loadgen: a closed-loop Modbus TCP load generator. N connections, each with exactly one
// request outstanding; the requests alternate between a "large" read and a "small" read (by
// default FC03 0..124 and FC04 0..18, the common block). Every reply is checked (transaction id,
// unit, function, byte count, MBAP length); any mismatch or exception reply counts as an error
// and makes the exit status 1. Bounded by --duration and --max-requests, whichever comes first.
//
// Prints one line of key=value: rps, p50_us, p99_us, p999_us, cpu_us_per_req (utime+stime of
// --pid from /proc/<pid>/stat over the measured window), jain (fairness over connections),
// requests, errors.
#include <arpa/inet.h>
#include <errno.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/epoll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

// Modbus Application Protocol V1.1b3 and Modbus Messaging on TCP/IP V1.0b: MBAP header is
// transaction id (2), protocol id (2, 0), length (2, unit + PDU), unit id (1).
constexpr std::size_t kMbapSize = 7;
constexpr std::size_t kMaxAdu = 260;  // 7 + 253, Messaging on TCP/IP 4.1

struct Read {
  std::uint8_t function = 3;
  std::uint16_t start = 0;
  std::uint16_t count = 125;  // 125: the FC03/FC04 maximum (Application Protocol 6.3, 6.4)
};

struct Args {
  std::string host = "127.0.0.1";
  std::uint16_t port = 502;
  int connections = 1;
  double duration_s = 3.0;
  double warmup_s = 0.5;
  std::uint64_t max_requests = 0;  // 0: no bound but time
  std::uint8_t unit = 1;
  Read large{3, 0, 125};
  Read small{4, 0, 19};  // the common block: input registers 0..18
  int pid = 0;           // the server, for CPU per request
};

struct Conn {
  int fd = -1;
  std::uint16_t tid = 0;
  bool large_next = true;
  Read pending{};
  Clock::time_point sent{};
  std::array<std::uint8_t, kMaxAdu> buf{};
  std::size_t have = 0;
  std::uint64_t done = 0;  // replies in the measured window
};

std::optional<Read> parse_read(const std::string& text) {
  Read r;
  unsigned f = 0, s = 0, c = 0;
  if (std::sscanf(text.c_str(), "%u:%u:%u", &f, &s, &c) != 3) return std::nullopt;
  if ((f != 3 && f != 4) || c == 0 || c > 125 || s + c > 65536) return std::nullopt;
  r.function = static_cast<std::uint8_t>(f);
  r.start = static_cast<std::uint16_t>(s);
  r.count = static_cast<std::uint16_t>(c);
  return r;
}

std::optional<std::uint64_t> cpu_ticks(int pid) {
  if (pid <= 0) return std::nullopt;
  std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(in, line)) return std::nullopt;
  // Fields after the ")" closing comm: state is field 3; utime and stime are fields 14 and 15
  // (proc(5)).
  const auto close = line.rfind(')');
  if (close == std::string::npos) return std::nullopt;
  std::istringstream rest(line.substr(close + 2));
  std::string field;
  std::uint64_t utime = 0, stime = 0;
  for (int i = 3; i <= 15 && rest >> field; ++i) {
    if (i == 14) utime = std::stoull(field);
    if (i == 15) stime = std::stoull(field);
  }
  return utime + stime;
}

void send_request(Conn& c, const Args& a) {
  c.pending = c.large_next ? a.large : a.small;
  c.large_next = !c.large_next;
  ++c.tid;
  const std::array<std::uint8_t, 12> adu = {static_cast<std::uint8_t>(c.tid >> 8),
                                            static_cast<std::uint8_t>(c.tid),
                                            0,
                                            0,
                                            0,
                                            6,
                                            a.unit,
                                            c.pending.function,
                                            static_cast<std::uint8_t>(c.pending.start >> 8),
                                            static_cast<std::uint8_t>(c.pending.start),
                                            static_cast<std::uint8_t>(c.pending.count >> 8),
                                            static_cast<std::uint8_t>(c.pending.count)};
  c.sent = Clock::now();
  c.have = 0;
  const ssize_t n = ::send(c.fd, adu.data(), adu.size(), MSG_NOSIGNAL);
  if (n != static_cast<ssize_t>(adu.size())) {
    std::perror("dg-loadgen: send");
    std::exit(2);
  }
}

// Returns the reply's full size once `c.buf` holds one, 0 while incomplete.
std::size_t complete_size(const Conn& c) {
  if (c.have < 6) return 0;
  const std::size_t len = (std::size_t{c.buf[4]} << 8) | c.buf[5];
  return c.have >= 6 + len ? 6 + len : 0;
}

// The checks the issue names: transaction id, function, byte count; plus protocol id, unit
// and the MBAP length agreeing with the byte count.
bool reply_ok(const Conn& c, const Args& a, std::size_t size, std::string& why) {
  const auto& b = c.buf;
  const std::uint16_t tid = static_cast<std::uint16_t>((b[0] << 8) | b[1]);
  const std::size_t want_bytes = std::size_t{c.pending.count} * 2;
  if (tid != c.tid)
    why = "transaction id";
  else if (b[2] != 0 || b[3] != 0)
    why = "protocol id";
  else if (b[6] != a.unit)
    why = "unit id";
  else if (b[7] != c.pending.function)
    why = "function (exception " + std::to_string(b[8]) + ")";
  else if (b[8] != want_bytes)
    why = "byte count";
  else if (size != kMbapSize + 2 + want_bytes)
    why = "length";
  else
    return true;
  return false;
}

double percentile(std::vector<std::uint32_t>& v, double p) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k] / 1000.0;
}

int usage(const char* why) {
  std::cerr << "dg-loadgen: " << why << "\n"
            << "usage: dg-loadgen --port P [--host H] [--connections N] [--duration S]\n"
               "       [--warmup S] [--max-requests M] [--unit U] [--large FC:START:COUNT]\n"
               "       [--small FC:START:COUNT] [--pid SERVER_PID]\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (i + 1 >= argc) return usage(("missing value for " + k).c_str());
    const std::string v = argv[++i];
    try {
      if (k == "--host")
        a.host = v;
      else if (k == "--port")
        a.port = static_cast<std::uint16_t>(std::stoul(v));
      else if (k == "--connections")
        a.connections = std::stoi(v);
      else if (k == "--duration")
        a.duration_s = std::stod(v);
      else if (k == "--warmup")
        a.warmup_s = std::stod(v);
      else if (k == "--max-requests")
        a.max_requests = std::stoull(v);
      else if (k == "--unit")
        a.unit = static_cast<std::uint8_t>(std::stoul(v));
      else if (k == "--pid")
        a.pid = std::stoi(v);
      else if (k == "--large" || k == "--small") {
        auto r = parse_read(v);
        if (!r) return usage("a read is FC:START:COUNT with FC 3 or 4 and COUNT 1..125");
        (k == "--large" ? a.large : a.small) = *r;
      } else
        return usage(("unknown argument " + k).c_str());
    } catch (const std::exception&) {
      return usage(("not a number: " + v).c_str());
    }
  }
  if (a.connections < 1) return usage("--connections must be at least 1");

  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(a.port);
  if (::inet_pton(AF_INET, a.host.c_str(), &addr.sin_addr) != 1) return usage("--host: IPv4");
  const int ep = ::epoll_create1(0);
  std::vector<Conn> conns(static_cast<std::size_t>(a.connections));
  for (std::size_t i = 0; i < conns.size(); ++i) {
    Conn& c = conns[i];
    c.fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (::connect(c.fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      std::perror("dg-loadgen: connect");
      return 2;
    }
    const int one = 1;
    ::setsockopt(c.fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.u64 = i;
    ::epoll_ctl(ep, EPOLL_CTL_ADD, c.fd, &ev);
    c.tid = static_cast<std::uint16_t>(i * 1000);  // distinct per connection: a mix-up shows
  }

  std::vector<std::uint32_t> latencies;
  latencies.reserve(1 << 22);
  std::uint64_t errors = 0, total = 0;
  const auto t0 = Clock::now();
  const auto measure_from =
      t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.warmup_s));
  const auto end = measure_from + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(a.duration_s));
  bool measuring = false;
  std::optional<std::uint64_t> cpu0;
  Clock::time_point window_start{};
  for (auto& c : conns) send_request(c, a);

  std::array<epoll_event, 256> events{};
  bool stop = false;
  Clock::time_point now = Clock::now();
  while (!stop) {
    const int n = ::epoll_wait(ep, events.data(), static_cast<int>(events.size()), 1000);
    if (n < 0 && errno != EINTR) {
      std::perror("dg-loadgen: epoll_wait");
      return 2;
    }
    if (n == 0) {
      std::cerr << "dg-loadgen: no reply for a second\n";
      return 1;
    }
    for (int e = 0; e < n; ++e) {
      Conn& c = conns[events[e].data.u64];
      const ssize_t got = ::recv(c.fd, c.buf.data() + c.have, c.buf.size() - c.have, 0);
      if (got <= 0) {
        std::cerr << "dg-loadgen: server closed a connection\n";
        return 1;
      }
      c.have += static_cast<std::size_t>(got);
      const std::size_t size = complete_size(c);
      if (size == 0) continue;
      now = Clock::now();
      std::string why;
      if (!reply_ok(c, a, size, why) || size != c.have) {
        if (why.empty()) why = "bytes after the reply";
        if (errors++ < 5) std::cerr << "dg-loadgen: bad reply: " << why << "\n";
      }
      if (!measuring && now >= measure_from) {
        measuring = true;
        window_start = now;
        cpu0 = cpu_ticks(a.pid);
      }
      if (measuring) {
        latencies.push_back(static_cast<std::uint32_t>(
            std::chrono::duration_cast<std::chrono::nanoseconds>(now - c.sent).count()));
        ++c.done;
        ++total;
      }
      if (now >= end || (a.max_requests != 0 && total >= a.max_requests)) {
        stop = true;
        break;
      }
      send_request(c, a);
    }
  }
  const auto cpu1 = cpu_ticks(a.pid);
  const double secs = std::chrono::duration<double>(now - window_start).count();
  double sum = 0, sum_sq = 0;
  for (const auto& c : conns) {
    sum += static_cast<double>(c.done);
    sum_sq += static_cast<double>(c.done) * static_cast<double>(c.done);
  }
  const double jain = sum_sq > 0 ? sum * sum / (static_cast<double>(conns.size()) * sum_sq) : 0;
  double cpu_us = -1;
  if (cpu0 && cpu1 && total > 0) {
    const double tick_us = 1e6 / static_cast<double>(::sysconf(_SC_CLK_TCK));
    cpu_us = static_cast<double>(*cpu1 - *cpu0) * tick_us / static_cast<double>(total);
  }
  std::printf(
      "rps=%.0f p50_us=%.1f p99_us=%.1f p999_us=%.1f cpu_us_per_req=%.2f jain=%.4f requests=%llu "
      "errors=%llu\n",
      secs > 0 ? static_cast<double>(total) / secs : 0, percentile(latencies, 0.50),
      percentile(latencies, 0.99), percentile(latencies, 0.999), cpu_us, jain,
      static_cast<unsigned long long>(total), static_cast<unsigned long long>(errors));
  for (auto& c : conns) ::close(c.fd);
  return errors == 0 ? 0 : 1;
}
