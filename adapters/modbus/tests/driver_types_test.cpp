// The modbus driver with 64-bit, string and labelled points: the register-map face it gives them,
// the frames of their reads and writes (four registers always by FC 16), a reply a byte short.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "driver.h"
#include "profile_support.h"
#include "simulator.h"

namespace drivegate::modbus_device {
namespace {

using namespace std::chrono_literals;

constexpr std::uint8_t kSlave = 3;

// write = "single": one-register writes go as FC 06, wider ones cannot.
const std::string kProfile =
    "[profile]\nname = \"types\"\nsource = \"this test\"\n[modbus]\nwrite = \"single\"\n" +
    support::point("total", "holding", 0, "u64", "byte_order = \"dcba\"\n") +
    support::point("limit", "holding", 4, "s32", "byte_order = \"badc\"\n") +
    support::point("mode", "holding", 6, "u16", "values = { 0 = \"off\", 2 = \"auto\" }\n") +
    support::point("name", "holding", 7, "string", "registers = 2\n") +
    support::point("state", "input", 0, "u16", "bits = { 0 = \"ready\", 3 = \"fault\" }\n");

Bytes frame(std::vector<std::uint8_t> pdu) {
  return encode(Framing::rtu, kSlave, pdu);
}

class ModbusDriverTypesTest : public support::DriverAtHand {
 protected:
  ModbusDriverTypesTest() : DriverAtHand(kSlave, support::parsed(kProfile)) {}
  std::size_t index(std::string_view name) {
    for (std::size_t i = 0; i < d.points().size(); ++i) {
      if (d.points()[i].name == name) return i;
    }
    ADD_FAILURE() << "no point " << name;
    return 0;
  }
};

TEST_F(ModbusDriverTypesTest, TheRegisterMapCarriesTypesRegistersAndLabels) {
  const auto& spec = d.points();
  EXPECT_EQ(spec[index("total")].type, PointType::u64);
  EXPECT_EQ(spec[index("total")].register_count(), 4);
  EXPECT_EQ(spec[index("limit")].type, PointType::i32);
  EXPECT_EQ(spec[index("name")].type, PointType::string);
  EXPECT_EQ(spec[index("name")].register_count(), 2);
  EXPECT_EQ(spec[index("name")].access(), Access::read);  // strings are read-only
  const PointSpec& mode = spec[index("mode")];
  EXPECT_FALSE(mode.bit_labels);
  ASSERT_EQ(mode.labels.size(), 2u);
  EXPECT_EQ(mode.labels[1].name, "auto");
  EXPECT_EQ(mode.labels[1].value, 2u);
  const PointSpec& state = spec[index("state")];
  EXPECT_TRUE(state.bit_labels);
  ASSERT_EQ(state.labels.size(), 2u);
  EXPECT_EQ(state.labels[1].name, "fault");
  EXPECT_EQ(state.labels[1].value, 3u);
}

TEST_F(ModbusDriverTypesTest, ReadsDecodeEachOrderAndAReplyAByteShortIsNone) {
  // FC 04 of input 0: its reply is one byte short of the register asked, then the data (0x0009)
  // cut to one byte: neither is the reply, and the point stays unknown.
  ASSERT_EQ(sent(), frame({0x04, 0x00, 0x00, 0x00, 0x01}));
  EXPECT_NE(d.on_receive(frame({0x04, 0x01, 0x09}), now).kind, RxKind::reply);
  EXPECT_TRUE(std::holds_alternative<std::monostate>(d.values()[index("state")]));
  EXPECT_EQ(d.on_receive(frame({0x04, 0x02, 0x00, 0x09}), now).kind, RxKind::reply);
  // FC 03 of holding 0..8: total (dcba), limit (badc), mode, name.
  ASSERT_EQ(sent(), frame({0x03, 0x00, 0x00, 0x00, 0x09}));
  // 0x1122334455667788 in dcba: 88 77 66 55 44 33 22 11; -2 in badc: FF FF FE FF; "Hi!".
  const std::vector<std::uint8_t> data = {0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22, 0x11, 0xFF,
                                          0xFF, 0xFE, 0xFF, 0x00, 0x02, 0x48, 0x69, 0x21, 0x00};
  std::vector<std::uint8_t> pdu = {0x03, 18};
  pdu.insert(pdu.end(), data.begin(), data.end());
  EXPECT_EQ(d.on_receive(frame(pdu), now).kind, RxKind::reply);
  // Published with the cycle's last block.
  EXPECT_EQ(d.values()[index("state")], Value(std::int64_t{9}));
  EXPECT_EQ(d.values()[index("total")], Value(std::int64_t{0x1122334455667788}));
  EXPECT_EQ(d.values()[index("limit")], Value(std::int64_t{-2}));
  EXPECT_EQ(d.values()[index("mode")], Value(std::int64_t{2}));
  EXPECT_EQ(d.values()[index("name")], Value(std::string("Hi!")));
}

TEST_F(ModbusDriverTypesTest, AOneByteShortReplyToASixtyFourBitPointLeavesItUnknown) {
  ASSERT_EQ(sent(), frame({0x04, 0x00, 0x00, 0x00, 0x01}));
  ASSERT_EQ(d.on_receive(frame({0x04, 0x02, 0x00, 0x09}), now).kind, RxKind::reply);
  ASSERT_EQ(sent(), frame({0x03, 0x00, 0x00, 0x00, 0x09}));
  // 17 bytes where 18 were asked, its byte count saying so; and one saying 18 over 17.
  std::vector<std::uint8_t> pdu = {0x03, 17};
  pdu.resize(2 + 17, 0x11);
  EXPECT_NE(d.on_receive(frame(pdu), now).kind, RxKind::reply);
  pdu[1] = 18;
  EXPECT_NE(d.on_receive(frame(pdu), now).kind, RxKind::reply);
  EXPECT_TRUE(std::holds_alternative<std::monostate>(d.values()[index("total")]));
  // Unanswered: a failed read, the point still unknown; the cycle over, what it read is
  // published.
  d.on_no_reply(now + 200ms);
  EXPECT_TRUE(std::holds_alternative<std::monostate>(d.values()[index("total")]));
  EXPECT_EQ(d.values()[index("state")], Value(std::int64_t{9}));
}

TEST_F(ModbusDriverTypesTest, WiderWritesGoAsFc16InThePointsOrderEvenWhereWriteIsSingle) {
  // 0x0000123456789ABC (within 2^53) to total, dcba: BC 9A 78 56 34 12 00 00.
  const WriteOp total = WriteOp::of_point(index("total"), std::int64_t{0x123456789ABC});
  ASSERT_EQ(d.apply(total, 1, now), WriteStatus::pending);
  EXPECT_EQ(sent(), frame({0x10, 0x00, 0x00, 0x00, 0x04, 0x08, 0xBC, 0x9A, 0x78, 0x56, 0x34, 0x12,
                           0x00, 0x00}));
  EXPECT_EQ(d.on_receive(frame({0x10, 0x00, 0x00, 0x00, 0x04}), now).kind, RxKind::ack);
  // 0x11223344 to limit, badc: 22 11 44 33.
  const WriteOp limit = WriteOp::of_point(index("limit"), std::int64_t{0x11223344});
  ASSERT_EQ(d.apply(limit, 2, now), WriteStatus::pending);
  EXPECT_EQ(sent(), frame({0x10, 0x00, 0x04, 0x00, 0x02, 0x04, 0x22, 0x11, 0x44, 0x33}));
  EXPECT_EQ(d.on_receive(frame({0x10, 0x00, 0x04, 0x00, 0x02}), now).kind, RxKind::ack);
  // One register: FC 06 as the profile says.
  ASSERT_EQ(d.apply(WriteOp::of_point(index("mode"), std::int64_t{2}), 3, now),
            WriteStatus::pending);
  EXPECT_EQ(sent(), frame({0x06, 0x00, 0x06, 0x00, 0x02}));
  // Beyond 2^53, a string, a NaN: refused, nothing sent.
  EXPECT_EQ(d.apply(WriteOp::of_point(index("total"), std::int64_t{1} << 60), 4, now),
            WriteStatus::invalid_value);
  EXPECT_EQ(d.apply(WriteOp::of_point(index("name"), std::string("x")), 5, now),
            WriteStatus::invalid_value);
  EXPECT_EQ(d.apply(WriteOp::of_point(index("name"), std::int64_t{1}), 6, now),
            WriteStatus::invalid_value);
}

// Every type of 32 and 64 bits in every byte order, in the input (FC 04) and holding (FC 03)
// tables: set in the simulator by value, read by the driver through its frames.
TEST(ModbusTypesRoundTrip, EveryOrderThroughFc03AndFc04) {
  std::string text = "[profile]\nname = \"orders\"\nsource = \"this test\"\n";
  std::vector<std::pair<std::string, std::string>> points;  // name, value
  int address = 0;
  for (const char* table : {"input", "holding"}) {
    for (const auto& [type, value] :
         {std::pair{"u32", "287454020"}, std::pair{"s32", "-2"}, std::pair{"f32", "12.5"},
          std::pair{"u64", "4822678189205111"}, std::pair{"s64", "-3"},
          std::pair{"f64", "-1234.5"}}) {
      for (const char* order : {"abcd", "badc", "cdab", "dcba"}) {
        const std::string name = std::string(table).substr(0, 1) + "_" + type + "_" + order;
        text += "[[point]]\nname = \"" + name + "\"\ntable = \"" + table +
                "\"\naddress = " + std::to_string(address) + "\ntype = \"" + type +
                "\"\nbyte_order = \"" + order + "\"\n";
        address += std::string(type).ends_with("64") ? 4 : 2;
        points.emplace_back(name, value);
      }
    }
    address = 0;
  }
  auto parsed = parse_profile(text, "orders.toml");
  ASSERT_TRUE(std::holds_alternative<Profile>(parsed))
      << ::testing::PrintToString(std::get<std::vector<std::string>>(parsed));
  const Profile& p = std::get<Profile>(parsed);
  ModbusSimulator sim(kSlave, p);
  for (const auto& [name, value] : points) {
    ASSERT_EQ(sim.control("set " + name + " " + value, TimePoint{}).rfind("ok", 0), 0u) << name;
  }
  ModbusDriver d = support::driver_of(kSlave, p);
  TimePoint now = TimePoint{} + 10s;
  bool saw_fc03 = false;
  bool saw_fc04 = false;
  int exchanges = 0;
  while (const auto ex = d.next_exchange(now)) {
    ASSERT_LT(++exchanges, 10);
    const auto decoded = decode_request(Framing::rtu, ex->frame);
    saw_fc03 = saw_fc03 || decoded.frame.pdu[0] == 0x03;
    saw_fc04 = saw_fc04 || decoded.frame.pdu[0] == 0x04;
    ASSERT_EQ(d.on_receive(sim.on_receive(ex->frame, now), now).kind, RxKind::reply);
  }
  EXPECT_TRUE(saw_fc03 && saw_fc04);
  for (std::size_t i = 0; i < d.points().size(); ++i) {
    const std::string& name = d.points()[i].name;
    const auto it =
        std::find_if(points.begin(), points.end(), [&](const auto& n) { return n.first == name; });
    ASSERT_NE(it, points.end());
    EXPECT_DOUBLE_EQ(as_double(d.values()[i]), std::stod(it->second)) << name;
  }
}

}  // namespace
}  // namespace drivegate::modbus_device
