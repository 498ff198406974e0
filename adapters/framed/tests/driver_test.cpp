// The framed driver on the real bus engine, simulated time and a simulated line (bus_rig.h),
// against the C++ adapters' own simulators (loaded from the build's plugins): the same frames on
// the wire as the C++ driver for the same scenario, and what an attacker's line does to it
// (damaged, refused, foreign and late replies, noise floods, silence), asserted as a PLC reads
// the registers. And the sequence number a description may carry.
#include "driver.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <functional>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "description_parser.h"
#include "plugin/plugins.h"
#include "protocol_fixture.h"

namespace drivegate::framed {
namespace {

using namespace std::chrono_literals;
using drivegate::test::BusRig;
using drivegate::test::OptionText;

// The C++ adapters, from the build's plugins.
const PluginRegistry& native() {
  static const PluginRegistry plugins = [] {
    PluginRegistry r;
    for (const char* id : {"nidec-washer", "mdriver-2400", "fdc1"}) {
      const std::string why =
          r.load_file(std::string(DRIVEGATE_BUILD_PLUGIN_DIR) + "/drivegate-" + id + ".so");
      EXPECT_TRUE(why.empty()) << why;
    }
    return r;
  }();
  return plugins;
}

const AdapterDescriptor& described(const std::string& protocol) {
  Options o;
  o.set("protocol", protocol);
  std::string error;
  const AdapterDescriptor* a = drivegate_adapter.specialise(o, error);
  EXPECT_NE(a, nullptr) << error;
  return *a;
}

// One device on a rig: framed's (or the C++ adapter's) driver, the C++ adapter's simulator.
struct Drive {
  Drive(const AdapterDescriptor& device, const std::string& id, const OptionText& options,
        const OptionText& sim_options, Millis poll = 500ms)
      : rig(device) {
    DeviceConfig dc = rig.device_config("drive", device.default_address, options);
    dc.poll_interval = poll;
    d = &rig.add_device(dc);
    const AdapterDescriptor& sim_adapter = *native().find(id);
    SimEnv env;
    env.address = sim_adapter.default_address;
    env.options = drivegate::test::options_of(sim_adapter, sim_options);
    std::string why;
    auto sim = sim_adapter.create_simulator(env, why);
    EXPECT_NE(sim, nullptr) << why;
    rig.add_simulator(std::move(sim));
    rig.start();
  }
  bool online(Millis limit = 5s) {
    return rig.run_until([&] { return (rig.value(*d, "status") & 1u) != 0; }, limit);
  }
  std::optional<Outcome> write(std::vector<std::uint16_t> values, std::uint16_t address = 0) {
    return rig.write_and_wait(*d, drivegate::Table::holding, address, std::move(values), 6s);
  }
  std::string sim(const std::string& line) { return rig.simulator().control(line, rig.now()); }
  std::uint32_t reg(std::string_view point) { return rig.value(*d, point); }
  // The frames the master sent, consecutive repeats (polls, resends) told once.
  std::vector<Bytes> distinct_frames() const {
    std::vector<Bytes> out;
    for (const auto& f : rig.sent()) {
      if (out.empty() || out.back() != f.bytes) out.push_back(f.bytes);
    }
    return out;
  }
  BusRig rig;
  Device* d = nullptr;
};

// ---- the same frames as the C++ driver --------------------------------------------------------

// A scenario a PLC plays: online, run at `rpm`, a speed change, a stop.
std::vector<Bytes> play(Drive& drive, std::uint16_t rpm, std::uint16_t then) {
  EXPECT_TRUE(drive.online());
  EXPECT_EQ(drive.write({1, rpm}), Outcome::ok);
  drive.rig.run_for(2s);
  EXPECT_EQ(drive.write({then}, 1), Outcome::ok);
  drive.rig.run_for(2s);
  EXPECT_EQ(drive.write({0}), Outcome::ok);
  drive.rig.run_for(2s);
  return drive.distinct_frames();
}

TEST(FramedDriver, NidecSendsTheCppDriversFramesForTheSameScenario) {
  const OptionText opts = {{"platform", "8"}};
  Drive cpp(*native().find("nidec-washer"), "nidec-washer", opts, opts);
  OptionText framed_opts = {{"protocol", "nidec-washer"}, {"platform", "8"}};
  Drive fr(described("nidec-washer"), "nidec-washer", framed_opts, opts);
  const auto want = play(cpp, 800, 600);
  const auto got = play(fr, 800, 600);
  EXPECT_EQ(got, want);
  ASSERT_GE(want.size(), 6u);  // ping, polls, CW 800, CW 600, stop
  EXPECT_EQ(want[0], test::hex("A5 02 08 00 00 00 00 00 00 00 AF"));
  EXPECT_EQ(fr.reg("speed_rpm"), 0u);
}

TEST(FramedDriver, MdriverSendsTheCppDriversFramesForTheSameScenario) {
  Drive cpp(*native().find("mdriver-2400"), "mdriver-2400", {}, {});
  Drive fr(described("mdriver-2400"), "mdriver-2400", {{"protocol", "mdriver-2400"}}, {});
  const auto want = play(cpp, 1149, 504);
  const auto got = play(fr, 1149, 504);
  EXPECT_EQ(got, want);
  EXPECT_EQ(want.front(), test::hex("00 01 00 03 01 12 00 06 38"));  // the fixed-code check
}

TEST(FramedDriver, Fdc1SendsTheCppDriversFramesForTheSameScenario) {
  const OptionText opts = {{"slave_mode", "true"}, {"refresh_s", "1"}};
  const OptionText sim = {{"slave_mode", "true"}};
  Drive cpp(*native().find("fdc1"), "fdc1", opts, sim);
  OptionText framed_opts = {{"protocol", "fdc1"}};
  framed_opts.insert(framed_opts.end(), opts.begin(), opts.end());
  Drive fr(described("fdc1"), "fdc1", framed_opts, sim);
  const auto want = play(cpp, 2000, 2500);
  const auto got = play(fr, 2000, 2500);
  EXPECT_EQ(got, want);
}

// ---- an attacker's line -----------------------------------------------------------------------

// Both drivers, so that an attack is known to cost framed what it costs the C++ adapter.
class NidecUnderAttack : public ::testing::TestWithParam<bool> {
 protected:
  NidecUnderAttack()
      : drive(GetParam() ? described("nidec-washer") : *native().find("nidec-washer"),
              "nidec-washer",
              GetParam() ? OptionText{{"protocol", "nidec-washer"}, {"platform", "8"}}
                         : OptionText{{"platform", "8"}},
              {{"platform", "8"}}) {}
  Drive drive;
};

TEST_P(NidecUnderAttack, EveryOtherReplyDamagedCostsResendsNotTheDrive) {
  ASSERT_TRUE(drive.online());
  int n = 0;
  drive.rig.line().device_filter = [&](Bytes b) {
    if (++n % 2 == 0 && !b.empty()) b.back() ^= 0x5A;
    return b;
  };
  EXPECT_EQ(drive.write({1, 800}), Outcome::ok);
  drive.rig.run_for(5s);
  EXPECT_GT(drive.reg("bad_checksum"), 3u);
  EXPECT_GT(drive.reg("retries"), 3u);
  EXPECT_EQ(drive.reg("status") & 0x11u, 0x01u);  // online, not comm_lost
  EXPECT_EQ(drive.reg("speed_rpm"), 800u);
  EXPECT_EQ(drive.reg("command"), 1u);
}

TEST_P(NidecUnderAttack, NacksAreResentAndAStaleAckIsForeign) {
  ASSERT_TRUE(drive.online());
  EXPECT_THAT(drive.sim("nack 2"), ::testing::HasSubstr("ok"));
  EXPECT_EQ(drive.write({1, 800}), Outcome::ok);
  EXPECT_GE(drive.reg("nacks"), 2u);
  // A stop ACK before every reply: the answer to no frame in flight, dropped, the wait goes on.
  drive.rig.line().device_filter = [](Bytes b) {
    Bytes stale = test::hex("A5 27 00 00 00 00 82");
    stale.insert(stale.end(), b.begin(), b.end());
    return stale;
  };
  drive.rig.run_for(3s);
  EXPECT_GT(drive.reg("foreign_frames"), 2u);
  EXPECT_EQ(drive.reg("command"), 1u);  // the stale stop ACK stopped nothing
  EXPECT_EQ(drive.reg("status") & 0x11u, 0x01u);
}

TEST_P(NidecUnderAttack, NoiseBeforeEveryReplyLosesNothing) {
  ASSERT_TRUE(drive.online());
  drive.rig.line().device_filter = [](Bytes b) {
    // Header bytes that start no frame (A5 A5 is no mode of V07), as many as the 100 ms reply
    // timeout leaves room for. None after it: on a one-wire line that would meet the next echo.
    Bytes noisy(25, 0xA5);
    noisy.insert(noisy.end(), b.begin(), b.end());
    return noisy;
  };
  EXPECT_EQ(drive.write({1, 700}), Outcome::ok);
  drive.rig.run_for(5s);  // past the 3 s ramp
  EXPECT_EQ(drive.reg("speed_rpm"), 700u);
  EXPECT_EQ(drive.reg("status") & 0x11u, 0x01u);
  EXPECT_EQ(drive.reg("timeouts"), 0u);
}

TEST_P(NidecUnderAttack, SilenceIsCommLostWritesAre0x0BAndItComesBack) {
  ASSERT_TRUE(drive.online());
  EXPECT_EQ(drive.write({1, 800}), Outcome::ok);
  drive.rig.line().device_filter = [](Bytes) { return Bytes{}; };
  drive.rig.run_for(6500ms);
  EXPECT_NE(drive.reg("status") & 0x10u, 0u);  // comm_lost
  EXPECT_EQ(drive.reg("command"), 0u);         // section 7: the inverter stopped by itself
  EXPECT_EQ(drive.write({1, 800}), Outcome::no_response);
  drive.rig.line().device_filter = nullptr;
  ASSERT_TRUE(drive.online(10s));  // probed, pinged again, back
  EXPECT_EQ(drive.write({1, 500}), Outcome::ok);
}

TEST_P(NidecUnderAttack, ARequestWithOnePartItCannotTakeChangesNothing) {
  ASSERT_TRUE(drive.online());
  const std::size_t sent = drive.rig.sent().size();
  // Reverse with spin (motion 1): no reverse; the setpoint before it is not stored either.
  EXPECT_EQ(drive.write({1}, drive.rig.devices()[0]->map().find("motion")->address), Outcome::ok);
  EXPECT_EQ(drive.write({2, 1234}), Outcome::invalid_value);
  EXPECT_EQ(drive.reg("setpoint_rpm"), 0u);
  EXPECT_EQ(drive.reg("command"), 0u);
  drive.rig.run_for(100ms);
  for (std::size_t i = sent; i < drive.rig.sent().size(); ++i) {
    EXPECT_EQ(drive.rig.sent()[i].bytes[1], 0x05) << "only polls went out";
  }
}

INSTANTIATE_TEST_SUITE_P(, NidecUnderAttack, ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& i) {
                           return i.param ? "Framed" : "Native";
                         });

// ---- a sequence number ------------------------------------------------------------------------

TEST(FramedSequence, EveryRequestCarriesTheNextAndOnlyItsOwnReplyAnswers) {
  auto parsed = parse_description(R"([protocol]
name = "seq"
summary = "a drive numbering its frames"
document = "t"
[line]
baud = 9600
[check.x]
kind = "xor"
[[message]]
name = "read"
direction = "request"
layout = "52 seq:u8 x:x"
values = { seq = "sequence" }
replies = ["status"]
[[message]]
name = "status"
direction = "reply"
layout = "53 seq:u8 temperature:u8 x:x"
echo = ["seq"]
[[point]]
name = "temperature"
table = "input"
type = "u16"
description = "t"
[poll]
send = "read"
)",
                                  "seq.toml");
  ASSERT_TRUE(std::holds_alternative<std::shared_ptr<const Description>>(parsed));
  const auto d = std::get<std::shared_ptr<const Description>>(parsed);
  DeviceEnv env;
  env.poll_interval = 100ms;
  FramedDriver driver(d, env);
  TimePoint now{};
  auto ex = driver.next_exchange(now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, test::hex("52 01 53"));
  // The reply to another request (a late one): foreign. Its own: the reply.
  EXPECT_EQ(driver.on_receive(test::hex("53 00 15 46"), now).kind, RxKind::foreign);
  EXPECT_EQ(driver.on_receive(test::hex("53 01 15 47"), now).kind, RxKind::reply);
  EXPECT_EQ(std::get<std::int64_t>(driver.values()[0]), 0x15);
  now += 100ms;
  ex = driver.next_exchange(now);
  ASSERT_TRUE(ex.has_value());
  EXPECT_EQ(ex->frame, test::hex("52 02 50"));
}

}  // namespace
}  // namespace drivegate::framed
