// drivegate capture: a pcap of one bus, fetched from the running daemon's
// /api/v1/capture (docs/capture.md) over plain HTTP/1.1, de-chunked, written to a file or stdout
// as it comes (so it can feed `wireshark -k -i -`).
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iostream>

#include "capture_progress.h"
#include "commands.h"
#include "daemon_http.h"
#include "dechunk.h"
#include "http_client.h"
#include "status_buses.h"

namespace drivegate::cli {

namespace {

constexpr Option kCaptureOptions[] = {
    {"bus", 'b', "NAME", "the bus to capture, as the configuration names it"},
    {"seconds", 's', "N", "how long to capture: 1..300 seconds (default 10)"},
    {"write", 'w', "FILE", "write the pcap to FILE (default: standard output)"},
    kDaemonConfigOption,
    kHttpOption,
    {"progress", 0, nullptr,
     "show the frames and bytes received and the seconds left on stderr, even when it is not a "
     "terminal (default: only in a terminal)"},
    {"no-progress", 0, nullptr, "never show them"},
    kHelpOption,
};

// Extra time past the capture's own for the daemon to finish and the bytes to arrive.
constexpr std::chrono::seconds kSlack{15};
// Asking the daemon which buses it has, after it refused one: a small answer, at once or never.
constexpr std::chrono::seconds kStatusTimeout{5};
constexpr std::size_t kStatusMaxBytes = 8 << 20;

// ", its buses: a, b" from the daemon's status JSON; empty when that cannot be had (the refusal
// is reported all the same).
std::string configured_buses(const DaemonHttp& http) {
  std::string error;
  const auto status = http_get(http.host, http.port, "/api/v1/status",
                               std::chrono::milliseconds(kStatusTimeout), kStatusMaxBytes, error);
  if (!status || status->head.status != 200) return {};
  const auto names = bus_names(status->body);
  if (!names) return {};
  if (names->empty()) return "; the daemon has no bus";
  std::string out = "; the daemon's buses: ";
  for (std::size_t i = 0; i < names->size(); ++i) out += (i == 0 ? "" : ", ") + (*names)[i];
  return out;
}

}  // namespace

int capture(std::span<const std::string> args) {
  const CommandLine cli(
      "drivegate capture", kCaptureOptions,
      {"-b NAME [-s N] [-w FILE] [-c FILE | --http HOST:PORT]"},
      "Captures every frame of bus NAME for N seconds from the running daemon ([http] capture =\n"
      "true) and writes a pcap (link type USER0 = 147, docs/capture.md). Open it with the\n"
      "dissectors of tools/wireshark/. The daemon is asked where the [http] listen of its\n"
      "configuration says.");
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  if (!parsed->operands.empty()) {
    return cli.usage_error("unexpected argument '" + parsed->operands.front() + "'");
  }
  const std::string bus = parsed->value("bus").value_or("");
  if (bus.empty()) return cli.usage_error("--bus is required");
  int seconds = 10;
  if (const auto v = parsed->value("seconds")) {
    const auto [p, ec] = std::from_chars(v->data(), v->data() + v->size(), seconds);
    if (ec != std::errc{} || p != v->data() + v->size() || seconds < 1 || seconds > 300) {
      return cli.usage_error("--seconds needs a number of seconds (1..300), not '" + *v + "'");
    }
  }
  const std::string file = parsed->value("write").value_or("");
  const auto found = daemon_http(cli, "drivegate capture", *parsed, exit_status);
  if (!found) return exit_status;
  const DaemonHttp& http = *found;
  if (!http.capture) {
    std::cerr << "drivegate capture: " << http.config
              << " says [http] capture = false: the daemon serves no captures (set capture = "
                 "true and restart it: docs/capture.md)\n";
    return 1;
  }
  const bool tty = ::isatty(STDERR_FILENO) == 1;
  const auto progress_flag = parsed->last_of({"progress", "no-progress"});
  const bool show_progress = progress_flag ? *progress_flag == "progress" : tty;

  std::string error;
  const int fd = connect_to(http.host, http.port, error);
  if (fd < 0) {
    std::cerr << "drivegate capture: cannot connect to " << unreachable(http, error) << "\n";
    return 1;
  }
  const std::string request = get_request(
      http.host, http.port,
      "/api/v1/capture?bus=" + escape_query(bus) + "&seconds=" + std::to_string(seconds),
      "application/vnd.tcpdump.pcap");
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

  CaptureProgress progress(std::cerr, tty, bus, std::chrono::seconds(seconds));
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds) + kSlack;
  std::string head;
  std::optional<ResponseHead> h;
  Dechunker dechunk;
  std::string body;
  std::size_t written = 0;
  bool eof = false;
  char buf[16384];
  while (!eof && !dechunk.done()) {
    const auto now = std::chrono::steady_clock::now();
    if (show_progress) progress.tick(now);
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now);
    if (left.count() <= 0) {
      if (show_progress) progress.finish(now, false);
      std::cerr << "drivegate capture: the daemon did not end the capture in time\n";
      break;
    }
    // Awake at least once a second while showing progress, so the seconds count down on a
    // quiet bus too.
    const auto wait = show_progress ? std::min<long>(left.count(), 1000) : left.count();
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(wait)) <= 0) continue;
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
          std::cerr << "drivegate capture: " << unreachable(http, "not an HTTP response") << "\n";
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
        ::close(fd);
        while (!why.empty() && (why.back() == '\n' || why.back() == '\r')) why.pop_back();
        // 404: no bus of that name. Which are there is a question of the daemon's status, not of
        // the capture route: asked there, so the refusal can say what to ask for instead.
        std::string buses;
        if (h->status == 404) {
          if (why.find(bus) == std::string::npos) why += (why.empty() ? "'" : " '") + bus + "'";
          buses = configured_buses(http);
        }
        std::cerr << "drivegate capture: the daemon answered " << h->status << " " << h->reason
                  << (why.empty() ? "" : ": " + why) << buses << "\n";
        return 1;
      }
      if (show_progress) progress.started(std::chrono::steady_clock::now());
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
    progress.feed(body);
  }
  ::close(fd);
  const bool complete = h && (!h->chunked || dechunk.done());
  if (show_progress) progress.finish(std::chrono::steady_clock::now(), complete);
  if (!out) {
    std::cerr << "drivegate capture: write failed\n";
    return 1;
  }
  if (!file.empty()) {
    std::cerr << "drivegate capture: " << progress.counter().frames() << " frames, " << written
              << " bytes of pcap in " << file << (complete ? "" : " (cut short)") << "\n";
  }
  return complete ? 0 : 1;
}

}  // namespace drivegate::cli
