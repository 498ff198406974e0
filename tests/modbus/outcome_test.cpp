// The gateway's outcomes (gateway/outcome.h) as its northbounds say them: one Modbus exception per
// outcome and one outcome per exception (modbus/modbus_exception.h), the codes clients got before
// the gateway had outcomes of its own; a DCMD's result naming the same exception; and a denied
// write reaching the wire as exception 0x01 through the daemon's own Modbus backend.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <array>
#include <boost/asio/io_context.hpp>
#include <set>
#include <utility>
#include <vector>

#include "fake_adapter.h"
#include "gateway/gateway.h"
#include "modbus/backend_switch.h"
#include "modbus/modbus_exception.h"
#include "modbus/pdu.h"
#include "mqtt/command_result.h"
#include "one_fake_device.h"

namespace drivegate {
namespace {

using modbus::Exception;

// Every outcome, in enum order, and the exception a Modbus client gets for it (Modbus Application
// Protocol V1.1b3, section 7).
constexpr std::array<std::pair<Outcome, Exception>, 8> kTable = {{
    {Outcome::ok, Exception::none},
    {Outcome::no_such_device, Exception::gateway_path_unavailable},  // 0x0A
    {Outcome::no_such_point, Exception::illegal_data_address},       // 0x02
    {Outcome::denied, Exception::illegal_function},                  // 0x01
    {Outcome::invalid_value, Exception::illegal_data_value},         // 0x03
    {Outcome::busy, Exception::server_device_busy},                  // 0x06
    {Outcome::refused, Exception::server_device_failure},            // 0x04
    {Outcome::no_response, Exception::gateway_target_failed},        // 0x0B
}};

TEST(Outcome, EachIsOneModbusExceptionAndNoTwoShareOne) {
  ASSERT_EQ(kTable.size(), kOutcomeNames.size());  // every outcome is in the table
  std::set<Exception> codes;
  for (std::size_t i = 0; i < kTable.size(); ++i) {
    const auto [outcome, code] = kTable[i];
    EXPECT_EQ(static_cast<std::size_t>(outcome), i);
    EXPECT_EQ(modbus_exception(outcome), code) << to_string(outcome);
    codes.insert(modbus_exception(outcome));
  }
  EXPECT_EQ(codes.size(), kTable.size());
}

// docs/mqtt.md, "Commands": `ok`, or the exception's code and its name in the specification.
TEST(Outcome, ADcmdResultNamesTheExceptionAModbusClientGets) {
  for (const auto& [outcome, code] : kTable) {
    const std::string expected =
        outcome == Outcome::ok ? "ok"
                               : fmt::format("exception 0x{:02X} ({})", static_cast<unsigned>(code),
                                             modbus::to_string(code));
    EXPECT_EQ(mqtt::command_result(outcome), expected) << to_string(outcome);
  }
}

// An operate client writing an adapter point (maintain's): the gateway denies it, and the bytes
// the connection sends are the exception response 0x90 0x01, counted as a denied write.
TEST(Outcome, ADeniedWriteReachesTheWireAsException01) {
  test::OneFakeDevice fake;  // never opened: the gateway judges the write before any line
  Gateway* gateway = fake.gateway();
  ASSERT_NE(gateway, nullptr);
  gateway->start();
  BackendSwitch backend;
  backend.set(gateway);
  modbus::Dispatcher dispatcher(backend, {});

  const MappedPoint* limit = gateway->find("d1")->map().find("limit");  // u32, holding
  ASSERT_NE(limit, nullptr);
  const auto hi = static_cast<std::uint8_t>(limit->address >> 8);
  const auto lo = static_cast<std::uint8_t>(limit->address & 0xFF);
  // Write multiple registers (6.12): two registers, four bytes, the value 50.
  const std::vector<std::uint8_t> request = {0x10, hi, lo, 0x00, 0x02, 0x04, 0x00, 0x00, 0x00, 50};
  std::array<std::uint8_t, modbus::kMaxPduSize> out{};
  bool answered_later = false;
  const auto r = dispatcher.handle({AccessLevel::operate, WordOrder::big}, 1, request, out,
                                   [&](Exception) { answered_later = true; });

  ASSERT_EQ(r.status, modbus::Dispatcher::Result::Status::reply);
  EXPECT_EQ(std::vector<std::uint8_t>(out.begin(), out.begin() + r.size),
            (std::vector<std::uint8_t>{0x90, 0x01}));
  EXPECT_TRUE(r.denied);  // the server's writes_denied
  EXPECT_FALSE(answered_later);
  EXPECT_EQ(gateway->find("d1")->writes_in_flight(), 0u);  // nothing reached the driver
  gateway->stop();
}

}  // namespace
}  // namespace drivegate
