// WriteLedger (include/drivegate/write_ledger.h): the bookkeeping of writes on their way to a
// drive that every driver keeps, and attempts_before().
#include "drivegate/write_ledger.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "drivegate/driver_base.h"

namespace drivegate {
namespace {

using ::testing::ElementsAre;
using namespace std::chrono_literals;

struct Job {
  std::string what;
};

const TimePoint t0{};

std::vector<Completion> taken(WriteLedger<Job>& w) {
  std::vector<Completion> out;
  w.take_completions(out);
  return out;
}

MATCHER_P2(Is, ticket, result, "") {
  return arg.ticket == static_cast<Ticket>(ticket) && arg.result == result;
}

TEST(WriteLedger, SettlesInTheOrderAskedEveryTicketOnce) {
  WriteLedger<Job> w;
  w.push({"run"}, 1, t0 + 2500ms);
  w.push({"setpoint"}, 2, t0 + 2600ms);
  EXPECT_EQ(w.size(), 2u);
  EXPECT_EQ(w.front().job.what, "run");
  w.settle_front(WriteResult::ok);
  EXPECT_THAT(taken(w), ElementsAre(Is(1, WriteResult::ok)));
  EXPECT_TRUE(taken(w).empty());  // handed over once
  w.settle_front(WriteResult::refused);
  EXPECT_THAT(taken(w), ElementsAre(Is(2, WriteResult::refused)));
  EXPECT_TRUE(w.empty());
  w.settle_front(WriteResult::ok);  // nothing left: nothing settles
  EXPECT_TRUE(taken(w).empty());
}

TEST(WriteLedger, AJoinedTicketSettlesWithTheEntryItJoined) {
  WriteLedger<Job> w;
  auto& e = w.push({"run"}, 1, t0 + 1s);
  w.join(e, 7);
  w.settle_front(WriteResult::ok);
  EXPECT_THAT(taken(w), ElementsAre(Is(1, WriteResult::ok), Is(7, WriteResult::ok)));
}

TEST(WriteLedger, ExpiresAtTheDeadlineNotBefore) {
  WriteLedger<Job> w;
  w.push({"a"}, 1, t0 + 2500ms);
  w.push({"b"}, 2, t0 + 1000ms);
  EXPECT_EQ(w.next_deadline(), t0 + 1000ms);
  EXPECT_EQ(w.expire(t0 + 999ms), 0u);
  EXPECT_EQ(w.expire(t0 + 1000ms), 1u);
  EXPECT_THAT(taken(w), ElementsAre(Is(2, WriteResult::no_response)));
  EXPECT_EQ(w.front().job.what, "a");
  EXPECT_EQ(w.next_deadline(), t0 + 2500ms);
  EXPECT_EQ(w.expire(t0 + 3000ms), 1u);
  EXPECT_FALSE(w.next_deadline().has_value());
}

TEST(WriteLedger, SupersedingLeavesTheOneOnTheLine) {
  WriteLedger<Job> w;
  w.push({"on the line"}, 1, t0 + 1s).sent = true;
  w.push({"waiting"}, 2, t0 + 1s);
  w.push({"waiting too"}, 3, t0 + 1s);
  EXPECT_TRUE(w.front_on_line());
  EXPECT_EQ(w.settle_unsent(), 2u);
  EXPECT_THAT(taken(w),
              ElementsAre(Is(2, WriteResult::no_response), Is(3, WriteResult::no_response)));
  EXPECT_EQ(w.size(), 1u);
  EXPECT_EQ(w.first_unsent(), nullptr);
  EXPECT_EQ(w.settle_all(), 1u);
  EXPECT_THAT(taken(w), ElementsAre(Is(1, WriteResult::no_response)));
}

TEST(WriteLedger, TheDriverHearsOfEachEntryAfterItLeftTheQueue) {
  std::vector<std::string> heard;
  WriteLedger<Job>* self = nullptr;
  WriteLedger<Job> w([&](const WriteLedger<Job>::Entry& e, WriteResult r) {
    heard.push_back(e.job.what + (r == WriteResult::ok ? " ok" : " failed"));
    EXPECT_EQ(self->size(), 0u);  // already gone when the driver hears of it
  });
  self = &w;
  w.push({"action"}, 1, t0 + 1s);
  w.settle_front(WriteResult::ok);
  w.push({"action"}, 2, t0 + 1s);
  w.expire(t0 + 2s);
  EXPECT_THAT(heard, ElementsAre("action ok", "action failed"));
}

TEST(WriteLedger, AnUndoWithoutTicketsGoesFirstAndSettlesSilently) {
  WriteLedger<Job> w;
  w.push({"setpoint"}, 4, t0 + 1s);
  w.push_front({"undo"}, {}, t0 + 1s);
  EXPECT_EQ(w.first_unsent()->job.what, "undo");
  w.settle_front(WriteResult::ok);
  EXPECT_TRUE(taken(w).empty());
  w.complete(9, WriteResult::refused);  // settled without an entry of its own
  EXPECT_TRUE(w.has_completions());
  EXPECT_THAT(taken(w), ElementsAre(Is(9, WriteResult::refused)));
}

TEST(WriteLedger, ASendByDeadlineStillSendsAtItFailsAfterIt) {
  WriteLedger<Job> w;
  w.push({"a"}, 1, t0 + 1000ms);
  w.push({"b"}, 2, t0 + 1001ms);
  EXPECT_EQ(w.expire_after(t0 + 1000ms), 0u);  // the send-by itself: still sendable
  EXPECT_EQ(w.expire_after(t0 + 1000ms + std::chrono::nanoseconds(1)), 1u);
  EXPECT_THAT(taken(w), ElementsAre(Is(1, WriteResult::no_response)));
  EXPECT_EQ(w.front().job.what, "b");
}

TEST(WriteLedger, AWriteTakenForTheLineSettlesWhenTheDriverSays) {
  std::vector<std::string> heard;
  WriteLedger<Job> w(
      [&](const WriteLedger<Job>::Entry& e, WriteResult) { heard.push_back(e.job.what); });
  w.push({"on the line"}, 1, t0 + 1s);
  w.push({"next"}, 2, t0 + 1s);
  const auto e = w.take_front();
  EXPECT_EQ(w.size(), 1u);
  EXPECT_TRUE(taken(w).empty());     // out of the queue, not settled
  EXPECT_EQ(w.expire(t0 + 2s), 1u);  // what it holds no longer includes the one taken
  EXPECT_THAT(taken(w), ElementsAre(Is(2, WriteResult::no_response)));
  w.settle(e, WriteResult::refused);
  EXPECT_THAT(taken(w), ElementsAre(Is(1, WriteResult::refused)));
  EXPECT_THAT(heard, ElementsAre("next", "on the line"));
}

TEST(WriteLedger, AForwardedRequestSettlesWithTheReplyAsItCame) {
  WriteLedger<Job> w;
  w.push({"fc 03"}, 5, t0 + 1s);
  const auto e = w.take_front();
  w.settle(e, WriteResult::ok, Bytes{0x83, 0x02});
  const auto out = taken(w);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].ticket, 5u);
  EXPECT_EQ(out[0].reply, (Bytes{0x83, 0x02}));
}

