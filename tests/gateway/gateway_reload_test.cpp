// Reload (issue 24): a device whose settings are unchanged moves to the new gateway as it runs,
// whatever changes beside it; a bus whose own settings are unchanged keeps its port open.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <boost/asio/io_context.hpp>

#include "plugin/adapter_options.h"
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
  const Bus* bus_a = old->buses()[0].get();
  auto next = build(config());
  next->adopt(*old);
  EXPECT_EQ(next->find("a1"), a1);  // the same objects, with their state
  EXPECT_EQ(next->find("b1"), b1);
  EXPECT_EQ(next->buses()[0].get(), bus_a);  // the same line, port open
  EXPECT_TRUE(old->devices().empty());
  EXPECT_TRUE(old->buses().empty());
  EXPECT_EQ(next->devices().size(), 3u);
}

TEST_F(GatewayReload, WhereItWasDeclaredDoesNotCount) {
  auto old = build(config());
  const Device* a1 = old->find("a1");
  auto moved = config();
  for (auto& b : moved.buses) b.line += 40;
  for (auto& d : moved.devices) d.line += 40;
  auto next = build(moved);
  next->adopt(*old);
  EXPECT_EQ(next->find("a1"), a1);
  EXPECT_TRUE(old->buses().empty());
}

// Issue 24: a neighbour's change on the line leaves a device as it runs, and the line open.
TEST_F(GatewayReload, AChangedDeviceStartsAfreshAloneItsNeighboursAndLineKept) {
  auto old = build(config());
  const Device* a1 = old->find("a1");
  const Device* a2 = old->find("a2");
  const Bus* bus_a = old->buses()[0].get();
  auto changed = config();
  changed.devices[1].poll_interval = Millis(250);  // a2, on bus a
  auto next = build(changed);
  next->adopt(*old);
  EXPECT_EQ(next->find("a1"), a1);  // kept, on the kept line
  EXPECT_NE(next->find("a2"), a2);  // afresh
  EXPECT_EQ(next->buses()[0].get(), bus_a);
  EXPECT_EQ(old->devices().size(), 1u);  // the old a2 stays behind, to be stopped
  // The kept line now polls the kept a1 and the new a2, not the old a2.
  const auto& stations = bus_a->stations();
  ASSERT_EQ(stations.size(), 2u);
  EXPECT_EQ(stations[0], static_cast<const Station*>(a1));
  EXPECT_EQ(stations[1], static_cast<const Station*>(next->find("a2")));
}

TEST_F(GatewayReload, ChangedLineSettingsReopenTheLineButKeepItsDevices) {
  auto old = build(config());
  const Device* a1 = old->find("a1");
  const Bus* bus_a = old->buses()[0].get();
  auto changed = config();
  changed.buses[0].baud = 9600;
  auto next = build(changed);
  next->adopt(*old);
  EXPECT_NE(next->buses()[0].get(), bus_a);  // a new line (the old one is stopped first)
  EXPECT_EQ(next->find("a1"), a1);           // the device, as it ran
  EXPECT_EQ(next->buses()[0]->stations().front(), static_cast<const Station*>(a1));
  EXPECT_EQ(old->buses().size(), 1u);
}

TEST_F(GatewayReload, AnAddedDeviceJoinsAKeptLine) {
  auto old = build(config());
  const Device* b1 = old->find("b1");
  const Bus* bus_b = old->buses()[1].get();
  auto added = config();
  added.devices.push_back(added.devices[2]);
  added.devices.back().name = "b2";
  added.devices.back().unit_id = 4;
  added.devices.back().address = 4;
  auto next = build(added);
  next->adopt(*old);
  EXPECT_EQ(next->find("b1"), b1);
  EXPECT_EQ(next->buses()[1].get(), bus_b);
  EXPECT_EQ(bus_b->stations().size(), 2u);
}

TEST_F(GatewayReload, ReadsReachTheKeptDevicesByUnit) {
  auto old = build(config());
  auto next = build(config());
  next->adopt(*old);
  old.reset();  // the old gateway is gone; the kept devices live on in the new one
  std::array<std::uint16_t, 1> status{};
  for (const std::uint8_t unit : {std::uint8_t{1}, std::uint8_t{2}, std::uint8_t{3}}) {
    EXPECT_EQ(next->read({}, unit, Table::input, 0, status), Outcome::ok);
  }
  EXPECT_EQ(next->read({}, 4, Table::input, 0, status), Outcome::no_such_device);
}

}  // namespace
}  // namespace drivegate
