// The journal's native protocol sent by hand (daemon/app/journal_socket.h), to a datagram socket
// of the test's own standing in for journald: each field as the protocol has it, a value with a
// newline in its binary form; and where no journal takes the entry, the audit trail's record
// goes to the fallback logger instead of nowhere (app/logging.h).
#include "app/journal_socket.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>

#include <sstream>

#include "app/logging.h"
#include "fake_journald.h"
#include "temp_dir.h"

namespace drivegate {
namespace {

using ::testing::HasSubstr;

using test::FakeJournald;
using test::JournalAt;

TEST(JournalDatagram, EachFieldOnALineAndANewlineInABinaryValue) {
  const std::vector<std::string> fields = {"MESSAGE=write ok", "EVENT=command", "not a field",
                                           "WHY=two\nlines"};
  std::string binary = "WHY\n";
  binary += std::string("\x09\0\0\0\0\0\0\0", 8);
  binary += "two\nlines\n";
  EXPECT_EQ(journal_datagram(fields), "MESSAGE=write ok\nEVENT=command\n" + binary);
}

TEST(JournalSocket, SendsTheEntryAsOneDatagram) {
  test::TempDir dir;
  FakeJournald journald((dir / "socket").string());
  ASSERT_TRUE(journald.bound());
  const JournalSocket socket((dir / "socket").string());
  const std::vector<std::string> fields = {"MESSAGE=hello", "PRIORITY=6"};
  EXPECT_FALSE(socket.send(fields));
  EXPECT_EQ(journald.receive(), "MESSAGE=hello\nPRIORITY=6\n");
}

// No journald: the socket is not there, and sending says so (sd_journal_sendv() says success).
TEST(JournalSocket, SaysWhenNoJournalIsThere) {
  test::TempDir dir;
  const JournalSocket socket((dir / "none").string());
  const std::vector<std::string> fields = {"MESSAGE=hello"};
  EXPECT_EQ(socket.send(fields), std::errc::no_such_file_or_directory);
}

// The audit trail's writer, as `drivegate write` makes it (always the journal): its records reach
// the journal when one is there, and the fallback logger (stderr) when none is: never neither.
TEST(JournalWriter, ARecordReachesTheJournalOrTheFallbackNeverNeither) {
  test::TempDir dir;
  std::ostringstream fallback_text;
  auto fallback = std::make_shared<spdlog::logger>(
      "drivegate", std::make_shared<spdlog::sinks::ostream_sink_mt>(fallback_text));
  const std::vector<std::string> fields = {"EVENT=command", "SOURCE=cli", "RESULT=ok"};
  {
    JournalAt none((dir / "none").string());
    const auto writer = make_journal_writer(fallback, /*always_journal=*/true);
    writer->info("write to washer (unit 1) from cli root: setpoint_rpm=300: ok", fields);
  }
  EXPECT_THAT(fallback_text.str(),
              HasSubstr("write to washer (unit 1) from cli root: setpoint_rpm=300: ok"));
  fallback_text.str("");
  {
    FakeJournald journald((dir / "socket").string());
    ASSERT_TRUE(journald.bound());
    JournalAt there((dir / "socket").string());
    const auto writer = make_journal_writer(fallback, /*always_journal=*/true);
    writer->info("write to washer (unit 1) from cli root: setpoint_rpm=400: ok", fields);
    EXPECT_EQ(journald.receive(),
              "MESSAGE=write to washer (unit 1) from cli root: setpoint_rpm=400: ok\n"
              "PRIORITY=6\nSYSLOG_IDENTIFIER=drivegate\nEVENT=command\nSOURCE=cli\nRESULT=ok\n");
  }
  EXPECT_EQ(fallback_text.str(), "");
}

}  // namespace
}  // namespace drivegate
