// SlaveHost (daemon/modbus/slave_host.h) on a manual clock, with a backend whose writes complete
// when the test says: what goes onto the master's line, and when, for every kind of request the
// issue names (docs/serial-listeners.md). The frames are the serial line codec's.
#include "modbus/slave_host.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/null_sink.h>

#include <boost/asio/io_context.hpp>
#include <optional>

#include "hand_backend.h"
#include "manual_clock.h"

namespace drivegate::slave {
namespace {

using namespace std::chrono_literals;
using modbus::Exception;
using modbus_serial::Framing;

class SlaveHostTest : public ::testing::Test {
 protected:
  static std::shared_ptr<SlavePolicy> policy(WriteReply reply, bool broadcast, AccessLevel access,
                                             Millis reply_timeout) {
    auto p = std::make_shared<SlavePolicy>();
    p->reply_timeout = reply_timeout;
    p->session.access = access;
    p->session.source.kind = SourceKind::modbus_serial;
    p->write_reply = reply;
    p->broadcast = broadcast;
    return p;
  }
  void make(WriteReply reply = WriteReply::confirmed, bool broadcast = false,
            AccessLevel access = AccessLevel::operate, Millis reply_timeout = Millis(0)) {
    auto p = policy(reply, broadcast, access, reply_timeout);
    host_ = std::make_shared<SlaveHost>(
        io_, clock_, backend_, modbus::DeviceIdentity{}, Framing::rtu, modbus::Delimit::silence,
        timing_, p, counters_, log_, "test", [this](Bytes frame) { sent_.push_back(frame); });
  }
  void receive(std::uint8_t unit, const Bytes& pdu) {
    host_->receive(modbus_serial::encode(Framing::rtu, unit, pdu));
    run_ready();
  }
  void advance(std::chrono::microseconds d) {
    clock_.advance(d);
    run_ready();
  }
  // The handlers that are due, a bounded number of them: a timer left a microsecond short of its
  // deadline on the manual clock waits that microsecond in real time and asks the clock again,
  // so poll() until nothing is ready would spin as long as real time keeps passing it (and did,
  // under AddressSanitizer).
  void run_ready() {
    for (int i = 0; i < 64 && io_.poll_one() > 0; ++i) {
    }
    io_.restart();
  }
  Bytes frame(std::uint8_t unit, const Bytes& pdu) {
    return modbus_serial::encode(Framing::rtu, unit, pdu);
  }

  // Before io_: the host's timer detaches from it as the io_context goes.
  test::ManualClock clock_;
  boost::asio::io_context io_;
  HandBackend backend_;
  const modbus::LineTiming timing_ = modbus::line_timing(19200, 11);  // t3.5 = 2006 us
  LineCounters counters_;
  std::shared_ptr<spdlog::logger> log_ =
      std::make_shared<spdlog::logger>("t", std::make_shared<spdlog::sinks::null_sink_mt>());
  std::vector<Bytes> sent_;
  std::shared_ptr<SlaveHost> host_;
};

const Bytes kRead = {0x03, 0x00, 0x10, 0x00, 0x02};           // FC 03, holding 16, 2 registers
const Bytes kReadReply = {0x03, 0x04, 0x00, 116, 0x00, 117};  // 100 + address
const Bytes kWrite = {0x06, 0x00, 0x01, 0x02, 0x58};          // FC 06, holding 1 = 600

// Serial Line 2.5.1.1: the reply starts no earlier than 3.5 characters after the request, and
// as soon as possible after that.
TEST_F(SlaveHostTest, AReadIsAnsweredOnceTheSilenceHasPassedNotBefore) {
  make();
  receive(1, kRead);
  EXPECT_TRUE(sent_.empty());
  advance(timing_.t35 - 1us);
  EXPECT_TRUE(sent_.empty());
  advance(1us);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, kReadReply)));
  EXPECT_EQ(counters_.counts.server_messages, 1U);
  EXPECT_EQ(counters_.counts.bus_messages, 1U);
}

