// dg-serial-listener-bench: the Modbus RTU master of bench/serial_listener.sh. It sits
// on the master's end of a pseudo-terminal pair whose other end is a drivegated serial listener,
// and makes the pty behave like the wire (Serial Line 2.5.1.1):
//
//   - the request's bytes are written one at a time, a character time apart (busy-waiting on the
//     steady clock: a character is 11 bits, 8E1; the pty ignores parity and speed);
//   - the reply's first byte is timestamped as it arrives (poll() returning: under SCHED_FIFO, as
//     bench/serial_listener.sh runs it, the wake-up is prompt); the reply gap is that arrival - the time the request's last
//     byte was written (write() returned). It includes the pty hops both ways (through socat:
//     see --probe) and the daemon's 3.5-character silence;
//   - the reply occupies the line for its own wire time (reply bytes x character) from its first
//     byte (or to its last byte's arrival, if later), then the master keeps the 3.5-character
//     silence (1.75 ms above 19200 baud) before the next request's first character.
//
// So a transaction takes req x char + gap + reply x char + t3.5, and with a gap of exactly t3.5
// the run goes at the wire's limit, 1 / (req x char + t3.5 + reply x char + t3.5).
//
// Usage:
//   dg-serial-listener-bench --port PATH --baud B [--count N] [--unit U] [--addr A] [--qty Q]
//       [--bits 11] [--warmup-s 20] [--gaps FILE] [--label TEXT]
//     First waits (--warmup-s at most) until FC04 input register 0 of the unit has its online bit,
//     then sends N x FC03 (A, Q) and checks every reply (address, function, byte count, CRC; an
//     exception is wrong). Prints one line:
//       serial label= baud= n= ok= no_reply= wrong= master_late= char_us= t35_us= req_bytes=
//       reply_bytes= rps= limit_rps= ratio= gap_p50_us= gap_p99_us= gap_max_us= gap_min_us=
//       above_t35_p50_us= above_t35_p99_us= reply_reads_max= seconds=
//     master_late counts requests where this process itself wrote a byte more than 1.5
//     characters after the one before (it was preempted): the daemon is right to discard those,
//     and they are not the daemon's fault. Exit status 1 if any request got no or a wrong reply.
//   dg-serial-listener-bench --probe PATH_A PATH_B [--count N]
//     No daemon: the pty pair's own latency, both directions (1 byte A -> B, 11 bytes B -> A),
//     write() returned -> first byte read. Prints "probe n= a_to_b_p50_us= ... b_to_a_max_us=".
//   dg-serial-listener-bench --frames PATH_A PATH_B READER_CPU --baud B [--count N]
//     No daemon: N request-sized frames written on A a character per byte, read on B by a thread
//     on READER_CPU under SCHED_OTHER (as the daemon runs), judged by the framer's own rule: how
//     many the transport alone makes look cut by a gap of more than 1.5 characters.
#include <fcntl.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;
using Ns = std::chrono::nanoseconds;

long long now_ns() {
  return std::chrono::duration_cast<Ns>(Clock::now().time_since_epoch()).count();
}

std::uint16_t crc16(const std::uint8_t* p, std::size_t n) {
  std::uint16_t crc = 0xFFFF;
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= p[i];
    for (int b = 0; b < 8; ++b) crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0xA001)
                                                : static_cast<std::uint16_t>(crc >> 1);
  }
  return crc;
}

std::vector<std::uint8_t> request(std::uint8_t unit, std::uint8_t fc, unsigned addr, unsigned qty) {
  std::vector<std::uint8_t> f = {unit, fc, static_cast<std::uint8_t>(addr >> 8),
                                 static_cast<std::uint8_t>(addr), static_cast<std::uint8_t>(qty >> 8),
                                 static_cast<std::uint8_t>(qty)};
  const auto c = crc16(f.data(), f.size());
  f.push_back(static_cast<std::uint8_t>(c));
  f.push_back(static_cast<std::uint8_t>(c >> 8));
  return f;
}

