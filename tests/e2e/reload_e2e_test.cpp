// SIGHUP: a good new configuration is applied without dropping a Modbus TCP connection; a bad
// one is refused and the daemon keeps serving the old one. [server] limits apply at once to the
// open connections; a listen change waits for a restart. On simulated drives of the tests' own
// (test-drive, tests/support/test_adapter), but for a profile's content, which needs an adapter
// that reads one (modbus, on an ED3100).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <future>
#include <sstream>

#include "e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using ::testing::Not;

std::string drive(const std::filesystem::path& port, int unit) {
  return "[[bus]]\nname = \"line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\nadapter = \"test-drive\"\n"
         "unit_id = " +
         std::to_string(unit) + "\n";
}

bool online(Plc& plc) {
  const auto r = plc.input(reg::status, 1);
  return r.ok() && (r.regs[0] & reg::online) != 0;
}

// A drive at unit 1, online, with a PLC connected to the daemon.
class ReloadE2E : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(plc_.connect());
    ASSERT_TRUE(eventually([&] { return online(plc_); }, 10s));
  }
  TempDir dir_;
  Sim sim_{"test-drive", dir_ / "drive"};
  Daemon daemon_{dir_, drive(dir_ / "drive", 1)};
  Plc plc_{daemon_.port(), 1};
};

TEST_F(ReloadE2E, GoodConfigSwapsDevicesKeepingConnections) {
  // The same drive moves to unit 2; the open connection sees the change.
  std::ofstream(daemon_.config()) << drive(dir_ / "drive", 2);
  daemon_.process().signal(SIGHUP);
  ASSERT_TRUE(eventually([&] { return plc_.input(reg::status, 1).exception == 0x0A; }, 10s));
  plc_.unit(2);
  EXPECT_TRUE(eventually([&] { return online(plc_); }, 10s));
  EXPECT_TRUE(daemon_.process().running());
}

TEST_F(ReloadE2E, BadConfigIsRefusedAndTheOldOneKeepsServing) {
  std::ofstream(daemon_.config()) << "[[device]]\nname = 5\n";
  daemon_.process().signal(SIGHUP);
  std::this_thread::sleep_for(1s);
  EXPECT_TRUE(daemon_.process().running());
  EXPECT_TRUE(online(plc_));
  EXPECT_EQ(plc_.write(reg::command, {1, 700}), 0);
}

// --- a reload is a diff, applied with the least disturbance ----------------------

// Two devices on one line, `poll_b` the second one's poll_ms.
std::string pair_on_one_line(const std::filesystem::path& port, const std::string& adapter,
                             int poll_b, const std::string& first_extra = "") {
  std::string toml = "[[bus]]\nname = \"line\"\nport = \"" + port.string() + "\"\n";
  for (int unit = 1; unit <= 2; ++unit) {
    toml += "\n[[device]]\nname = \"dev-" + std::to_string(unit) +
            "\"\nbus = \"line\"\nadapter = \"" + adapter + "\"\nunit_id = " + std::to_string(unit) +
            "\naddress = " + std::to_string(unit) +
            (unit == 2 ? "\npoll_ms = " + std::to_string(poll_b) : std::string()) + "\n" +
            (unit == 1 ? first_extra : std::string());
  }
  return toml;
}

bool online_unit(Plc& plc, int unit) {
  plc.unit(unit);
  return online(plc);
}

// Two drives on one line (the second's poll_ms 500), both online, the first running at 2000 rpm
// on the PLC's command: where every reload test of a running drive starts.
struct RunningPair {
  TempDir dir;
  Sim sim{"test-drive", dir / "line", {"--address", "1", "--address", "2"}};
  Daemon daemon{dir, pair_on_one_line(dir / "line", "test-drive", 500), {}, dir / "drivegated.log"};
  Plc plc{daemon.port()};

  void start() {
    ASSERT_TRUE(plc.connect());
    ASSERT_TRUE(eventually([&] { return online_unit(plc, 1) && online_unit(plc, 2); }, 10s));
    plc.unit(1);
    ASSERT_EQ(plc.write(reg::command, {1, 2000}), 0);
    ASSERT_TRUE(eventually(
        [&] { return sim.control("@1 state").find(" speed=2000 ") != std::string::npos; }, 15s))
        << sim.control("@1 state");
  }
};

