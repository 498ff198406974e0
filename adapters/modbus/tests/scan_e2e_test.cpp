// `drivegate scan` end to end: the real program on one end of a pseudo-terminal pair,
// pymodbus's serial slave (tests/support/pymodbus_slave.h) on the other, at an address the scan
// must find among those it probes, with an identification the scan must report and match to a
// profile. The snippet it prints is checked by the daemon's own --check-config.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <sstream>

#include "e2e.h"
#include "pymodbus_slave.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using ::testing::StartsWith;

struct Scan {
  int status;
  std::string out;  // stdout
  std::string err;  // stderr
  std::chrono::milliseconds took;
};

// `drivegate scan ARGS...`, to its end (60 s at most).
Scan scan(const TempDir& dir, std::vector<std::string> args) {
  args.insert(args.begin(), {(bin_dir() / "drivegate").string(), "scan"});
  const auto started = std::chrono::steady_clock::now();
  Child child(args, dir / "scan.err");
  std::string out;
  while (auto line = child.read_line(60s)) out += *line + "\n";
  const int status = child.wait_exit(10s);
  const auto took = std::chrono::duration_cast<std::chrono::milliseconds>(
      std::chrono::steady_clock::now() - started);
  return {status, out, slurp(dir / "scan.err"), took};
}

// The report's line per slave: "address N: ...".
std::vector<std::string> slave_lines(const std::string& out) {
  std::vector<std::string> lines;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) {
    if (std::regex_search(line, std::regex("^address [0-9]+: "))) lines.push_back(line);
  }
  return lines;
}

std::vector<std::string> lines_starting(const std::string& text, const std::string& prefix) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind(prefix, 0) == 0) out.push_back(line);
  }
  return out;
}

TEST(ScanE2E, FindsThePymodbusSlaveAtItsAddressWithItsIdentificationAndProfile) {
  if (!have_pymodbus_tools())
    GTEST_SKIP() << "needs socat and python3-pymodbus (tools/deps.sh test)";
  TempDir dir;
  std::filesystem::create_directory(dir / "profiles");
  // One profile for the slave's product family, one for another product of its vendor: only
  // the first is suggested. Both are the example profile's shape with an identification.
  const auto profile = [&](const std::string& name, const std::string& product) {
    std::ofstream(dir / "profiles" / (name + ".toml"))
        << "[profile]\nname = \"" << name
        << "\"\nsource = \"adapters/modbus/tests/scan_e2e_test.cpp\"\n"
        << "identification = { vendor_name = \"drivegate-test\", product_code = \"" << product
        << "\" }\n[[point]]\nname = \"control\"\ntable = \"holding\"\naddress = 0\ntype = "
           "\"u16\"\n";
  };
  profile("pymb", "PYMB-*");
  profile("other", "OTHER-1");
  PymodbusSlave slave(
      dir, {"--unit 17", "--vendor drivegate-test", "--product-code PYMB-17", "--revision 3.0"});
  // Addresses 1-40, 300 ms each: a Python slave on a loaded machine (CI runs four of these
  // tests at once on two cores) may take longer than 50 ms to answer, and a slave that answers
  // after its timeout is, rightly, not found.
  const auto r = scan(dir, {"--port", slave.port().string(), "--baud", "19200", "--parity", "even",
                            "--addresses", "1-40", "--timeout-ms", "300", "--profiles",
                            (dir / "profiles").string(), "--progress"});
  ASSERT_EQ(r.status, 0) << r.out << r.err << slurp(dir / "slave.err");

  // Exactly one slave, at 17, with what pymodbus says it is, and the matching profile.
  const std::string pymb = (dir / "profiles" / "pymb.toml").string();
  EXPECT_EQ(slave_lines(r.out),
            std::vector<std::string>{"address 17: holding register 0 = 6; VendorName "
                                     "\"drivegate-test\", ProductCode \"PYMB-17\", "
                                     "MajorMinorRevision \"3.0\"; profile " +
                                     pymb})
      << r.out;
  EXPECT_THAT(r.out, HasSubstr("\n1 slave found on " + slave.port().string() +
                               " (19200 baud 8E1, rtu), addresses 1-40\n"));
  EXPECT_EQ(lines_starting(r.out, "note:"), std::vector<std::string>{}) << r.out;
  EXPECT_THAT(r.out, HasSubstr("\n[[device]]\nname = \"a-17\"\nbus = \"a\"\nadapter = \"modbus\"\n"
                               "unit_id = 17\naddress = 17\n[device.options]\nprofile = \"" +
                               pymb + "\"\n"));
  EXPECT_EQ(r.out.find("other.toml"), std::string::npos) << "suggested only on a match";

  // The bound first, then progress at most once a second.
  EXPECT_THAT(r.err, StartsWith("drivegate scan: 40 addresses on " + slave.port().string() +
                                " (19200 baud, 8 data, parity even, 1 stop), rtu, 300 ms each: at "
                                "most 13 s if none answers, "))
      << r.err;
  // The pty's dropped parity is warned of once, apart from the progress.
  EXPECT_EQ(lines_starting(r.err, "drivegate scan: warning: ").size(), 1u) << r.err;
  auto progress = lines_starting(r.err, "drivegate scan: ");
  std::erase_if(progress,
                [](const std::string& l) {
    return l.starts_with("drivegate scan: warning: "); });
  EXPECT_GE(progress.size(), 3u) << r.err;  // the bound, the first and the last count
  EXPECT_LE(progress.size(), 3u + static_cast<std::size_t>(r.took / 1s)) << r.err;
  EXPECT_EQ(progress.back(),
            "drivegate scan: 40 of 40 addresses, 1 slave found, at most 0 s left");

  // The snippet is a configuration the daemon takes, once the slave's line is free.
  slave.kill();
  const std::string snippet = r.out.substr(r.out.find("# drivegate.toml"));
  std::ofstream(dir / "found.toml") << snippet;
  Child check({(bin_dir() / "drivegated").string(), "--check-config", (dir / "found.toml").string(),
               "--plugin-dir", plugin_dir().string()},
              dir / "check.err");
  EXPECT_EQ(check.wait_exit(20s), 0) << snippet << slurp(dir / "check.err");
}

