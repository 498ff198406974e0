// Reload: a bus whose settings and devices are all unchanged moves to the new gateway as it runs,
// devices and all; any change on a bus (its settings, or any device on it) rebuilds that bus.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <boost/asio/io_context.hpp>

#include "config/adapter_options.h"
#include "fake_adapter.h"
#include "gateway/gateway.h"

namespace drivegate {
namespace {

class GatewayReload : public ::testing::Test {
 protected:
  GatewayReload() { plugins_.add(test::kFakeAdapter); }

  // Two lines: "a" with devices a1 (unit 1) and a2 (unit 2), "b" with b1 (unit 3). The ports do
  // not exist; nothing here is started.
  static Config config() {
    Config c;
    c.path = "drivegate.toml";
    for (const char* name : {"a", "b"}) {
      BusConfig b;
      b.name = name;
      b.port = std::string("/nonexistent/tty-") + name;
      b.baud = 4800;
      c.buses.push_back(b);
    }
    const auto device = [](const char* name, const char* bus, std::uint8_t unit) {
      DeviceConfig d;
      d.name = name;
      d.bus = bus;
      d.adapter = "fake";
      d.unit_id = unit;
      d.address = unit;
      d.options = default_options(test::kFakeAdapter);
      return d;
    };
    c.devices = {device("a1", "a", 1), device("a2", "a", 2), device("b1", "b", 3)};
    return c;
  }

  std::unique_ptr<Gateway> build(const Config& c) {
    std::vector<std::string> errors;
    auto gw = Gateway::build(io_, c, plugins_, log_, errors);
    EXPECT_TRUE(errors.empty()) << errors.front();
    return gw;
  }

  boost::asio::io_context io_;
  PluginRegistry plugins_;
  std::shared_ptr<spdlog::logger> log_ =
      std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>());
};

TEST_F(GatewayReload, AnUnchangedConfigKeepsEveryBusAndDevice) {
  auto old = build(config());
  const Device* a1 = old->find("a1");
  const Device* b1 = old->find("b1");
  auto next = build(config());
  EXPECT_EQ(next->adopt_unchanged(*old), (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(next->find("a1"), a1);  // the same objects, with their state
  EXPECT_EQ(next->find("b1"), b1);
  EXPECT_TRUE(old->devices().empty());
  EXPECT_EQ(next->devices().size(), 3u);
}

TEST_F(GatewayReload, WhereItWasDeclaredDoesNotCount) {
  auto old = build(config());
  auto moved = config();
  for (auto& b : moved.buses) b.line += 40;
  for (auto& d : moved.devices) d.line += 40;
  auto next = build(moved);
  EXPECT_EQ(next->adopt_unchanged(*old).size(), 2u);
}

TEST_F(GatewayReload, AChangedDeviceRebuildsOnlyItsBus) {
  auto old = build(config());
  const Device* a1 = old->find("a1");
  const Device* b1 = old->find("b1");
  auto changed = config();
  changed.devices[1].poll_interval = Millis(250);  // a2, on bus a
  auto next = build(changed);
  EXPECT_EQ(next->adopt_unchanged(*old), (std::vector<std::string>{"b"}));
  EXPECT_NE(next->find("a1"), a1);  // bus a starts afresh, a1 included
  EXPECT_EQ(next->find("b1"), b1);
  EXPECT_EQ(old->devices().size(), 2u);  // a1 and a2 stay behind, to be stopped
}

TEST_F(GatewayReload, ChangedLineSettingsOrAnAddedDeviceRebuildTheBus) {
  auto old = build(config());
  auto changed = config();
  changed.buses[0].baud = 9600;
  auto next = build(changed);
  EXPECT_EQ(next->adopt_unchanged(*old), (std::vector<std::string>{"b"}));

  old = build(config());
  auto added = config();
  added.devices.push_back(added.devices[2]);
  added.devices.back().name = "b2";
  added.devices.back().unit_id = 4;
  added.devices.back().address = 4;
  next = build(added);
  EXPECT_EQ(next->adopt_unchanged(*old), (std::vector<std::string>{"a"}));
}

TEST_F(GatewayReload, ReadsReachTheKeptDevicesByUnit) {
  auto old = build(config());
  auto next = build(config());
  next->adopt_unchanged(*old);
  old.reset();  // the old gateway is gone; the kept devices live on in the new one
  std::array<std::uint16_t, 1> status{};
  for (const std::uint8_t unit : {std::uint8_t{1}, std::uint8_t{2}, std::uint8_t{3}}) {
    EXPECT_EQ(next->read({}, unit, modbus::RegisterTable::input_registers, 0, status),
              modbus::Exception::none);
  }
  EXPECT_EQ(next->read({}, 4, modbus::RegisterTable::input_registers, 0, status),
            modbus::Exception::gateway_path_unavailable);
}

}  // namespace
}  // namespace drivegate
