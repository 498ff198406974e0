// Captures end to end (docs/capture.md): drivegated on every built adapter's simulator, one bus
// each, `drivegate capture` fetching ~2 s of each bus over /api/v1/capture, and tshark decoding
// the pcaps with the build's Wireshark plugin folder (build/wireshark/, tools/wireshark/README.md):
// every packet decoded by its adapter's protocol, no malformed packet and no Lua error, every
// checksum good, both directions present. The adapters and what to expect of their captures come
// from their own scenarios (adapters/<id>/tests/e2e_test.cpp, tests/support/e2e_adapters.h).
// Also the refusals of the route as a client sees them (400, 404, a capture that is not enabled),
// and what `drivegate capture` shows while it runs and says when refused.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <sstream>

#include "e2e.h"
#include "e2e_adapters.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;

using AdapterCase = E2eAdapter;

// Every adapter whose scenario registered itself (tests/support/e2e_adapters.h) and whose plugin
// is in the build's plugin directory.
std::vector<AdapterCase> built_cases() {
  std::vector<AdapterCase> out;
  for (const auto& c : e2e_adapters()) {
    if (std::filesystem::exists(plugin_dir() / ("drivegate-" + c.id + ".so"))) out.push_back(c);
  }
  return out;
}

// The build's plugin folder, as installed: every adapter's dissector and the shipped
// descriptions' generated data beside drivegate.lua, which loads them.
std::filesystem::path dissector() {
  return std::filesystem::path(DRIVEGATE_TEST_WIRESHARK_DIR) / "drivegate.lua";
}

std::optional<std::filesystem::path> tshark() {
  for (const char* p : {"/usr/bin/tshark", "/usr/local/bin/tshark"}) {
    if (std::filesystem::exists(p)) return std::filesystem::path(p);
  }
  return std::nullopt;
}

// Runs `argv` to its end; its stdout, line by line.
std::vector<std::string> run_lines(std::vector<std::string> argv, int* status = nullptr,
                                   std::chrono::milliseconds timeout = 60s) {
  Child c(std::move(argv), "/dev/null");
  std::vector<std::string> lines;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    auto line = c.read_line(1s);
    if (!line) {
      if (!c.running()) break;
      continue;
    }
    lines.push_back(std::move(*line));
  }
  // Lines still buffered after the exit.
  while (auto line = c.read_line(100ms)) lines.push_back(std::move(*line));
  const int rc = c.wait_exit(5s);
  if (status != nullptr) *status = rc;
  return lines;
}

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (const char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur.push_back(c);
    }
  }
  out.push_back(cur);
  return out;
}

// One raw HTTP GET; the status code (0: no answer).
int http_status(int port, const std::string& target) {
  const int fd = connect_loopback(port);
  int status = 0;
  if (fd >= 0) {
    const std::string req = "GET " + target + " HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n";
    if (::write(fd, req.data(), req.size()) == static_cast<ssize_t>(req.size())) {
      char buf[64] = {};
      pollfd p{fd, POLLIN, 0};
      if (::poll(&p, 1, 5000) > 0 && ::read(fd, buf, sizeof buf - 1) > 12) {
        status = std::atoi(buf + 9);
      }
    }
  }
  ::close(fd);
  return status;
}

std::string config(const TempDir& dir, const std::vector<AdapterCase>& cases, int http_port,
                   bool capture) {
  std::ostringstream c;
  c << "[http]\nlisten = \"127.0.0.1:" << http_port
    << "\"\ncapture = " << (capture ? "true" : "false") << "\n";
  int unit = 1;
  for (const auto& a : cases) {
    c << "\n[[bus]]\nname = \"" << a.id << "\"\nport = \"" << (dir / a.id).string() << "\"\n"
      << a.bus_extra << "\n[[device]]\nname = \"" << a.id << "-drive\"\nbus = \"" << a.id
      << "\"\nadapter = \"" << a.id << "\"\nunit_id = " << unit++ << "\n"
      << a.device_extra;
  }
  return c.str();
}

class Capture : public ::testing::Test {
 protected:
  void SetUp() override {
    cases_ = built_cases();
    if (cases_.empty()) GTEST_SKIP() << "no adapter built";
    for (const auto& a : cases_) {
      sims_.push_back(std::make_unique<Sim>(a.id, dir_ / a.id, a.sim_args));
    }
    http_port_ = free_port();
    daemon_ = std::make_unique<Daemon>(dir_, config(dir_, cases_, http_port_, true),
                                       std::vector<std::string>{}, dir_ / "drivegated.log");
    Plc plc(daemon_->port());
    ASSERT_TRUE(plc.connect());
    for (std::size_t i = 0; i < cases_.size(); ++i) {
      plc.unit(static_cast<int>(i) + 1);
      ASSERT_TRUE(
          eventually([&] { return (plc.input(reg::status, 1).regs[0] & reg::online) != 0; }, 15s))
          << cases_[i].id << " never online";
      // Running, so the gateway has commands to send as well as polls (fdc1 in slave mode
      // sends only its speed).
      EXPECT_EQ(
          plc.write(reg::command, {1 /*run_forward*/, static_cast<std::uint16_t>(cases_[i].rpm)}),
          0)
          << cases_[i].id;
    }
  }
  std::vector<std::string> capture_args(const std::string& bus, int seconds,
                                        const std::filesystem::path& file) const {
    return {(bin_dir() / "drivegate").string(),
            "capture",
            "--bus",
            bus,
            "--seconds",
            std::to_string(seconds),
            "-w",
            file.string(),
            "--http",
            "127.0.0.1:" + std::to_string(http_port_)};
  }

