// An option the engineer must set ([options.NAME] with `example` and no `default`): read from the
// profile, refused with the option's description when a device leaves it out (in the daemon's
// own configuration errors, naming the device's line), used when a device sets it (the bytes on
// the wire follow the device's value, not the example), and its example taken by the simulator.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <boost/asio/io_context.hpp>

#include "adapter_under_test.h"
#include "bus_rig.h"
#include "config/config_loader.h"
#include "gateway/gateway.h"
#include "plugin/adapter_options.h"
#include "profile_options.h"
#include "profile_support.h"

namespace drivegate::modbus_device::modbus_required_option_test {
namespace {

using namespace std::chrono_literals;
using namespace support;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr std::uint8_t kSlave = 7;

// The drive in % of its maximum frequency (support::kPercentProfile: 16384 = 100 %, rpm = % x
// max_frequency_hz x 120 / motor_poles / 100), but the maximum frequency's factory value is not
// cited, so it is required.
const std::string kProfile = support::replaced(
    support::replaced(kPercentProfile, "name = \"pct-drive\"", "name = \"req-drive\""),
    "[options.max_frequency_hz]\ndefault = 50\nmin = 10\nmax = 400\ndescription = \"maximum "
    "frequency\"\n",
    "[options.max_frequency_hz]\nmin = 1\nmax = 400\nexample = 50\nunit = \"Hz\"\n"
    "description = \"maximum frequency P105 of the active parameter set: set it to the drive's "
    "P105\"\n");

// kProfile with `from` replaced by `to`.
std::string with(const std::string& from, const std::string& to) {
  return support::replaced(kProfile, from, to);
}

Bytes fc06(std::uint16_t address, std::uint16_t value) {
  return support::fc06_frame(kSlave, address, value);
}

TEST(RequiredOption, IsReadWithItsExampleAndShownRequired) {
  const Profile p = parsed(kProfile);
  const ProfileOption& max = p.options[*p.find_option("max_frequency_hz")];
  EXPECT_TRUE(max.required);
  EXPECT_EQ(max.value, 50);
  EXPECT_FALSE(p.options[*p.find_option("motor_poles")].required);
  EXPECT_EQ(options_text(p), "max_frequency_hz = 50 (required), motor_poles = 4 (default)");
}

TEST(RequiredOption, DefaultAndExampleTogetherOrNeitherAreErrorsOnTheirLines) {
  expect_refused(errors_of,
                 {{with("example = 50\n", "example = 50\ndefault = 50\n"),
                   {"p.toml:13: options.max_frequency_hz.example: and default together"}},
                  {with("example = 50\n", ""),
                   {"p.toml:10: options.max_frequency_hz: needs a default (the drive's factory "
                    "value, cited) or an example"}},
                  {with("example = 50\n", "example = 500\n"),
                   {"options.max_frequency_hz.example: must be in min..max (1..400)"}},
                  {with("example = 50\n", "example = \"50\"\n"),
                   {"options.max_frequency_hz.example: must be a number"}}});
}

TEST(RequiredOption, ADeviceThatLeavesItOutIsRefusedNamingItAndItsDescription) {
  Profile p = parsed(kProfile);
  std::string error;
  EXPECT_FALSE(apply_options(p, Options{}, error));
  EXPECT_EQ(error,
            "option max_frequency_hz is required and not set: maximum frequency P105 of the "
            "active parameter set: set it to the drive's P105 [Hz] (1..400; set it in "
            "[device.options])");
  // The simulator takes the example.
  Profile sim = parsed(kProfile);
  EXPECT_TRUE(apply_options(sim, Options{}, error, Unset::example)) << error;
  EXPECT_EQ(sim.options[*sim.find_option("max_frequency_hz")].value, 50);
  // The device schema's "not set" is not set; a value out of range is refused with the range.
  Options o;
  o.set("max_frequency_hz", kUnsetOption);
  EXPECT_FALSE(apply_options(p, o, error));
  EXPECT_THAT(error, HasSubstr("option max_frequency_hz is required and not set"));
  o.set("max_frequency_hz", 401.0);
  EXPECT_FALSE(apply_options(p, o, error));
  EXPECT_EQ(error, "option max_frequency_hz: must be a number in 1..400 (got 401)");
  o.set("max_frequency_hz", std::int64_t{60});
  EXPECT_TRUE(apply_options(p, o, error)) << error;
  EXPECT_EQ(options_text(p), "max_frequency_hz = 60 (required), motor_poles = 4 (default)");
}

// The daemon's own path: the configuration loads (the option is the profile's), and building the
// gateway refuses the device at its line, naming the option and what to set it to.
TEST(RequiredOption, TheDaemonRefusesTheDeviceAtItsLine) {
  const ProfileFile f(kProfile, "req.toml");
  PluginRegistry plugins;
  plugins.add(drivegate_adapter);
  const auto config = [&](const std::string& options) {
    return "[[bus]]\nname = \"a\"\nport = \"/nonexistent/tty\"\n\n"
           "[[device]]\nname = \"fan\"\nbus = \"a\"\nadapter = \"modbus\"\nunit_id = 1\n"
           "address = 7\n[device.options]\nprofile = \"" +
           f.path + "\"\n" + options;
  };
  boost::asio::io_context io;
  auto log = std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>());

