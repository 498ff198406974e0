// What happened, and when, end to end (docs/audit.md): the real daemon on a simulated test
// drive (the test plugin, tests/support/test_adapter), its history read back the ways an
// engineer reads it (GET /api/v1/events, `drivegate events`, `-f`, the log), after each kind of
// write: a PLC's on an operate listener, a read-only client's refused one, the failsafe's stop
// when the PLC goes away, a reload, and the shutdown stop. And the trends of /api/v1/trends
// following the drive.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "e2e.h"
#include "http_get.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::AllOf;
using ::testing::HasSubstr;

std::string config(const std::filesystem::path& port, int read_port, int http_port, int poll_ms) {
  return "[[listener]]\naddress = \"127.0.0.1:0\"\naccess = \"operate\"\n\n"
         "[[listener]]\naddress = \"127.0.0.1:" +
         std::to_string(read_port) +
         "\"\naccess = \"read\"\n\n"
         "[http]\nlisten = \"127.0.0.1:" +
         std::to_string(http_port) +
         "\"\nrequests_per_s = 0\n\n"
         "[[bus]]\nname = \"drive-line\"\nport = \"" +
         port.string() +
         "\"\n\n[[device]]\nname = \"drive\"\nbus = \"drive-line\"\nadapter = \"test-drive\"\n"
         "unit_id = 1\npoll_ms = " +
         std::to_string(poll_ms) + "\nfailsafe_timeout_ms = 1000\nfailsafe_action = \"stop\"\n";
}

// `drivegate events ARGS...` run to its end: its output.
std::string events_cli(int http_port, std::vector<std::string> args) {
  std::vector<std::string> argv = {(bin_dir() / "drivegate").string(), "events", "--http",
                                   "127.0.0.1:" + std::to_string(http_port)};
  argv.insert(argv.end(), args.begin(), args.end());
  Child c(std::move(argv), "/dev/null");
  std::string out;
  while (auto line = c.read_line(10s)) out += *line + "\n";
  EXPECT_EQ(c.wait_exit(), 0) << out;
  return out;
}

class HistoryE2E : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(observer_.connect());
    ASSERT_TRUE(eventually([&] { return (status() & reg::online) != 0; }, 10s))
        << "never online; sim says " << sim_.control("state");
  }
  std::uint16_t status() { return observer_.input(reg::status, 1).regs.at(0); }
  std::string events(const std::string& query) {
    return http_get(http_port_, "/api/v1/events" + query).body;
  }

  TempDir dir_;
  int read_port_ = free_port();
  int http_port_ = free_port();
  std::filesystem::path log_ = dir_ / "drivegated.log";
  Sim sim_{"test-drive", dir_ / "drive"};
  Daemon daemon_{dir_, config(dir_ / "drive", read_port_, http_port_, 500), {}, log_};
  Plc observer_{daemon_.port()};
};

TEST_F(HistoryE2E, EveryWriteAndWhatCameOfItIsInTheHistory) {
  // A PLC runs the drive; a read-only client tries to stop it.
  {
    Plc plc(daemon_.port());
    ASSERT_TRUE(plc.connect());
    ASSERT_EQ(plc.write(reg::command, {1 /*run_forward*/, 800}), 0);
    Plc reader(read_port_);
    ASSERT_TRUE(reader.connect());
    EXPECT_EQ(reader.write(reg::command, {0}), 1);  // exception 01: not its to write
  }  // the PLC is gone: the failsafe will stop the drive

  // The history through the CLI, oldest first: the PLC's run with its client address, the
  // refusal with why.
  const std::string commands = events_cli(http_port_, {"--kind", "command"});
  EXPECT_THAT(commands, AllOf(HasSubstr("  command  "), HasSubstr("drive"),
                              HasSubstr("from modbus 127.0.0.1:"),
                              HasSubstr("setpoint_rpm=800 command=run_forward: ok"),
                              HasSubstr("on 127.0.0.1:" + std::to_string(read_port_)),
                              HasSubstr("denied (beyond access read)")))
      << commands;
  EXPECT_LT(commands.find("run_forward: ok"), commands.find("denied")) << commands;

  // The failsafe stops the drive when the PLC went away: its own command and the trip.
  ASSERT_TRUE(eventually(
      [&] {
        return events("?kind=failsafe_tripped").find("\"failsafe_tripped\"") != std::string::npos;
      },
      5s))
      << events("");
  ASSERT_TRUE(eventually(
      [&] { return events("?kind=command").find("\"source\":\"failsafe\"") != std::string::npos; },
      5s))
      << events("?kind=command");
  EXPECT_THAT(events("?kind=command&limit=1"),
              AllOf(HasSubstr("\"points\":\"command=stop\""), HasSubstr("\"result\":\"ok\"")));
  EXPECT_THAT(events("?device=drive&kind=drive_started"), HasSubstr("run_forward"));

  // -f: a write made while it follows shows up within 2 s.
  Child follow({(bin_dir() / "drivegate").string(), "events", "-f", "-n", "1", "--http",
                "127.0.0.1:" + std::to_string(http_port_)},
               "/dev/null");
  ASSERT_TRUE(follow.read_line(10s).has_value());  // the newest entry first
  Plc plc(daemon_.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_EQ(plc.write(reg::setpoint, {650}), 0);
  bool seen = false;
  const auto deadline = std::chrono::steady_clock::now() + 2s;
  while (!seen && std::chrono::steady_clock::now() < deadline) {
    const auto line = follow.read_line(std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now()));
    seen = line && line->find("setpoint_rpm=650: ok") != std::string::npos;
  }
  EXPECT_TRUE(seen) << "drivegate events -f did not show the write within 2 s";

  // Trends: the drive's speed and setpoint, once a second.
  EXPECT_TRUE(eventually(
      [&] {
        const std::string t = http_get(http_port_, "/api/v1/trends?device=drive").body;
        return t.find("\"speed_rpm\"") != std::string::npos && t.find("650") != std::string::npos;
      },
      5s))
      << http_get(http_port_, "/api/v1/trends?device=drive").body;
  EXPECT_EQ(http_get(http_port_, "/api/v1/events?kind=nonsense").status, 400);
  EXPECT_EQ(http_get(http_port_, "/api/v1/events?limit=x").status, 400);

  // A reload: what changed.
  std::ofstream(daemon_.config()) << config(dir_ / "drive", read_port_, http_port_, 400);
  daemon_.process().signal(SIGHUP);
  EXPECT_TRUE(eventually(
      [&] { return events("?kind=reload").find("device drive changed") != std::string::npos; }, 5s))
      << events("?kind=reload");

  // Shutdown stops the running drive: recorded as shutdown's (in the log: its journal stand-in).
  ASSERT_EQ(plc.write(reg::command, {1}), 0);
  ASSERT_TRUE(eventually([&] { return (status() & reg::running) != 0; }, 5s));
  EXPECT_EQ(daemon_.stop(), 0);
  EXPECT_THAT(slurp(log_), AllOf(HasSubstr("from shutdown: command=stop: ok"),
                                 HasSubstr("from failsafe: command=stop: ok")))
      << slurp(log_);
}

}  // namespace
}  // namespace drivegate::test