int open_raw(const char* path) {
  const int fd = ::open(path, O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) {
    std::fprintf(stderr, "dg-serial-listener-bench: %s: %s\n", path, std::strerror(errno));
    std::exit(2);
  }
  termios t{};
  if (tcgetattr(fd, &t) == 0) {
    cfmakeraw(&t);
    tcsetattr(fd, TCSANOW, &t);
  }
  return fd;
}

// Until `due` (steady ns): sleeps while more than 200 us away (unless `spin`), then spins.
void wait_until(long long due, bool spin = false) {
  for (;;) {
    const long long left = due - now_ns();
    if (left <= 0) return;
    if (!spin && left > 200'000) {
      const long long s = left - 150'000;
      timespec ts{static_cast<time_t>(s / 1'000'000'000LL), static_cast<long>(s % 1'000'000'000LL)};
      nanosleep(&ts, nullptr);
    }
  }
}

// Reads what is there into `buf`; returns the count (0: nothing yet).
std::size_t read_some(int fd, std::vector<std::uint8_t>& buf) {
  std::uint8_t tmp[512];
  const ssize_t n = ::read(fd, tmp, sizeof tmp);
  if (n <= 0) return 0;
  buf.insert(buf.end(), tmp, tmp + n);
  return static_cast<std::size_t>(n);
}

// Discards everything until `quiet_ns` have passed with nothing received.
void drain(int fd, long long quiet_ns) {
  std::vector<std::uint8_t> junk;
  long long last = now_ns();
  while (now_ns() - last < quiet_ns) {
    junk.clear();
    if (read_some(fd, junk) > 0) last = now_ns();
    else usleep(200);
  }
}