// Two drives on one line, the first running at 2000 rpm on the PLC's command; only the second's
// poll_ms changes. The first keeps its command block (run, 2000), a new setpoint reaches it, and
// the line is not reopened; the log says what changed and what was kept.
TEST(ReloadDiffE2E, ANeighboursChangeLeavesARunningDriveAsItRuns) {
  RunningPair pair;
  ASSERT_NO_FATAL_FAILURE(pair.start());
  auto& [dir, sim, daemon, plc] = pair;

  std::ofstream(daemon.config()) << pair_on_one_line(dir / "line", "test-drive", 250);
  daemon.process().signal(SIGHUP);
  ASSERT_TRUE(eventually(
      [&] {
        return slurp(dir / "drivegated.log").find("configuration reloaded") != std::string::npos;
      },
      10s));
  const std::string log = slurp(dir / "drivegated.log");
  EXPECT_NE(log.find("reload: device dev-2 changed (poll_ms 500 -> 250): started afresh"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("1 kept as they run: dev-1"), std::string::npos) << log;
  EXPECT_EQ(log.find("reopened"), std::string::npos) << log;
  // The port was opened once, at start-up: the reload kept it open.
  std::size_t opened = 0;
  for (auto at = log.find("bus line: "); at != std::string::npos;
       at = log.find("bus line: ", at + 1)) {
    if (log.compare(log.find('\n', at) - 5, 5, " open") == 0) ++opened;
  }
  EXPECT_EQ(opened, 1u) << log;
  plc.unit(1);
  const auto held = plc.holding(reg::command, 2);
  ASSERT_TRUE(held.ok());
  EXPECT_EQ(held.regs[0], 1);     // run_forward, as before the reload
  EXPECT_EQ(held.regs[1], 2000);  // and its setpoint
  EXPECT_EQ(plc.write(reg::setpoint, {2800}), 0);
  EXPECT_TRUE(eventually(
      [&] { return sim.control("@1 state").find(" speed=2800 ") != std::string::npos; }, 15s))
      << sim.control("@1 state");
  plc.unit(1);
  EXPECT_EQ(plc.write(reg::command, {0}), 0);
}

// The running drive itself is changed (its budget_ms): the new device starts from what the
// drive reports, run at 2000 rpm, never "stop" over a turning motor; the log says what it found,
// and a new setpoint reaches it.
TEST(ReloadDiffE2E, AChangedRunningDriveStartsFromWhatItReports) {
  RunningPair pair;
  ASSERT_NO_FATAL_FAILURE(pair.start());
  auto& [dir, sim, daemon, plc] = pair;

  EXPECT_EQ(slurp(dir / "drivegated.log").find("found running"), std::string::npos);  // stopped
  std::ofstream(daemon.config()) << pair_on_one_line(dir / "line", "test-drive", 500,
                                                     "budget_ms = 900\n");
  daemon.process().signal(SIGHUP);
  // What the log says after the reload line (the daemon's start-up found nothing running).
  const auto since_reload = [&] {
    const std::string all = slurp(dir / "drivegated.log");
    const auto at = all.find("SIGHUP");
    return at == std::string::npos ? std::string() : all.substr(at);
  };
  ASSERT_TRUE(eventually(
      [&] { return since_reload().find("device dev-1: found running") != std::string::npos; }, 10s))
      << slurp(dir / "drivegated.log");
  const std::string log = since_reload();
  EXPECT_NE(log.find("reload: device dev-1 changed (budget_ms 1000 -> 900): started afresh"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("device dev-1: found running (run_forward, setpoint 2000 rpm"),
            std::string::npos)
      << log;
  plc.unit(1);
  const auto held = plc.holding(reg::command, 2);
  ASSERT_TRUE(held.ok());
  EXPECT_EQ(held.regs[0], 1);     // run_forward: what the drive does
  EXPECT_EQ(held.regs[1], 2000);  // at the speed it reports
  EXPECT_NE(plc.input(reg::status, 1).regs.at(0) & reg::running, 0);
  EXPECT_NE(sim.control("@1 state").find(" speed=2000 "), std::string::npos);  // never stopped
  EXPECT_EQ(plc.write(reg::setpoint, {2800}), 0) << slurp(dir / "drivegated.log");
  EXPECT_TRUE(eventually(
      [&] { return sim.control("@1 state").find(" speed=2800 ") != std::string::npos; }, 15s))
      << sim.control("@1 state");
  EXPECT_EQ(plc.write(reg::command, {0}), 0);
}

// The same change with on_start = "stop": the new device stops the drive it finds running, and
// the log says so.
TEST(ReloadDiffE2E, OnStartStopStopsADriveFoundRunning) {
  RunningPair pair;
  ASSERT_NO_FATAL_FAILURE(pair.start());
  auto& [dir, sim, daemon, plc] = pair;
  std::ofstream(daemon.config()) << pair_on_one_line(dir / "line", "test-drive", 500,
                                                     "on_start = \"stop\"\n");
  daemon.process().signal(SIGHUP);
  EXPECT_TRUE(eventually(
      [&] {
        return slurp(dir / "drivegated.log").find("device dev-1: stop on start confirmed") !=
               std::string::npos;
      },
      15s))
      << slurp(dir / "drivegated.log");
  EXPECT_NE(
      slurp(dir / "drivegated.log")
          .find("device dev-1: found running (speed 2000 rpm): stopping it (on_start = stop)"),
      std::string::npos)
      << slurp(dir / "drivegated.log");
  plc.unit(1);
  EXPECT_EQ(plc.holding(reg::command, 1).regs.at(0), 0);
  EXPECT_TRUE(
      eventually([&] { return (plc.input(reg::status, 1).regs.at(0) & reg::running) == 0; }, 15s));
  EXPECT_NE(sim.control("@1 state").find(" target=0 "), std::string::npos);
}

// A drive with a 2 s failsafe, run by a PLC that then goes away; half a second later a reload
// changes only its neighbour. The failsafe still trips on time and stops the drive.
TEST(ReloadDiffE2E, ANeighboursChangeDoesNotDisarmTheFailsafe) {
  TempDir dir;
  Sim sim("test-drive", dir / "line", {"--address", "1", "--address", "2"});
  const std::string failsafe = "failsafe_timeout_ms = 2000\nfailsafe_action = \"stop\"\n";
  Daemon daemon(dir, pair_on_one_line(dir / "line", "test-drive", 500, failsafe), {},
                dir / "drivegated.log");
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return online_unit(plc, 1) && online_unit(plc, 2); }, 10s));
  plc.unit(1);
  ASSERT_EQ(plc.write(reg::command, {1, 1500}), 0);
  const auto last_write = std::chrono::steady_clock::now();
  ASSERT_TRUE(eventually(
      [&] { return sim.control("@1 state").find("running=1") != std::string::npos; }, 5s));
  std::this_thread::sleep_for(500ms);
  std::ofstream(daemon.config()) << pair_on_one_line(dir / "line", "test-drive", 250, failsafe);
  daemon.process().signal(SIGHUP);
  ASSERT_TRUE(eventually(
      [&] { return sim.control("@1 state").find("running=0") != std::string::npos; }, 8s))
      << "the failsafe never stopped the drive after the reload";
  const auto stopped = std::chrono::steady_clock::now() - last_write;
  EXPECT_LT(stopped, 4s);  // 2 s failsafe, a poll, and wide margins
  plc.unit(1);
  EXPECT_NE(plc.input(reg::status, 1).regs.at(0) & (1 << 5), 0);  // latched
  EXPECT_NE(slurp(dir / "drivegated.log").find("failsafe stop"), std::string::npos);
}

