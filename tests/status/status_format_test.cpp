// What the status JSON and the metrics are made of: a device's points read a table at a time give
// what reading them one by one gives, and the JSON string writer escapes what RFC 8259 says.
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include "fake_adapter.h"
#include "base/json.h"
#include "status/status_view.h"
#include "gateway/device.h"
#include "gateway/value_codec.h"

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
    } else if (auto v = decode_value(p.spec, regs)) {
      out.emplace_back(&p, std::move(*v));
    }
  }
  return out;
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
  const TimePoint t0 = TimePoint{} + std::chrono::hours(1);
  DeviceConfig cfg;
  cfg.name = "dev";
  cfg.unit_id = 1;
  Device device(
      cfg, test::kFakeAdapter, std::move(driver),
      std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>()), t0);
  device.link().health.frame_good(t0);

  const auto now = t0 + Millis(250);
  const auto want = one_by_one(device, now);
  std::vector<PointValue> got;
  point_values(device, now, got);
  ASSERT_EQ(got.size(), want.size());
  // Every point but the string one (decode_value gives no value for strings, read either way).
  EXPECT_EQ(got.size() + 1, device.map().points().size());
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
  EXPECT_EQ(by_name("serial"), Value{});
  EXPECT_EQ(by_name("relay"), Value{std::int64_t{1}});
  EXPECT_EQ(by_name("pressure"), Value{3.5});
}

}  // namespace
}  // namespace drivegate
