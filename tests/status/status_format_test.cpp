// What the status JSON and the metrics are made of: a device's points read a table at a time give
// what reading them one by one gives, what is not known has no value, and the JSON string writer
// escapes what RFC 8259 says.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>

#include "base/json.h"
#include "fake_adapter.h"
#include "gateway/device.h"
#include "gateway/value_codec.h"
#include "status/status_view.h"

namespace drivegate {
namespace {

TEST(JsonString, EscapesQuotesBackslashesAndControlCharacters) {
  EXPECT_EQ(json_string(""), "\"\"");
  EXPECT_EQ(json_string("speed_rpm"), "\"speed_rpm\"");
  EXPECT_EQ(json_string("a\"b"), "\"a\\\"b\"");
  EXPECT_EQ(json_string("\\"), "\"\\\\\"");
  EXPECT_EQ(json_string("x\ny\tz"), "\"x\\ny\\tz\"");
  EXPECT_EQ(json_string(std::string_view("\x01\x1f\0", 3)), "\"\\u0001\\u001f\\u0000\"");
  EXPECT_EQ(json_string("\xc2\xb0"
                        "C"),
            "\"\xc2\xb0"
            "C\"");  // UTF-8 as it is
  EXPECT_EQ(json_string("tail\""), "\"tail\\\"\"");
  std::string out = "[";
  append_json_string(out, "a");
  out += ", ";
  append_json_string(out, "b\"c");
  EXPECT_EQ(out, "[\"a\", \"b\\\"c\"");
}

// The per-point reads point_values() made before it read whole tables: each point on its own.
std::vector<PointValue> one_by_one(Device& device, TimePoint now) {
  static const Session kReader{AccessLevel::read, WordOrder::big};
  std::vector<PointValue> out;
  for (const MappedPoint& p : device.map().points()) {
    const bool bits = p.spec.table == Table::coil || p.spec.table == Table::discrete;
    std::vector<std::uint16_t> regs(bits ? 1 : p.spec.register_count());
    if (device.read(kReader, p.spec.table, p.address, regs, now) != Outcome::ok) {
      continue;
    }
    if (bits) {
      out.emplace_back(&p, std::int64_t{regs[0] != 0 ? 1 : 0});
    } else if (p.spec.type == PointType::string) {
      out.emplace_back(&p, decode_text(regs));
    } else if (auto v = decode_value(p.spec, regs)) {
      out.emplace_back(&p, std::move(*v));
    }
  }
  return out;
}

// When the fake drive last answered.
const TimePoint kHeard = TimePoint{} + std::chrono::hours(1);

// A device of the fake adapter around `driver`, its drive answering at kHeard.
std::unique_ptr<Device> answering(std::unique_ptr<test::FakeDriver> driver) {
  DeviceConfig cfg;
  cfg.name = "dev";
  cfg.unit_id = 1;
  auto device = std::make_unique<Device>(
      cfg, test::kFakeAdapter, std::move(driver),
      std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>()),
      kHeard);
  device->link().health.frame_good(kHeard);
  return device;
}

TEST(PointValues, ATableAtATimeReadsWhatPointByPointReads) {
  auto driver = std::make_unique<test::FakeDriver>(DeviceEnv{});
  test::FakeDriver& fake = *driver;
  PointSpec coil;
  coil.name = "relay";
  coil.table = Table::coil;
  fake.points_.push_back(coil);
  PointSpec door;
  door.name = "door";
  door.table = Table::discrete;
  fake.points_.push_back(door);
  PointSpec text;
  text.name = "serial";
  text.table = Table::input;
  text.type = PointType::string;
  text.string_registers = 2;
  fake.points_.push_back(text);
  fake.values_ = {std::int64_t{-123} /* x0.1 */,
                  std::int64_t{4242},
                  3.5,
                  0.25,  // gain
                  std::int64_t{1},
                  std::int64_t{0},
                  std::string("AB12")};
  fake.common_.speed_rpm = 1499;
  fake.common_.running = true;
  const TimePoint t0 = kHeard;
  const auto owner = answering(std::move(driver));
  Device& device = *owner;

  const auto now = t0 + Millis(250);
  const auto want = one_by_one(device, now);
  std::vector<PointValue> got;
  point_values(device, now, got);
  ASSERT_EQ(got.size(), want.size());
  // Every point, the string one with its text.
  EXPECT_EQ(got.size(), device.map().points().size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(got[i].first, want[i].first) << i;
    EXPECT_EQ(got[i].second, want[i].second) << got[i].first->spec.name;
  }
  // The reused vector is replaced, not appended to.
  point_values(device, now, got);
  EXPECT_EQ(got.size(), want.size());
  const auto by_name = [&](std::string_view n) {
    for (const auto& [p, v] : got) {
      if (p->spec.name == n) return v;
    }
    return Value{};
  };
  EXPECT_EQ(by_name("speed_rpm"), Value{std::int64_t{1499}});
  EXPECT_EQ(by_name("serial"), Value{std::string("AB12")});
  EXPECT_EQ(by_name("relay"), Value{std::int64_t{1}});
  EXPECT_EQ(by_name("pressure"), Value{3.5});
}

// What is not known is never a plausible number: a speed the drive cannot give reads -32768 in
// speed_rpm, a float not known NaN, an integer not known 0 (no value to spare); the documents and
// MQTT, which read point_values(), get no value (null in the JSON, NaN in /metrics).
TEST(PointValues, WhatIsNotKnownHasNoValue) {
  auto driver = std::make_unique<test::FakeDriver>(DeviceEnv{});
  test::FakeDriver& fake = *driver;
  fake.values_ = {Value{},  // temperature: never read
                  std::int64_t{4242},
                  std::numeric_limits<double>::quiet_NaN(),  // pressure: a float reading NaN
                  Value{}};                                  // gain: never read
  fake.common_.speed_rpm = 0;
  fake.common_.speed_unknown = true;
  const TimePoint t0 = kHeard;
  const auto owner = answering(std::move(driver));
  Device& device = *owner;
  const Session reader{AccessLevel::read, WordOrder::big};
  const auto regs = [&](Table t, std::uint16_t address, std::size_t n) {
    std::vector<std::uint16_t> out(n);
    EXPECT_EQ(device.read(reader, t, address, out, t0), Outcome::ok);
    return out;
  };
  EXPECT_EQ(regs(Table::input, 6, 1), std::vector<std::uint16_t>{0x8000});  // speed_rpm
  const auto at = [&](std::string_view n) { return device.map().find(n)->address; };
  EXPECT_EQ(regs(Table::input, at("temperature"), 1), std::vector<std::uint16_t>{0});
  const auto pressure = regs(Table::input, at("pressure"), 2);
  EXPECT_TRUE(std::isnan(std::bit_cast<float>((std::uint32_t{pressure[0]} << 16) | pressure[1])));
  const auto gain = regs(Table::holding, at("gain"), 2);
  EXPECT_TRUE(std::isnan(std::bit_cast<float>((std::uint32_t{gain[0]} << 16) | gain[1])));

  std::vector<PointValue> got;
  point_values(device, t0, got);
  const auto by_name = [&](std::string_view n) -> std::optional<Value> {
    for (const auto& [p, v] : got) {
      if (p->spec.name == n) return v;
    }
    return std::nullopt;
  };
  for (const char* unknown : {"speed_rpm", "temperature", "pressure", "gain"}) {
    EXPECT_EQ(by_name(unknown), Value{}) << unknown;
  }
  EXPECT_EQ(by_name("limit"), Value{std::int64_t{4242}});
  EXPECT_TRUE(std::isnan(number_of(Value{})));
  EXPECT_EQ(number_of(Value{std::int64_t{-3}}), -3.0);
  // A speed the register cannot carry is unknown too, whatever the driver says of it.
  fake.common_.speed_unknown = false;
  fake.common_.speed_rpm = 40000;
  EXPECT_EQ(regs(Table::input, 6, 1), std::vector<std::uint16_t>{0x8000});
  fake.common_.speed_rpm = -32767;
  EXPECT_EQ(regs(Table::input, 6, 1), std::vector<std::uint16_t>{0x8001});
}

}  // namespace
}  // namespace drivegate
