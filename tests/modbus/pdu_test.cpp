// Dispatch of every function against a fake backend. Golden request / response PDUs are the
// examples of the Modbus Application Protocol Specification V1.1b3 (section cited on each).
#include "pdu.h"

#include <gtest/gtest.h>

#include <optional>
#include <string>
#include <vector>

#include "fake_backend.h"
#include "mbap.h"

namespace drivegate::modbus::pdu_test {
namespace {

using Bytes = std::vector<std::uint8_t>;
using test::FakeBackend;
using Status = Dispatcher::Result::Status;

void set_bits(std::vector<std::uint16_t>& table, std::size_t at, const Bytes& packed,
              std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) table[at + i] = (packed[i / 8] >> (i % 8)) & 1u;
}

Bytes regs(std::uint16_t address, std::uint16_t count) {
  return {static_cast<std::uint8_t>(address >> 8), static_cast<std::uint8_t>(address),
          static_cast<std::uint8_t>(count >> 8), static_cast<std::uint8_t>(count)};
}
Bytes cat(std::initializer_list<Bytes> parts) {
  Bytes out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  return out;
}

class Pdu : public ::testing::Test {
 protected:
  Pdu() : dispatcher_(backend_, DeviceIdentity{"drivegate", "drivegate", "0.1.0"}) {
    // 6.1 example: coils 20..38 (addresses 0x13..0x25) read CD 6B 05.
    set_bits(backend_.table(Table::coil), 0x13, {0xCD, 0x6B, 0x05}, 19);
    // 6.2 example: discrete inputs 197..218 (addresses 0xC4..0xD9) read AC DB 35.
    set_bits(backend_.table(Table::discrete), 0xC4, {0xAC, 0xDB, 0x35}, 22);
    // 6.3 example: registers 108..110 (addresses 0x6B..0x6D) hold 0x022B, 0x0000, 0x0064.
    auto& holding = backend_.table(Table::holding);
    holding[0x6B] = 0x022B;
    holding[0x6C] = 0x0000;
    holding[0x6D] = 0x0064;
    // 6.17 example: registers 4..9 (addresses 3..8) hold 00FE 0ACD 0001 0003 000D 00FF.
    const std::uint16_t rw[] = {0x00FE, 0x0ACD, 0x0001, 0x0003, 0x000D, 0x00FF};
    for (std::size_t i = 0; i < 6; ++i) holding[3 + i] = rw[i];
    // 6.4 example: input register 9 (address 0x08) holds 0x000A.
    backend_.table(Table::input)[0x08] = 0x000A;
  }

  // Dispatches `request` for `unit`; a write that completes inside write() (immediate mode) is
  // finished at once, as the connection would. Sets `pending_` when it has not completed yet.
  Bytes run(const Bytes& request, std::uint8_t unit = 1) {
    std::array<std::uint8_t, kMaxPduSize> out{};
    done_.reset();
    auto r = dispatcher_.handle(session_, unit, request, out, [this](Exception e) { done_ = e; });
    denied_ = r.denied;
    if (r.status == Status::reply) {
      pending_ = false;
      return Bytes(out.begin(), out.begin() + static_cast<long>(r.size));
    }
    pending_ = true;
    request_ = request;
    unit_ = unit;
    if (!done_) return {};
    return finish();
  }
  Bytes finish() {
    EXPECT_TRUE(done_.has_value());
    std::array<std::uint8_t, kMaxPduSize> out{};
    const auto n = dispatcher_.complete(session_, unit_, request_, *done_, out);
    return Bytes(out.begin(), out.begin() + static_cast<long>(n));
  }