double pct(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

bool write_all(int fd, const std::uint8_t* p, std::size_t n) {
  while (n > 0) {
    const ssize_t w = ::write(fd, p, n);
    if (w < 0) {
      if (errno == EAGAIN || errno == EINTR) continue;
      return false;
    }
    p += w;
    n -= static_cast<std::size_t>(w);
  }
  return true;
}

// Waits (poll) until `want` bytes or `timeout_ns` after `start`; returns the first byte's
// arrival (0: none: poll's return, so it includes this process's wake-up), the last's in *last,
// the number of reads that brought data in *reads. Blocking, not spinning: run under SCHED_FIFO
// (bench/serial_listener.sh uses chrt) the wake-up is prompt, and a spinning real-time task would
// keep the kernel's own work off this CPU.
long long receive(int fd, std::vector<std::uint8_t>& buf, std::size_t want, long long start,
                  long long timeout_ns, long long* last, int* reads) {
  long long first = 0;
  *reads = 0;
  while (buf.size() < want) {
    const long long left = start + timeout_ns - now_ns();
    if (left <= 0) break;
    pollfd p{fd, POLLIN, 0};
    timespec ts{static_cast<time_t>(left / 1'000'000'000LL), static_cast<long>(left % 1'000'000'000LL)};
    if (ppoll(&p, 1, &ts, nullptr) <= 0) continue;
    const long long t = now_ns();
    if (read_some(fd, buf) > 0) {
      if (first == 0) first = t;
      *last = t;
      ++*reads;
    }
  }
  return first;
}

int probe(const char* a_path, const char* b_path, int n) {
  const int a = open_raw(a_path);
  const int b = open_raw(b_path);
  drain(a, 20'000'000);
  drain(b, 20'000'000);
  std::vector<double> ab, ba;
  std::vector<std::uint8_t> buf;
  const std::uint8_t one = 0x55;
  const std::vector<std::uint8_t> eleven(11, 0xAA);
  for (int i = 0; i < n; ++i) {
    long long last = 0;
    int reads = 0;
    buf.clear();
    write_all(a, &one, 1);
    long long w = now_ns();
    long long f = receive(b, buf, 1, w, 100'000'000, &last, &reads);
    if (f) ab.push_back(static_cast<double>(f - w) / 1e3);
    buf.clear();
    write_all(b, eleven.data(), eleven.size());
    w = now_ns();
    f = receive(a, buf, eleven.size(), w, 100'000'000, &last, &reads);
    if (f) ba.push_back(static_cast<double>(f - w) / 1e3);
    usleep(1000);
  }
  std::printf("probe n=%d a_to_b_p50_us=%.1f a_to_b_p99_us=%.1f a_to_b_max_us=%.1f "
              "b_to_a_p50_us=%.1f b_to_a_p99_us=%.1f b_to_a_max_us=%.1f lost=%zu\n",
              n, pct(ab, 0.5), pct(ab, 0.99), pct(ab, 1.0), pct(ba, 0.5), pct(ba, 0.99),
              pct(ba, 1.0), 2 * static_cast<std::size_t>(n) - ab.size() - ba.size());
  return 0;
}

// --frames: no daemon. FRAMES frames of 8 bytes, each byte a character apart, written on A (this
// thread, CPU and policy as started); a reader thread on READER_CPU under SCHED_OTHER, as the
// daemon runs, reads B with poll() and applies the framer's rule (daemon/modbus/slave_framer.cpp:
// a read of n bytes at t began at t - n characters, not before the last read; a gap of more than
// 1.5 characters inside a frame cuts it). Counts the frames the transport alone would have cut.
int frames(const char* a_path, const char* b_path, int n, unsigned baud, unsigned bits,
           int reader_cpu) {
  const double char_ns = 1e9 * bits / baud;
  const double t15_ns = baud > 19200 ? 0.75e6 : 1.5 * char_ns;
  const auto c_ns = static_cast<long long>(char_ns);
  const int a = open_raw(a_path);
  const int b = open_raw(b_path);
  drain(a, 20'000'000);
  drain(b, 20'000'000);
  int cut = 0;
  std::vector<double> worst;  // per frame, the largest gap the framer would see, us
  std::thread reader([&] {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(reader_cpu, &set);
    pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    sched_param sp{};
    pthread_setschedparam(pthread_self(), SCHED_OTHER, &sp);
    std::uint8_t tmp[64];
    for (int f = 0; f < n; ++f) {
      std::size_t got = 0;
      long long last = 0;
      double frame_worst = 0;
      while (got < 8) {
        pollfd p{b, POLLIN, 0};
        if (poll(&p, 1, 1000) <= 0) break;
        const long long t = now_ns();
        const ssize_t r = ::read(b, tmp, sizeof tmp);
        if (r <= 0) continue;
        long long began = t - static_cast<long long>(r) * c_ns;
        if (got > 0) {
          if (began < last) began = last;
          frame_worst = std::max(frame_worst, static_cast<double>(began - last));
        }
        last = t;
        got += static_cast<std::size_t>(r);
      }
      if (frame_worst > t15_ns) ++cut;
      worst.push_back(frame_worst / 1e3);
    }
  });
  const std::uint8_t req[8] = {1, 3, 0, 0, 0, 3, 0x05, 0xCB};
  for (int f = 0; f < n; ++f) {
    const long long due = now_ns() + 5'000'000;
    for (int k = 0; k < 8; ++k) {
      wait_until(due + k * c_ns, k > 0);
      write_all(a, &req[k], 1);
    }
  }
  reader.join();
  std::printf("frames baud=%u n=%d cut=%d t15_us=%.0f worst_gap_p50_us=%.0f worst_gap_p99_us=%.0f "
              "worst_gap_max_us=%.0f\n",
              baud, n, cut, t15_ns / 1e3, pct(worst, 0.5), pct(worst, 0.99), pct(worst, 1.0));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string port, gaps_path, label = "-";
  unsigned baud = 19200, bits = 11, unit = 1, addr = 0, qty = 3;
  int count = 500;
  double warmup_s = 20;
  long long timeout_ns = 100'000'000;  // the master's response timeout
  const char* probe_a = nullptr;
  const char* probe_b = nullptr;
  int reader_cpu = -1;
  for (int i = 1; i < argc; ++i) {
    const std::string_view a = argv[i];
    auto val = [&]() -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "dg-serial-listener-bench: %s needs a value\n", argv[i]);
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--port") port = val();
    else if (a == "--baud") baud = static_cast<unsigned>(std::atoi(val()));
    else if (a == "--bits") bits = static_cast<unsigned>(std::atoi(val()));
    else if (a == "--count") count = std::atoi(val());
    else if (a == "--unit") unit = static_cast<unsigned>(std::atoi(val()));
    else if (a == "--addr") addr = static_cast<unsigned>(std::atoi(val()));
    else if (a == "--qty") qty = static_cast<unsigned>(std::atoi(val()));
    else if (a == "--warmup-s") warmup_s = std::atof(val());
    else if (a == "--gaps") gaps_path = val();
    else if (a == "--timeout-ms") timeout_ns = std::atoll(val()) * 1'000'000LL;
    else if (a == "--label") label = val();
    else if (a == "--probe") {
      probe_a = val();
      probe_b = val();
    } else if (a == "--frames") {
      probe_a = val();
      probe_b = val();
      reader_cpu = std::atoi(val());
    } else {
      std::fprintf(stderr, "dg-serial-listener-bench: unknown option %s\n", argv[i]);
      return 2;
    }
  }
  if (probe_a && reader_cpu >= 0) return frames(probe_a, probe_b, count, baud, bits, reader_cpu);
  if (probe_a) return probe(probe_a, probe_b, count);
  if (port.empty() || qty < 1 || qty > 125) {
    std::fprintf(stderr, "dg-serial-listener-bench: --port PATH --baud B [--count N] ...\n");
    return 2;
  }
  // Serial Line 2.5.1.1: 3.5 characters, fixed at 1.75 ms above 19200 baud; 1.5: 750 us.
  const double char_ns = 1e9 * bits / baud;
  const double t35_ns = baud > 19200 ? 1.75e6 : 3.5 * char_ns;
  const double t15_ns = baud > 19200 ? 0.75e6 : 1.5 * char_ns;
  const int fd = open_raw(port.c_str());
  drain(fd, 20'000'000);

  const auto req = request(static_cast<std::uint8_t>(unit), 3, addr, qty);
  const std::size_t reply_len = 5 + 2 * qty;
  std::vector<std::uint8_t> buf;

  // Warm-up: whole frames, until the unit reports online (FC04 input 0, bit 0).
  {
    const auto probe_req = request(static_cast<std::uint8_t>(unit), 4, 0, 1);
    const long long until = now_ns() + static_cast<long long>(warmup_s * 1e9);
    bool online = false;
    while (!online && now_ns() < until) {
      buf.clear();
      write_all(fd, probe_req.data(), probe_req.size());
      long long last = 0;
      int reads = 0;
      receive(fd, buf, 7, now_ns(), 200'000'000, &last, &reads);
      online = buf.size() == 7 && buf[1] == 4 && crc16(buf.data(), 7) == 0 && (buf[4] & 1);
      drain(fd, 50'000'000);
    }
    if (!online) {
      std::fprintf(stderr, "dg-serial-listener-bench: unit %u never online over %s\n", unit,
                   port.c_str());
      return 1;
    }
  }

  std::vector<double> gaps;
  gaps.reserve(static_cast<std::size_t>(count));
  int ok = 0, no_reply = 0, wrong = 0, master_late = 0, reads_max = 0;
  const auto c_ns = static_cast<long long>(char_ns);
  // The first byte's character ends at `due`; the run begins as it starts.
  long long due = now_ns() + 1'000'000;
  const long long begin = due - c_ns;
  long long end = begin;
  long long answered_ns = 0;  // the answered transactions' time on the line
  for (int i = 0; i < count; ++i) {
    long long prev = 0;
    long long last_written = 0;
    bool late = false;
    long long written_at[256];
    for (std::size_t k = 0; k < req.size(); ++k) {
      wait_until(due + static_cast<long long>(k) * c_ns, k > 0);
      write_all(fd, &req[k], 1);
      last_written = now_ns();
      written_at[k] = last_written;
      if (k > 0 && static_cast<double>(last_written - prev) > char_ns + t15_ns) late = true;
      prev = last_written;
    }
    if (late) ++master_late;
    buf.clear();
    long long last = 0;
    int reads = 0;
    const long long first = receive(fd, buf, reply_len, last_written, timeout_ns, &last, &reads);
    reads_max = std::max(reads_max, reads);
    bool good = first != 0 && buf.size() == reply_len && buf[0] == unit && buf[1] == 3 &&
                buf[2] == 2 * qty && crc16(buf.data(), reply_len) == 0;
    if (first == 0) {
      ++no_reply;
    } else if (!good) {
      ++wrong;
    } else {
      ++ok;
      gaps.push_back(static_cast<double>(first - last_written) / 1e3);
    }
    if (!good) {
      // Each byte's write() return against its due time, for the run's record (stderr).
      std::fprintf(stderr, "request %d: %s, %zu bytes back; byte written at due +us:", i,
                   first == 0 ? "no reply" : "wrong reply", buf.size());
      for (std::size_t k = 0; k < req.size(); ++k) {
        std::fprintf(stderr, " %.0f",
                     static_cast<double>(written_at[k] - due - static_cast<long long>(k) * c_ns) /
                         1e3);
      }
      std::fprintf(stderr, "%s\n", late ? " (master late)" : "");
      // Resync: let the line fall silent, as a master does after its response timeout.
      drain(fd, 50'000'000);
      end = now_ns();
      due = end + c_ns;
      continue;
    }
    // The reply is on the line for its own wire time, then the 3.5-character silence.
    const long long reply_end = std::max(first + static_cast<long long>(reply_len) * c_ns, last);
    const long long start = end;
    end = reply_end + static_cast<long long>(t35_ns);
    due = end + c_ns;
    answered_ns += end - start;
  }
  const double seconds = static_cast<double>(end - begin) / 1e9;
  const double limit_s =
      (static_cast<double>(req.size() + reply_len) * char_ns + 2 * t35_ns) / 1e9;
  const double rps = count / seconds;
  const double rps_answered = answered_ns > 0 ? ok / (static_cast<double>(answered_ns) / 1e9) : 0;
  if (!gaps_path.empty()) {
    if (FILE* f = std::fopen(gaps_path.c_str(), "w")) {
      for (double g : gaps) std::fprintf(f, "%.1f\n", g);
      std::fclose(f);
    }
  }
  const double t35_us = t35_ns / 1e3;
  std::printf("serial label=%s baud=%u n=%d ok=%d no_reply=%d wrong=%d master_late=%d "
              "char_us=%.1f t35_us=%.1f req_bytes=%zu reply_bytes=%zu rps=%.2f limit_rps=%.2f "
              "ratio=%.3f ratio_answered=%.3f gap_p50_us=%.0f gap_p99_us=%.0f gap_max_us=%.0f gap_min_us=%.0f "
              "above_t35_p50_us=%.0f above_t35_p99_us=%.0f reply_reads_max=%d seconds=%.2f\n",
              label.c_str(), baud, count, ok, no_reply, wrong, master_late, char_ns / 1e3, t35_us,
              req.size(), reply_len, rps, 1.0 / limit_s, rps * limit_s, rps_answered * limit_s, pct(gaps, 0.5),
              pct(gaps, 0.99), pct(gaps, 1.0), pct(gaps, 0.0), pct(gaps, 0.5) - t35_us,
              pct(gaps, 0.99) - t35_us, reads_max, seconds);
  ::close(fd);
  return no_reply + wrong > 0 ? 1 : 0;
}