// What the line's masters read of the drives' faults (gateway/fault_reads.h) is the host's own
// record: the same with each request, and kept when a reload changes the listener's policy.
TEST_F(SlaveHostTest, ItsRecordOfTheFaultsReadGoesWithEveryRequestAndOutlivesAReload) {
  make();
  receive(1, kRead);
  advance(1s);
  ASSERT_EQ(backend_.fault_reads.size(), 1u);
  const std::shared_ptr<FaultReads> record = backend_.fault_reads.front();
  ASSERT_NE(record, nullptr);
  host_->set_policy(policy(WriteReply::confirmed, false, AccessLevel::maintain, Millis(0)));
  receive(1, kWrite);
  ASSERT_EQ(backend_.fault_reads.size(), 2u);
  EXPECT_EQ(backend_.fault_reads.back(), record);
}

// A read of the fault state counts for what the master sends after its reply went out; one whose
// reply may not have gone out (the line went) never counts, not even once other replies did.
TEST_F(SlaveHostTest, AReadCountsOnceItsReplyWentOutNeverIfItWasDropped) {
  make();
  const Bytes read_state = {0x03, 0x00, 0x00, 0x00, 0x01};  // holding 0: kFaultState
  receive(1, read_state);
  host_->reset();  // the line went: the reply is dropped
  advance(1s);
  ASSERT_TRUE(sent_.empty());
  receive(1, kWrite);
  backend_.pending.front()(Exception::none);
  advance(1s);  // its echo goes out
  receive(1, kWrite);
  ASSERT_EQ(backend_.writes_fault_seen.size(), 2u);
  EXPECT_FALSE(backend_.writes_fault_seen[0]) << "the dropped reply's read never counts";
  EXPECT_FALSE(backend_.writes_fault_seen[1]) << "nor once another reply went out";
  backend_.pending.back()(Exception::none);
  advance(1s);

  receive(1, read_state);
  advance(timing_.t35);         // the reply goes out
  ASSERT_EQ(sent_.size(), 3u);  // the writes' echoes, this reply
  receive(1, kWrite);
  ASSERT_EQ(backend_.writes_fault_seen.size(), 3u);
  EXPECT_TRUE(backend_.writes_fault_seen.back());
}

TEST_F(SlaveHostTest, AUnitNobodyServesGetsSilence) {
  make();
  receive(9, kRead);
  advance(1s);
  EXPECT_TRUE(sent_.empty());
  EXPECT_EQ(counters_.counts.other_units, 1U);
  EXPECT_EQ(counters_.counts.server_messages, 0U);
}

TEST_F(SlaveHostTest, AConfirmedWriteIsAnsweredWhenTheDriveTookIt) {
  make();
  receive(1, kWrite);
  advance(100ms);
  EXPECT_TRUE(sent_.empty());
  ASSERT_EQ(backend_.pending.size(), 1U);
  EXPECT_EQ(backend_.writes[0].values, (std::vector<std::uint16_t>{600}));
  backend_.pending[0](Exception::none);
  advance(0us);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, kWrite)));  // the echo (6.6)
}

TEST_F(SlaveHostTest, ADriveThatDidNotAnswerIs0x0B) {
  make();
  receive(1, kWrite);
  backend_.pending[0](Exception::gateway_target_failed);
  advance(timing_.t35);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, {0x86, 0x0B})));
  EXPECT_EQ(counters_.counts.bus_exception_errors, 1U);
}

// The master gave up on the write (its timeout) and sent its next request: that one is answered,
// and the write's result, when it comes, is never put on the line, where the master would take
// it for the answer to something else.
TEST_F(SlaveHostTest, AReplyIsNeverSentLate) {
  make();
  receive(1, kWrite);
  advance(300ms);
  receive(1, kRead);
  advance(timing_.t35);
  ASSERT_THAT(sent_, ::testing::ElementsAre(frame(1, kReadReply)));
  backend_.pending[0](Exception::none);  // the drive took it after all
  advance(1s);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, kReadReply)));
  EXPECT_EQ(counters_.counts.server_no_response, 1U);
}

