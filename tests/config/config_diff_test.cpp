// What a reload changes (config/config_diff.h), said in words for the log: the devices kept as
// they run, the ones started afresh and why, the lines reopened and why, listener policies.
#include "config/config_diff.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace drivegate {
namespace {

using ::testing::ElementsAre;
using ::testing::IsEmpty;

Config two_lines() {
  Config c;
  for (const char* name : {"a", "b"}) {
    BusConfig b;
    b.name = name;
    b.port = std::string("/dev/tty-") + name;
    b.baud = 9600;
    c.buses.push_back(b);
  }
  for (const char* name : {"a1", "a2", "b1"}) {
    DeviceConfig d;
    d.name = name;
    d.bus = std::string(1, name[0]);
    d.adapter = "ed3100";
    d.options.set("monitors", std::vector<std::string>{"0D00"});
    c.devices.push_back(d);
  }
  return c;
}

TEST(ConfigDiff, SaysWhatChangedKeyByKey) {
  BusConfig a;
  BusConfig b = a;
  b.line = 40;  // where it was declared does not count
  EXPECT_THAT(changes(a, b), IsEmpty());
  b.baud = 19200;
  b.parity = Parity::even;
  EXPECT_THAT(changes(a, b), ElementsAre("baud 0 -> 19200", "parity none -> even"));

  DeviceConfig d;
  d.options.set("monitors", std::vector<std::string>{"0D00"});
  DeviceConfig e = d;
  e.poll_interval = Millis(250);
  e.options.set("monitors", std::vector<std::string>{"0D00", "0D01"});
  e.options.set("timeout_ms", std::int64_t{120});
  EXPECT_THAT(changes(d, e), ElementsAre("poll_ms 500 -> 250",
                                         "option monitors [0D00] -> [0D00, 0D01]",
                                         "option timeout_ms (none) -> 120"));
  EXPECT_TRUE(same_settings(d, d));
  EXPECT_FALSE(same_settings(d, e));
}

// What the adapter read (Driver::files_read, filled in by the gateway) is a setting like the
// others: the same file with other content, or another file, is a changed device.
TEST(ConfigDiff, AFileTheDeviceReadsIsComparedByContent) {
  DeviceConfig d;
  d.files_read = "profile /etc/drivegate/profiles/vfd.toml (content 00000000000000a1)";
  DeviceConfig e = d;
  EXPECT_TRUE(same_settings(d, e));
  e.files_read = "profile /etc/drivegate/profiles/vfd.toml (content 00000000000000b2)";
  EXPECT_THAT(changes(d, e),
              ElementsAre("profile /etc/drivegate/profiles/vfd.toml (content 00000000000000a1) -> "
                          "profile /etc/drivegate/profiles/vfd.toml (content 00000000000000b2)"));
  e.files_read.clear();
  EXPECT_THAT(changes(d, e),
              ElementsAre("profile /etc/drivegate/profiles/vfd.toml (content 00000000000000a1) -> "
                          "(no file)"));
}

TEST(ConfigDiff, SortsDevicesAndBusesByWhatHappensToThem) {
  const Config running = two_lines();
  Config next = two_lines();
  next.devices[1].poll_interval = Millis(250);  // a2 changed
  next.devices.erase(next.devices.begin() + 2);  // b1 removed
  DeviceConfig c1 = next.devices[0];
  c1.name = "c1";
  c1.bus = "c";
  next.devices.push_back(c1);  // added, on a new line
  next.buses[1].baud = 19200;  // line b reopened
  BusConfig c = next.buses[0];
  c.name = "c";
  next.buses.push_back(c);
  const ConfigDiff d = diff_config(running, next);
  EXPECT_THAT(d.devices_kept, ElementsAre("a1"));
  ASSERT_EQ(d.devices_changed.size(), 1u);
  EXPECT_EQ(d.devices_changed[0].name, "a2");
  EXPECT_THAT(d.devices_changed[0].what, ElementsAre("poll_ms 500 -> 250"));
  EXPECT_THAT(d.devices_added, ElementsAre("c1"));
  EXPECT_THAT(d.devices_removed, ElementsAre("b1"));
  EXPECT_THAT(d.buses_kept, ElementsAre("a"));
  ASSERT_EQ(d.buses_reopened.size(), 1u);
  EXPECT_THAT(d.buses_reopened[0].what, ElementsAre("baud 9600 -> 19200"));
  EXPECT_THAT(d.buses_added, ElementsAre("c"));
  EXPECT_THAT(d.buses_removed, IsEmpty());
}

TEST(ConfigDiff, ListenerPolicyChangesAreNamed) {
  modbus::ListenerPolicy a;
  a.access = AccessLevel::operate;
  modbus::ListenerPolicy b = a;
  EXPECT_THAT(changes(a, b), IsEmpty());
  b.access = AccessLevel::read;
  b.word_order = WordOrder::little;
  EXPECT_THAT(changes(a, b), ElementsAre("access operate -> read", "word_order big -> little"));
}

}  // namespace
}  // namespace drivegate
