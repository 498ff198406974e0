// dg-loadgen: a closed-loop Modbus TCP load generator. N connections, each with exactly one
// request outstanding; the requests alternate between a "large" read and a "small" read (by
// default FC03 0..124 and FC04 0..18, the common block). Every reply is checked (transaction id,
// unit, function, byte count, MBAP length); any mismatch or exception reply counts as an error
// and makes the exit status 1. Bounded by --duration and --max-requests, whichever comes first.
//
// Prints one line of key=value: rps, p50_us, p99_us, p999_us, cpu_us_per_req (utime+stime of
// --pid from /proc/<pid>/stat over the measured window), jain (fairness over connections),
// requests, errors; with --self-cpu also loadgen_cpu_us_per_req (its own utime+stime, getrusage).
//
// TLS (Modbus/TCP Security; the MBAP ADU travels unchanged inside TLS): --tls-ca CA.pem, with
// --tls-cert / --tls-key the client certificate. Each connection is opened and handshaken
// blocking, then the same closed loop runs over SSL_write / SSL_read on non-blocking sockets,
// with the same reply checks and the same output line. The plaintext loop is a separate
// function, untouched by TLS: no per-request cost for it.
//
// --handshakes: for the duration, each of --connections C slots repeatedly connects, completes a
// full TLS handshake (client certificate), sends one small read, checks its reply and closes
// (close_notify, then close); the C slots run in parallel on one epoll thread (C = 1:
// sequential). Prints hs_per_s, hs_p50_us / hs_p99_us (connect -> client handshake done),
// cycle_p50_us / cycle_p99_us (connect -> reply checked), cpu_us_per_hs (the server, as
// above), resumed (handshakes that resumed a session: 0 unless --resume, which offers each new
// connection the session (ticket) of the last one), handshakes, errors. --flood: a handshake
// flood, as a hostile client makes one: connections the server closes (a rate limit) are counted
// in errors and the slot connects again at once, never giving up (bench/flood.sh).
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <openssl/err.h>
#include <openssl/ssl.h>
#include <openssl/x509v3.h>
#include <sys/epoll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <csignal>
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
  Read small{4, 0, 19};   // the common block: input registers 0..18
  int pid = 0;            // the server, for CPU per request
  bool self_cpu = false;  // also report the load generator's own CPU per request
  // TLS: on when tls_ca is set.
  std::string tls_ca, tls_cert, tls_key;
  std::string tls_max;  // "1.2": no TLS 1.3 (default: whatever both sides prefer)
  bool handshakes = false;
  bool resume = false;  // handshake mode: offer the previous connection's session
  bool flood = false;   // handshake mode: a connection the server refuses is no reason to stop
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

using Request = std::array<std::uint8_t, 12>;

