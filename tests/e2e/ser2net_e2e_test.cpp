// Buses behind a serial device server, end to end: Debian's ser2net bridges TCP ports on
// 127.0.0.1 to simulated drives' pseudo-terminals (tests/support/ser2net.h), and drivegated
// reaches them through `tcp://` and `rfc2217://` buses with no change to any adapter. The polled
// drive is the tests' own (test-drive, tests/support/test_adapter); the streaming one is fdc1, the
// only adapter whose device streams (skipped where it is not built). Shown here:
// - a polled drive and a streaming one behind ser2net read the same registers as the same
//   simulator on a local pty, in one daemon, and writes reach the drive behind it;
// - ser2net killed: the device is comm_lost and writes get 0x0B; ser2net back on the same port:
//   the bus reconnects by itself;
// - RFC 2217: drivegate sets the line settings on the server's device, and frames holding 0xFF
//   (doubled in Telnet) cross both ways.
#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <termios.h>

#include <map>

#include "e2e.h"
#include "ser2net.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using ::testing::AnyOf;
using ::testing::Contains;
using ::testing::HasSubstr;

// The adapters' points after the common block (`drivegate regmap`).
namespace td {
inline constexpr int drive_state = 32, points_end = 33;  // input: the state byte, bit 0 running
inline constexpr int accel_time = 16;                    // holding, 0.1 s
inline constexpr std::uint16_t kStall = 2;  // native_fault, input 4..5 (test_adapter/codec.h)
}  // namespace td
namespace fdc1 {
inline constexpr int points_end = 38;  // motor_on 32, current_a 33 (mA) .. sent_speed_rpm 37
}  // namespace fdc1
inline constexpr int bus_reopens = 27;  // u32, common block
inline constexpr std::uint16_t kCommLost = 1;

