// The journal and the history under a flood of writes (docs/audit.md): the real drivegated on a
// simulated drive of the tests' own (test-drive), stormed for six seconds by clients that each open a new connection for
// every write, accepted (an operate listener) and refused (a read-only listener, and a unit that
// does not exist). Asserted: the lines the daemon writes stay within a bound, far below one a
// write; every write is in the audit trail, one by one or counted in a summary, and the summaries
// and /metrics agree on how many were folded; the plant's events recorded before the storm, and
// the command that started the drive, are still in the history. Wide margins: the bound is the
// fold's own arithmetic, whatever the machine's speed.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <iostream>
#include <regex>
#include <thread>

#include "e2e.h"
#include "http_get.h"
#include "modbus_flood.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;

// The sum of a family's samples whose labels contain `labels` ("" for all).
double metric_sum(int http_port, const std::string& family, const std::string& labels) {
  const std::string body = http_get(http_port, "/metrics").body;
  double sum = 0;
  std::size_t at = 0;
  while ((at = body.find("\n" + family + "{", at)) != std::string::npos) {
    const auto close = body.find('}', at);
    const auto end = body.find('\n', close);
    if (body.substr(at, close - at).find(labels) != std::string::npos) {
      sum += std::atof(body.substr(close + 2, end - close - 2).c_str());
    }
    at = end;
  }
  return sum;
}

// One write on a new connection, as a client that reconnects for every request: the exception
// code (0: written), or -1 if no answer came.
int write_once(int port, std::uint8_t unit, std::uint16_t address, std::uint16_t value) {
  const auto reply = raw_request(port, unit, fc06(address, value));
  if (reply.empty()) return -1;
  return (reply[0] & 0x80) != 0 && reply.size() > 1 ? reply[1] : 0;
}

