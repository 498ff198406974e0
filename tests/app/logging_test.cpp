// The journal entry of one message: its fields come from the logger's context (DEVICE=, BUS=,
// UNIT=), never from the message's text.
#include "app/logging.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace drivegate {
namespace {

using ::testing::ElementsAre;

TEST(LogContext, JournalFieldsComeFromTheContext) {
  EXPECT_THAT(journal_fields("stall", spdlog::level::warn, "drivegated",
                             {.device = "washer-1", .bus = "line", .unit = 3}),
              ElementsAre("MESSAGE=stall", "PRIORITY=4", "SYSLOG_IDENTIFIER=drivegated",
                          "DEVICE=washer-1", "BUS=line", "UNIT=3"));
  EXPECT_THAT(journal_fields("device x: y", spdlog::level::info, "drivegated", {}),
              ElementsAre("MESSAGE=device x: y", "PRIORITY=6", "SYSLOG_IDENTIFIER=drivegated"));
}

}  // namespace
}  // namespace drivegate