// --- a reload reads content --------------------------------------------------------------------

// One ED3100 on a 9600 8E1 line: the `ed3100` adapter with `extra` keys, or the `modbus` adapter
// with the profile at `profile`.
std::string vfd(const std::filesystem::path& port, const std::string& extra,
                const std::filesystem::path& profile = {}) {
  return "[[bus]]\nname = \"line\"\nport = \"" + port.string() +
         "\"\nbaud = 9600\nparity = \"even\"\n\n[[device]]\nname = \"vfd\"\nbus = \"line\"\n"
         "unit_id = 1\naddress = 1\n" +
         extra +
         (profile.empty()
              ? "adapter = \"ed3100\"\n"
              : "adapter = \"modbus\"\n[device.options]\nprofile = \"" + profile.string() + "\"\n");
}

// A profile file edited, then SIGHUP: the device that reads it is a changed device, started
// afresh with the new content (here the speed's scale doubled), not "kept as it runs" with the
// old one; the drive it finds running runs on. A profile edited into something that does not
// load refuses the reload, with the reason, and the device goes on as it was.
TEST(ReloadDiffE2E, AnEditedProfileIsAChangedDevice) {
  REQUIRE_ADAPTER("ed3100");
  REQUIRE_ADAPTER("modbus");
  TempDir dir;
  const auto shipped =
      std::filesystem::path(DRIVEGATE_SOURCE_DIR) / "adapters/modbus/profiles/ed3100-standard.toml";
  const std::string text = slurp(shipped);
  const std::string old_scale = "scale = 0.3                 # 0.01 Hz (format bit 3";
  ASSERT_NE(text.find(old_scale), std::string::npos) << "the shipped profile changed";
  const auto profile = dir / "vfd.toml";
  std::ofstream(profile) << text;
  Sim sim("ed3100", dir / "line", {"--address", "1", "--set", "sim_reply_form=standard"});
  ASSERT_THAT(sim.control("run forward 5000"), HasSubstr("ok"));  // 50.00 Hz: 1500 rpm
  Daemon daemon(dir, vfd(dir / "line", "", profile), {}, dir / "drivegated.log");
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  const auto speed = [&] {
    const auto r = plc.input(reg::speed, 1);
    return r.ok() ? static_cast<int>(r.regs[0]) : -1;
  };
  ASSERT_TRUE(eventually([&] { return speed() == 1500; }, 10s)) << speed();

  std::string edited = text;
  edited.replace(edited.find(old_scale), std::string("scale = 0.3").size(), "scale = 0.6");
  std::ofstream(profile) << edited;
  daemon.process().signal(SIGHUP);
  ASSERT_TRUE(eventually(
      [&] {
        return slurp(dir / "drivegated.log").find("configuration reloaded") != std::string::npos;
      },
      10s));
  const std::string log = slurp(dir / "drivegated.log");
  EXPECT_THAT(log, HasSubstr("reload: device vfd changed (profile " + profile.string()));
  EXPECT_THAT(log, Not(HasSubstr("kept as they run: vfd")));
  EXPECT_TRUE(eventually([&] { return speed() == 3000; }, 10s)) << speed();
  EXPECT_THAT(sim.control("state"), HasSubstr("running=1"));  // found running, runs on

  std::ofstream(profile) << "[profile]\nname = 5\n";
  daemon.process().signal(SIGHUP);
  ASSERT_TRUE(eventually(
      [&] {
        return slurp(dir / "drivegated.log").find("new configuration refused") != std::string::npos;
      },
      10s));
  EXPECT_THAT(slurp(dir / "drivegated.log"), HasSubstr(profile.string() + ":"));
  EXPECT_EQ(speed(), 3000);
  EXPECT_TRUE(daemon.process().running());
}