// reply_timeout_ms: the master's response timeout. A drive that takes the write within it is
// answered; one that takes it later is not: the master stopped listening, and a reply that
// leaves now could meet its next request on the line. The host then serves the next request.
TEST_F(SlaveHostTest, AReplyPastTheMastersResponseTimeoutIsNeverSent) {
  make(WriteReply::confirmed, false, AccessLevel::operate, 500ms);
  receive(1, kWrite);
  advance(499ms);
  backend_.pending[0](Exception::none);
  advance(0us);
  ASSERT_THAT(sent_, ::testing::ElementsAre(frame(1, kWrite)));

  receive(1, kWrite);
  advance(501ms);
  backend_.pending[1](Exception::none);  // the drive took it, too late for the master
  advance(1s);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, kWrite)));
  EXPECT_EQ(counters_.counts.server_no_response, 1U);
  // An exception is a reply like any other: too late is too late.
  receive(2, kWrite);
  advance(600ms);
  backend_.pending[2](Exception::gateway_target_failed);
  advance(1s);
  EXPECT_EQ(sent_.size(), 1U);
  EXPECT_EQ(counters_.counts.server_no_response, 2U);
  // Nothing is left waiting: the next request is served as ever.
  receive(1, kRead);
  advance(timing_.t35);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, kWrite), frame(1, kReadReply)));
  EXPECT_EQ(counters_.counts.server_no_response, 2U);
}

// The timeout counts from when the reply could first leave (3.5 characters after the request);
// a reload changes it for the requests after it, not for the one waiting.
TEST_F(SlaveHostTest, TheResponseTimeoutCountsFromTheSilenceAndAReloadAppliesToTheNextRequest) {
  make(WriteReply::confirmed, false, AccessLevel::operate, 500ms);
  receive(1, kWrite);
  advance(timing_.t35 + 500ms);  // exactly at the deadline: still in time
  backend_.pending[0](Exception::none);
  advance(0us);
  ASSERT_EQ(sent_.size(), 1U);

  receive(1, kWrite);
  host_->set_policy(policy(WriteReply::confirmed, false, AccessLevel::operate, 5s));
  advance(timing_.t35 + 501ms);
  backend_.pending[1](Exception::none);  // past the 500 ms it was taken with
  advance(0us);
  EXPECT_EQ(sent_.size(), 1U);
  receive(1, kWrite);
  advance(4s);
  backend_.pending[2](Exception::none);  // within the new 5 s
  advance(0us);
  EXPECT_EQ(sent_.size(), 2U);
}

// write_reply = accepted answers at once: the timeout has nothing to drop.
TEST_F(SlaveHostTest, AnAcceptedWriteIsAnsweredWhateverTheResponseTimeout) {
  make(WriteReply::accepted, false, AccessLevel::operate, 20ms);
  receive(1, kWrite);
  advance(timing_.t35);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, kWrite)));
  backend_.pending[0](Exception::none);
  advance(1s);
  EXPECT_EQ(counters_.counts.server_no_response, 0U);
}

// Even a retry of the very same write: answered once, for the retry.
TEST_F(SlaveHostTest, ARetriedWriteIsAnsweredOnce) {
  make();
  receive(1, kWrite);
  advance(300ms);
  receive(1, kWrite);
  ASSERT_EQ(backend_.pending.size(), 2U);
  backend_.pending[0](Exception::none);
  advance(1s);
  EXPECT_TRUE(sent_.empty());  // the first one's answer is not the retry's
  backend_.pending[1](Exception::none);
  advance(0us);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, kWrite)));
}

TEST_F(SlaveHostTest, AnAcceptedWriteIsAnsweredAtOnceAndAFailureLaterCounted) {
  make(WriteReply::accepted);
  receive(1, kWrite);
  advance(timing_.t35);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, kWrite)));
  ASSERT_EQ(backend_.pending.size(), 1U);
  backend_.pending[0](Exception::gateway_target_failed);
  advance(1s);
  EXPECT_EQ(sent_.size(), 1U);  // nothing more on the line
  EXPECT_EQ(counters_.counts.write_timeouts, 1U);
}

// The master polls on before the drive has settled the write it was told was accepted: the
// failure that comes later is still counted (and logged).
TEST_F(SlaveHostTest, AnAcceptedWritesFailureIsCountedAfterTheNextRequestsToo) {
  make(WriteReply::accepted);
  receive(1, kWrite);
  advance(timing_.t35);
  receive(1, kRead);
  advance(timing_.t35);
  ASSERT_EQ(sent_.size(), 2U);
  backend_.pending[0](Exception::gateway_target_failed);
  advance(0us);
  EXPECT_EQ(counters_.counts.write_timeouts, 1U);
  EXPECT_EQ(sent_.size(), 2U);
}