TEST(WriteLedger, TwoLedgersOfOneDriverSettleIntoItsOneList) {
  Completions done;
  WriteLedger<Job> runs(done);
  WriteLedger<Job> acks(done);
  runs.push({"run"}, 1, t0 + 1s);
  acks.push({"ack"}, 2, t0 + 1s);
  acks.settle_front(WriteResult::ok);
  runs.settle_front(WriteResult::refused);
  runs.complete(3, WriteResult::no_response);
  EXPECT_FALSE(done.empty());
  std::vector<Completion> out;
  done.take(out);
  EXPECT_THAT(out, ElementsAre(Is(2, WriteResult::ok), Is(1, WriteResult::refused),
                               Is(3, WriteResult::no_response)));
  EXPECT_TRUE(done.empty());
  EXPECT_FALSE(runs.has_completions());
}

TEST(Refusal, ApplyAnswersWhatTheJudgementSaid) {
  EXPECT_FALSE(refusal(WriteCheck::ok).has_value());
  EXPECT_EQ(refusal(WriteCheck::invalid_value), WriteStatus::invalid_value);
  EXPECT_EQ(refusal(WriteCheck::refused), WriteStatus::refused);
}

TEST(AttemptsBefore, OnlyTheAttemptsThatStartBeforeTheDeadlineAndAlwaysOne) {
  // 215 ms an attempt (nidec-washer: frame and echo, 100 ms timeout, guard, gap).
  const Millis per{215};
  EXPECT_EQ(attempts_before(t0 + 2500ms, t0, per, 3), 3);
  EXPECT_EQ(attempts_before(t0 + 430ms, t0, per, 3), 2);
  EXPECT_EQ(attempts_before(t0 + 431ms, t0, per, 3), 3);
  EXPECT_EQ(attempts_before(t0 + 1ms, t0, per, 3), 1);
  EXPECT_EQ(attempts_before(t0, t0 + 1s, per, 3), 1);  // past it: the one already decided on
}

}  // namespace
}  // namespace drivegate