// --- every write's outcome is the truth ---------------------------------------------------------

// A run on its way to a slow drive (60 ms before each reply) when a SIGHUP changes the device's
// poll_ms: the reload waits for it, the PLC gets the drive's answer (the write echoed, not 0x0B
// "the gateway stopped" over a drive that took it), the drive runs, and the new device shows the
// run it finds.
TEST(ReloadDiffE2E, AWriteInFlightAtAReloadGetsTheDrivesAnswer) {
  TempDir dir;
  Sim sim("test-drive", dir / "line", {"--address", "1", "--turnaround-ms", "60"});
  const auto config = [&](const std::string& extra) {
    return "[[bus]]\nname = \"line\"\nport = \"" + (dir / "line").string() +
           "\"\n\n[[device]]\nname = \"vfd\"\nbus = \"line\"\nadapter = \"test-drive\"\n"
           "unit_id = 1\n" +
           extra;
  };
  Daemon daemon(dir, config(""), {}, dir / "drivegated.log");
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return online(plc); }, 10s));
  std::ofstream(daemon.config()) << config("poll_ms = 250\n");
  // FC 16: command = run_forward, setpoint = 1500 rpm.
  const std::vector<std::uint8_t> run = {0x10, 0x00, 0x00, 0x00, 0x02,
                                         0x04, 0x00, 0x01, 0x05, 0xDC};
  // The drive took the run (its reply still 60 ms away, the write not yet answered).
  const auto took = [&] { return sim.control("state").find(" running=1 ") != std::string::npos; };
  ASSERT_FALSE(took());
  auto reply = std::async(std::launch::async, [&] { return raw_request(daemon.port(), 1, run); });
  ASSERT_TRUE(eventually(took, 5s)) << sim.control("state");
  daemon.process().signal(SIGHUP);
  EXPECT_EQ(reply.get(), (std::vector<std::uint8_t>{0x10, 0x00, 0x00, 0x00, 0x02}));
  ASSERT_TRUE(eventually(
      [&] {
        return slurp(dir / "drivegated.log").find("configuration reloaded") != std::string::npos;
      },
      10s));
  const std::string log = slurp(dir / "drivegated.log");
  EXPECT_THAT(log, HasSubstr("reload: waiting for the writes in flight"));
  EXPECT_THAT(log, HasSubstr("reload: device vfd changed (poll_ms 500 -> 250)"));
  EXPECT_THAT(log, Not(HasSubstr("the gateway stopped")));
  EXPECT_TRUE(
      eventually([&] { return sim.control("state").find("running=1") != std::string::npos; }, 5s))
      << sim.control("state");
  EXPECT_TRUE(eventually(
      [&] {
        const auto held = plc.holding(reg::command, 1);
        return held.ok() && held.regs[0] == 1;  // run_forward, as found
      },
      10s))
      << slurp(dir / "drivegated.log");
  EXPECT_EQ(plc.write(reg::command, {0}), 0);
}