// The master talks again before the 3.5-character silence its request asked for: the exception
// reply that was due is not put over it (counted as not answered, FC 08 0x0F, not as an
// exception sent, 0x0D), and what it sent into the silence is no request either.
TEST_F(SlaveHostTest, AReplyNotSentIsNotCountedAsSent) {
  make();
  receive(1, {0x03, 0x00, 0x10, 0x00, 0x00});  // quantity 0: exception 03, due after t3.5
  advance(timing_.t35 / 2);
  receive(1, kRead);
  advance(1s);
  EXPECT_TRUE(sent_.empty());
  EXPECT_EQ(counters_.counts.bus_exception_errors, 0U);
  EXPECT_EQ(counters_.counts.server_no_response, 1U);
  EXPECT_EQ(counters_.counts.broken_frames, 1U);
}

TEST_F(SlaveHostTest, ABroadcastReadWriteIsNoWrite) {
  make(WriteReply::confirmed, true);
  // 0x17: read holding 0 x1, write holding 1 x1 = 600 (Application Protocol 6.17).
  receive(0, {0x17, 0x00, 0x00, 0x00, 0x01, 0x00, 0x01, 0x00, 0x01, 0x02, 0x02, 0x58});
  advance(1s);
  EXPECT_TRUE(backend_.writes.empty());
  EXPECT_TRUE(sent_.empty());
}

TEST_F(SlaveHostTest, ABroadcastWriteIsRefusedUnlessAllowedAndNeverAnswered) {
  make();
  receive(0, kWrite);
  advance(1s);
  EXPECT_TRUE(sent_.empty());
  EXPECT_TRUE(backend_.writes.empty());
  EXPECT_TRUE(backend_.refused.empty());  // not a write beyond the listener's access
  EXPECT_EQ(backend_.refused_broadcasts, 1);
  EXPECT_EQ(counters_.counts.broadcasts_refused, 1U);
  EXPECT_EQ(counters_.counts.server_no_response, 1U);
  // A read to address 0 is no request at all.
  receive(0, kRead);
  advance(1s);
  EXPECT_TRUE(sent_.empty());
}

TEST_F(SlaveHostTest, ABroadcastWriteAllowedReachesEveryUnitAndIsNeverAnswered) {
  make(WriteReply::confirmed, true);
  receive(0, kWrite);
  for (auto& done : backend_.pending) done(Exception::none);
  advance(1s);
  EXPECT_TRUE(sent_.empty());
  ASSERT_EQ(backend_.writes.size(), 2U);
  EXPECT_EQ(backend_.writes[0].unit, 1);
  EXPECT_EQ(backend_.writes[1].unit, 2);
}

TEST_F(SlaveHostTest, AReadListenersWriteIs01AndReachesNoDrive) {
  make(WriteReply::confirmed, false, AccessLevel::read);
  receive(1, kWrite);
  advance(timing_.t35);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, {0x86, 0x01})));
  EXPECT_TRUE(backend_.writes.empty());
}

// FC 08 00: the request back (Application Protocol 6.8.1), after the silence.
TEST_F(SlaveHostTest, Fc08ReturnsTheQueryData) {
  make();
  receive(2, {0x08, 0x00, 0x00, 0xA5, 0x37});
  advance(timing_.t35);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(2, {0x08, 0x00, 0x00, 0xA5, 0x37})));
}

// The port closed while a reply waited for its silence: it is not sent, on this line or the
// next one opened.
TEST_F(SlaveHostTest, AReplyDueWhenTheLineWentIsDropped) {
  make();
  receive(1, kRead);
  host_->reset();
  advance(1s);
  EXPECT_TRUE(sent_.empty());
  receive(1, kRead);
  advance(timing_.t35);
  EXPECT_THAT(sent_, ::testing::ElementsAre(frame(1, kReadReply)));
}

}  // namespace
}  // namespace drivegate::slave