TEST(ScanE2E, AnAsciiSlaveWithoutTheRegisterOrAnIdentityIsFoundByItsException) {
  if (!have_pymodbus_tools())
    GTEST_SKIP() << "needs socat and python3-pymodbus (tools/deps.sh test)";
  TempDir dir;
  // No holding 0 (exception 02 to the probe), no identification objects.
  PymodbusSlave slave(dir, {"--unit 7", "--framing ascii", "--no-control"});
  const auto r = scan(
      dir, {"--port", slave.port().string(), "--framing", "ascii", "-a", "5-9", "--no-progress"});
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  EXPECT_EQ(slave_lines(r.out),
            std::vector<std::string>{"address 7: exception 02 (illegal data address) to a read of "
                                     "holding register 0; identification without objects; no "
                                     "profile suggested without VendorName and ProductCode"})
      << r.out;
  EXPECT_THAT(r.out, HasSubstr("\n1 slave found on " + slave.port().string() +
                               " (19200 baud 8E1, ascii), addresses 5-9\n"));
  // Nothing matched: the snippet names a profile still to write, which the daemon refuses.
  EXPECT_THAT(r.out, HasSubstr("# no profile matches it: write one (docs/profiles.md) and name it "
                               "here\nprofile = \"/etc/drivegate/profiles/slave-7.toml\"\n"));
  EXPECT_EQ(r.err.find("of 5 addresses"), std::string::npos) << "--no-progress: " << r.err;
}

TEST(ScanE2E, NothingOnTheLineIsNoSlaveAndExitZero) {
  if (!have_pymodbus_tools())
    GTEST_SKIP() << "needs socat and python3-pymodbus (tools/deps.sh test)";
  TempDir dir;
  PymodbusSlave slave(dir, {"--unit 7"});
  const auto r = scan(dir, {"--port", slave.port().string(), "-a", "1-3,8", "-t", "20"});
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_EQ(r.out, "no slave found on " + slave.port().string() +
                       " (19200 baud 8E1, rtu), addresses 1-3,8\n");
}

// A slave answering 150 ms after a probe of 100 ms, at the end of the range (here the only
// address asked): no later probe is there to hear it, the wait after the last one does. It is
// found, marked late, and the note says to raise the timeout. `drivegate sim modbus` with a
// turnaround is the late slave; the pty it is on takes no parity, which the scan warns of.
TEST(ScanE2E, ASlaveAnsweringLateAtTheEndOfTheRangeIsFoundAndNoted) {
  TempDir dir;
  Sim slave("modbus", dir / "late", {"--address", "17", "--turnaround-ms", "150"});
  const auto r =
      scan(dir, {"--port", (dir / "late").string(), "-a", "17", "-t", "100", "--no-progress"});
  ASSERT_EQ(r.status, 0) << r.out << r.err;
  const auto lines = slave_lines(r.out);
  ASSERT_EQ(lines.size(), 1u) << r.out;
  EXPECT_THAT(lines[0], StartsWith("address 17: holding register 0 = "));
  EXPECT_THAT(lines[0], HasSubstr(", late; "));
  EXPECT_THAT(r.out, HasSubstr("\nnote: address 17 answered after its wait (found all the same): "
                               "a longer --timeout-ms suits it\n"));
  EXPECT_THAT(r.err, HasSubstr("drivegate scan: warning: " + (dir / "late").string() +
                               " did not take every setting asked: parity even (the port has "
                               "none)"));
}

TEST(ScanE2E, ABadParityIsAUsageError) {
  TempDir dir;
  const auto r = scan(dir, {"--port", "/dev/ttyUSB0", "--parity", "mark"});
  EXPECT_EQ(r.status, 2);
  EXPECT_EQ(r.out, "");
  EXPECT_THAT(r.err,
              StartsWith("drivegate scan: --parity must be none, even or odd, not 'mark'\n"));
  EXPECT_THAT(r.err, HasSubstr("usage: drivegate scan --port DEVICE"));
  for (const auto& bad :
       std::vector<std::vector<std::string>>{{"--parity", "even"},  // no --port
                                             {"--port", "/dev/ttyUSB0", "-a", "0-10"},
                                             {"--port", "/dev/ttyUSB0", "--framing", "binary"},
                                             {"--port", "/dev/ttyUSB0", "--timeout-ms", "5"},
                                             {"--port", "tcp://host"}}) {
    EXPECT_EQ(scan(dir, bad).status, 2) << bad.back();
  }
}

TEST(ScanE2E, APortThatDoesNotExistExitsOneNamingIt) {
  TempDir dir;
  const std::string port = (dir / "ttyUSB9").string();
  const auto r = scan(dir, {"--port", port, "--no-progress"});
  EXPECT_EQ(r.status, 1);
  EXPECT_EQ(r.out, "") << "nothing was scanned";
  EXPECT_THAT(r.err,
              HasSubstr("drivegate scan: cannot open " + port + ": No such file or directory\n"));
}

}  // namespace
}  // namespace drivegate::test