TEST(StressAudit, AFloodOfWritesFromNewConnectionsLeavesTheJournalAndHistoryReadable) {
  TempDir dir;
  Sim sim("test-drive", dir / "drive");
  const int read_port = free_port();
  const int http_port = free_port();
  const std::filesystem::path log = dir / "drivegated.log";
  // The plant's events kept to 50 entries: with one history for everything, a few dozen
  // commands pushed them out; their own shelf has room for this test's few.
  const std::string toml =
      "[[listener]]\naddress = \"127.0.0.1:0\"\naccess = \"operate\"\n\n"
      "[[listener]]\naddress = \"127.0.0.1:" +
      std::to_string(read_port) +
      "\"\naccess = \"read\"\n\n[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port) +
      "\"\nrequests_per_s = 0\n\n[history]\nevents = 50\n\n"
      "[[bus]]\nname = \"line\"\nport = \"" +
      (dir / "drive").string() +
      "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\nadapter = \"test-drive\"\n"
      "unit_id = 1\npoll_ms = 100\n";
  Daemon daemon(dir, toml, {}, log);
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  const auto status = [&] { return plc.input(reg::status, 1).regs.at(0); };
  ASSERT_TRUE(eventually([&] { return (status() & reg::online) != 0; }, 10s));

  // Before the storm: the plant's events (comm lost and back) and the run that started the drive.
  ASSERT_THAT(sim.control("silent on"), HasSubstr("ok"));
  ASSERT_TRUE(eventually([&] { return (status() & reg::comm_lost) != 0; }, 15s));
  ASSERT_THAT(sim.control("silent off"), HasSubstr("ok"));
  ASSERT_TRUE(eventually([&] { return (status() & reg::online) != 0; }, 15s));
  ASSERT_EQ(plc.write(reg::command, {1 /*run_forward*/, 800}), 0);
  ASSERT_TRUE(eventually(
      [&] {
        return http_get(http_port, "/api/v1/events?kind=comm_restored")
                   .body.find("answers again") != std::string::npos;
      },
      5s));
  std::uint64_t sent = 1;  // the run

  // The storm: accepted setpoints (each a new value) from two clients, refusals from four on the
  // read-only listener and from one writing to a unit nobody serves, every write on a connection
  // of its own.
  const std::size_t log_before = slurp(log).size();
  std::atomic<std::uint64_t> answered{0};
  std::atomic<std::uint64_t> accepted{0};
  std::atomic<std::uint64_t> lost{0};
  const auto until = std::chrono::steady_clock::now() + 6s;
  std::vector<std::thread> clients;
  const auto client = [&](int port, std::uint8_t unit, std::uint16_t first, std::uint16_t step) {
    for (std::uint16_t v = first; std::chrono::steady_clock::now() < until;
         v = static_cast<std::uint16_t>(300 + (v - 300 + step) % 1000)) {
      const int code = write_once(port, unit, reg::setpoint, v);
      if (code < 0) {
        ++lost;
        continue;
      }
      ++answered;
      if (code == 0) ++accepted;
    }
  };
  for (std::uint16_t c = 0; c < 2; ++c) clients.emplace_back(client, daemon.port(), 1, 300 + c, 2);
  for (std::uint16_t c = 0; c < 4; ++c) clients.emplace_back(client, read_port, 1, 300 + c, 4);
  clients.emplace_back(client, daemon.port(), 9, 300, 1);
  for (auto& t : clients) t.join();
  sent += answered.load();
  std::cerr << answered.load() << " writes answered (" << accepted.load() << " accepted), "
            << lost.load() << " unanswered\n";
  EXPECT_GT(accepted.load(), 20u);  // it really stormed, both ways
  EXPECT_GT(answered.load(), 1'000u);
  EXPECT_EQ(lost.load(), 0u);

  // Every write is counted, and the history still has what happened before the storm.
  ASSERT_TRUE(eventually(
      [&] {
        return metric_sum(http_port, "drivegate_writes_total", "source=\"modbus\"") ==
               static_cast<double>(sent);
      },
      10s))
      << metric_sum(http_port, "drivegate_writes_total", "source=\"modbus\"") << " of " << sent;
  EXPECT_THAT(http_get(http_port, "/api/v1/events?kind=comm_lost").body,
              HasSubstr("comm lost: the drive stopped answering"));
  EXPECT_THAT(http_get(http_port, "/api/v1/events?kind=command&limit=1000").body,
              HasSubstr("setpoint_rpm=800 command=run_forward: ok"));
  const double folded_metric = metric_sum(http_port, "drivegate_audit_folded_total", "");

  // Stopped, the daemon writes the summaries still pending: then the journal (its stand-in, the
  // log) has every write, one by one or in a summary.
  ASSERT_EQ(daemon.stop(), 0);
  const std::string text = slurp(log);
  const std::string storm = text.substr(log_before);
  const std::regex one(R"( write to (drive \(unit 1\)|unit 9) from modbus 127\.0\.0\.1:)");
  const std::regex folded(
      R"( (\d+) writes? to .* from modbus 127\.0\.0\.1 on .*folded into this record)");
  std::uint64_t in_journal = 0;
  std::uint64_t in_summaries = 0;
  std::size_t storm_lines = 0;
  for (std::size_t at = 0; at < text.size();) {
    const auto end = std::min(text.find('\n', at), text.size());
    const std::string line = text.substr(at, end - at);
    if (at >= log_before) ++storm_lines;
    std::smatch m;
    if (std::regex_search(line, m, folded)) {
      in_summaries += std::stoull(m[1]);
    } else if (std::regex_search(line, one)) {
      ++in_journal;
    }
    at = end + 1;
  }
  std::cerr << storm_lines << " lines from the storm on; " << in_journal << " writes one by one, "
            << in_summaries << " in summaries\n";
  EXPECT_EQ(in_journal + in_summaries, sent);
  EXPECT_EQ(static_cast<double>(in_summaries), folded_metric);
  // The fold's bound (command_fold.h): the accepted and the refused each at most a burst of 100
  // and 10 a second, and one summary a key an interval; five keys here; and the listener's lines
  // about refusals, a burst of 10 and one a second. A line a write would be thousands.
  EXPECT_LT(storm_lines, 2u * (100 + 6 * 10) + 5 * 3 + 10 + 6 + 40) << storm;
  EXPECT_LT(storm_lines * 10, sent);
}

}  // namespace
}  // namespace drivegate::test
