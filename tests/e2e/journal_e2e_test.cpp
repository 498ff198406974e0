// What reaches the journal (docs/audit.md), end to end: the audit record of `drivegate write`
// reaches journald, or stderr when there is none, never neither; and a read-only client that
// connects anew for every write, on a Modbus TCP listener and on an RTU-over-TCP one, gets a few
// lines about it, not one a connection, while the audit trail still counts every write. Without
// journald, the daemon's stderr is its journal's stand-in.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <regex>
#include <sstream>

#include "drivegate/crc.h"
#include "e2e.h"
#include "fake_journald.h"

namespace drivegate::test::journal_e2e_test {
namespace {

using namespace std::chrono_literals;
using ::testing::AllOf;
using ::testing::HasSubstr;
using ::testing::Not;

std::string drive(const std::filesystem::path& port) {
  return "[[bus]]\nname = \"line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\n"
         "adapter = \"test-drive\"\nunit_id = 1\n";
}

// `drivegate write` audits its write into the journal, the daemon being stopped. Without journald
// (no socket) the record goes to stderr; with one, to the journal with its fields, and not to
// stderr as well.
TEST(Journal, DrivegateWritesAuditRecordReachesTheJournalOrStderr) {
  TempDir dir;
  Sim sim("test-drive", dir / "drive");
  std::ofstream(dir / "drivegate.toml") << drive(dir / "drive");
  const auto write = [&](const std::string& assignment) {
    Child c(
        {(bin_dir() / "drivegate").string(), "write", "--config", (dir / "drivegate.toml").string(),
         "--device", "drive", "--plugin-dir", plugin_dir().string(), assignment},
        dir / "stderr");
    const std::string out = c.read_line(20s).value_or("(nothing)");
    EXPECT_EQ(c.wait_exit(20s), 0) << out << "\n" << slurp(dir / "stderr");
    return out;
  };

  {
    JournalAt none((dir / "no-journald").string());
    EXPECT_EQ(write("setpoint_rpm=300"), "setpoint_rpm=300: ok");
  }
  const std::string without = slurp(dir / "stderr");
  EXPECT_THAT(without, AllOf(HasSubstr("write to drive (unit 1) from cli "),
                             HasSubstr(": setpoint_rpm=300: ok, ")))
      << without;

  FakeJournald journald((dir / "journal").string());
  ASSERT_TRUE(journald.bound());
  {
    JournalAt there((dir / "journal").string());
    EXPECT_EQ(write("setpoint_rpm=400"), "setpoint_rpm=400: ok");
  }
  const std::string entry = journald.receive();
  EXPECT_THAT(entry,
              AllOf(HasSubstr("MESSAGE=write to drive (unit 1) from cli "),
                    HasSubstr("\nEVENT=command\n"), HasSubstr("\nDEVICE=drive\n"),
                    HasSubstr("\nSOURCE=cli\n"), HasSubstr("\nPOINTS=setpoint_rpm=400\n"),
                    HasSubstr("\nRESULT=ok\n"), HasSubstr("\nSYSLOG_IDENTIFIER=drivegate\n")))
      << entry;
  EXPECT_THAT(slurp(dir / "stderr"), Not(HasSubstr("write to drive")));
}

// One RTU frame on a new connection to 127.0.0.1:`port`: the reply's bytes (empty if none came).
std::vector<std::uint8_t> rtu_once(int port, Bytes frame) {
  append_crc16_modbus(frame);
  const int fd = connect_loopback(port);
  if (fd < 0) return {};
  std::vector<std::uint8_t> reply;
  if (::write(fd, frame.data(), frame.size()) == static_cast<ssize_t>(frame.size())) {
    const auto deadline = std::chrono::steady_clock::now() + 5s;
    while (reply.size() < 5 && std::chrono::steady_clock::now() < deadline) {
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      std::uint8_t buf[64];
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n <= 0) break;
      reply.insert(reply.end(), buf, buf + n);
    }
  }
  ::close(fd);
  return reply;
}

// A read-only client writing on a new connection each time, 60 times on a Modbus TCP listener and
// 60 on an RTU-over-TCP one: each write is refused with exception 01; each listener says so in a
// burst of lines, not in one a connection; and the audit trail has all 120, one by one or folded
// into the summaries the daemon writes as it stops.
TEST(Journal, AReadOnlyClientConnectingForEveryWriteIsAFewLinesNotOneAConnection) {
  TempDir dir;
  Sim sim("test-drive", dir / "drive");
  const int tcp_port = free_port();
  const int rtu_port = free_port();
  Daemon daemon(dir,
                "[[listener]]\naddress = \"127.0.0.1:0\"\naccess = \"operate\"\n\n"
                "[[listener]]\naddress = \"127.0.0.1:" +
                    std::to_string(tcp_port) +
                    "\"\naccess = \"read\"\n\n[[listener]]\naddress = \"127.0.0.1:" +
                    std::to_string(rtu_port) + "\"\nframing = \"rtu\"\naccess = \"read\"\n\n" +
                    drive(dir / "drive"),
                {}, dir / "drivegated.log");
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(
      eventually([&] { return (plc.input(reg::status, 1).regs.at(0) & reg::online) != 0; }, 10s));

  constexpr int kWrites = 60;
  for (int i = 0; i < kWrites; ++i) {
    const auto v = static_cast<std::uint8_t>(100 + i);
    EXPECT_EQ(raw_request(tcp_port, 1, {0x06, 0x00, 0x01, 0x01, v}),
              (std::vector<std::uint8_t>{0x86, 0x01}));
    const auto reply = rtu_once(rtu_port, {0x01, 0x06, 0x00, 0x01, 0x01, v});
    ASSERT_GE(reply.size(), 3u) << i;
    EXPECT_EQ(reply[1], 0x86);
    EXPECT_EQ(reply[2], 0x01);
  }
  ASSERT_EQ(daemon.stop(), 0);

  const std::string text = slurp(dir / "drivegated.log");
  std::size_t tcp_lines = 0;
  std::size_t rtu_lines = 0;
  std::uint64_t audited = 0;
  const std::regex summary(
      R"( (\d+) writes? to drive \(unit 1\) from modbus(_rtu_tcp)? 127\.0\.0\.1 on )");
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.find("beyond its access level") != std::string::npos) {
      ++(line.find("(rtu over tcp)") != std::string::npos ? rtu_lines : tcp_lines);
    }
    std::smatch m;
    if (std::regex_search(line, m, summary)) {
      audited += std::stoull(m[1]);
    } else if (line.find(" write to drive (unit 1) from modbus") != std::string::npos &&
               line.find(": denied (beyond access read)") != std::string::npos) {
      ++audited;
    }
  }
  // A burst of 10 a listener, then one a second (the writes take a few seconds at most).
  EXPECT_GE(tcp_lines, 1u);
  EXPECT_GE(rtu_lines, 1u);
  EXPECT_LE(tcp_lines, 10u + 10) << text;
  EXPECT_LE(rtu_lines, 10u + 10) << text;
  EXPECT_EQ(audited, 2u * kWrites) << text;
}

}  // namespace
}  // namespace drivegate::test::journal_e2e_test