// The next request of `c` (large and small alternate); its send time is now.
inline Request next_request(Conn& c, const Args& a) {
  c.pending = c.large_next ? a.large : a.small;
  c.large_next = !c.large_next;
  ++c.tid;
  const Request adu = {static_cast<std::uint8_t>(c.tid >> 8),
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
  return adu;
}

void send_request(Conn& c, const Args& a) {
  const Request adu = next_request(c, a);
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
               "       [--small FC:START:COUNT] [--pid SERVER_PID] [--self-cpu]\n"
               "       [--tls-ca CA.pem [--tls-cert CERT.pem --tls-key KEY.pem] [--tls-max 1.2]\n"
               "        [--handshakes [--resume] [--flood]]]\n";
  return 2;
}

double self_cpu_us() {
  rusage ru{};
  ::getrusage(RUSAGE_SELF, &ru);
  const auto us = [](const timeval& t) {
    return static_cast<double>(t.tv_sec) * 1e6 + static_cast<double>(t.tv_usec);
  };
  return us(ru.ru_utime) + us(ru.ru_stime);
}

// CPU us per request (or handshake) of the server between two /proc samples; -1 if unknown.
double server_cpu_us(std::optional<std::uint64_t> cpu0, std::optional<std::uint64_t> cpu1,
                     std::uint64_t count) {
  if (!cpu0 || !cpu1 || count == 0) return -1;
  const double tick_us = 1e6 / static_cast<double>(::sysconf(_SC_CLK_TCK));
  return static_cast<double>(*cpu1 - *cpu0) * tick_us / static_cast<double>(count);
}

// The closed loop's output line, plaintext and TLS alike.
void print_result(const Args& a, const std::vector<std::uint64_t>& done,
                  std::vector<std::uint32_t>& latencies, std::uint64_t total, std::uint64_t errors,
                  double secs, std::optional<std::uint64_t> cpu0, std::optional<std::uint64_t> cpu1,
                  double self0) {
  double sum = 0, sum_sq = 0;
  for (const auto d : done) {
    sum += static_cast<double>(d);
    sum_sq += static_cast<double>(d) * static_cast<double>(d);
  }
  const double jain = sum_sq > 0 ? sum * sum / (static_cast<double>(done.size()) * sum_sq) : 0;
  const double cpu_us = server_cpu_us(cpu0, cpu1, total);
  std::printf(
      "rps=%.0f p50_us=%.1f p99_us=%.1f p999_us=%.1f cpu_us_per_req=%.2f jain=%.4f requests=%llu "
      "errors=%llu",
      secs > 0 ? static_cast<double>(total) / secs : 0, percentile(latencies, 0.50),
      percentile(latencies, 0.99), percentile(latencies, 0.999), cpu_us, jain,
      static_cast<unsigned long long>(total), static_cast<unsigned long long>(errors));
  if (a.self_cpu) {
    std::printf(" loadgen_cpu_us_per_req=%.2f",
                total > 0 ? (self_cpu_us() - self0) / static_cast<double>(total) : -1.0);
  }
  std::printf("\n");
}

// ---- TLS -------------------------------------------------------------------------------------

// Prints `what` and OpenSSL's error queue (emptying it).
void tls_error(const std::string& what) {
  std::cerr << "dg-loadgen: " << what;
  char text[256];
  while (const unsigned long e = ERR_get_error()) {
    ERR_error_string_n(e, text, sizeof text);
    std::cerr << ": " << text;
  }
  std::cerr << "\n";
}

// The client's context: TLS 1.2 at least (as the server requires), the server's certificate
// verified against --tls-ca (and its address checked, below), the client certificate if given.
// read_ahead: one recv takes whatever the socket holds instead of a 5-byte record header and
// then the record, so bytes may wait in the SSL object: every read loop below checks
// SSL_has_pending before it waits on epoll.
SSL_CTX* make_client_context(const Args& a) {
  SSL_CTX* ctx = SSL_CTX_new(TLS_client_method());
  if (ctx == nullptr) {
    tls_error("SSL_CTX_new");
    return nullptr;
  }
  SSL_CTX_set_min_proto_version(ctx, TLS1_2_VERSION);
  if (a.tls_max == "1.2") SSL_CTX_set_max_proto_version(ctx, TLS1_2_VERSION);
  if (SSL_CTX_load_verify_locations(ctx, a.tls_ca.c_str(), nullptr) != 1) {
    tls_error("cannot load CA " + a.tls_ca);
    return nullptr;
  }
  if (!a.tls_cert.empty() &&
      (SSL_CTX_use_certificate_chain_file(ctx, a.tls_cert.c_str()) != 1 ||
       SSL_CTX_use_PrivateKey_file(ctx, a.tls_key.c_str(), SSL_FILETYPE_PEM) != 1 ||
       SSL_CTX_check_private_key(ctx) != 1)) {
    tls_error("cannot load client certificate " + a.tls_cert + " / key " + a.tls_key);
    return nullptr;
  }
  SSL_CTX_set_verify(ctx, SSL_VERIFY_PEER, nullptr);
  SSL_CTX_set_read_ahead(ctx, 1);
  return ctx;
}

// A client SSL on `fd` that checks the server's certificate names the address connected to.
SSL* new_client_ssl(SSL_CTX* ctx, int fd, const Args& a) {
  SSL* ssl = SSL_new(ctx);
  if (ssl == nullptr) return nullptr;
  SSL_set_fd(ssl, fd);
  X509_VERIFY_PARAM_set1_ip_asc(SSL_get0_param(ssl), a.host.c_str());
  SSL_set_connect_state(ssl);
  return ssl;
}

// "TLSv1.3 TLS_AES_256_GCM_SHA384, group X25519": what was negotiated.
std::string tls_description(SSL* ssl) {
  std::string s = std::string(SSL_get_version(ssl)) + " " + SSL_get_cipher_name(ssl);
  const int group = static_cast<int>(SSL_get_negotiated_group(ssl));
  if (group != NID_undef) {
    const char* name = OBJ_nid2sn(group);
    s += ", group " + std::string(name != nullptr ? name : "?");
  }
  int sig = NID_undef;
  if (SSL_get_peer_signature_type_nid(ssl, &sig) == 1 && sig != NID_undef) {
    const char* name = OBJ_nid2sn(sig);
    s += ", server signature " + std::string(name != nullptr ? name : "?");
  }
  return s;
}

int set_nonblocking(int fd) {
  const int flags = ::fcntl(fd, F_GETFL);
  return ::fcntl(fd, F_SETFL, flags | O_NONBLOCK);
}

// One TLS connection of the closed loop.
struct TlsConn {
  Conn c;
  SSL* ssl = nullptr;
  Request out{};               // the request being written: SSL_write is retried with it
  bool write_blocked = false;  // SSL_write wants the socket (readable or writable) first
  std::uint32_t events = EPOLLIN;
};

// The epoll interest of `fd` (registered under `index`): EPOLL_CTL_MOD only when it changes.
void watch(int ep, int fd, std::size_t index, std::uint32_t& current, std::uint32_t events) {
  if (current == events) return;
  current = events;
  epoll_event ev{};
  ev.events = events;
  ev.data.u64 = index;
  ::epoll_ctl(ep, EPOLL_CTL_MOD, fd, &ev);
}

// Writes t.out (again, after a want). false: the connection failed.
bool tls_flush(TlsConn& t, int ep, std::size_t index) {
  const int n = SSL_write(t.ssl, t.out.data(), static_cast<int>(t.out.size()));
  if (n > 0) {  // no partial writes (SSL_MODE_ENABLE_PARTIAL_WRITE is off): all of it
    t.write_blocked = false;
    watch(ep, t.c.fd, index, t.events, EPOLLIN);
    return true;
  }
  const int err = SSL_get_error(t.ssl, n);
  if (err == SSL_ERROR_WANT_WRITE || err == SSL_ERROR_WANT_READ) {
    t.write_blocked = true;
    watch(ep, t.c.fd, index, t.events, err == SSL_ERROR_WANT_WRITE ? EPOLLOUT : EPOLLIN);
    return true;
  }
  tls_error("SSL_write");
  return false;
}

// The closed loop of main(), over TLS: same requests, same checks, same output.
int run_tls(const Args& a, const sockaddr_in& addr) {
  SSL_CTX* ctx = make_client_context(a);
  if (ctx == nullptr) return 2;
  const int ep = ::epoll_create1(0);
  std::vector<TlsConn> conns(static_cast<std::size_t>(a.connections));
  for (std::size_t i = 0; i < conns.size(); ++i) {
    TlsConn& t = conns[i];
    Conn& c = t.c;
    c.fd = ::socket(AF_INET, SOCK_STREAM, 0);
    if (::connect(c.fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
      std::perror("dg-loadgen: connect");
      return 2;
    }
    const int one = 1;
    ::setsockopt(c.fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    t.ssl = new_client_ssl(ctx, c.fd, a);
    if (t.ssl == nullptr || SSL_connect(t.ssl) != 1) {  // blocking: set-up, not measured
      tls_error("TLS handshake");
      return 2;
    }
    set_nonblocking(c.fd);
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.u64 = i;
    ::epoll_ctl(ep, EPOLL_CTL_ADD, c.fd, &ev);
    c.tid = static_cast<std::uint16_t>(i * 1000);
  }
  std::cerr << "dg-loadgen: " << tls_description(conns[0].ssl) << "\n";

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
  double self0 = 0;
  Clock::time_point window_start{};
  for (std::size_t i = 0; i < conns.size(); ++i) {
    conns[i].out = next_request(conns[i].c, a);
    if (!tls_flush(conns[i], ep, i)) return 2;
  }

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
    for (int e = 0; e < n && !stop; ++e) {
      const std::size_t i = events[e].data.u64;
      TlsConn& t = conns[i];
      Conn& c = t.c;
      if (t.write_blocked) {
        if (!tls_flush(t, ep, i)) return 2;
        if (t.write_blocked) continue;
      }
      // Read until OpenSSL needs the socket again: bytes it already holds (a record read ahead,
      // or the rest of a record) are never left waiting for an epoll event that will not come.
      bool more = true;
      while (more) {
        const int got =
            SSL_read(t.ssl, c.buf.data() + c.have, static_cast<int>(c.buf.size() - c.have));
        if (got <= 0) {
          const int err = SSL_get_error(t.ssl, got);
          if (err == SSL_ERROR_WANT_READ) {
            watch(ep, c.fd, i, t.events, EPOLLIN);
            break;
          }
          if (err == SSL_ERROR_WANT_WRITE) {
            watch(ep, c.fd, i, t.events, EPOLLOUT);
            break;
          }
          tls_error("server closed a connection (SSL error " + std::to_string(err) + ")");
          return 1;
        }
        c.have += static_cast<std::size_t>(got);
        more = SSL_has_pending(t.ssl) == 1;
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
          if (a.self_cpu) self0 = self_cpu_us();
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
        t.out = next_request(c, a);
        if (!tls_flush(t, ep, i)) return 2;
        if (t.write_blocked) break;
      }
    }
  }
  const auto cpu1 = cpu_ticks(a.pid);
  const double secs = std::chrono::duration<double>(now - window_start).count();
  std::vector<std::uint64_t> done;
  for (const auto& t : conns) done.push_back(t.c.done);
  print_result(a, done, latencies, total, errors, secs, cpu0, cpu1, self0);
  for (auto& t : conns) {
    SSL_shutdown(t.ssl);  // close_notify, as a client that is done would
    SSL_free(t.ssl);
    ::close(t.c.fd);
  }
  SSL_CTX_free(ctx);
  return errors == 0 ? 0 : 1;
}

// One slot of the handshake mode: connect, handshake, one small read, close, again.
struct HsSlot {
  enum class Step { handshake, send, reply };
  Conn c;
  SSL* ssl = nullptr;
  Step step = Step::handshake;
  Request out{};
  Clock::time_point start{}, handshaken{};
  std::uint32_t events = 0;  // 0: not registered with epoll
};

// Handshake mode: the small read is the request sent (unit, --small).
int run_handshakes(const Args& a, const sockaddr_in& addr) {
  SSL_CTX* ctx = make_client_context(a);
  if (ctx == nullptr) return 2;
  const int ep = ::epoll_create1(0);
  std::vector<HsSlot> slots(static_cast<std::size_t>(a.connections));
  SSL_SESSION* last_session = nullptr;  // --resume: offered to the next connection
  std::uint64_t errors = 0, total = 0, resumed = 0, failures = 0;
  std::string description;

  const auto set_events = [&](HsSlot& s, std::size_t i, std::uint32_t ev_mask) {
    if (s.events == 0) {
      s.events = ev_mask;
      epoll_event ev{};
      ev.events = ev_mask;
      ev.data.u64 = i;
      ::epoll_ctl(ep, EPOLL_CTL_ADD, s.c.fd, &ev);
    } else {
      watch(ep, s.c.fd, i, s.events, ev_mask);
    }
  };
  const auto close_slot = [&](HsSlot& s) {
    if (s.ssl != nullptr) SSL_free(s.ssl);
    if (s.c.fd >= 0) ::close(s.c.fd);  // removes it from epoll
    s.ssl = nullptr;
    s.c.fd = -1;
    s.events = 0;
  };
  const auto open_slot = [&](HsSlot& s) -> bool {
    s.c.fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK, 0);
    const int one = 1;
    ::setsockopt(s.c.fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    s.start = Clock::now();
    if (::connect(s.c.fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 &&
        errno != EINPROGRESS) {
      std::perror("dg-loadgen: connect");
      return false;
    }
    s.ssl = new_client_ssl(ctx, s.c.fd, a);
    if (s.ssl == nullptr) return false;
    if (last_session != nullptr) SSL_set_session(s.ssl, last_session);
    s.step = HsSlot::Step::handshake;
    s.c.have = 0;
    return true;
  };
  // Advances slot i as far as the socket lets it. 1: cycle done (reply in s.c.buf), 0: waiting,
  // -1: failed.
  const auto advance = [&](HsSlot& s, std::size_t i) -> int {
    if (s.step == HsSlot::Step::handshake) {
      const int r = SSL_do_handshake(s.ssl);
      if (r != 1) {
        const int err = SSL_get_error(s.ssl, r);
        if (err == SSL_ERROR_WANT_READ || err == SSL_ERROR_WANT_WRITE) {
          set_events(s, i, err == SSL_ERROR_WANT_READ ? EPOLLIN : EPOLLOUT);
          return 0;
        }
        if (failures < 5) tls_error("TLS handshake");
        ERR_clear_error();
        return -1;
      }
      s.handshaken = Clock::now();
      s.c.large_next = false;  // every cycle sends the small read
      s.out = next_request(s.c, a);
      s.step = HsSlot::Step::send;
    }
    if (s.step == HsSlot::Step::send) {
      const int n = SSL_write(s.ssl, s.out.data(), static_cast<int>(s.out.size()));
      if (n <= 0) {
        const int err = SSL_get_error(s.ssl, n);
        if (err == SSL_ERROR_WANT_READ || err == SSL_ERROR_WANT_WRITE) {
          set_events(s, i, err == SSL_ERROR_WANT_READ ? EPOLLIN : EPOLLOUT);
          return 0;
        }
        if (failures < 5) tls_error("SSL_write");
        ERR_clear_error();
        return -1;
      }
      s.step = HsSlot::Step::reply;
    }
    for (;;) {  // reply: as in run_tls, never waiting on epoll for bytes OpenSSL holds
      const int got =
          SSL_read(s.ssl, s.c.buf.data() + s.c.have, static_cast<int>(s.c.buf.size() - s.c.have));
      if (got <= 0) {
        const int err = SSL_get_error(s.ssl, got);
        if (err == SSL_ERROR_WANT_READ || err == SSL_ERROR_WANT_WRITE) {
          set_events(s, i, err == SSL_ERROR_WANT_READ ? EPOLLIN : EPOLLOUT);
          return 0;
        }
        if (failures < 5) tls_error("no reply (SSL error " + std::to_string(err) + ")");
        ERR_clear_error();
        return -1;
      }
      s.c.have += static_cast<std::size_t>(got);
      if (complete_size(s.c) != 0) return 1;
      if (SSL_has_pending(s.ssl) != 1) {
        set_events(s, i, EPOLLIN);
        return 0;
      }
    }
  };

  std::vector<std::uint32_t> hs_lat, cycle_lat;
  hs_lat.reserve(1 << 20);
  cycle_lat.reserve(1 << 20);
  const auto t0 = Clock::now();
  const auto measure_from =
      t0 + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(a.warmup_s));
  const auto end = measure_from + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(a.duration_s));
  bool measuring = false, stop = false;
  std::optional<std::uint64_t> cpu0, cpu1;
  double self0 = 0, self1 = 0;
  Clock::time_point window_start{}, window_end{}, now = t0;
  std::size_t open_slots = 0;

  // Runs slot i until it waits on the socket, starting new cycles as old ones finish. Once the
  // window is over, the cycles in flight are finished (not counted) and no new one starts, so
  // the server sees no handshake cut short.
  const auto drive = [&](std::size_t i) -> bool {
    HsSlot& s = slots[i];
    for (;;) {
      const int r = advance(s, i);
      if (r == 0) return true;
      now = Clock::now();
      if (r < 0) {
        ++errors;
        if (++failures >= 20 && !a.flood) {
          std::cerr << "dg-loadgen: 20 failed connections, giving up\n";
          return false;
        }
      } else {
        const std::size_t size = complete_size(s.c);
        std::string why;
        if (!reply_ok(s.c, a, size, why) || size != s.c.have) {
          if (why.empty()) why = "bytes after the reply";
          if (errors++ < 5) std::cerr << "dg-loadgen: bad reply: " << why << "\n";
        }
        if (description.empty()) description = tls_description(s.ssl);
        if (!measuring && now >= measure_from) {
          measuring = true;
          window_start = now;
          cpu0 = cpu_ticks(a.pid);
          if (a.self_cpu) self0 = self_cpu_us();
        }
        if (measuring && !stop) {
          hs_lat.push_back(static_cast<std::uint32_t>(
              std::chrono::duration_cast<std::chrono::nanoseconds>(s.handshaken - s.start)
                  .count()));
          cycle_lat.push_back(static_cast<std::uint32_t>(
              std::chrono::duration_cast<std::chrono::nanoseconds>(now - s.start).count()));
          ++total;
          if (SSL_session_reused(s.ssl) == 1) ++resumed;
        }
        if (a.resume) {
          SSL_SESSION* session = SSL_get1_session(s.ssl);  // the newest ticket received
          if (session != nullptr && SSL_SESSION_is_resumable(session) == 1) {
            if (last_session != nullptr) SSL_SESSION_free(last_session);
            last_session = session;
          } else if (session != nullptr) {
            SSL_SESSION_free(session);
          }
        }
        SSL_shutdown(s.ssl);  // close_notify; the server's is not waited for
      }
      close_slot(s);
      --open_slots;
      if (!stop && (now >= end || (a.max_requests != 0 && total >= a.max_requests))) {
        stop = true;
        window_end = now;
        cpu1 = cpu_ticks(a.pid);
        if (a.self_cpu) self1 = self_cpu_us();
      }
      if (stop) return true;
      if (!open_slot(s)) return false;
      ++open_slots;
    }
  };

  for (std::size_t i = 0; i < slots.size(); ++i) {
    if (!open_slot(slots[i])) return 2;
    ++open_slots;
    if (!drive(i)) return 2;
  }
  std::array<epoll_event, 256> events{};
  while (open_slots > 0) {
    const int n = ::epoll_wait(ep, events.data(), static_cast<int>(events.size()), 1000);
    if (n < 0 && errno != EINTR) {
      std::perror("dg-loadgen: epoll_wait");
      return 2;
    }
    if (n == 0) {
      std::cerr << "dg-loadgen: no progress for a second\n";
      return 1;
    }
    for (int e = 0; e < n; ++e) {
      const std::size_t i = events[e].data.u64;
      if (slots[i].c.fd < 0) continue;
      if (!drive(i)) return 1;
    }
  }
  const double secs = std::chrono::duration<double>(window_end - window_start).count();
  if (!description.empty()) std::cerr << "dg-loadgen: " << description << "\n";
  std::printf(
      "hs_per_s=%.0f hs_p50_us=%.1f hs_p99_us=%.1f cycle_p50_us=%.1f cycle_p99_us=%.1f "
      "cpu_us_per_hs=%.1f",
      secs > 0 ? static_cast<double>(total) / secs : 0, percentile(hs_lat, 0.50),
      percentile(hs_lat, 0.99), percentile(cycle_lat, 0.50), percentile(cycle_lat, 0.99),
      server_cpu_us(cpu0, cpu1, total));
  if (a.self_cpu) {
    std::printf(" loadgen_cpu_us_per_hs=%.1f",
                total > 0 ? (self1 - self0) / static_cast<double>(total) : -1.0);
  }
  std::printf(" resumed=%llu handshakes=%llu errors=%llu\n",
              static_cast<unsigned long long>(resumed), static_cast<unsigned long long>(total),
              static_cast<unsigned long long>(errors));
  for (auto& s : slots) close_slot(s);
  if (last_session != nullptr) SSL_SESSION_free(last_session);
  SSL_CTX_free(ctx);
  return errors == 0 || a.flood ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    if (k == "--self-cpu" || k == "--handshakes" || k == "--resume" || k == "--flood") {
      (k == "--self-cpu"     ? a.self_cpu
       : k == "--handshakes" ? a.handshakes
       : k == "--flood"      ? a.flood
                             : a.resume) = true;
      continue;
    }
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
      else if (k == "--tls-ca")
        a.tls_ca = v;
      else if (k == "--tls-cert")
        a.tls_cert = v;
      else if (k == "--tls-key")
        a.tls_key = v;
      else if (k == "--tls-max")
        a.tls_max = v;
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
  if (a.tls_ca.empty() && (!a.tls_cert.empty() || !a.tls_key.empty() || !a.tls_max.empty()))
    return usage("--tls-cert, --tls-key and --tls-max need --tls-ca");
  if (a.tls_cert.empty() != a.tls_key.empty()) return usage("--tls-cert and --tls-key go together");
  if (!a.tls_max.empty() && a.tls_max != "1.2") return usage("--tls-max: only 1.2");
  if (a.handshakes && a.tls_ca.empty()) return usage("--handshakes needs --tls-ca");
  if (a.resume && !a.handshakes) return usage("--resume is for --handshakes");
  if (a.flood && !a.handshakes) return usage("--flood is for --handshakes");

  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(a.port);
  if (::inet_pton(AF_INET, a.host.c_str(), &addr.sin_addr) != 1) return usage("--host: IPv4");
  if (!a.tls_ca.empty()) {
    std::signal(SIGPIPE, SIG_IGN);  // SSL_write has no MSG_NOSIGNAL: a closed peer is an error
    return a.handshakes ? run_handshakes(a, addr) : run_tls(a, addr);
  }
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
  double self0 = 0;
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
        if (a.self_cpu) self0 = self_cpu_us();
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
  std::vector<std::uint64_t> done;
  for (const auto& c : conns) done.push_back(c.done);
  print_result(a, done, latencies, total, errors, secs, cpu0, cpu1, self0);
  for (auto& c : conns) ::close(c.fd);
  return errors == 0 ? 0 : 1;
}