// A listener's access changed from operate to read applies to the open connection, and the log
// says so.
TEST(ReloadDiffE2E, AnAccessChangeIsLogged) {
  TempDir dir;
  Sim sim("test-drive", dir / "drive");
  const auto config = [&](const char* access) {
    return "[[listener]]\naddress = \"127.0.0.1:0\"\naccess = \"" + std::string(access) + "\"\n\n" +
           drive(dir / "drive", 1);
  };
  Daemon daemon(dir, config("operate"), {}, dir / "drivegated.log");
  Plc plc(daemon.port(), 1);
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return online(plc); }, 10s));
  EXPECT_EQ(plc.write(reg::heartbeat, {1}), 0);
  std::ofstream(daemon.config()) << config("read");
  daemon.process().signal(SIGHUP);
  ASSERT_TRUE(eventually(
      [&] {
        return slurp(dir / "drivegated.log").find("configuration reloaded") != std::string::npos;
      },
      10s));
  EXPECT_NE(slurp(dir / "drivegated.log").find("access operate -> read"), std::string::npos)
      << slurp(dir / "drivegated.log");
  EXPECT_EQ(plc.write(reg::heartbeat, {2}), 0x01);
}

// --- [server] on SIGHUP -------------------------------------------------------------------

std::string server_section(const std::string& keys) {
  return "[server]\n" + keys + "\n\n";
}

// A TCP client that connects and never sends a byte.
class SilentClient {
 public:
  explicit SilentClient(int port) : fd_(connect_loopback(port)), connected_(fd_ >= 0) {}
  ~SilentClient() { ::close(fd_); }
  SilentClient(const SilentClient&) = delete;
  SilentClient& operator=(const SilentClient&) = delete;
  [[nodiscard]] bool connected() const { return connected_; }
  // True when the daemon closed the connection (EOF or reset) within `timeout`.
  bool closed_by_peer(std::chrono::milliseconds timeout) {
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, static_cast<int>(timeout.count())) <= 0) return false;
    char b;
    return ::recv(fd_, &b, 1, 0) <= 0;
  }

 private:
  int fd_;
  bool connected_ = false;
};

