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
  EXPECT_THAT(changes(d, e),
              ElementsAre("poll_ms 500 -> 250", "option monitors [0D00] -> [0D00, 0D01]",
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
  next.devices[1].poll_interval = Millis(250);   // a2 changed
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
  ListenerPolicyConfig a;
  a.access = AccessLevel::operate;
  ListenerPolicyConfig b = a;
  EXPECT_THAT(changes(a, b), IsEmpty());
  b.access = AccessLevel::read;
  b.word_order = WordOrder::little;
  EXPECT_THAT(changes(a, b), ElementsAre("access operate -> read", "word_order big -> little"));
}

// The one statement of what a reload applies at once and what waits for a restart.
ListenerConfig tcp(const std::string& host, std::uint16_t port) {
  ListenerConfig l;
  l.host = host;
  l.port = port;
  return l;
}

ListenerConfig serial(const std::string& port, ListenerFraming framing) {
  ListenerConfig l = tcp("", 0);
  l.framing = framing;
  l.serial = BusConfig{.name = "listener " + port, .port = port, .baud = 19200};
  return l;
}

TEST(ReloadPlan, NothingChangedPlansNothing) {
  Config c = two_lines();
  c.listeners = {tcp("0.0.0.0", 502), serial("/dev/ttyS1", ListenerFraming::rtu)};
  Config same = c;
  same.http.line = 7;  // where a section is in the file is no change
  same.mqtt.line = 9;
  const ReloadPlan p = plan_reload(c, same);
  EXPECT_THAT(p.tcp_listeners_restart, IsEmpty());
  EXPECT_THAT(p.serial_listeners_restart, IsEmpty());
  EXPECT_THAT(p.listener_policies, IsEmpty());
  EXPECT_THAT(p.server_limits, IsEmpty());
  EXPECT_THAT(p.sections_restart, IsEmpty());
  EXPECT_FALSE(p.mqtt_session);
}

TEST(ReloadPlan, AListenerMovedWaitsForARestartItsPolicyDoesNot) {
  Config running;
  running.listeners = {tcp("0.0.0.0", 502), tcp("127.0.0.1", 1502),
                       serial("/dev/ttyS1", ListenerFraming::rtu)};
  Config next = running;
  next.listeners[1].port = 1503;                           // moved
  next.listeners[0].policy.access = AccessLevel::read;     // applied at once
  next.listeners[2].framing = ListenerFraming::ascii;      // another framing: another listener
  next.listeners.push_back(tcp("127.0.0.1", 802));         // added
  next.listeners.back().policy.tls = ListenerTlsConfig{};  // TLS or not is the socket's
  const ReloadPlan p = plan_reload(running, next);
  EXPECT_THAT(p.tcp_listeners_restart,
              ElementsAre("127.0.0.1:1503", "127.0.0.1:802 (TLS)", "127.0.0.1:1502 (removed)"));
  EXPECT_THAT(p.serial_listeners_restart, ElementsAre("serial /dev/ttyS1 (rtu) (removed or moved)",
                                                      "serial /dev/ttyS1 (ascii) (added)"));
  ASSERT_EQ(p.listener_policies.size(), 1u);
  EXPECT_EQ(p.listener_policies[0].name, "0.0.0.0:502");
  EXPECT_THAT(p.listener_policies[0].what, ElementsAre("access maintain -> read"));
  // What waits goes on as it runs.
  Config applied = next;
  p.keep_what_waits(running, applied);
  ASSERT_EQ(applied.listeners.size(), 3u);
  EXPECT_EQ(applied.listeners[1].port, 1502);
}

TEST(ReloadPlan, ServerLimitsApplyHttpAndHistoryWaitMqttStartsAfresh) {
  Config running;
  Config next = running;
  next.server.max_clients = 64;
  next.server.idle_timeout = Millis(5000);
  next.http.capture = true;
  next.history.events = 10;
  next.mqtt.group_id = "plant";
  const ReloadPlan p = plan_reload(running, next);
  EXPECT_THAT(p.server_limits,
              ElementsAre("max_clients 32 -> 64", "idle_timeout_ms 60000 -> 5000"));
  EXPECT_THAT(p.sections_restart, ElementsAre("[http]", "[history]"));
  EXPECT_TRUE(p.mqtt_session);
  Config applied = next;
  p.keep_what_waits(running, applied);
  EXPECT_FALSE(applied.http.capture);
  EXPECT_EQ(applied.history.events, running.history.events);
  EXPECT_EQ(applied.server.max_clients, 64u);
  EXPECT_EQ(applied.mqtt.group_id, "plant");
}

}  // namespace
}  // namespace drivegate
