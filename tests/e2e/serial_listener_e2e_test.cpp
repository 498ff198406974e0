// drivegate as a Modbus RTU / ASCII slave (docs/serial-listeners.md), end to end: the
// real daemon with a simulated drive of the tests' own (test-drive) behind it, and on a serial
// listener's line a master nobody here wrote, pymodbus's serial client
// (tests/e2e/pymodbus_serial_master.py), across a socat pseudo-terminal pair. What it reads is held
// to what a Modbus TCP client reads of the same drive, what it writes to what the simulated drive
// shows.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "drivegate/crc.h"
#include "e2e.h"
#include "http_get.h"
#include "pymodbus_slave.h"  // have_pymodbus_tools
#include "serial_master.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::Not;

class SerialListenerE2E : public ::testing::Test {
 protected:
  // `listener`: the serial [[listener]]'s keys after its port.
  void start(const std::string& listener, const std::string& device_options = "") {
    if (!have_pymodbus_tools()) GTEST_SKIP() << "socat and python3-pymodbus: tools/deps.sh test";
    make_line();
    sim_ = std::make_unique<Sim>("test-drive", dir_ / "line");
    // The first listener is the TCP one the harness moves to a free port (--listen).
    toml_ =
        "[[listener]]\naddress = \"127.0.0.1:502\"\naccess = \"operate\"\n"
        "allow = [\"127.0.0.1\"]\n\n"
        "[[listener]]\nport = \"" +
        (dir_ / "s").string() + "\"\nbaud = 19200\n" + listener +
        "\n[[bus]]\nname = \"line\"\nport = \"" + (dir_ / "line").string() +
        "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\n"
        "adapter = \"test-drive\"\nunit_id = 1\n" +
        device_options;
    daemon_ =
        std::make_unique<Daemon>(dir_, toml_, std::vector<std::string>{}, dir_ / "daemon.log");
    plc_ = std::make_unique<Plc>(daemon_->port());
    ASSERT_TRUE(plc_->connect());
    ASSERT_TRUE(
        eventually([&] { return (plc_->input(reg::status, 1).regs[0] & reg::online) != 0; }, 10s))
        << "never online; sim says " << sim_->control("state");
    ASSERT_TRUE(eventually(
        [&] {
          return slurp(dir_ / "daemon.log").find("(rtu): ") != std::string::npos ||
                 slurp(dir_ / "daemon.log").find("(ascii): ") != std::string::npos;
        },
        5s));
  }
  // Runs the master on the line with `steps`; one line of output a step.
  std::vector<std::string> master(const std::vector<std::string>& steps,
                                  const std::string& framing = "rtu") {
    return run_master({"--port", (dir_ / "m").string(), "--framing", framing}, steps);
  }
  // The same master over TCP, RTU frames on the socket ("RTU over TCP").
  std::vector<std::string> tcp_master(int port, const std::vector<std::string>& steps) {
    return run_master({"--tcp", "127.0.0.1:" + std::to_string(port)}, steps);
  }
  std::vector<std::string> run_master(const std::vector<std::string>& where,
                                      const std::vector<std::string>& steps) {
    return run_serial_master(where, steps, dir_ / "master.err");
  }
  std::string log() { return slurp(dir_ / "daemon.log"); }

  // The pseudo-terminal pair, made again after `line_` went (an adapter plugged back).
  void make_line() {
    line_ = std::make_unique<PtyPair>(dir_ / "m", dir_ / "s", dir_ / "socat.err");
  }

  TempDir dir_;
  std::string toml_;
  std::unique_ptr<PtyPair> line_;
  std::unique_ptr<Sim> sim_;
  std::unique_ptr<Daemon> daemon_;
  std::unique_ptr<Plc> plc_;
};