  TempDir dir_;
  std::vector<AdapterCase> cases_;
  std::vector<std::unique_ptr<Sim>> sims_;
  int http_port_ = 0;
  std::unique_ptr<Daemon> daemon_;
};

TEST_F(Capture, EveryBusDecodesInTsharkWithGoodChecksumsBothWays) {
  const auto ts = tshark();
  if (!ts) GTEST_SKIP() << "tshark is not installed (tools/deps.sh tshark)";
  // Two buses at a time (the daemon streams at most two captures at once), two seconds each.
  for (std::size_t first = 0; first < cases_.size(); first += 2) {
    std::vector<std::unique_ptr<Child>> fetches;
    for (std::size_t i = first; i < std::min(first + 2, cases_.size()); ++i) {
      const auto& a = cases_[i];
      fetches.push_back(std::make_unique<Child>(capture_args(a.id, 2, dir_ / (a.id + ".pcap"))));
    }
    for (std::size_t i = 0; i < fetches.size(); ++i) {
      ASSERT_EQ(fetches[i]->wait_exit(30s), 0)
          << "drivegate capture --bus " << cases_[first + i].id;
    }
  }
  for (const auto& a : cases_) {
    SCOPED_TRACE(a.id);
    const auto file = dir_ / (a.id + ".pcap");
    ASSERT_GT(std::filesystem::file_size(file), 24u);
    const std::string lua = "lua_script:" + dissector().string();
    int rc = -1;
    // The whole dissection, as text: nothing malformed, no Lua error, no bad checksum.
    const auto verbose = run_lines({ts->string(), "-r", file.string(), "-X", lua, "-V"}, &rc);
    ASSERT_EQ(rc, 0);
    ASSERT_FALSE(verbose.empty());
    for (const auto& line : verbose) {
      EXPECT_THAT(line, ::testing::Not(::testing::HasSubstr("Malformed"))) << line;
      EXPECT_THAT(line, ::testing::Not(::testing::HasSubstr("Lua Error"))) << line;
      EXPECT_THAT(line, ::testing::Not(::testing::HasSubstr("[incorrect"))) << line;
    }
    // Packet by packet: adapter, direction, flags, protocol, checksum status.
    const auto rows =
        run_lines({ts->string(), "-r", file.string(), "-X", lua, "-T", "fields", "-E",
                   "separator=/t", "-e", "drivegate.adapter", "-e", "drivegate.direction", "-e",
                   "drivegate.flags", "-e", "_ws.col.Protocol", "-e", a.checksum_field},
                  &rc);
    ASSERT_EQ(rc, 0);
    std::map<std::string, int> directions;
    int frames = 0;
    for (const auto& row : rows) {
      const auto f = split(row, '\t');
      ASSERT_EQ(f.size(), 5u) << row;
      const int flags = std::stoi(f[2], nullptr, 16);
      if ((flags & 0x02) != 0) continue;  // noise: shown raw, by design not decoded
      ++frames;
      EXPECT_EQ(f[0], a.capture_id.empty() ? a.id : a.capture_id) << row;
      EXPECT_EQ(f[3], a.protocol) << row;
      ++directions[f[1]];
      // One status per checksum field in the frame (fdc1 has two): all Good (1).
      ASSERT_FALSE(f[4].empty()) << "no checksum verified: " << row;
      for (const auto& s : split(f[4], ',')) EXPECT_EQ(s, "1") << row;
      EXPECT_EQ(flags & 0x01, 0) << "the gateway judged it damaged: " << row;
    }
    EXPECT_GE(frames, 2);
    EXPECT_GT(directions["0"], 0) << "nothing gateway -> drive";
    EXPECT_GT(directions["1"], 0) << "nothing drive -> gateway";
  }
}

