// The write queue on its own (gateway/write_queue.h): every transition of a request and of what
// the driver was handed, the illegal ones refused with nothing changed, deadlines on a clock the
// test moves, and what the device asks of the line in each state.
#include "gateway/write_queue.h"

#include <gtest/gtest.h>

namespace drivegate::write_queue_test {
namespace {

using State = WriteRequest::State;
using Handed = WriteQueue::Handed;
using LastExchange = WriteQueue::LastExchange;

constexpr Millis kTimeout{500};

class WriteQueueTest : public ::testing::Test {
 protected:
  // A request of `parts` parts (a stop when `urgent`), pushed at `at`.
  WriteRequest& push(std::size_t parts, TimePoint at, bool urgent = false,
                     bool reads_only = false) {
    auto r = std::make_unique<WriteRequest>();
    r->parts.assign(parts, WritePart{nullptr, Value{}});
    r->urgent = urgent;
    r->reads_only = reads_only;
    return q_.push(std::move(r), at);
  }
  // The driver takes `r`'s next part, pending: its ticket.
  Ticket hand(WriteRequest& r, TimePoint at) {
    const Ticket t = q_.ticket();
    ++r.next;
    EXPECT_TRUE(q_.handed(r, t, at));
    return t;
  }

  TimePoint t0_ = TimePoint{} + std::chrono::hours(1);
  WriteQueue q_{kTimeout};
};

TEST_F(WriteQueueTest, APushedRequestIsQueuedDueByTheWriteTimeout) {
  WriteRequest& r = push(2, t0_);
  EXPECT_EQ(r.state(), State::queued);
  EXPECT_FALSE(r.started());
  EXPECT_FALSE(r.carried());
  EXPECT_EQ(r.deadline, t0_ + kTimeout);
  EXPECT_EQ(q_.head(), &r);
  EXPECT_EQ(q_.last_queued(), &r);
  EXPECT_EQ(q_.size(), 1u);
  // Queued at the head: it wants a write turn, whether the driver is due or not.
  EXPECT_EQ(q_.pending(false), PendingWrites::waiting);
  EXPECT_EQ(q_.pending(true), PendingWrites::waiting);
}

TEST_F(WriteQueueTest, EveryLegalTransitionOfARequest) {
  WriteRequest& r = push(3, t0_);
  // queued -> carried: due by the write timeout from the hand, not from the push.
  const Ticket first = hand(r, t0_ + Millis(100));
  EXPECT_EQ(r.state(), State::carried);
  EXPECT_EQ(r.carried(), first);
  EXPECT_TRUE(r.started());
  EXPECT_EQ(r.deadline, t0_ + Millis(100) + kTimeout);
  EXPECT_EQ(q_.carrying(first), &r);
  EXPECT_EQ(q_.last_queued(), nullptr);  // started: nothing joins it any more
  // carried -> between: the part was confirmed; the next one is due from the confirmation.
  EXPECT_TRUE(q_.confirmed(r, t0_ + Millis(300)));
  EXPECT_EQ(r.state(), State::between);
  EXPECT_FALSE(r.carried());
  EXPECT_EQ(q_.carrying(first), nullptr);
  EXPECT_EQ(r.deadline, t0_ + Millis(300) + kTimeout);
  EXPECT_TRUE(r.started());
  // between -> carried, with a new ticket.
  const Ticket second = hand(r, t0_ + Millis(400));
  EXPECT_NE(second, first);
  EXPECT_EQ(r.state(), State::carried);
  EXPECT_EQ(q_.carrying(second), &r);
  EXPECT_EQ(r.deadline, t0_ + Millis(400) + kTimeout);
  // any -> gone.
  const auto gone = q_.remove(&r);
  EXPECT_EQ(gone.get(), &r);
  EXPECT_TRUE(q_.empty());
  EXPECT_EQ(q_.carrying(second), nullptr);
  EXPECT_EQ(q_.head(), nullptr);
}

TEST_F(WriteQueueTest, IllegalTransitionsAreRefusedAndChangeNothing) {
  WriteRequest& r = push(2, t0_);
  // queued: nothing to confirm.
  EXPECT_FALSE(q_.confirmed(r, t0_ + Millis(50)));
  EXPECT_EQ(r.state(), State::queued);
  EXPECT_EQ(r.deadline, t0_ + kTimeout);
  // carried: a second part is not handed while one is carried.
  const Ticket t = hand(r, t0_ + Millis(100));
  EXPECT_FALSE(q_.handed(r, q_.ticket(), t0_ + Millis(200)));
  EXPECT_EQ(r.carried(), t);
  EXPECT_EQ(r.deadline, t0_ + Millis(100) + kTimeout);
  // between: confirmed twice is refused.
  EXPECT_TRUE(q_.confirmed(r, t0_ + Millis(300)));
  EXPECT_FALSE(q_.confirmed(r, t0_ + Millis(350)));
  EXPECT_EQ(r.state(), State::between);
  EXPECT_EQ(r.deadline, t0_ + Millis(300) + kTimeout);
  // gone: removed twice is nothing.
  EXPECT_NE(q_.remove(&r), nullptr);
  EXPECT_EQ(q_.remove(&r), nullptr);
}

TEST_F(WriteQueueTest, WhatTheDriverWasHandedUntilTheNextExchange) {
  EXPECT_EQ(q_.handed_since(), Handed::nothing);
  EXPECT_EQ(q_.last_exchange(), LastExchange::polled);
  // nothing -> part -> part_and_stop.
  WriteRequest& part = push(1, t0_);
  hand(part, t0_);
  EXPECT_EQ(q_.handed_since(), Handed::part);
  WriteRequest& stop = push(1, t0_, true);
  hand(stop, t0_);
  EXPECT_EQ(q_.handed_since(), Handed::part_and_stop);
  // any -> nothing; the exchange carried a write.
  q_.exchanged();
  EXPECT_EQ(q_.handed_since(), Handed::nothing);
  EXPECT_EQ(q_.last_exchange(), LastExchange::wrote);
  // Nothing handed since: the next exchange is a poll.
  q_.exchanged();
  EXPECT_EQ(q_.last_exchange(), LastExchange::polled);
  // nothing -> stop -> part_and_stop.
  ASSERT_TRUE(q_.confirmed(stop, t0_));
  hand(stop, t0_);
  EXPECT_EQ(q_.handed_since(), Handed::stop);
  ASSERT_TRUE(q_.confirmed(part, t0_));
  hand(part, t0_);
  EXPECT_EQ(q_.handed_since(), Handed::part_and_stop);
  // The same kind again stays where it is.
  ASSERT_TRUE(q_.confirmed(part, t0_));
  hand(part, t0_);
  EXPECT_EQ(q_.handed_since(), Handed::part_and_stop);
}

TEST_F(WriteQueueTest, TakingEveryRequestForgetsTheStopsHanded) {
  WriteRequest& stop = push(1, t0_, true);
  hand(stop, t0_);
  ASSERT_EQ(q_.handed_since(), Handed::stop);
  EXPECT_EQ(q_.take_all().size(), 1u);
  EXPECT_TRUE(q_.empty());
  EXPECT_EQ(q_.handed_since(), Handed::nothing);
  EXPECT_EQ(q_.pending(true), PendingWrites::none);

  // A queued part handed stays owed to the line: the driver still holds it.
  hand(push(1, t0_), t0_);
  hand(push(1, t0_, true), t0_);
  ASSERT_EQ(q_.handed_since(), Handed::part_and_stop);
  EXPECT_EQ(q_.take_all().size(), 2u);
  EXPECT_EQ(q_.handed_since(), Handed::part);
  EXPECT_EQ(q_.pending(false), PendingWrites::waiting);
}

TEST_F(WriteQueueTest, WhatTheDeviceAsksOfTheLine) {
  EXPECT_EQ(q_.pending(true), PendingWrites::none);
  // A stop carried: urgent while it was handed since the last exchange, then while the driver
  // wants the line to resend it.
  WriteRequest& stop = push(1, t0_, true);
  hand(stop, t0_);
  EXPECT_EQ(q_.pending(false), PendingWrites::urgent);
  q_.exchanged();
  EXPECT_EQ(q_.pending(true), PendingWrites::urgent);
  EXPECT_EQ(q_.pending(false), PendingWrites::none);
  // A queued part: waiting; carried, it waits only while the driver wants the line.
  WriteRequest& part = push(2, t0_);
  EXPECT_EQ(q_.pending(false), PendingWrites::waiting);
  hand(part, t0_);
  EXPECT_EQ(q_.pending(false), PendingWrites::waiting);  // handed since the last exchange
  q_.exchanged();
  EXPECT_EQ(q_.pending(false), PendingWrites::none);
  q_.remove(&stop);
  EXPECT_EQ(q_.pending(true), PendingWrites::waiting);
  // Between its parts it wants a write turn again.
  ASSERT_TRUE(q_.confirmed(part, t0_));
  EXPECT_EQ(q_.pending(false), PendingWrites::waiting);
}

TEST_F(WriteQueueTest, AfterAWriteADuePollGoesFirst) {
  EXPECT_TRUE(q_.may_release(true));  // nothing written yet
  hand(push(1, t0_), t0_);
  q_.exchanged();
  ASSERT_EQ(q_.last_exchange(), LastExchange::wrote);
  EXPECT_FALSE(q_.may_release(true));
  EXPECT_TRUE(q_.may_release(false));
  q_.exchanged();  // the poll
  EXPECT_TRUE(q_.may_release(true));
}

TEST_F(WriteQueueTest, EachKindHasItsOwnPlaces) {
  for (std::size_t i = 0; i < kMaxQueuedWrites; ++i) {
    EXPECT_FALSE(q_.full(false));
    push(1, t0_);
  }
  EXPECT_TRUE(q_.full(false));
  EXPECT_FALSE(q_.full(true));
  EXPECT_FALSE(q_.full(false, true));
  for (std::size_t i = 0; i < kMaxQueuedWrites; ++i) push(1, t0_, true);
  EXPECT_TRUE(q_.full(true));
  for (std::size_t i = 0; i < kMaxQueuedWrites; ++i) push(1, t0_, false, true);
  EXPECT_TRUE(q_.full(false, true));
  EXPECT_EQ(q_.size(), 3 * kMaxQueuedWrites);
}

TEST_F(WriteQueueTest, StopsAreNeitherTheHeadNorJoined) {
  WriteRequest& stop = push(1, t0_, true);
  EXPECT_EQ(q_.head(), nullptr);
  EXPECT_EQ(q_.last_queued(), nullptr);
  WriteRequest& first = push(1, t0_);
  WriteRequest& second = push(1, t0_);
  push(1, t0_, true);
  EXPECT_EQ(q_.head(), &first);
  EXPECT_EQ(q_.last_queued(), &second);
  q_.remove(&first);
  EXPECT_EQ(q_.head(), &second);
  hand(second, t0_);
  EXPECT_EQ(q_.last_queued(), nullptr);
  EXPECT_EQ(q_.requests().front().get(), &stop);  // oldest first
}

}  // namespace
}  // namespace drivegate::write_queue_test