std::string read_file(const std::filesystem::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
std::string bus(const std::string& name, const std::string& port, const std::string& extra = "") {
  return "[[bus]]\nname = \"" + name + "\"\nport = \"" + port + "\"\n" + extra + "\n";
}
// The test drive at address 31 (9600 8N1, test_adapter/README.md).
std::string td_device(const std::string& name, const std::string& on, int unit) {
  return "[[device]]\nname = \"" + name + "\"\nbus = \"" + on +
         "\"\nadapter = \"test-drive\"\nunit_id = " + std::to_string(unit) + "\naddress = 31\n\n";
}
std::string fdc1_device(const std::string& name, const std::string& on, int unit) {
  return "[[device]]\nname = \"" + name + "\"\nbus = \"" + on +
         "\"\nadapter = \"fdc1\"\nunit_id = " + std::to_string(unit) +
         "\n[device.options]\nslave_mode = true\n\n";
}
std::string tcp(int port) {
  return "tcp://127.0.0.1:" + std::to_string(port);
}

// What a PLC reads of a device that does not depend on the line it is on: the common block's
// status, faults and speed (not data_age and the counters, 7..30), the adapter's input points and
// the holding registers given as {address, count}. An exception is a value too.
using Values = std::map<std::string, std::uint16_t>;
Values values(Plc& plc, int points_end, const std::vector<std::pair<int, int>>& holding) {
  Values v;
  const auto put = [&v](const std::string& table, int at, const Plc::Read& r) {
    if (!r.ok()) {
      v[table + std::to_string(at) + " exception"] = static_cast<std::uint16_t>(r.exception);
      return;
    }
    for (std::size_t i = 0; i < r.regs.size(); ++i) {
      v[table + std::to_string(at + static_cast<int>(i))] = r.regs[i];
    }
  };
  put("input ", reg::status, plc.input(reg::status, reg::data_age));
  put("input ", 32, plc.input(32, points_end - 32));
  for (const auto& [at, n] : holding) put("holding ", at, plc.holding(at, n));
  return v;
}
std::string differences(const Values& near, const Values& far) {
  std::ostringstream out;
  for (const auto& [key, value] : near) {
    const auto it = far.find(key);
    if (it == far.end()) {
      out << key << ": " << value << " on the pty, missing behind ser2net\n";
    } else if (it->second != value) {
      out << key << ": " << value << " on the pty, " << it->second << " behind ser2net\n";
    }
  }
  for (const auto& [key, value] : far) {
    if (!near.contains(key)) out << key << ": " << value << " behind ser2net only\n";
  }
  return out.str();
}
Values td_values(Plc& plc) {
  return values(plc, td::points_end, {{reg::command, 3}, {td::accel_time, 1}});
}
Values fdc1_values(Plc& plc) {
  return values(plc, fdc1::points_end, {{reg::command, 3}});
}

// The line settings of a tty as `stty -a` names them ("speed 19200", "parodd", "-cstopb", "cs8").
std::vector<std::string> stty(const std::filesystem::path& tty) {
  const int fd = ::open(tty.c_str(), O_RDONLY | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  termios t{};
  const bool ok = fd >= 0 && ::tcgetattr(fd, &t) == 0;
  if (fd >= 0) ::close(fd);
  if (!ok) return {"cannot read " + tty.string()};
  const auto flag = [&t](tcflag_t bit, const char* name) {
    return std::string((t.c_cflag & bit) != 0 ? "" : "-") + name;
  };
  std::string speed = "other";
  using Speed = std::pair<speed_t, const char*>;
  for (const auto& [code, name] : {Speed{B1200, "1200"}, Speed{B9600, "9600"},
                                   Speed{B19200, "19200"}, Speed{B38400, "38400"}}) {
    if (::cfgetospeed(&t) == code) speed = name;
  }
  return {"speed " + speed,
          flag(PARENB, "parenb"),
          flag(PARODD, "parodd"),
          flag(CMSPAR, "cmspar"),
          (t.c_cflag & CSIZE) == CS8 ? "cs8" : "not cs8",
          flag(CSTOPB, "cstopb")};
}

bool online(Plc& plc) {
  const auto r = plc.input(reg::status, 1);
  return r.ok() && (r.regs[0] & reg::online) != 0;
}
std::int16_t speed(Plc& plc) {
  return static_cast<std::int16_t>(plc.input(reg::speed, 1).regs[0]);
}

// Two test drives at their simulator's defaults in one daemon: "near" on a local pty (unit 1),
// "far" on the same kind of pty behind ser2net, reached over raw TCP (unit 2).
class Ser2netTestDrive : public ::testing::Test {
 protected:
  Ser2netTestDrive()
      : near_sim_("test-drive", dir_ / "near", {"--address", "31"}),
        far_sim_("test-drive", dir_ / "far", {"--address", "31"}),
        ser2net_(dir_, {{.port = port_, .device = dir_ / "far", .settings = "9600n81"}}),
        daemon_(dir_,
                bus("near", (dir_ / "near").string()) + td_device("near", "near", 1) +
                    bus("far", tcp(port_), "network_delay_ms = 20\nreopen_max_ms = 1000\n") +
                    td_device("far", "far", 2),
                {}, dir_ / "drivegated.log") {}
  void SetUp() override {
    ASSERT_TRUE(near_.connect());
    ASSERT_TRUE(far_.connect());
    ASSERT_TRUE(eventually([&] { return online(near_) && online(far_); }, 10s))
        << "never online; far sim says " << far_sim_.control("state") << "\ndaemon log:\n"
        << log();
  }
  std::string log() { return read_file(dir_ / "drivegated.log"); }
  std::string far_port() { return "127.0.0.1:" + std::to_string(port_); }
  void run_far_at_1270() {
    ASSERT_EQ(far_.write(reg::setpoint, {1270}), 0);
    ASSERT_EQ(far_.write(reg::command, {1 /*run_forward*/}), 0);
    ASSERT_TRUE(eventually([&] { return speed(far_) == 1270; }, 10s)) << far_sim_.control("state");
  }

  TempDir dir_;
  int port_ = free_port();
  Sim near_sim_;
  Sim far_sim_;
  Ser2net ser2net_;
  Daemon daemon_;
  Plc near_{daemon_.port(), 1};
  Plc far_{daemon_.port(), 2};
};

TEST_F(Ser2netTestDrive, RawTcpReadsWhatTheLocalPtyReadsAndWritesReachTheDrive) {
  // Polled through: a fault raised on both drives reads the same on both, then its clearing.
  for (Sim* sim : {&near_sim_, &far_sim_}) ASSERT_EQ(sim->control("fault stall"), "ok fault=stall");
  Values near;
  Values far;
  ASSERT_TRUE(eventually(
      [&] {
        near = td_values(near_);
        far = td_values(far_);
        return near == far && far["input 5"] == td::kStall;
      },
      5s))
      << differences(near, far) << "far native_fault " << far["input 5"];
  EXPECT_TRUE(far["input 0"] & reg::fault);
  for (Sim* sim : {&near_sim_, &far_sim_}) ASSERT_EQ(sim->control("clear"), "ok");
  ASSERT_TRUE(eventually(
      [&] {
        near = td_values(near_);
        far = td_values(far_);
        return near == far && far["input 5"] == 0;
      },
      5s))
      << differences(near, far) << "far native_fault " << far["input 5"];
  EXPECT_EQ(far["input 0"] & (reg::online | reg::fault | reg::comm_lost), reg::online);
  EXPECT_EQ(far["input 32"], 0);     // drive_state: stopped
  EXPECT_EQ(far["holding 16"], 15);  // accel_time: the factory 1.5 s
  const auto counters = far_.input(reg::status, 31);
  ASSERT_TRUE(counters.ok());
  EXPECT_GT(counters.u32(reg::frames_good), 0u);
  EXPECT_EQ(counters.u32(reg::bad_checksum), 0u);
  EXPECT_LT(counters.u32(reg::data_age), 1500u);
  EXPECT_THAT(log(), HasSubstr("bus far: tcp " + far_port() + " open (network_delay 20 ms)"));

  // A run order through Modbus reaches the drive behind ser2net, and only that one.
  run_far_at_1270();
  EXPECT_THAT(far_sim_.control("state"), HasSubstr("running=1"));
  EXPECT_THAT(far_sim_.control("state"), HasSubstr(" target=1270 "));
  EXPECT_EQ(far_.input(td::drive_state, 1).regs[0], 1);  // running, forward
  EXPECT_TRUE(far_.input(reg::status, 1).regs[0] & reg::running);
  EXPECT_EQ(far_.holding(reg::command, 2).regs, (std::vector<std::uint16_t>{1, 1270}));
  EXPECT_THAT(near_sim_.control("state"), HasSubstr("running=0"));
  EXPECT_EQ(speed(near_), 0);
  // A setting written, in force once the drive answered, and read back.
  ASSERT_EQ(far_.write(td::accel_time, {30}), 0);  // 3.0 s
  EXPECT_THAT(far_sim_.control("state"), HasSubstr(" accel=30 "));
  EXPECT_EQ(far_.holding(td::accel_time, 1).regs[0], 30);
  EXPECT_THAT(near_sim_.control("state"), HasSubstr(" accel=15 "));
}

TEST_F(Ser2netTestDrive, KilledServerIsCommLostAndTheBusReconnectsWhenItIsBack) {
  run_far_at_1270();
  ser2net_.kill();
  const auto killed_at = std::chrono::steady_clock::now();
  ASSERT_TRUE(
      eventually([&] { return (far_.input(reg::status, 1).regs[0] & reg::comm_lost) != 0; }, 8s))
      << log();
  EXPECT_LT(std::chrono::steady_clock::now() - killed_at, 5s);  // comm_timeout_ms 3000
  auto r = far_.input(reg::status, 2);
  EXPECT_FALSE(r.regs[0] & reg::online);
  EXPECT_EQ(r.regs[reg::fault_code], kCommLost);
  EXPECT_EQ(far_.write(reg::command, {0}), 0x0B);
  EXPECT_EQ(far_.write(td::accel_time, {30}), 0x0B);
  EXPECT_TRUE(online(near_));  // the local bus is not concerned
  // A killed ser2net closes with FIN, or with RST when a request of ours was still unread in its
  // socket (RFC 1122 4.2.2.13): both say the server went away, each in its own words.
  const auto reopening = ": closing tcp " + far_port() + " and reopening";
  EXPECT_THAT(log(), AnyOf(HasSubstr("bus far: the server closed the connection" + reopening),
                           HasSubstr("bus far: read: Connection reset by peer" + reopening)));

  // Back on the same port: the bus finds it by itself (reopen_max_ms 1000).
  ser2net_.start();
  const auto back_at = std::chrono::steady_clock::now();
  ASSERT_TRUE(eventually([&] { return online(far_); }, 10s)) << log();
  RecordProperty("online_after_restart_ms",
                 static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(
                                      std::chrono::steady_clock::now() - back_at)
                                      .count()));
  EXPECT_LT(std::chrono::steady_clock::now() - back_at, 4s);
  r = far_.input(reg::status, 31);
  EXPECT_EQ(r.regs[reg::fault_code], 0);
  EXPECT_GE(r.u32(bus_reopens), 1u);
  EXPECT_EQ(occurrences(log(), "bus far: tcp " + far_port() + " open"), 2u) << log();
  // The drive ran on meanwhile; it reads so again, and orders reach it.
  EXPECT_TRUE(eventually([&] { return speed(far_) == 1270; }, 5s)) << far_sim_.control("state");
  ASSERT_EQ(far_.write(reg::command, {0 /*stop*/}), 0);
  EXPECT_THAT(far_sim_.control("state"), HasSubstr(" target=0 "));
  EXPECT_TRUE(eventually([&] { return speed(far_) == 0; }, 10s));
}

// Two FDC1 controllers (streaming, 1200 8N1) in slave mode: "near" on a local pty (unit 1), "far"
// behind ser2net over raw TCP (unit 2). A device that streams unasked is fdc1's alone: the test
// drive is polled, so this one runs where fdc1 is built.
class Ser2netFdc1 : public ::testing::Test {
 protected:
  void SetUp() override {
    REQUIRE_ADAPTER("fdc1");
    near_sim_ = std::make_unique<Sim>("fdc1", dir_ / "near",
                                      std::vector<std::string>{"--set", "slave_mode=true"});
    far_sim_ = std::make_unique<Sim>("fdc1", dir_ / "far",
                                     std::vector<std::string>{"--set", "slave_mode=true"});
    ser2net_ = std::make_unique<Ser2net>(
        dir_,
        std::vector<Ser2netPort>{{.port = port_, .device = dir_ / "far", .settings = "1200n81"}});
    daemon_ = std::make_unique<Daemon>(
        dir_,
        bus("near", (dir_ / "near").string()) + fdc1_device("near", "near", 1) +
            bus("far", tcp(port_), "network_delay_ms = 20\n") + fdc1_device("far", "far", 2),
        std::vector<std::string>{}, dir_ / "drivegated.log");
    near_ = std::make_unique<Plc>(daemon_->port(), 1);
    far_ = std::make_unique<Plc>(daemon_->port(), 2);
    ASSERT_TRUE(near_->connect());
    ASSERT_TRUE(far_->connect());
    ASSERT_TRUE(eventually([&] { return online(*near_) && online(*far_); }, 10s))
        << "never online; far sim says " << far_sim_->control("state") << "\ndaemon log:\n"
        << read_file(dir_ / "drivegated.log");
  }

  TempDir dir_;
  int port_ = free_port();
  std::unique_ptr<Sim> near_sim_;
  std::unique_ptr<Sim> far_sim_;
  std::unique_ptr<Ser2net> ser2net_;
  std::unique_ptr<Daemon> daemon_;
  std::unique_ptr<Plc> near_;
  std::unique_ptr<Plc> far_;
};

TEST_F(Ser2netFdc1, TheStreamOverRawTcpReadsAsOnTheLocalPty) {
  Values near;
  Values far;
  ASSERT_TRUE(eventually([&] {
    return (near = fdc1_values(*near_)) == (far = fdc1_values(*far_));
  })) << differences(near, far);
  EXPECT_EQ(far["input 0"] & (reg::online | reg::running | reg::comm_lost), reg::online);
  EXPECT_EQ(far["input 32"], 0);  // motor off

  for (Plc* plc : {near_.get(), far_.get()}) ASSERT_EQ(plc->write(reg::command, {1, 2000}), 0);
  ASSERT_TRUE(eventually([&] { return speed(*near_) == 2000 && speed(*far_) == 2000; }, 10s))
      << far_sim_->control("state");
  ASSERT_TRUE(eventually([&] {
    return (near = fdc1_values(*near_)) == (far = fdc1_values(*far_));
  })) << differences(near, far);
  EXPECT_TRUE(far["input 0"] & reg::running);
  EXPECT_EQ(far["input 32"], 1);     // motor on
  EXPECT_EQ(far["input 33"], 2400);  // 2000 rpm x 0.0012 A/rpm, in mA
  EXPECT_EQ(far["input 37"], 2000);  // the speed programmed over the line
  EXPECT_THAT(far_sim_->control("state"), HasSubstr("motor=on rpm=2000"));
  const auto counters = far_->input(reg::status, 31);
  EXPECT_LT(counters.u32(reg::data_age), 1500u);  // streamed every 500 ms
  EXPECT_GT(counters.u32(reg::frames_good), 0u);
  EXPECT_THAT(read_file(dir_ / "drivegated.log"),
              HasSubstr("bus far: tcp 127.0.0.1:" + std::to_string(port_) + " open"));
}

// RFC 2217: ser2net opens the device at 9600 8N2; the bus asks 19200 8O1. A pty keeps speed,
// PARODD and CSTOPB (it forces CS8 and clears PARENB), so each setting seen on it differs from
// ser2net's own. A run in reverse at 255 rpm holds 0xFF in its request, and every reply while it
// turns holds 0xFF (its speed, -255), which ser2net sends doubled both ways.
TEST(Ser2netRfc2217, DrivegateSetsTheLineAndFramesWith0xFFCrossBothWays) {
  TempDir dir;
  const int port = free_port();
  Sim sim("test-drive", dir / "drive", {"--address", "31"});
  Ser2net ser2net(
      dir, {{.port = port, .device = dir / "drive", .settings = "9600n82", .rfc2217 = true}});

  // A client that negotiates nothing gets the connector's settings.
  {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
    std::vector<std::string> line;
    EXPECT_TRUE(eventually([&] {
      line = stty(dir / "drive");
      return line[0] == "speed 9600";
    })) << ::testing::PrintToString(line);
    EXPECT_THAT(line, Contains("-parodd"));
    EXPECT_THAT(line, Contains("cstopb"));
    ::close(fd);
  }

  Daemon daemon(dir,
                bus("far", "rfc2217://127.0.0.1:" + std::to_string(port),
                    "baud = 19200\nparity = \"odd\"\ndata_bits = 8\nstop_bits = 1\n"
                    "network_delay_ms = 20\n") +
                    td_device("drive", "far", 1),
                {}, dir / "drivegated.log");
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return online(plc); }, 10s))
      << "never online; sim says " << sim.control("state") << "\ndaemon log:\n"
      << read_file(dir / "drivegated.log") << "ser2net log:\n"
      << ser2net.log();
  const auto line = stty(dir / "drive");
  EXPECT_THAT(line, Contains("speed 19200"));
  EXPECT_THAT(line, Contains("parodd"));  // odd, not mark
  EXPECT_THAT(line, Contains("-cmspar"));
  EXPECT_THAT(line, Contains("-cstopb"));  // data bits: a pty is cs8 whatever is asked
  EXPECT_THAT(read_file(dir / "drivegated.log"),
              HasSubstr("bus far: rfc2217 127.0.0.1:" + std::to_string(port) +
                        " (set to 19200 8O1) open (network_delay 20 ms)"));

  // To the drive: "3C 1F 03 00 FF A3" (run_reverse, 255 rpm); from it, once at speed,
  // "3E 1F 01 03 00 FF 01 9F" (read: running in reverse, -255 rpm).
  ASSERT_EQ(plc.write(reg::command, {2 /*run_reverse*/, 255}), 0);
  EXPECT_THAT(sim.control("state"), HasSubstr(" target=-255 "));
  ASSERT_TRUE(eventually([&] { return speed(plc) == -255; }, 5s)) << sim.control("state");
  EXPECT_EQ(plc.input(td::drive_state, 1).regs[0], 3);  // running, reverse
  const auto frames_at_speed = plc.input(reg::status, 31).u32(reg::frames_good);
  EXPECT_TRUE(eventually(
      [&] { return plc.input(reg::status, 31).u32(reg::frames_good) > frames_at_speed + 2; }));
  EXPECT_EQ(speed(plc), -255);
  const auto counters = plc.input(reg::status, 31);
  EXPECT_EQ(counters.u32(reg::bad_checksum), 0u);
  EXPECT_EQ(counters.regs[reg::fault_code], 0);
  EXPECT_EQ(plc.holding(reg::command, 2).regs, (std::vector<std::uint16_t>{2, 255}));
}

}  // namespace
}  // namespace drivegate::test