TEST(ReloadServerE2E, ShorterIdleTimeoutClosesASilentClientWhileAPollingOneIsServed) {
  TempDir dir;
  Sim sim{"test-drive", dir / "drive"};
  const auto log = dir / "drivegated.log";
  Daemon daemon{dir, server_section("idle_timeout_ms = 60000") + drive(dir / "drive", 1), {}, log};
  Plc busy{daemon.port(), 1};
  ASSERT_TRUE(busy.connect());
  ASSERT_TRUE(eventually([&] { return online(busy); }, 10s));
  SilentClient silent(daemon.port());
  ASSERT_TRUE(silent.connected());
  // `busy` asks every 50 ms or so throughout: the new timeout counts from a client's last request,
  // so a pause here longer than 1 s would (rightly) close it too at the reload.
  const auto poll_busy = [&] {
    const auto r = busy.input(reg::status, 1);
    ASSERT_TRUE(r.ok()) << "the polling client lost service: " << r.exception;
  };
  // `silent` stays silent past the coming 1 s: the 60 s in force keeps it open.
  const auto connected = std::chrono::steady_clock::now();
  while (std::chrono::steady_clock::now() - connected < 1500ms) {
    poll_busy();
    if (HasFatalFailure()) return;
    ASSERT_FALSE(silent.closed_by_peer(50ms));
  }

  std::ofstream(daemon.config()) << server_section("idle_timeout_ms = 1000") +
                                        drive(dir / "drive", 1);
  daemon.process().signal(SIGHUP);
  const auto sighup = std::chrono::steady_clock::now();
  bool closed = false;
  while (!closed && std::chrono::steady_clock::now() - sighup < 5s) {
    poll_busy();
    if (HasFatalFailure()) return;
    closed = silent.closed_by_peer(50ms);
  }
  EXPECT_TRUE(closed) << "the silent client was not closed within 5 s of SIGHUP";
  EXPECT_TRUE(online(busy));
  EXPECT_TRUE(eventually([&] {
    return slurp(log).find(
               "[server] applied without closing a connection: idle_timeout_ms "
               "60000 -> 1000") != std::string::npos;
  }));
  EXPECT_EQ(slurp(log).find("next restart"), std::string::npos);
  EXPECT_TRUE(daemon.process().running());
}

// The listening socket stays where it is; the log says a restart is needed. Started without
// --listen (which would override [server] listen, and so hide the change).
TEST(ReloadServerE2E, ListenChangeIsLoggedAndTheOldAddressKeepsServing) {
  TempDir dir;
  Sim sim{"test-drive", dir / "drive"};
  const auto log = dir / "drivegated.log";
  const int port = free_port();
  int other = free_port();
  while (other == port) other = free_port();
  const auto config = [&](int p) {
    return server_section("listen = \"127.0.0.1:" + std::to_string(p) + "\"") +
           drive(dir / "drive", 1);
  };
  std::ofstream(dir / "drivegate.toml") << config(port);
  Child daemon({(bin_dir() / "drivegated").string(), "--config", (dir / "drivegate.toml").string(),
                "--plugin-dir", plugin_dir().string()},
               log);
  ASSERT_TRUE(eventually(
      [&] {
        Plc probe(port);
        return probe.connect();
      },
      15s));
  Plc plc{port, 1};
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return online(plc); }, 10s));

  std::ofstream(dir / "drivegate.toml") << config(other);
  daemon.signal(SIGHUP);
  EXPECT_TRUE(
      eventually([&] { return slurp(log).find("configuration reloaded") != std::string::npos; }));
  EXPECT_NE(slurp(log).find("listener 127.0.0.1:" + std::to_string(other) +
                            ": takes effect at the next restart"),
            std::string::npos);
  EXPECT_EQ(slurp(log).find("[server] applied"), std::string::npos);  // nothing else changed
  EXPECT_TRUE(online(plc));
  Plc newcomer{port, 1};
  EXPECT_TRUE(newcomer.connect());
  Plc elsewhere{other, 1};
  EXPECT_FALSE(elsewhere.connect());
  EXPECT_TRUE(daemon.running());
}

}  // namespace
}  // namespace drivegate::test
