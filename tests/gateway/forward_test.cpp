// Pass-through requests at the device (Device::forward, gateway/forward_access.h): every refusal
// is in the audit trail with its reason and never reaches the driver, a whole read is forwarded
// and not recorded, a write is, and reads never lock writes out of the device's queue. On the
// real device with a forwarding fake driver and clock.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include "fake_adapter.h"
#include "gateway/device.h"
#include "rtu_frames.h"

namespace drivegate::forward_test {
namespace {

using namespace std::chrono_literals;
using test::joined;
using test::with_crc;
using ::testing::HasSubstr;

constexpr std::uint8_t kSlave = 9;

// A write a slave at 1 would run: holding 0x2000 := 0x001E.
const Bytes kRun = with_crc({0x01, 0x06, 0x20, 0x00, 0x00, 0x1E});

// The real device: a pass-through one (the fake driver forwards), with its history.
class ForwardTest : public ::testing::Test {
 protected:
  void SetUp() override {
    DeviceConfig cfg;
    cfg.name = "window";
    cfg.unit_id = 12;
    cfg.address = kSlave;
    auto driver = std::make_unique<test::FakeDriver>(DeviceEnv{});
    driver->traits_.write_timeout = 60s;
    driver->common_.ready = true;
    driver->forwarding = true;
    fake_ = driver.get();
    device_ = std::make_unique<Device>(
        cfg, test::kFakeAdapter, std::move(driver),
        std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>()), t0_,
        &history_);
    device_->link().health.frame_good(t0_);
  }
  static Session client(AccessLevel access) {
    return Session{
        access, WordOrder::big, true,
        Source{.kind = SourceKind::modbus, .listener = "0.0.0.0:502", .client = "192.0.2.7:50122"}};
  }
  Outcome forward(AccessLevel access, const Bytes& pdu) {
    return device_->forward(
        client(access), pdu,
        [this](Outcome o, std::span<const std::uint8_t>) { answers_.push_back(o); }, t0_);
  }
  // The driver answers the request it is carrying out with `reply`.
  void answer(const Bytes& reply) {
    fake_->completions.push_back({fake_->last_ticket, WriteResult::ok, reply});
    device_->next_exchange(t0_, Turn::poll);
  }
  std::vector<Event> commands() { return history_.events().query({.kind = EventKind::command}); }

  History history_{100};
  TimePoint t0_ = TimePoint{} + std::chrono::hours(1);
  test::FakeDriver* fake_ = nullptr;
  std::unique_ptr<Device> device_;
  std::vector<Outcome> answers_;
};

TEST_F(ForwardTest, AReadClientsMalformedReadIsRefusedAtOnceAndAudited) {
  const Bytes trailing = joined({{0x03, 0x00, 0x00, 0x00, 0x01}, kRun});
  EXPECT_EQ(forward(AccessLevel::read, trailing), Outcome::invalid_value);
  EXPECT_TRUE(fake_->forwarded.empty());  // never handed to the driver
  const auto c = commands();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].device, "window");
  EXPECT_EQ(c[0].field("result"), "invalid_value");
  EXPECT_EQ(c[0].field("points"), Device::describe_pdu(trailing));
  EXPECT_THAT(std::string(c[0].field("why")), HasSubstr("13 bytes where its length is 5"));
  EXPECT_TRUE(answers_.empty());  // refused at once: the return value is the answer
}

TEST_F(ForwardTest, AFunctionOfUnknownLengthIsDeniedEvenToMaintainAndAudited) {
  EXPECT_EQ(forward(AccessLevel::maintain, {0x41, 0x12, 0x34}), Outcome::denied);
  EXPECT_TRUE(fake_->forwarded.empty());
  const auto c = commands();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].field("result"), "denied");
  EXPECT_THAT(std::string(c[0].field("why")), HasSubstr("its length is unknown"));
}

TEST_F(ForwardTest, AWholeReadIsForwardedUnrecordedAndAWriteIsRecordedWhenItSettles) {
  ASSERT_EQ(forward(AccessLevel::read, {0x03, 0x00, 0x00, 0x00, 0x01}), Outcome::ok);
  ASSERT_EQ(fake_->forwarded.size(), 1u);
  answer({0x03, 0x02, 0x00, 0x07});
  EXPECT_TRUE(commands().empty());  // a read is not a write
  ASSERT_EQ(forward(AccessLevel::maintain, {0x06, 0x00, 0x01, 0x00, 0x03}), Outcome::ok);
  ASSERT_EQ(fake_->forwarded.size(), 2u);
  answer({0x06, 0x00, 0x01, 0x00, 0x03});
  const auto c = commands();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].field("points"), "pdu 06 00 01 00 03");
  EXPECT_EQ(c[0].field("result"), "ok");
  EXPECT_EQ(answers_, (std::vector<Outcome>{Outcome::ok, Outcome::ok}));
}

// Reads fill their places (and are refused busy past them); a write from a maintain client
// still finds one of its own, and is carried out once the reads ahead of it are answered.
TEST_F(ForwardTest, ReadsFillingTheQueueNeverRefuseAWriteBusy) {
  const Bytes read = {0x03, 0x00, 0x00, 0x00, 0x01};
  for (std::size_t i = 0; i < kMaxQueuedWrites; ++i) {
    ASSERT_EQ(forward(AccessLevel::read, read), Outcome::ok);
  }
  EXPECT_EQ(forward(AccessLevel::read, read), Outcome::busy);
  const Bytes write = {0x06, 0x00, 0x01, 0x00, 0x03};
  ASSERT_EQ(forward(AccessLevel::maintain, write), Outcome::ok);
  for (std::size_t i = 0; i < kMaxQueuedWrites; ++i) answer({0x03, 0x02, 0x00, 0x07});
  ASSERT_EQ(fake_->forwarded.size(), kMaxQueuedWrites + 1);
  EXPECT_EQ(fake_->forwarded.back(), write);
  answer(write);
  EXPECT_EQ(answers_.back(), Outcome::ok);
  // Writes have as many places as reads, and no more.
  for (std::size_t i = 0; i < kMaxQueuedWrites; ++i) {
    ASSERT_EQ(forward(AccessLevel::maintain, write), Outcome::ok);
  }
  EXPECT_EQ(forward(AccessLevel::maintain, write), Outcome::busy);
}

}  // namespace
}  // namespace drivegate::forward_test
