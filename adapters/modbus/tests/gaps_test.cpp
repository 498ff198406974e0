// Gaps that heal, on the real bus engine against the adapter's simulator (`drivegate sim modbus`,
// its `missing` and `refuse` commands): a block the slave refuses with exception 02 is searched,
// the refused registers skipped and the rest read in the largest blocks that avoid them, the new
// plan logged once; a slave that refuses now and then, or everything, shrinks no plan.
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "adapter_bench.h"
#include "adapter_under_test.h"
#include "codec.h"
#include "common_block.h"
#include "temp_dir.h"

namespace drivegate::modbus_device::modbus_gaps_test {
namespace {

using namespace std::chrono_literals;
using namespace test::common_block;

bool ok(const std::string& answer) {
  return answer.rfind("ok", 0) == 0;
}

// A read request as it goes on the wire: function, start, count.
struct Read {
  std::uint8_t function = 0;
  std::uint16_t start = 0;
  std::uint16_t count = 0;
  friend bool operator==(const Read&, const Read&) = default;
  friend bool operator<(const Read& a, const Read& b) {
    return std::tie(a.function, a.start, a.count) < std::tie(b.function, b.start, b.count);
  }
};

std::vector<Read> reads(const std::vector<Bytes>& frames) {
  std::vector<Read> r;
  for (const Bytes& f : frames) {
    if (f.size() != 8 || f[1] < 1 || f[1] > 4) continue;
    r.push_back({f[1], static_cast<std::uint16_t>(f[2] << 8 | f[3]),
                 static_cast<std::uint16_t>(f[4] << 8 | f[5])});
  }
  return r;
}

std::set<Read> distinct(const std::vector<Read>& r) {
  return {r.begin(), r.end()};
}

// What the devices logged, through a sink on the rig's logger.
struct Heard {
  explicit Heard(test::AdapterBench& b)
      : sink(std::make_shared<spdlog::sinks::ostream_sink_mt>(out)) {
    sink->set_pattern("%v");
    b.rig.log()->sinks().push_back(sink);
    b.rig.log()->set_level(spdlog::level::info);
  }
  [[nodiscard]] std::size_t count(std::string_view what) const {
    const std::string s = out.str();
    std::size_t n = 0;
    for (auto at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
    return n;
  }
  std::ostringstream out;
  std::shared_ptr<spdlog::sinks::ostream_sink_mt> sink;
};

// 59 u16 points on holding 0, 2 ... 116 and a u32 on 118..119, max_gap 1: one block of 120
// registers, read through the 59 unused registers between the points.
std::filesystem::path wide_profile(const test::TempDir& dir) {
  std::ostringstream o;
  o << "[profile]\nname = \"wide\"\nsource = \"a test\"\n"
       "[modbus]\nmax_registers = 125\nmax_gap = 1\ntimeout_ms = 100\n";
  for (int i = 0; i < 59; ++i) {
    o << "[[point]]\nname = \"p" << i << "\"\ntable = \"holding\"\naddress = " << 2 * i
      << "\ntype = \"u16\"\n";
  }
  o << "[[point]]\nname = \"last\"\ntable = \"holding\"\naddress = 118\ntype = \"u32\"\n";
  const auto file = dir / "wide.toml";
  std::ofstream(file) << o.str();
  return file;
}

// The 120-register block with holding 61 (unused, between p30 and p31) missing: found within
// 2 x ceil(log2 119) + 1 reads, skipped, and the points read in the two blocks around it; the
// plan is logged once, and the PLC reads the points on both sides.
TEST(ModbusGaps, OneMissingRegisterInA120RegisterBlockIsFoundAndSkipped) {
  test::TempDir dir;
  test::AdapterBench b(drivegate_adapter, {.options = {{"profile", wide_profile(dir).string()}}});
  Heard heard(b);
  ASSERT_TRUE(ok(b.control("missing holding 61")));
  ASSERT_TRUE(ok(b.control("raw holding 60 1234")));
  ASSERT_TRUE(ok(b.control("raw holding 62 4321")));
  ASSERT_TRUE(ok(b.control("raw holding 118 1 2")));
  const TimePoint start = b.rig.now();
  ASSERT_TRUE(b.until_online());
  b.rig.run_for(3s);
  const std::vector<Read> all = reads(b.frames(start));
  // The whole block, refused: the search begins at once.
  const Read whole{0x03, 0, 120};
  ASSERT_GE(all.size(), 2u);
  EXPECT_EQ(all[0], whole);
  // Then the search, until the first read of the new plan.
  const Read left{0x03, 0, 61};
  const Read right{0x03, 62, 58};
  std::size_t searched = 0;
  std::size_t i = 0;
  for (; i < all.size() && !(all[i] == left); ++i) {
    if (!(all[i] == whole)) ++searched;
  }
  ASSERT_LT(i, all.size()) << "the new plan never read";
  EXPECT_GE(searched, 7u);
  EXPECT_LE(searched, 2u * 7u + 1u);
  // From then on the two blocks around holding 61, and nothing else.
  const std::vector<Read> after(all.begin() + static_cast<long>(i), all.end());
  EXPECT_EQ(distinct(after), (std::set<Read>{left, right}));
  EXPECT_GE(after.size(), 8u);  // polled every 500 ms
  EXPECT_EQ(b.read("p30"), 1234u);
  EXPECT_EQ(b.read("p31"), 4321u);
  EXPECT_EQ(b.read("last"), 0x00010002u);
  EXPECT_EQ(heard.count("read plan: holding 0..60, holding 62..119; skips holding 61 "), 1u)
      << heard.out.str();
  EXPECT_EQ(heard.count("read plan"), 1u);
  EXPECT_EQ(heard.count("is refused"), 0u);  // no point is lost
  EXPECT_EQ(b.status() & kCommLost, 0u);
}

// The example's motor current (input 202..203, a float) is one register short in this slave:
// only that point is unknown, said so once; the speed beside it is read.
TEST(ModbusGaps, APointTheSlaveLacksIsUnknownAndTheRestRead) {
  test::AdapterBench b(drivegate_adapter);
  Heard heard(b);
  ASSERT_TRUE(ok(b.control("missing input 203")));
  const TimePoint start = b.rig.now();
  ASSERT_TRUE(b.until_online());
  b.rig.run_for(2s);
  EXPECT_EQ(heard.count("point motor_current (input 202..203) is refused by the slave"), 1u)
      << heard.out.str();
  EXPECT_EQ(heard.count("read plan: input 200, input 210, holding 0..1, holding 100; skips input "
                        "202..203 "),
            1u)
      << heard.out.str();
  // The last second: the new plan only.
  EXPECT_EQ(distinct(reads(b.frames(b.rig.now() - 1s))),
            (std::set<Read>{{0x04, 200, 1}, {0x04, 210, 1}, {0x03, 0, 2}, {0x03, 100, 1}}));
  EXPECT_TRUE(std::isnan(b.read_f32("motor_current")));
  ASSERT_TRUE(b.run_forward_at(1200));
  EXPECT_TRUE(b.rig.run_until([&] { return b.read_i16("speed_rpm") == 1200; }, 5s));
  (void)start;
}

// A block read before, refused once with 02 (a drive that refuses while busy): not searched, the
// plan unchanged, the block asked again at its next cycle.
TEST(ModbusGaps, ABlockReadBeforeAndRefusedOnceIsNotSplit) {
  test::AdapterBench b(drivegate_adapter);
  Heard heard(b);
  ASSERT_TRUE(b.until_online());
  b.rig.run_for(1s);
  const TimePoint from = b.rig.now();
  ASSERT_TRUE(ok(b.control("refuse input 200 2 1")));
  b.rig.run_for(3s);
  const std::set<Read> plan = {{0x04, 200, 4}, {0x04, 210, 1}, {0x03, 0, 2}, {0x03, 100, 1}};
  EXPECT_EQ(distinct(reads(b.frames(from))), plan);
  EXPECT_EQ(heard.count("read plan"), 0u);
  EXPECT_EQ(b.status() & kCommLost, 0u);
}

// Every other reply turned into exception 02 on the way back (a glitching slave), for 10 s: blocks
// refused three times in a row are searched, but no part is ever refused twice in a row alone,
// so nothing is skipped; once the slave is sound, the plan is the one it was.
TEST(ModbusGaps, ASlaveRefusingEveryOtherRequestKeepsItsPlan) {
  test::AdapterBench b(drivegate_adapter);
  Heard heard(b);
  ASSERT_TRUE(b.until_online());
  bool refuse = false;
  b.rig.line().device_filter = [&](Bytes reply) {
    if (!std::exchange(refuse, !refuse)) return reply;
    return encode(Framing::rtu, reply[0], Bytes{static_cast<std::uint8_t>(reply[1] | 0x80), 0x02});
  };
  b.rig.run_for(10s);
  b.rig.line().device_filter = nullptr;
  b.rig.run_for(2s);
  const std::set<Read> plan = {{0x04, 200, 4}, {0x04, 210, 1}, {0x03, 0, 2}, {0x03, 100, 1}};
  EXPECT_EQ(distinct(reads(b.frames(b.rig.now() - 1s))), plan);
  EXPECT_EQ(heard.count("read plan"), 0u) << heard.out.str();
  EXPECT_EQ(heard.count("refuse"), 0u) << heard.out.str();
  EXPECT_EQ(b.status() & kCommLost, 0u);
  EXPECT_NE(b.status() & kOnline, 0u);
}

// A slave that refuses every register: nothing is skipped, the search gives up after a handful of
// reads, none begins again, and the device goes comm_lost (its state is never read).
TEST(ModbusGaps, ASlaveRefusingEverythingGoesCommLostWithoutALoop) {
  test::AdapterBench b(drivegate_adapter);
  Heard heard(b);
  for (const char* r : {"holding 0", "holding 1", "holding 100", "input 200", "input 201",
                        "input 202", "input 203", "input 210"}) {
    ASSERT_TRUE(ok(b.control(std::string("missing ") + r)));
  }
  const TimePoint start = b.rig.now();
  ASSERT_TRUE(b.rig.run_until([&] { return (b.status() & kCommLost) != 0; }, 5s));
  b.rig.run_for(30s);
  const std::set<Read> plan = {{0x04, 200, 4}, {0x04, 210, 1}, {0x03, 0, 2}, {0x03, 100, 1}};
  std::size_t searched = 0;
  for (const Read& r : reads(b.frames(start))) searched += plan.contains(r) ? 0 : 1;
  EXPECT_LE(searched, 4u);
  EXPECT_EQ(heard.count("the slave refuses every read"), 1u) << heard.out.str();
  EXPECT_EQ(heard.count("read plan"), 0u);
  EXPECT_NE(b.status() & kCommLost, 0u);
}

}  // namespace
}  // namespace drivegate::modbus_device::modbus_gaps_test