  auto r = parse_config(config(""), "gw.toml", plugins);
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  std::vector<std::string> errors;
  EXPECT_EQ(Gateway::build(io, *r.config, plugins, log, errors), nullptr);
  EXPECT_THAT(errors, ElementsAre(HasSubstr(
                          "gw.toml:5: device fan: adapter 'modbus' refused the device: option "
                          "max_frequency_hz is required and not set: maximum frequency P105 of "
                          "the active parameter set: set it to the drive's P105 [Hz]")));

  r = parse_config(config("max_frequency_hz = 60\n"), "gw.toml", plugins);
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  errors.clear();
  EXPECT_NE(Gateway::build(io, *r.config, plugins, log, errors), nullptr)
      << ::testing::PrintToString(errors);

  r = parse_config(config("max_frequency_hz = 0.5\n"), "gw.toml", plugins);
  ASSERT_TRUE(r.config) << ::testing::PrintToString(r.errors);
  errors.clear();
  EXPECT_EQ(Gateway::build(io, *r.config, plugins, log, errors), nullptr);
  EXPECT_THAT(errors, ElementsAre(HasSubstr("gw.toml:5: device fan: adapter 'modbus' refused the "
                                            "device: option max_frequency_hz: must be a number "
                                            "in 1..400 (got 0.5)")));
}

// Set, the device's value is the one on the wire: 900 rpm at 60 Hz and 4 poles is 18 rpm a %,
// 50 % = raw 8192 (the example's 50 Hz would send 60 % = 9830). The simulator, given nothing,
// runs at its example and still answers.
TEST(RequiredOption, OnTheBusTheDevicesValueIsOnTheWire) {
  const ProfileFile f(kProfile, "req.toml");
  const AdapterDescriptor& a = specialised_for(f.path);
  test::BusRig rig(a);
  Device& d = rig.add_device("d", kSlave, {{"profile", f.path}, {"max_frequency_hz", "60"}});
  rig.add_simulator(kSlave, {{"profile", f.path}});
  rig.start();
  ASSERT_TRUE(rig.run_until([&] { return d.online(); }, 3s));
  const std::size_t mark = rig.sent().size();
  EXPECT_EQ(rig.write_and_wait(d, Table::holding, 1, {900}), Outcome::ok);
  std::vector<Bytes> writes;
  for (std::size_t i = mark; i < rig.sent().size(); ++i) {
    if (rig.sent()[i].bytes[1] == 0x06) writes.push_back(rig.sent()[i].bytes);
  }
  EXPECT_THAT(writes, ElementsAre(fc06(1, 8192)));
  EXPECT_EQ(rig.value(d, "setpoint_rpm"), 900u);
}

}  // namespace
}  // namespace drivegate::modbus_device::modbus_required_option_test