// The common block as a TCP client reads it, through RTU: status, fault code, the setpoint
// written over the serial line reaching the drive, and the exceptions a TCP client gets: 0x02
// for an unmapped address, 0x03 for a setpoint the drive cannot run. A unit nobody serves is
// silence, not 0x0B: other slaves may share the line.
TEST_F(SerialListenerE2E, AnRtuMasterReadsWritesAndGetsTheExceptionsATcpClientGets) {
  start("access = \"operate\"\n");
  const auto tcp = plc_->input(reg::status, 2);
  const auto out = master({"read",
                           "1",
                           "input",
                           "0",
                           "2",  // status, fault_code
                           "write",
                           "1",
                           std::to_string(reg::setpoint),
                           "600",  // FC 06
                           "read",
                           "1",
                           "holding",
                           std::to_string(reg::setpoint),
                           "1",
                           "read",
                           "1",
                           "holding",
                           "9000",
                           "1",  // unmapped
                           "write",
                           "1",
                           std::to_string(reg::setpoint),
                           "60000",  // out of range
                           "read",
                           "9",
                           "input",
                           "0",
                           "1"});  // nobody at 9
  ASSERT_EQ(out.size(), 6U) << ::testing::PrintToString(out) << slurp(dir_ / "master.err");
  EXPECT_EQ(out[0], "ok " + std::to_string(tcp.regs[0]) + " " + std::to_string(tcp.regs[1]));
  EXPECT_EQ(out[1], "ok");
  EXPECT_EQ(out[2], "ok 600");
  EXPECT_EQ(out[3], "exception 2");
  EXPECT_EQ(out[4], "exception 3");
  EXPECT_EQ(out[5], "none");
  // What the serial master wrote is what a TCP client reads, and what the drive holds.
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs[0], 600);
  // Run forward at 600 and stop, FC 16 over the line; the drive runs and stops.
  EXPECT_THAT(master({"writes", "1", "0", "1,600"}), ElementsAre("ok"));
  EXPECT_TRUE(eventually(
      [&] {
        const auto state = sim_->control("state");
        return state.find(" target=600 ") != std::string::npos &&
               state.find(" running=1 ") != std::string::npos;
      },
      5s))
      << sim_->control("state");
  EXPECT_THAT(master({"write", "1", "0", "0"}), ElementsAre("ok"));
  EXPECT_TRUE(eventually(
      [&] { return sim_->control("state").find(" running=0 ") != std::string::npos; }, 10s))
      << sim_->control("state");
  // The audit trail names the serial line as the source.
  EXPECT_THAT(log(), HasSubstr("from modbus_serial"));
}

// Noise, a frame cut in half and a frame with a bad CRC on the line between good requests: none
// is answered, and the good request after each gets its own right answer.
TEST_F(SerialListenerE2E, NoiseAndHalfFramesNeverProduceAWrongAnswer) {
  start("access = \"operate\"\n");
  const auto setpoint = std::to_string(reg::setpoint);
  const auto out = master({"raw",   "ff00ff13",  // noise
                           "sleep", "20",       "read",
                           "1",     "holding",  setpoint,
                           "1",     "raw",      "010600",  // half a write request
                           "sleep", "20",       "read",
                           "1",     "holding",  setpoint,
                           "1",     "raw",      "0106000104b00000",  // a whole write, its CRC wrong
                           "sleep", "20",       "read",
                           "1",     "holding",  setpoint,
                           "1"});
  ASSERT_EQ(out.size(), 6U) << ::testing::PrintToString(out);
  EXPECT_EQ(out[0], "reply ");
  EXPECT_EQ(out[1], "ok 0");
  EXPECT_EQ(out[2], "reply ");
  EXPECT_EQ(out[3], "ok 0");
  EXPECT_EQ(out[4], "reply ");
  EXPECT_EQ(out[5], "ok 0");  // the write with the bad CRC was not applied
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs[0], 0);
}