  FakeBackend backend_;
  Dispatcher dispatcher_;
  Session session_{AccessLevel::maintain, WordOrder::big};  // unless a test says otherwise
  std::optional<Exception> done_;
  bool pending_ = false;
  bool denied_ = false;
  Bytes request_;
  std::uint8_t unit_ = 0;
};

// --- golden vectors -----------------------------------------------------------------------

TEST_F(Pdu, ReadCoils_6_1) {
  EXPECT_EQ(run({0x01, 0x00, 0x13, 0x00, 0x13}), (Bytes{0x01, 0x03, 0xCD, 0x6B, 0x05}));
}
TEST_F(Pdu, ReadDiscreteInputs_6_2) {
  EXPECT_EQ(run({0x02, 0x00, 0xC4, 0x00, 0x16}), (Bytes{0x02, 0x03, 0xAC, 0xDB, 0x35}));
}
TEST_F(Pdu, ReadHoldingRegisters_6_3) {
  EXPECT_EQ(run({0x03, 0x00, 0x6B, 0x00, 0x03}),
            (Bytes{0x03, 0x06, 0x02, 0x2B, 0x00, 0x00, 0x00, 0x64}));
}
TEST_F(Pdu, ReadInputRegisters_6_4) {
  EXPECT_EQ(run({0x04, 0x00, 0x08, 0x00, 0x01}), (Bytes{0x04, 0x02, 0x00, 0x0A}));
}
TEST_F(Pdu, WriteSingleCoil_6_5) {
  EXPECT_EQ(run({0x05, 0x00, 0xAC, 0xFF, 0x00}), (Bytes{0x05, 0x00, 0xAC, 0xFF, 0x00}));
  EXPECT_EQ(backend_.table(Table::coil)[0xAC], 1);
  EXPECT_EQ(run({0x05, 0x00, 0xAC, 0x00, 0x00}), (Bytes{0x05, 0x00, 0xAC, 0x00, 0x00}));
  EXPECT_EQ(backend_.table(Table::coil)[0xAC], 0);
}
TEST_F(Pdu, WriteSingleRegister_6_6) {
  EXPECT_EQ(run({0x06, 0x00, 0x01, 0x00, 0x03}), (Bytes{0x06, 0x00, 0x01, 0x00, 0x03}));
  EXPECT_EQ(backend_.table(Table::holding)[1], 3);
}
TEST_F(Pdu, WriteMultipleCoils_6_11) {
  EXPECT_EQ(run({0x0F, 0x00, 0x13, 0x00, 0x0A, 0x02, 0xCD, 0x01}),
            (Bytes{0x0F, 0x00, 0x13, 0x00, 0x0A}));
  ASSERT_EQ(backend_.writes.size(), 1u);
  EXPECT_EQ(backend_.writes[0].table, Table::coil);
  EXPECT_EQ(backend_.writes[0].address, 0x13);
  // CD 01: coils 20..29 = 1 0 1 1 0 0 1 1 1 0 (6.11)
  EXPECT_EQ(backend_.writes[0].values, (std::vector<std::uint16_t>{1, 0, 1, 1, 0, 0, 1, 1, 1, 0}));
}
TEST_F(Pdu, WriteMultipleRegisters_6_12) {
  EXPECT_EQ(run({0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02}),
            (Bytes{0x10, 0x00, 0x01, 0x00, 0x02}));
  EXPECT_EQ(backend_.writes.at(0).values, (std::vector<std::uint16_t>{0x000A, 0x0102}));
}
TEST_F(Pdu, ReadWriteMultipleRegisters_6_17) {
  EXPECT_EQ(
      run({0x17, 0x00, 0x03, 0x00, 0x06, 0x00, 0x0E, 0x00, 0x03, 0x06, 0x00, 0xFF, 0x00, 0xFF, 0x00,
           0xFF}),
      (Bytes{0x17, 0x0C, 0x00, 0xFE, 0x0A, 0xCD, 0x00, 0x01, 0x00, 0x03, 0x00, 0x0D, 0x00, 0xFF}));
  EXPECT_EQ(backend_.writes.at(0).address, 0x0E);
  EXPECT_EQ(backend_.writes.at(0).values, (std::vector<std::uint16_t>{0xFF, 0xFF, 0xFF}));
}
TEST_F(Pdu, ReadWriteWritesBeforeItReads_6_17) {
  // Read 14..16 right after writing them: the response carries the new values.
  EXPECT_EQ(run(cat({{0x17}, regs(0x0E, 2), regs(0x0E, 2), {0x04, 0x12, 0x34, 0x56, 0x78}})),
            (Bytes{0x17, 0x04, 0x12, 0x34, 0x56, 0x78}));
}
TEST_F(Pdu, ExceptionExample_7) {
  // Section 7 example: read coils at 1185 (0x04A1), which does not exist here.
  EXPECT_EQ(run({0x01, 0x04, 0xA1, 0x00, 0x01}), (Bytes{0x81, 0x02}));
}

// --- device identification (6.21) ---------------------------------------------------------

Bytes object(std::uint8_t id, const std::string& s) {
  Bytes b(2 + s.size());
  b[0] = id;
  b[1] = static_cast<std::uint8_t>(s.size());
  std::copy(s.begin(), s.end(), b.begin() + 2);
  return b;
}

TEST_F(Pdu, DeviceIdentificationBasicStream_6_21) {
  EXPECT_EQ(run({0x2B, 0x0E, 0x01, 0x00}), cat({{0x2B, 0x0E, 0x01, 0x81, 0x00, 0x00, 0x03},
                                                object(0, "drivegate"),
                                                object(1, "drivegate"),
                                                object(2, "0.1.0")}));
}
TEST_F(Pdu, DeviceIdentificationStreamFromObject2_6_21) {
  EXPECT_EQ(run({0x2B, 0x0E, 0x01, 0x02}),
            cat({{0x2B, 0x0E, 0x01, 0x81, 0x00, 0x00, 0x01}, object(2, "0.1.0")}));
}
TEST_F(Pdu, DeviceIdentificationUnknownObjectInStreamRestartsAt0_6_21) {
  const Bytes r = run({0x2B, 0x0E, 0x01, 0x80});
  ASSERT_GE(r.size(), 8u);
  EXPECT_EQ(r[6], 3);  // three objects
  EXPECT_EQ(r[7], 0);  // from object 0
}
TEST_F(Pdu, DeviceIdentificationRegularAndExtendedAnswerTheBasicObjects_6_21) {
  for (std::uint8_t code : {std::uint8_t{0x02}, std::uint8_t{0x03}}) {
    const Bytes r = run({0x2B, 0x0E, code, 0x00});
    ASSERT_GE(r.size(), 7u);
    EXPECT_EQ(r[2], code);
    EXPECT_EQ(r[6], 3);
  }
}
TEST_F(Pdu, DeviceIdentificationIndividual_6_21) {
  EXPECT_EQ(run({0x2B, 0x0E, 0x04, 0x01}),
            cat({{0x2B, 0x0E, 0x04, 0x81, 0x00, 0x00, 0x01}, object(1, "drivegate")}));
  EXPECT_EQ(run({0x2B, 0x0E, 0x04, 0x03}), (Bytes{0xAB, 0x02}));  // no such object
}
TEST_F(Pdu, DeviceIdentificationBadCodeMeiAndLength_6_21) {
  EXPECT_EQ(run({0x2B, 0x0E, 0x00, 0x00}), (Bytes{0xAB, 0x03}));
  EXPECT_EQ(run({0x2B, 0x0E, 0x05, 0x00}), (Bytes{0xAB, 0x03}));
  EXPECT_EQ(run({0x2B, 0x0E, 0x01}), (Bytes{0xAB, 0x03}));
  EXPECT_EQ(run({0x2B, 0x0E, 0x01, 0x00, 0x00}), (Bytes{0xAB, 0x03}));
  EXPECT_EQ(run({0x2B, 0x0D, 0x01, 0x00}), (Bytes{0xAB, 0x01}));  // CANopen MEI: not served
  EXPECT_EQ(run({0x2B}), (Bytes{0xAB, 0x01}));
}
TEST_F(Pdu, DeviceIdentificationMoreFollowsWhenObjectsDoNotFit_6_21) {
  FakeBackend backend;
  Dispatcher d(backend, {std::string(200, 'v'), std::string(200, 'p'), std::string(200, 'r')});
  std::array<std::uint8_t, kMaxPduSize> out{};
  const Bytes req{0x2B, 0x0E, 0x01, 0x00};
  auto r = d.handle(session_, 1, req, out, {});
  ASSERT_EQ(r.size, 7u + 2 + 200);
  EXPECT_EQ(out[4], 0xFF);  // more follows
  EXPECT_EQ(out[5], 0x01);  // next object id
  EXPECT_EQ(out[6], 1);
  const Bytes next{0x2B, 0x0E, 0x01, 0x01};
  r = d.handle(session_, 1, next, out, {});
  EXPECT_EQ(out[4], 0xFF);
  EXPECT_EQ(out[5], 0x02);
  EXPECT_EQ(out[7], 0x01);
  const Bytes last{0x2B, 0x0E, 0x01, 0x02};
  r = d.handle(session_, 1, last, out, {});
  EXPECT_EQ(out[4], 0x00);
  EXPECT_EQ(out[6], 1);
}
TEST_F(Pdu, DeviceIdentificationLongObjectIsCut_6_21) {
  FakeBackend backend;
  Dispatcher d(backend, {std::string(300, 'v'), "p", "1"});
  std::array<std::uint8_t, kMaxPduSize> out{};
  const Bytes req{0x2B, 0x0E, 0x04, 0x00};
  const auto r = d.handle(session_, 1, req, out, {});
  EXPECT_EQ(r.size, kMaxPduSize);
  EXPECT_EQ(out[8], kMaxPduSize - 9);
}

// --- quantity, byte count, length and address checks ------------------------------------

struct Check {
  const char* name;
  Bytes request;
  Bytes response;
};
void PrintTo(const Check& c, std::ostream* os) {
  *os << c.name;
}

class PduChecks : public Pdu, public ::testing::WithParamInterface<Check> {};

TEST_P(PduChecks, Answers) {
  const auto& c = GetParam();
  EXPECT_EQ(run(c.request), c.response);
}

Bytes coils_payload(std::uint16_t n) {
  return Bytes((n + 7u) / 8u, 0x00);
}
Bytes regs_payload(std::uint16_t n) {
  return Bytes(2u * n, 0x00);
}

INSTANTIATE_TEST_SUITE_P(
    ApplicationProtocol, PduChecks,
    ::testing::Values(
        // 6.1 read coils: 1..2000, start + quantity <= 65536
        Check{"fc01_qty0", cat({{0x01}, regs(0x0500, 0)}), {0x81, 0x03}},
        Check{"fc01_qty2001", cat({{0x01}, regs(0x0500, 2001)}), {0x81, 0x03}},
        Check{"fc01_overflow", cat({{0x01}, regs(0xFFFF, 2)}), {0x81, 0x02}},
        Check{"fc01_unmapped", cat({{0x01}, regs(0xFFFF, 1)}), {0x81, 0x02}},
        Check{"fc01_short", {0x01, 0x00, 0x00, 0x01}, {0x81, 0x03}},
        Check{"fc01_long", {0x01, 0x00, 0x00, 0x00, 0x01, 0x00}, {0x81, 0x03}},
        // 6.2 read discrete inputs: 1..2000
        Check{"fc02_qty0", cat({{0x02}, regs(0, 0)}), {0x82, 0x03}},
        Check{"fc02_qty2001", cat({{0x02}, regs(0x0500, 2001)}), {0x82, 0x03}},
        Check{"fc02_overflow", cat({{0x02}, regs(0xFFF0, 0x20)}), {0x82, 0x02}},
        Check{"fc02_hole", cat({{0x02}, regs(0x03FF, 2)}), {0x82, 0x02}},
        // 6.3 / 6.4 read registers: 1..125
        Check{"fc03_qty0", cat({{0x03}, regs(0, 0)}), {0x83, 0x03}},
        Check{"fc03_qty126", cat({{0x03}, regs(0, 126)}), {0x83, 0x03}},
        Check{"fc03_overflow", cat({{0x03}, regs(0xFFF0, 0x11)}), {0x83, 0x02}},
        Check{"fc03_short", {0x03, 0x00}, {0x83, 0x03}},
        Check{"fc04_qty0", cat({{0x04}, regs(0, 0)}), {0x84, 0x03}},
        Check{"fc04_qty126", cat({{0x04}, regs(0, 126)}), {0x84, 0x03}},
        Check{"fc04_overflow", cat({{0x04}, regs(0xFF84, 125)}), {0x84, 0x02}},
        Check{"fc04_function_only", {0x04}, {0x84, 0x03}},
        // 6.5 write single coil: FF00 or 0000 only
        Check{"fc05_value", {0x05, 0x00, 0x01, 0x12, 0x34}, {0x85, 0x03}},
        Check{"fc05_value_00ff", {0x05, 0x00, 0x01, 0x00, 0xFF}, {0x85, 0x03}},
        Check{"fc05_short", {0x05, 0x00, 0x01, 0xFF}, {0x85, 0x03}},
        Check{"fc05_hole", {0x05, 0x04, 0x00, 0xFF, 0x00}, {0x85, 0x02}},
        // 6.6 write single register
        Check{"fc06_long", {0x06, 0x00, 0x01, 0x00, 0x03, 0x00}, {0x86, 0x03}},
        Check{"fc06_unmapped", {0x06, 0xFF, 0xFF, 0x00, 0x03}, {0x86, 0x02}},
        // 6.11 write multiple coils: 1..1968, byte count = ceil(N / 8)
        Check{"fc15_qty0", cat({{0x0F}, regs(0, 0), {0x00}}), {0x8F, 0x03}},
        Check{
            "fc15_qty1969", cat({{0x0F}, regs(0, 1969), {247}, coils_payload(1969)}), {0x8F, 0x03}},
        Check{"fc15_byte_count", cat({{0x0F}, regs(0, 10), {0x01, 0xCD}}), {0x8F, 0x03}},
        Check{"fc15_truncated", cat({{0x0F}, regs(0, 10), {0x02, 0xCD}}), {0x8F, 0x03}},
        Check{"fc15_extra", cat({{0x0F}, regs(0, 10), {0x02, 0xCD, 0x01, 0x00}}), {0x8F, 0x03}},
        Check{"fc15_short", {0x0F, 0x00, 0x00, 0x00, 0x01}, {0x8F, 0x03}},
        Check{"fc15_overflow", cat({{0x0F}, regs(0xFFFF, 2), {0x01, 0x03}}), {0x8F, 0x02}},
        // 6.12 write multiple registers: 1..123, byte count = 2N
        Check{"fc16_qty0", cat({{0x10}, regs(0, 0), {0x00}}), {0x90, 0x03}},
        Check{"fc16_qty124", cat({{0x10}, regs(0, 124), {248}, regs_payload(124)}), {0x90, 0x03}},
        Check{"fc16_byte_count", cat({{0x10}, regs(0, 2), {0x03, 0, 0, 0}}), {0x90, 0x03}},
        Check{"fc16_truncated", cat({{0x10}, regs(0, 2), {0x04, 0, 0, 0}}), {0x90, 0x03}},
        Check{"fc16_overflow", cat({{0x10}, regs(0xFFFF, 2), {0x04, 0, 0, 0, 0}}), {0x90, 0x02}},
        Check{"fc16_unmapped", cat({{0x10}, regs(0x1000, 1), {0x02, 0, 0}}), {0x90, 0x02}},
        // 6.17 read / write multiple registers: read 1..125, write 1..121, byte count = 2N
        Check{"fc23_read0", cat({{0x17}, regs(0, 0), regs(0, 1), {0x02, 0, 0}}), {0x97, 0x03}},
        Check{"fc23_read126", cat({{0x17}, regs(0, 126), regs(0, 1), {0x02, 0, 0}}), {0x97, 0x03}},
        Check{"fc23_write0", cat({{0x17}, regs(0, 1), regs(0, 0), {0x00}}), {0x97, 0x03}},
        Check{"fc23_write122",
              cat({{0x17}, regs(0, 1), regs(0, 122), {244}, regs_payload(122)}),
              {0x97, 0x03}},
        Check{"fc23_byte_count", cat({{0x17}, regs(0, 1), regs(0, 1), {0x01, 0, 0}}), {0x97, 0x03}},
        Check{"fc23_truncated", cat({{0x17}, regs(0, 1), regs(0, 1), {0x02, 0}}), {0x97, 0x03}},
        Check{"fc23_short", cat({{0x17}, regs(0, 1), regs(0, 1)}), {0x97, 0x03}},
        Check{"fc23_read_overflow",
              cat({{0x17}, regs(0xFFFF, 2), regs(0, 1), {0x02, 0, 0}}),
              {0x97, 0x02}},
        Check{"fc23_write_overflow",
              cat({{0x17}, regs(0, 1), regs(0xFFFF, 2), {0x04, 0, 0, 0, 0}}),
              {0x97, 0x02}},
        Check{"fc23_read_unmapped",
              cat({{0x17}, regs(0x0400, 1), regs(0, 1), {0x02, 0, 0}}),
              {0x97, 0x02}},
        // section 7, code 01: functions not served
        Check{"fc00", {0x00}, {0x80, 0x01}}, Check{"fc07", {0x07}, {0x87, 0x01}},
        Check{"fc08_diagnostics", {0x08, 0x00, 0x00, 0x12, 0x34}, {0x88, 0x01}},
        Check{"fc11_report_id", {0x11}, {0x91, 0x01}},
        Check{"fc14_file_record", {0x14, 0x00}, {0x94, 0x01}}, Check{"fc7f", {0x7F}, {0xFF, 0x01}},
        Check{"fc80", {0x80, 0x01}, {0x80, 0x01}}, Check{"fcff", {0xFF}, {0xFF, 0x01}}),
    [](const auto& p) { return std::string(p.param.name); });

TEST_F(Pdu, LargestQuantitiesAreServed) {
  EXPECT_EQ(run(cat({{0x01}, regs(0x0500, 2000)})).size(), 2u + 250);
  EXPECT_EQ(run(cat({{0x02}, regs(0x0500, 2000)})).size(), 2u + 250);
  EXPECT_EQ(run(cat({{0x03}, regs(0, 125)})).size(), 2u + 250);
  EXPECT_EQ(run(cat({{0x04}, regs(0, 125)})).size(), 2u + 250);
  EXPECT_EQ(run(cat({{0x0F}, regs(0x0500, 1968), {246}, coils_payload(1968)})),
            cat({{0x0F}, regs(0x0500, 1968)}));
  EXPECT_EQ(run(cat({{0x10}, regs(0, 123), {246}, regs_payload(123)})),
            cat({{0x10}, regs(0, 123)}));
  EXPECT_EQ(run(cat({{0x17}, regs(0, 125), regs(0, 121), {242}, regs_payload(121)})).size(),
            2u + 250);
  // The last address of the table with quantity 1 is not an overflow.
  EXPECT_EQ(run(cat({{0x03}, regs(0xFFFF, 1)})), (Bytes{0x83, 0x02}));  // unmapped here, not 03
}

TEST_F(Pdu, UnknownUnitIsGatewayPathUnavailable) {
  EXPECT_EQ(run({0x03, 0x00, 0x00, 0x00, 0x01}, 9), (Bytes{0x83, 0x0A}));
  EXPECT_EQ(run({0x06, 0x00, 0x00, 0x00, 0x01}, 9), (Bytes{0x86, 0x0A}));
  EXPECT_EQ(run({0x01, 0x00, 0x00, 0x00, 0x01}, 0), (Bytes{0x81, 0x0A}));
}

TEST_F(Pdu, SynchronousRefusalIsAnsweredAtOnceAndDoneIsNotUsed) {
  backend_.reject_value = 0x7777;
  EXPECT_EQ(run({0x06, 0x00, 0x01, 0x77, 0x77}), (Bytes{0x86, 0x03}));
  EXPECT_FALSE(pending_);
  EXPECT_FALSE(done_.has_value());
}

TEST_F(Pdu, DeferredWriteIsPendingUntilDone) {
  backend_.mode = FakeBackend::Mode::deferred;
  EXPECT_EQ(run({0x06, 0x00, 0x01, 0x00, 0x03}), Bytes{});
  EXPECT_TRUE(pending_);
  EXPECT_FALSE(done_.has_value());
  backend_.complete();
  EXPECT_EQ(finish(), (Bytes{0x06, 0x00, 0x01, 0x00, 0x03}));
}

TEST_F(Pdu, DeviceRefusalAndTimeoutBecomeExceptions) {
  backend_.mode = FakeBackend::Mode::deferred;
  run({0x05, 0x00, 0x01, 0xFF, 0x00});
  backend_.complete(Exception::server_device_failure);  // the drive said no
  EXPECT_EQ(finish(), (Bytes{0x85, 0x04}));
  run({0x10, 0x00, 0x01, 0x00, 0x01, 0x02, 0x00, 0x01});
  backend_.complete(Exception::gateway_target_failed);  // the drive did not answer
  EXPECT_EQ(finish(), (Bytes{0x90, 0x0B}));
  run(cat({{0x17}, regs(3, 1), regs(0, 1), {0x02, 0, 0}}));
  backend_.complete(Exception::gateway_target_failed);
  EXPECT_EQ(finish(), (Bytes{0x97, 0x0B}));
  EXPECT_EQ(backend_.table(Table::coil)[1], 0);
}

// 6.17: a read range that cannot be served is refused before the write starts, so the write is
// never applied (before the fix the setpoint changed and the client saw 0x97 0x02).
TEST_F(Pdu, ReadWriteWithAnUnmappedReadRangeWritesNothing_6_17) {
  auto& holding = backend_.table(Table::holding);
  // Read 0x03FF..0x0400 (0x0400 is in the hole), write 0x0010 = 0x1234.
  EXPECT_EQ(run(cat({{0x17}, regs(0x03FF, 2), regs(0x0010, 1), {0x02, 0x12, 0x34}})),
            (Bytes{0x97, 0x02}));
  EXPECT_FALSE(pending_);
  EXPECT_FALSE(done_.has_value());
  EXPECT_TRUE(backend_.writes.empty());
  EXPECT_EQ(holding[0x10], 0);
  // A deferred backend is not even asked: nothing waits for a device.
  backend_.mode = FakeBackend::Mode::deferred;
  EXPECT_EQ(run(cat({{0x17}, regs(0x04FF, 1), regs(0x0010, 1), {0x02, 0x12, 0x34}})),
            (Bytes{0x97, 0x02}));
  EXPECT_TRUE(backend_.writes.empty());
  EXPECT_TRUE(backend_.pending.empty());
}

TEST_F(Pdu, ReadWriteWithAReadRangePastTheTableEndWritesNothing_6_17) {
  // 0xFF84 + 125 = 65537 > 65536: 0x02 without asking the backend for anything.
  EXPECT_EQ(run(cat({{0x17}, regs(0xFF84, 125), regs(0x0010, 1), {0x02, 0x12, 0x34}})),
            (Bytes{0x97, 0x02}));
  // 0x0FFF + 2 is within 65536 but past the fake's 4096-entry image: the backend's own 0x02.
  EXPECT_EQ(run(cat({{0x17}, regs(0x0FFF, 2), regs(0x0010, 1), {0x02, 0x12, 0x34}})),
            (Bytes{0x97, 0x02}));
  EXPECT_TRUE(backend_.writes.empty());
  EXPECT_EQ(backend_.table(Table::holding)[0x10], 0);
}

TEST_F(Pdu, ReadWriteWithAnUnknownUnitWritesNothing_6_17) {
  EXPECT_EQ(run(cat({{0x17}, regs(3, 1), regs(0x0010, 1), {0x02, 0x12, 0x34}}), 9),
            (Bytes{0x97, 0x0A}));
  EXPECT_TRUE(backend_.writes.empty());
}

TEST_F(Pdu, ReadWriteWithAGoodReadRangeStillWritesThenReads_6_17) {
  backend_.mode = FakeBackend::Mode::deferred;
  // Read 0x0F..0x11, write 0x10..0x11: pending until the drive confirms.
  EXPECT_EQ(run(cat({{0x17}, regs(0x0F, 3), regs(0x10, 2), {0x04, 0x12, 0x34, 0x56, 0x78}})),
            Bytes{});
  EXPECT_TRUE(pending_);
  ASSERT_EQ(backend_.writes.size(), 1u);
  EXPECT_EQ(backend_.writes[0].address, 0x10);
  EXPECT_EQ(backend_.writes[0].values, (std::vector<std::uint16_t>{0x1234, 0x5678}));
  backend_.complete();
  EXPECT_EQ(finish(), (Bytes{0x17, 0x06, 0x00, 0x00, 0x12, 0x34, 0x56, 0x78}));
}

// The longest write beside the longest read: the read range check must not clobber the values.
TEST_F(Pdu, ReadWriteLargestQuantitiesKeepTheWriteValues_6_17) {
  Bytes payload;
  for (std::uint16_t i = 0; i < 121; ++i) {
    payload.push_back(static_cast<std::uint8_t>(0xA0 | (i >> 8)));
    payload.push_back(static_cast<std::uint8_t>(i));
  }
  const Bytes r = run(cat({{0x17}, regs(0x0200, 125), regs(0x0200, 121), {242}, payload}));
  ASSERT_EQ(r.size(), 2u + 250);
  ASSERT_EQ(backend_.writes.size(), 1u);
  for (std::uint16_t i = 0; i < 121; ++i) {
    EXPECT_EQ(backend_.writes[0].values[i], 0xA000 | i) << i;
    EXPECT_EQ(r[2 + 2 * i], 0xA0 | (i >> 8)) << i;
    EXPECT_EQ(r[3 + 2 * i], static_cast<std::uint8_t>(i)) << i;
  }
}

TEST_F(Pdu, ReadsAreServedWhileAWriteIsPending) {
  backend_.mode = FakeBackend::Mode::deferred;
  run({0x06, 0x00, 0x6B, 0x00, 0x07});
  const Bytes write_request = request_;
  EXPECT_EQ(run({0x03, 0x00, 0x6B, 0x00, 0x01}), (Bytes{0x03, 0x02, 0x02, 0x2B}));
  request_ = write_request;
  backend_.complete();
  EXPECT_EQ(finish(), (Bytes{0x06, 0x00, 0x6B, 0x00, 0x07}));
  EXPECT_EQ(run({0x03, 0x00, 0x6B, 0x00, 0x01}), (Bytes{0x03, 0x02, 0x00, 0x07}));
}

// --- access levels (Modbus/TCP Security: an unauthorised request is exception 01) ----------

TEST_F(Pdu, AReadOnlySessionGetsException01ForEveryWriteFunctionAndTheBackendSeesNone) {
  session_.access = AccessLevel::read;
  const std::vector<Bytes> writes = {
      {0x05, 0x00, 0xAC, 0xFF, 0x00},
      {0x06, 0x00, 0x01, 0x00, 0x03},
      {0x0F, 0x00, 0x13, 0x00, 0x0A, 0x02, 0xCD, 0x01},
      {0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02},
      {0x17, 0x00, 0x03, 0x00, 0x06, 0x00, 0x0E, 0x00, 0x03, 0x06, 0x00, 0xFF, 0x00, 0xFF, 0x00,
       0xFF},
      // Malformed too: the access check comes first, so nothing about the request is revealed.
      {0x10, 0x00, 0x01, 0x00, 0x00},
  };
  for (const Bytes& w : writes) {
    EXPECT_EQ(run(w), (Bytes{static_cast<std::uint8_t>(w[0] | 0x80), 0x01})) << int{w[0]};
    EXPECT_TRUE(denied_);
  }
  EXPECT_TRUE(backend_.writes.empty());
  EXPECT_EQ(backend_.reads, 0u);  // not even 0x17's read range was looked at
  // Reads are served as before.
  EXPECT_EQ(run({0x04, 0x00, 0x08, 0x00, 0x01}), (Bytes{0x04, 0x02, 0x00, 0x0A}));
  EXPECT_FALSE(denied_);
  EXPECT_EQ(backend_.last_session.access, AccessLevel::read);
}

TEST_F(Pdu, AnOperateSessionIsRefusedWhatTheBackendReservesForMaintain) {
  session_.access = AccessLevel::operate;
  backend_.maintain_from = 0x0100;
  EXPECT_EQ(run({0x06, 0x00, 0x01, 0x00, 0x03}), (Bytes{0x06, 0x00, 0x01, 0x00, 0x03}));
  EXPECT_FALSE(denied_);
  EXPECT_EQ(run({0x10, 0x00, 0xFF, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02}), (Bytes{0x90, 0x01}));
  EXPECT_TRUE(denied_);
  EXPECT_EQ(backend_.writes.size(), 1u);
  session_.access = AccessLevel::maintain;
  EXPECT_EQ(run({0x10, 0x00, 0xFF, 0x00, 0x02, 0x04, 0x00, 0x0A, 0x01, 0x02}),
            (Bytes{0x10, 0x00, 0xFF, 0x00, 0x02}));
  EXPECT_FALSE(denied_);
}

TEST_F(Pdu, TheSessionReachesTheBackendWithEveryRead) {
  session_.word_order = WordOrder::little;
  run({0x03, 0x00, 0x6B, 0x00, 0x01});
  EXPECT_EQ(backend_.last_session.word_order, WordOrder::little);
}

TEST(PduMayWrite, OnlyWritingFunctions) {
  for (int fc = 0; fc < 256; ++fc) {
    const bool expected = fc == 0x05 || fc == 0x06 || fc == 0x0F || fc == 0x10 || fc == 0x17;
    EXPECT_EQ(may_write(static_cast<std::uint8_t>(fc)), expected) << fc;
  }
}

}  // namespace
}  // namespace drivegate::modbus::pdu_test