TEST_F(Capture, RefusesUnknownBusBadDurationAndLeavesTheBusUntapped) {
  EXPECT_EQ(http_status(http_port_, "/api/v1/capture?bus=nope&seconds=1"), 404);
  EXPECT_EQ(http_status(http_port_, "/api/v1/capture?bus=" + cases_[0].id + "&seconds=0"), 400);
  EXPECT_EQ(http_status(http_port_, "/api/v1/capture?bus=" + cases_[0].id + "&seconds=301"), 400);
  EXPECT_EQ(http_status(http_port_, "/api/v1/capture?seconds=1"), 400);
  // The tool's refusal names the bus asked for and the buses the daemon has.
  {
    Child c({(bin_dir() / "drivegate").string(), "capture", "--bus", "nope", "--http",
             "127.0.0.1:" + std::to_string(http_port_)},
            dir_ / "nope.err");
    EXPECT_EQ(c.wait_exit(30s), 1);
    const std::string err = read_text(dir_ / "nope.err");
    EXPECT_THAT(err, ::testing::HasSubstr("drivegate capture: the daemon answered 404 Not Found: "
                                          "no such bus 'nope'; the daemon's buses: "))
        << err;
    for (const auto& a : cases_) EXPECT_THAT(err, ::testing::HasSubstr(a.id)) << err;
    EXPECT_EQ(std::count(err.begin(), err.end(), '\n'), 1) << "one line: " << err;
  }
  // A client that leaves early: the capture (and its tap) ends, the daemon serves on.
  {
    Child early(capture_args(cases_[0].id, 300, dir_ / "early.pcap"));
    std::this_thread::sleep_for(500ms);
  }  // killed here
  EXPECT_EQ(http_status(http_port_, "/api/v1/capture?bus=nope"), 404);
  EXPECT_TRUE(daemon_->process().running());
}

// Captures are bounded. With two streaming, a third is refused at once (503, the
// daemon's reason printed, exit 1), the page is served all along, and once one ends the next
// capture is taken.
TEST_F(Capture, AThirdCaptureAtOnceIsRefusedAndThePageStaysServed) {
  std::vector<std::unique_ptr<Child>> long_ones;
  for (int i = 0; i < 2; ++i) {
    long_ones.push_back(std::make_unique<Child>(
        capture_args(cases_[0].id, 300, dir_ / ("long" + std::to_string(i) + ".pcap"))));
  }
  const auto streaming = [&] { return occurrences(slurp(dir_ / "drivegated.log"), " for 300 s"); };
  ASSERT_TRUE(eventually([&] { return streaming() == 2; }));
  Child third(capture_args(cases_[0].id, 1, dir_ / "third.pcap"), dir_ / "third.err");
  EXPECT_EQ(third.wait_exit(10s), 1);
  EXPECT_THAT(slurp(dir_ / "third.err"), ::testing::HasSubstr("captures are running already"));
  EXPECT_EQ(http_status(http_port_, "/api/v1/status"), 200);
  long_ones.pop_back();  // killed: its capture ends
  ASSERT_TRUE(eventually([&] {
    int next = -1;
    run_lines(capture_args(cases_[0].id, 1, dir_ / "next.pcap"), &next);
    return next == 0;
  }));
}

// Progress on stderr: frames, bytes and the seconds left, at most once a second; by
// default only when stderr is a terminal (here it is a file), with --progress anywhere.
TEST_F(Capture, ShowsProgressOnStderrAtMostOnceASecond) {
  const auto& bus = cases_[0].id;
  auto args = capture_args(bus, 3, dir_ / "progress.pcap");
  args.push_back("--progress");
  Child shown(args, dir_ / "progress.err");
  ASSERT_EQ(shown.wait_exit(30s), 0);
  const std::string err = read_text(dir_ / "progress.err");
  std::vector<std::string> updates;
  for (const auto& line : split(err, '\n')) {
    if (line.find(" s left") != std::string::npos) updates.push_back(line);
  }
  // Drawn at the start, about once a second, and at the end: 3..6 for 3 seconds, never a flood.
  EXPECT_GE(updates.size(), 3u) << err;
  EXPECT_LE(updates.size(), 6u) << err;
  ASSERT_FALSE(updates.empty()) << err;
  EXPECT_THAT(updates.front(), ::testing::StartsWith("drivegate capture: bus " + bus + ": "));
  EXPECT_THAT(updates.front(), ::testing::HasSubstr(", 3 s left")) << err;
  EXPECT_THAT(updates.back(), ::testing::HasSubstr(" bytes, 0 s left")) << err;
  EXPECT_THAT(updates.back(), ::testing::Not(::testing::HasSubstr(": 0 frames"))) << err;
  // The summary counts what the file holds.
  const auto size = std::filesystem::file_size(dir_ / "progress.pcap");
  EXPECT_THAT(err, ::testing::HasSubstr(" frames, " + std::to_string(size) + " bytes of pcap in "))
      << err;
  EXPECT_THAT(updates.back(), ::testing::HasSubstr(", " + std::to_string(size) + " bytes, "));

  Child quiet(capture_args(bus, 1, dir_ / "quiet.pcap"), dir_ / "quiet.err");
  ASSERT_EQ(quiet.wait_exit(30s), 0);
  EXPECT_THAT(read_text(dir_ / "quiet.err"), ::testing::Not(::testing::HasSubstr(" s left")));
}

TEST_F(Capture, IsRefusedWhenNotEnabled) {
  TempDir dir;
  auto cases = cases_;
  cases.resize(1);
  Sim sim(cases[0].id, dir / cases[0].id, cases[0].sim_args);
  const int http_port = free_port();
  Daemon daemon(dir, config(dir, cases, http_port, false));
  EXPECT_TRUE(eventually([&] { return http_status(http_port, "/api/v1/status") == 200; }));
  EXPECT_EQ(http_status(http_port, "/api/v1/capture?bus=" + cases[0].id), 403);
}

}  // namespace
}  // namespace drivegate::test