// Address 0 is a broadcast: never answered, and with broadcast = false (the default) a write
// there reaches no drive. FC 08 says what the line saw: 0x0E counts it with the other requests
// for us, 0x0F counts it as not answered, 0x0C counts the bad CRC.
TEST_F(SerialListenerE2E, ABroadcastWriteIsNotAppliedAndFc08CountsTheLine) {
  start("access = \"operate\"\n");
  static_assert(reg::setpoint == 1);
  const auto out = master({"rtu",        "0",  "06000104b0",  // broadcast: setpoint_rpm = 1200
                           "sleep",      "50", "raw",        "0103000000010000",  // bad CRC
                           "sleep",      "20", "rtu",        "1",
                           "0800001234",                      // return query data
                           "rtu",        "1",  "08000e0000",  // server message count
                           "rtu",        "1",  "08000f0000",  // server no response count
                           "rtu",        "1",  "08000c0000",  // bus communication error count
                           "rtu",        "1",  "0800990000",  // not a sub-function
                           "rtu",        "1",  "08000a0000",  // clear counters
                           "rtu",        "1",  "08000e0000"});
  ASSERT_EQ(out.size(), 9U) << ::testing::PrintToString(out);
  EXPECT_EQ(out[0], "reply ");
  EXPECT_EQ(out[1], "reply ");
  // 01 08 0000 1234, its CRC: the request itself (Application Protocol 6.8.1, 00).
  EXPECT_THAT(out[2], ::testing::StartsWith("reply 010800001234"));
  // Broadcast and this one: 2 processed; the broadcast not answered: 1; the bad CRC: 1.
  EXPECT_THAT(out[3], ::testing::StartsWith("reply 0108000e0003"));  // + this request: 3
  EXPECT_THAT(out[4], ::testing::StartsWith("reply 0108000f0001"));
  EXPECT_THAT(out[5], ::testing::StartsWith("reply 0108000c0001"));
  EXPECT_THAT(out[6], ::testing::StartsWith("reply 018801"));
  EXPECT_THAT(out[7], ::testing::StartsWith("reply 0108000a0000"));
  EXPECT_THAT(out[8], ::testing::StartsWith("reply 0108000e0001"));  // counted from the clear
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs[0], 0);             // the broadcast moved nothing
  EXPECT_THAT(log(), HasSubstr("broadcast write (function 0x06) refused"));
}

// Another master nobody here wrote: mbpoll (libmodbus's RTU client), as a commissioning engineer
// would use it on the PLC's port: it writes the setpoint and reads the command block back.
TEST_F(SerialListenerE2E, MbpollWritesAndReadsTheCommandBlockOverRtu) {
  start("access = \"operate\"\n");
  if (!std::filesystem::exists("/usr/bin/mbpoll")) GTEST_SKIP() << "mbpoll: tools/deps.sh";
  const auto run = [&](const std::vector<std::string>& args) {
    std::vector<std::string> argv = {"/usr/bin/mbpoll",
                                     "-m",
                                     "rtu",
                                     "-a",
                                     "1",
                                     "-b",
                                     "19200",
                                     "-P",
                                     "none",
                                     "-t",
                                     "4",
                                     "-1",
                                     "-o",
                                     "1"};
    argv.insert(argv.end(), args.begin(), args.end());
    Child c(argv, dir_ / "mbpoll.err");
    std::string out;
    while (auto line = c.read_line(10s)) out += *line + "\n";
    c.wait_exit(5s);
    return out;
  };
  // mbpoll counts registers from 1: -r 2 is holding 1, setpoint_rpm.
  EXPECT_THAT(run({"-r", "2", (dir_ / "m").string(), "750"}), HasSubstr("Written 1 references"));
  const auto read = run({"-r", "1", "-c", "3", (dir_ / "m").string()});
  EXPECT_THAT(read, HasSubstr("[1]: \t0\n"));    // command: stop
  EXPECT_THAT(read, HasSubstr("[2]: \t750\n"));  // setpoint_rpm
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs[0], 750);
}

