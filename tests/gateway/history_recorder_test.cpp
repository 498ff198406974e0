// The events a device records (gateway/history_recorder.h), on their own: each change once, the
// first state heard said as found, nothing of the drive's own while it does not answer.
#include "gateway/history_recorder.h"

#include <gtest/gtest.h>

#include <vector>

namespace drivegate {
namespace {

class HistoryRecorderTest : public ::testing::Test {
 protected:
  std::vector<EventKind> kinds() {
    std::vector<EventKind> out;
    for (const Event& e : history_.events().query({})) out.push_back(e.kind);
    return out;
  }
  HistoryRecorder::Seen seen(bool comm_lost, bool online, bool latched = false) {
    return {.comm_lost = comm_lost,
            .ever_good = true,
            .online = online,
            .latched = latched,
            .action = FailsafeAction::quick_stop,
            .failsafe_timeout = Millis(2000),
            .drive = drive_};
  }

  History history_{100};
  HistoryRecorder recorder_{&history_, "dev", 3};
  CommonState drive_;
};

TEST_F(HistoryRecorderTest, EachChangeIsRecordedOnce) {
  drive_.running = true;
  drive_.command = Command::run_forward;
  drive_.faults.set(Fault::stall);
  drive_.native_fault = 0x48;
  recorder_.seen(seen(false, true));
  recorder_.seen(seen(false, true));  // nothing changed: nothing more
  const auto found = history_.events().query({});
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].kind, EventKind::fault_raised);
  EXPECT_EQ(found[0].message, "dev: found with fault stall (native 0x48)");
  EXPECT_EQ(found[0].unit, 3);
  EXPECT_EQ(found[1].kind, EventKind::drive_started);
  EXPECT_EQ(found[1].message, "dev: found running (run_forward, setpoint 0 rpm)");

  drive_.faults = {};
  drive_.running = false;
  recorder_.seen(seen(false, true, true));
  EXPECT_EQ(kinds(), (std::vector{EventKind::fault_raised, EventKind::drive_started,
                                  EventKind::failsafe_tripped, EventKind::fault_cleared,
                                  EventKind::drive_stopped}));
  EXPECT_EQ(history_.events().query({}).at(2).message,
            "dev: failsafe quick_stop: no write from the PLC for 2000 ms");
}

TEST_F(HistoryRecorderTest, NothingOfTheDrivesOwnWhileItDoesNotAnswer) {
  recorder_.seen(seen(false, true));
  drive_.running = true;
  drive_.faults.set(Fault::stall);
  recorder_.seen(seen(true, false));
  EXPECT_EQ(kinds(), (std::vector{EventKind::comm_lost}));
  recorder_.seen(seen(false, true));
  EXPECT_EQ(kinds(), (std::vector{EventKind::comm_lost, EventKind::comm_restored,
                                  EventKind::fault_raised, EventKind::drive_started}));
}

TEST_F(HistoryRecorderTest, ALatchCarriedOverByAReloadIsNotATripAgain) {
  recorder_.latched_before();
  recorder_.seen(seen(false, false, true));
  EXPECT_TRUE(kinds().empty());
  recorder_.seen(seen(false, false, false));
  EXPECT_EQ(kinds(), (std::vector{EventKind::failsafe_cleared}));
}

}  // namespace
}  // namespace drivegate
