// drivegate events: the running daemon's history (docs/audit.md), from its HTTP side's
// /api/v1/events: commands with their source and result, faults, comm lost and back, failsafe
// trips, reloads. --follow keeps asking for what is newer, once a second, until interrupted.
#include <charconv>
#include <chrono>
#include <iostream>
#include <thread>

#include "commands.h"
#include "daemon_http.h"
#include "event_lines.h"
#include "history/event_log.h"
#include "http_client.h"

namespace drivegate::cli {

namespace {

constexpr Option kEventsOptions[] = {
    {"follow", 'f', nullptr, "keep printing new entries as they come, until interrupted"},
    {"lines", 'n', "N", "print the newest N entries first (1..1000, default 50)"},
    {"device", 'd', "NAME", "only entries of device NAME"},
    {"kind", 'k', "KIND", "only entries of one kind (command, fault_raised, ...: drivegate(1))"},
    kDaemonConfigOption,
    kHttpOption,
    kHelpOption,
};

constexpr std::chrono::seconds kTimeout{5};
constexpr std::size_t kMaxBytes = 16 << 20;
constexpr std::chrono::seconds kFollowPeriod{1};

}  // namespace

int events(std::span<const std::string> args) {
  const CommandLine cli(
      "drivegate events", kEventsOptions,
      {"[-f] [-n N] [-d NAME] [-k KIND] [-c FILE]",
       "[-f] [-n N] [-d NAME] [-k KIND] --http HOST:PORT"},
      "Prints the running daemon's history, oldest first, one entry a line: time (UTC), kind,\n"
      "device, what happened. Asks the daemon's HTTP side, where the [http] listen of its\n"
      "configuration says (a daemon without [http] has none: docs/http.md).");
  int exit_status = 0;
  const auto parsed = parse_command(cli, args, exit_status);
  if (!parsed) return exit_status;
  if (!parsed->operands.empty()) {
    return cli.usage_error("unexpected argument '" + parsed->operands.front() + "'");
  }
  unsigned lines = 50;
  if (const auto v = parsed->value("lines")) {
    const auto [p, ec] = std::from_chars(v->data(), v->data() + v->size(), lines);
    if (ec != std::errc{} || p != v->data() + v->size() || lines < 1 || lines > 1000) {
      return cli.usage_error("--lines needs a number 1..1000, not '" + *v + "'");
    }
  }
  const auto http = daemon_http(cli, "drivegate events", *parsed, exit_status);
  if (!http) return exit_status;
  std::string filter;
  if (const auto d = parsed->value("device")) filter += "&device=" + escape_query(*d);
  if (const auto k = parsed->value("kind")) filter += "&kind=" + escape_query(*k);
  const bool follow = parsed->has("follow");

  std::uint64_t after = 0;
  std::int64_t started = 0;  // the daemon's history's start: another value, a restart
  bool first = true;
  bool lost = false;
  for (;;) {
    const std::string target = "/api/v1/events?limit=" + std::to_string(first ? lines : kMaxQuery) +
                               (first ? std::string() : "&after=" + std::to_string(after)) + filter;
    std::string error;
    const auto got = http_get(http->host, http->port, target, kTimeout, kMaxBytes, error);
    bool more = false;  // a full page: ask again at once
    if (!got || got->head.status != 200) {
      const std::string why = !got ? error
                                   : std::to_string(got->head.status) + " " + got->head.reason +
                                         (got->body.empty() ? "" : ": " + got->body);
      if (!follow || first) {
        std::cerr << "drivegate events: " << unreachable(*http, why) << "\n";
        return 1;
      }
      if (!lost) std::cerr << "drivegate events: lost the daemon (" << why << "), trying again\n";
      lost = true;
    } else {
      const auto page = event_lines(got->body);
      if (!page) {
        std::cerr << "drivegate events: the daemon's answer is not the events document\n";
        return 1;
      }
      if (lost) std::cerr << "drivegate events: the daemon answers again\n";
      lost = false;
      if (!first && page->started_ms != started) {
        // Restarted: it numbers its entries afresh, and everything it has is new.
        std::cerr << "drivegate events: the daemon restarted\n";
        started = page->started_ms;
        after = 0;
        continue;
      }
      started = page->started_ms;
      for (const auto& l : page->lines) std::cout << l << "\n";
      std::cout.flush();
      after = std::max(after, page->newest_seq);
      if (first) after = std::max(after, page->last_seq);
      more = !first && page->lines.size() == kMaxQuery;
      first = false;
    }
    if (!follow) return 0;
    if (!more) std::this_thread::sleep_for(kFollowPeriod);
  }
}

}  // namespace drivegate::cli