// RTU over TCP, as SCADA drivers send to serial device servers: pymodbus's TCP client with its
// RTU framer on a read listener (the example). Reads are served with the serial line's
// frames; a write is exception 01; a unit nobody serves is silence, as on the line.
TEST_F(SerialListenerE2E, RtuOverTcpServesReadsAndRefusesWritesOnAReadListener) {
  const int port = free_port();
  start("access = \"operate\"\n\n[[listener]]\naddress = \"127.0.0.1:" + std::to_string(port) +
        "\"\nframing = \"rtu\"\nallow = [\"127.0.0.1\"]\naccess = \"read\"\n");
  ASSERT_EQ(plc_->write(reg::setpoint, {900}), 0);
  const auto setpoint = std::to_string(reg::setpoint);
  const auto out = tcp_master(
      port, {"read", "1", "holding", setpoint, "1", "write", "1", setpoint, "300", "read", "9",
             "holding", setpoint, "1", "rtu", "1", "0300010001"});  // the same read, raw
  ASSERT_EQ(out.size(), 4U) << ::testing::PrintToString(out) << slurp(dir_ / "master.err");
  EXPECT_EQ(out[0], "ok 900");
  EXPECT_EQ(out[1], "exception 1");
  EXPECT_EQ(out[2], "none");
  // 01 03 02 0384 (900) and its CRC, low byte first.
  EXPECT_THAT(out[3], ::testing::StartsWith("reply 0103020384"));
  EXPECT_EQ(out[3].size(), std::string("reply ").size() + 14);
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs[0], 900);
  EXPECT_THAT(log(), HasSubstr("(rtu over tcp)"));
}

// RTU over TCP: a client sends a run (setpoint and run_forward in one FC 16) and half-closes its
// side at once (shutdown SHUT_WR), as the Modbus TCP listener's clients may: it still gets the
// reply, the echo of what the drive took, CRC and all, and then the connection closes; the drive
// runs, and the audit trail says ok because the client was told.
TEST_F(SerialListenerE2E, RtuOverTcpAnswersAHalfClosedClientsRunThenCloses) {
  const int port = free_port();
  start("access = \"operate\"\n\n[[listener]]\naddress = \"127.0.0.1:" + std::to_string(port) +
        "\"\nframing = \"rtu\"\nallow = [\"127.0.0.1\"]\naccess = \"operate\"\n");
  Bytes run = {0x01, 0x10, 0x00, 0x00, 0x00, 0x02, 0x04, 0x00, 0x01, 0x03, 0x20};  // 1, 800
  append_crc16_modbus(run);
  const int fd = connect_loopback(port);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::write(fd, run.data(), run.size()), static_cast<ssize_t>(run.size()));
  ::shutdown(fd, SHUT_WR);
  Bytes in;
  bool closed = false;
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (!closed && std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    std::uint8_t buf[64];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n <= 0) {
      closed = true;
      break;
    }
    in.insert(in.end(), buf, buf + n);
  }
  ::close(fd);
  Bytes echo = {0x01, 0x10, 0x00, 0x00, 0x00, 0x02};
  append_crc16_modbus(echo);
  EXPECT_EQ(in, echo);
  EXPECT_TRUE(closed) << "the connection was not closed after the reply";
  EXPECT_THAT(sim_->control("state"), HasSubstr(" target=800 "));
  EXPECT_TRUE(
      eventually([&] { return (plc_->input(reg::status, 1).regs[0] & reg::running) != 0; }, 5s));
  EXPECT_THAT(log(), HasSubstr("command=run_forward: ok"));
  EXPECT_EQ(plc_->write(reg::command, {0}), 0);
}

