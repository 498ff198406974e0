// What a device writes while its failsafe is latched (gateway/failsafe_enforcer.h), on its own:
// each state's transitions on a clock the test moves, the fall-backs and the retry.
#include "gateway/failsafe_enforcer.h"

#include <gtest/gtest.h>

namespace drivegate {
namespace {

using State = FailsafeEnforcer::State;
using Settled = FailsafeEnforcer::Settled;

constexpr TimePoint kT0 = TimePoint{} + std::chrono::hours(1);

TEST(FailsafeEnforcerTest, AStopIsSentConfirmedAndSentAgainWhenTheDriveRunsAgain) {
  FailsafeEnforcer f;
  f.trip(FailsafeAction::stop);
  EXPECT_EQ(f.state(), State::due);
  EXPECT_EQ(f.send(kT0, true), FailsafeAction::stop);
  EXPECT_EQ(f.state(), State::sending);
  EXPECT_EQ(f.send(kT0, true), std::nullopt);  // one write in flight at a time
  EXPECT_EQ(f.settled(FailsafeAction::stop, Outcome::ok, true, kT0), Settled::confirmed);
  EXPECT_EQ(f.state(), State::confirmed);
  EXPECT_EQ(f.send(kT0, false), std::nullopt);         // stopped: nothing to do
  EXPECT_EQ(f.send(kT0, true), FailsafeAction::stop);  // runs again: stopped again
  EXPECT_EQ(f.state(), State::resending);
  EXPECT_EQ(f.settled(FailsafeAction::stop, Outcome::ok, true, kT0), Settled::reconfirmed);
  EXPECT_EQ(f.state(), State::confirmed);
}

TEST(FailsafeEnforcerTest, AStoppedDriveIsSentAStopButNotThePresetSpeed) {
  FailsafeEnforcer stop;
  stop.trip(FailsafeAction::stop);
  EXPECT_EQ(stop.send(kT0, false), FailsafeAction::stop);
  FailsafeEnforcer preset;
  preset.trip(FailsafeAction::preset);
  EXPECT_EQ(preset.send(kT0, false), std::nullopt);
  EXPECT_EQ(preset.state(), State::confirmed);
  EXPECT_EQ(preset.send(kT0, true), std::nullopt);  // a preset is never sent again
}

TEST(FailsafeEnforcerTest, HoldNeverWrites) {
  FailsafeEnforcer f;
  f.trip(FailsafeAction::hold);
  EXPECT_EQ(f.send(kT0, true), std::nullopt);
  EXPECT_EQ(f.state(), State::due);
}

TEST(FailsafeEnforcerTest, ARefusedPresetOrInvalidQuickStopFallsBackToAStop) {
  for (const auto& [action, outcome] :
       {std::pair{FailsafeAction::preset, Outcome::refused},
        std::pair{FailsafeAction::preset, Outcome::no_response},
        std::pair{FailsafeAction::quick_stop, Outcome::invalid_value}}) {
    FailsafeEnforcer f;
    f.trip(action);
    ASSERT_EQ(f.send(kT0, true), action);
    EXPECT_EQ(f.settled(action, outcome, true, kT0), Settled::fell_back);
    EXPECT_EQ(f.action(), FailsafeAction::stop);
    EXPECT_EQ(f.state(), State::due);
    EXPECT_EQ(f.send(kT0, true), FailsafeAction::stop);  // at once, no retry wait
  }
}

TEST(FailsafeEnforcerTest, AnInvalidStopGivesUpUntilTheNextTrip) {
  FailsafeEnforcer f;
  f.trip(FailsafeAction::stop);
  ASSERT_TRUE(f.send(kT0, true));
  EXPECT_EQ(f.settled(FailsafeAction::stop, Outcome::invalid_value, true, kT0), Settled::gave_up);
  EXPECT_EQ(f.state(), State::gave_up);
  EXPECT_EQ(f.send(kT0 + std::chrono::hours(1), true), std::nullopt);
  f.trip(FailsafeAction::stop);
  EXPECT_EQ(f.send(kT0, true), FailsafeAction::stop);
}

TEST(FailsafeEnforcerTest, AFailedWriteIsRetriedASecondAfterTheLastTick) {
  FailsafeEnforcer f;
  f.trip(FailsafeAction::quick_stop);
  ASSERT_TRUE(f.send(kT0, true));
  const TimePoint tick = kT0 + Millis(100);
  EXPECT_EQ(f.settled(FailsafeAction::quick_stop, Outcome::no_response, true, tick),
            Settled::retry);
  EXPECT_EQ(f.state(), State::due);
  EXPECT_EQ(f.action(), FailsafeAction::quick_stop);
  EXPECT_EQ(f.send(tick + FailsafeEnforcer::kRetry - Millis(1), true), std::nullopt);
  EXPECT_EQ(f.send(tick + FailsafeEnforcer::kRetry, true), FailsafeAction::quick_stop);
  // A failed re-send of a confirmed stop stays confirmed, and is retried likewise.
  EXPECT_EQ(f.settled(FailsafeAction::quick_stop, Outcome::ok, true, tick), Settled::confirmed);
  ASSERT_TRUE(f.send(tick + std::chrono::seconds(5), true));
  EXPECT_EQ(
      f.settled(FailsafeAction::quick_stop, Outcome::refused, true, tick + std::chrono::seconds(5)),
      Settled::retry);
  EXPECT_EQ(f.state(), State::confirmed);
  EXPECT_EQ(f.send(tick + std::chrono::seconds(5), true), std::nullopt);
  EXPECT_EQ(f.send(tick + std::chrono::seconds(6), true), FailsafeAction::quick_stop);
}

TEST(FailsafeEnforcerTest, AnOutcomeAfterTheResetOnlyEndsTheFlight) {
  FailsafeEnforcer f;
  f.trip(FailsafeAction::stop);
  ASSERT_TRUE(f.send(kT0, true));
  EXPECT_EQ(f.settled(FailsafeAction::stop, Outcome::invalid_value, false, kT0),
            Settled::unlatched);
  EXPECT_EQ(f.state(), State::due);
}

TEST(FailsafeEnforcerTest, ATripWhileAWriteIsInFlightWaitsForIt) {
  FailsafeEnforcer f;
  f.trip(FailsafeAction::stop);
  ASSERT_TRUE(f.send(kT0, true));
  f.trip(FailsafeAction::quick_stop);
  EXPECT_EQ(f.state(), State::sending);
  EXPECT_EQ(f.send(kT0, true), std::nullopt);
  EXPECT_EQ(f.settled(FailsafeAction::stop, Outcome::ok, true, kT0), Settled::confirmed);
}

}  // namespace
}  // namespace drivegate