// The PLC-loss failsafe (docs/safety.md) sees a serial master as it sees a TCP client: its
// heartbeats over the line keep a running drive running past the timeout, and when it falls
// silent the drive is stopped and the failsafe bit latches. Only reads (the TCP observer) do not
// feed it.
TEST_F(SerialListenerE2E, ASerialMastersWritesFeedTheFailsafeAndItsSilenceTripsIt) {
  start("access = \"operate\"\n", "poll_ms = 200\nfailsafe_timeout_ms = 1000\n");
  constexpr std::uint16_t kFailsafe = 1 << 5;
  // Run forward at 600, then a heartbeat every 300 ms for 2.4 s: more than twice the timeout.
  std::vector<std::string> steps = {"writes", "1", "0", "1,600"};
  for (int i = 1; i <= 8; ++i) {
    steps.insert(steps.end(),
                 {"sleep", "300", "write", "1", std::to_string(reg::heartbeat), std::to_string(i)});
  }
  const auto out = master(steps);
  ASSERT_EQ(out.size(), 9U) << ::testing::PrintToString(out);
  for (const auto& line : out) EXPECT_EQ(line, "ok");
  const auto state = sim_->control("state");
  EXPECT_THAT(state, HasSubstr(" target=600 "));
  EXPECT_THAT(state, HasSubstr(" running=1 ")) << "the failsafe fired while fed";
  EXPECT_EQ(plc_->input(reg::status, 1).regs[0] & kFailsafe, 0);
  // The master goes quiet: stopped within the timeout and a few polls, the bit latched.
  ASSERT_TRUE(eventually(
      [&] { return sim_->control("state").find(" running=0 ") != std::string::npos; }, 5s))
      << sim_->control("state");
  EXPECT_TRUE(
      eventually([&] { return (plc_->input(reg::status, 1).regs[0] & kFailsafe) != 0; }, 3s));
}

// The master's adapter unplugged and plugged back: the listener says so once, reopens the line
// with back-off, and serves the master again; the drive and the TCP side never noticed.
TEST_F(SerialListenerE2E, ALineUnpluggedAndBackIsReopenedAndLoggedOnce) {
  start("access = \"operate\"\n");
  ASSERT_THAT(master({"read", "1", "input", "0", "1"}), ElementsAre(::testing::StartsWith("ok ")));
  line_.reset();  // both ends of the pair go away
  ASSERT_TRUE(
      eventually([&] { return log().find("reopening (logged once") != std::string::npos; }, 5s))
      << log();
  std::this_thread::sleep_for(1500ms);  // several reopen attempts fail meanwhile
  EXPECT_EQ(occurrences(log(), "(logged once"), 1U) << log();
  EXPECT_NE(plc_->input(reg::status, 1).regs[0] & reg::online, 0);  // the drive never noticed
  make_line();
  ASSERT_TRUE(eventually([&] { return log().find("open again") != std::string::npos; }, 15s))
      << log();
  EXPECT_THAT(master({"read", "1", "input", "0", "1"}), ElementsAre(::testing::StartsWith("ok ")));
}

// SIGHUP with the listener's access changed to read: the next write over the line is 01, with the
// line left open (a policy, not a place: no restart needed).
TEST_F(SerialListenerE2E, AReloadAppliesTheNewAccessLevelAtOnce) {
  start("access = \"operate\"\n");
  const auto setpoint = std::to_string(reg::setpoint);
  ASSERT_THAT(master({"write", "1", setpoint, "300"}), ElementsAre("ok"));
  const auto at = toml_.find("access = \"operate\"\n", toml_.find("port = "));
  ASSERT_NE(at, std::string::npos);
  std::string next = toml_;
  next.replace(at, std::string("access = \"operate\"").size(), "access = \"read\"");
  std::ofstream(daemon_->config()) << next;
  daemon_->process().signal(SIGHUP);
  ASSERT_TRUE(
      eventually([&] { return log().find("configuration reloaded") != std::string::npos; }, 10s))
      << log();
  EXPECT_THAT(log(), Not(HasSubstr("takes effect at the next restart")));
  EXPECT_THAT(master({"write", "1", setpoint, "400", "read", "1", "holding", setpoint, "1"}),
              ElementsAre("exception 1", "ok 300"));
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs[0], 300);
}

// Serial listeners are named by their port wherever a listener is named: two of them with
// different access levels reload without a line about either while neither changed (their
// network addresses are all ":0", which once made every SIGHUP log "listener :0: access operate
// -> read"), and a change names the listener it is in. The register map names them the same way.
TEST_F(SerialListenerE2E, SerialListenersAreNamedByTheirPortInTheReloadLogAndTheRegisterMap) {
  if (!have_pymodbus_tools()) GTEST_SKIP() << "socat and python3-pymodbus: tools/deps.sh test";
  Child second({"/usr/bin/socat", "pty,raw,echo=0,link=" + (dir_ / "m2").string(),
                "pty,raw,echo=0,link=" + (dir_ / "s2").string()},
               dir_ / "socat2.err");
  for (int i = 0; i < 100 && !std::filesystem::exists(dir_ / "s2"); ++i) {
    std::this_thread::sleep_for(20ms);
  }
  const std::string s1 = "serial " + (dir_ / "s").string() + " (rtu)";
  const std::string s2 = "serial " + (dir_ / "s2").string() + " (rtu)";
  const int http_port = free_port();
  start("access = \"operate\"\n\n[[listener]]\nport = \"" + (dir_ / "s2").string() +
        "\"\nbaud = 19200\naccess = \"read\"\nword_order = \"little\"\n\n[http]\nlisten = "
        "\"127.0.0.1:" +
        std::to_string(http_port) + "\"\n");
  daemon_->process().signal(SIGHUP);
  ASSERT_TRUE(
      eventually([&] { return log().find("configuration reloaded") != std::string::npos; }, 10s))
      << log();
  EXPECT_THAT(log(), Not(HasSubstr("reload: listener"))) << "nothing changed";

  std::string next = toml_;
  next.replace(next.find("access = \"read\""), std::string("access = \"read\"").size(),
               "access = \"maintain\"");
  std::ofstream(daemon_->config()) << next;
  daemon_->process().signal(SIGHUP);
  ASSERT_TRUE(eventually([&] { return occurrences(log(), "configuration reloaded") == 2; }, 10s))
      << log();
  EXPECT_EQ(occurrences(log(), "reload: listener " + s2 + ": access read -> maintain"), 1u)
      << log();
  EXPECT_EQ(occurrences(log(), "reload: listener "), 1u) << log();

  // The register map, from the same file: each by its port, with its word order.
  Child regmap({(bin_dir() / "drivegate").string(), "regmap", "-c", daemon_->config().string(),
                "-f", "md", "-p", plugin_dir().string()},
               dir_ / "regmap.err");
  std::string md;
  while (auto line = regmap.read_line(10s)) md += *line + "\n";
  EXPECT_THAT(md, HasSubstr("- " + s1 + ": big: high word first (mbpoll -B)\n"));
  EXPECT_THAT(md, HasSubstr("- " + s2 + ": little: low word first (mbpoll without -B)\n"));
  EXPECT_THAT(md, Not(HasSubstr("- :0")));
  EXPECT_THAT(md, HasSubstr("| holding | 0 | 40001 | command | u16 | 1 |  | operate |"));
  // And the running daemon's /api/v1/regmap: the serial listeners with the TCP one.
  const std::string json = http_get(http_port, "/api/v1/regmap").body;
  EXPECT_THAT(json, HasSubstr("{\"address\": \"" + s1 + "\", \"word_order\": \"big\"}"));
  EXPECT_THAT(json, HasSubstr("{\"address\": \"" + s2 + "\", \"word_order\": \"little\"}"));
}

// A drive that went silent: over the line as over TCP, its status says comm_lost and a write to
// it is exception 0x0B (gateway target failed to respond), never an echo.
TEST_F(SerialListenerE2E, ASilentDrivesWriteIs0x0BOverTheLineToo) {
  start("access = \"operate\"\n");
  sim_->control("silent on");
  ASSERT_TRUE(
      eventually([&] { return (plc_->input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 10s));
  const auto setpoint = std::to_string(reg::setpoint);
  const auto out = master(
      {"write", "1", setpoint, "500", "read", "1", "input", std::to_string(reg::status), "1"});
  ASSERT_EQ(out.size(), 2U) << ::testing::PrintToString(out);
  EXPECT_EQ(out[0], "exception 11");
  const std::string tcp_status = std::to_string(plc_->input(reg::status, 1).regs[0]);
  EXPECT_EQ(out[1], "ok " + tcp_status);
}

// reply_timeout_ms, the master's response timeout: the drive goes silent under a run command, the
// master hears nothing within it and stops listening, and the write's 0x0B, which comes seconds
// later (the drive never answered: its write's deadline, 1.8 s), never
// reaches the line, where it would meet the master's next request. The master's next read is
// answered as ever.
TEST_F(SerialListenerE2E, AnAnswerPastTheMastersResponseTimeoutNeverReachesTheLine) {
  start("access = \"operate\"\nreply_timeout_ms = 200\n");
  sim_->control("silent on");
  static_assert(reg::command == 0);
  // The master listens on past the moment the 0x0B would come (1.8 s), with a wide margin.
  auto out = master({"rtu", "1", "0600000001",  // FC 06: command = run_forward
                     "listen", "6000"});
  ASSERT_EQ(out.size(), 2U) << ::testing::PrintToString(out);
  EXPECT_EQ(out[0], "reply ");  // nothing within 300 ms
  EXPECT_EQ(out[1], "heard ") << "a reply after the master's timeout reached the line";
  // The write's end, whenever the machine gets to it: the audit trail says what became of it.
  ASSERT_TRUE(eventually(
      [&] { return log().find(": command=run_forward: no response") != std::string::npos; }, 10s))
      << log();
  // The master's next requests are answered as ever; FC 08 counts the reply not sent.
  out = master({"read", "1", "input", std::to_string(reg::status), "1", "rtu", "1",
                "08000f0000"});  // FC 08: server no response count
  ASSERT_EQ(out.size(), 2U) << ::testing::PrintToString(out);
  EXPECT_THAT(out[0], ::testing::StartsWith("ok "));  // the status word, its CRC good
  EXPECT_THAT(out[1], ::testing::StartsWith("reply 0108000f0001"));  // the one dropped
  EXPECT_THAT(log(), HasSubstr("after the master's response timeout (reply_timeout_ms = 200); "
                               "that reply is dropped, never sent late"));
  EXPECT_EQ(plc_->holding(reg::command, 1).regs[0], 0);  // never in force
}

// A read listener on the line: a write is exception 01 and reaches no drive, reads are served.
TEST_F(SerialListenerE2E, AReadListenersMasterGetsException01ForAWrite) {
  start("access = \"read\"\n");
  const auto setpoint = std::to_string(reg::setpoint);
  const auto out = master({"write", "1", setpoint, "600", "read", "1", "holding", setpoint, "1"});
  ASSERT_EQ(out.size(), 2U) << ::testing::PrintToString(out);
  EXPECT_EQ(out[0], "exception 1");
  EXPECT_EQ(out[1], "ok 0");
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs[0], 0);
}

// ASCII framing (':', hex, LRC, CR LF) with pymodbus's ASCII framer. The line is 8 data bits
// here: Linux refuses 7 on a pseudo-terminal (EINVAL), where a real port takes the specification's
// default of 7 (Serial Line 2.5.2).
TEST_F(SerialListenerE2E, AnAsciiMasterReadsAndWrites) {
  start("framing = \"ascii\"\ndata_bits = 8\naccess = \"operate\"\n");
  const auto setpoint = std::to_string(reg::setpoint);
  const auto out = master({"write", "1", setpoint, "450", "read", "1", "holding", setpoint, "1",
                           "read", "1", "holding", "9000", "1"},
                          "ascii");
  ASSERT_EQ(out.size(), 3U) << ::testing::PrintToString(out) << slurp(dir_ / "master.err");
  EXPECT_EQ(out[0], "ok");
  EXPECT_EQ(out[1], "ok 450");
  EXPECT_EQ(out[2], "exception 2");
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs[0], 450);
}

}  // namespace
}  // namespace drivegate::test
