// The maintenance action `program` (plugin.cpp) as `drivegate action ... program KEY=VALUE...`
// carries it out: one write per prog_KEY, then prog_commit = 1, each waited for, and prog_message
// read after a failure. On the rig, with the device made in maintenance mode as the tool makes it.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "bench.h"
#include "driver.h"
#include "points.h"

namespace drivegate::fdc1 {
namespace {

// The codec test's standard vector (INPUT programming): 2000..3000 rpm, mode 2, 10.5/12.5,
// 21/25, 36/44 V.
const Bytes kProgramStandard = {0x48, 0x50, 0x07, 0xD0, 0x0B, 0xB8, 0x00, 0x02, 0x30, 0xB0, 0x39,
                                0xF6, 0x61, 0x5F, 0x73, 0xEB, 0xA6, 0xEC, 0xCC, 0x04, 0x35, 0x20};

// The README's example, as KEY=VALUE after `program`.
const std::vector<std::pair<std::string, double>> kStandard = {
    {"min_rpm", 2000},     {"max_rpm", 3000},    {"mode", 2},
    {"cut_out_12v", 10.5}, {"cut_in_12v", 12.5}, {"cut_out_24v", 21},
    {"cut_in_24v", 25},    {"cut_out_42v", 36},  {"cut_in_42v", 44}};

const MaintenanceAction& program_action() {
  EXPECT_EQ(drivegate_adapter.action_count, 1u);
  return drivegate_adapter.actions[0];
}

struct Maintenance : Bench {
  explicit Maintenance(Millis budget = Millis(1000))
      : Bench({.options = {}, .budget = budget, .maintenance = true}) {}

  // `drivegate action`: each parameter, then the commit; the first failure ends it.
  std::optional<Outcome> action(const std::vector<std::pair<std::string, double>>& params) {
    const MaintenanceAction& a = program_action();
    for (const auto& [key, value] : params) {
      const auto e = write_point(a.parameter_prefix + key, value);
      if (e != Outcome::ok) return e;
    }
    return write_point(a.commit_point, 1);
  }
  std::string message() { return read_text(program_action().message_point); }
  ProgStatus program_status() { return static_cast<ProgStatus>(read("prog_status")); }
};

TEST(Fdc1ProgramAction, TheActionFitsItsPoints) {
  const MaintenanceAction& a = program_action();
  EXPECT_EQ(std::string_view(a.name), "program");
  EXPECT_FALSE(std::string_view(a.summary).empty());
  Maintenance m;
  const MappedPoint* commit = m.drive->map().find(a.commit_point);
  ASSERT_NE(commit, nullptr);
  EXPECT_EQ(commit->spec.table, Table::holding);
  EXPECT_EQ(commit->spec.min, 1);
  EXPECT_EQ(commit->spec.max, 1);
  const MappedPoint* message = m.drive->map().find(a.message_point);
  ASSERT_NE(message, nullptr);
  EXPECT_EQ(message->spec.type, PointType::string);
  // The parameters `drivegate action` finds (writable, the prefix, not commit or message) are
  // exactly the frame's fields, by the names the README gives.
  std::set<std::string> params;
  for (const auto& p : m.drive->map().points()) {
    const std::string& n = p.spec.name;
    if (n.starts_with(a.parameter_prefix) && n != a.commit_point && n != a.message_point &&
        p.spec.access() == Access::read_write) {
      params.insert(n.substr(std::string_view(a.parameter_prefix).size()));
    }
  }
  EXPECT_EQ(params,
            (std::set<std::string>{"min_rpm", "max_rpm", "mode", "cut_out_12v", "cut_in_12v",
                                   "cut_out_24v", "cut_in_24v", "cut_out_42v", "cut_in_42v",
                                   "cut_out_special", "cut_in_special", "nominal_v"}));
}

TEST(Fdc1ProgramAction, OnlyInMaintenanceOrByOption) {
  Bench plain;
  EXPECT_EQ(plain.drive->map().find("prog_commit"), nullptr);
  Bench allowed({.options = {{"allow_nv_programming", "true"}}});
  EXPECT_NE(allowed.drive->map().find("prog_commit"), nullptr);
}

TEST(Fdc1ProgramAction, AValidProgramIsSentAndConfirmedByTheEcho) {
  Maintenance m;
  ASSERT_TRUE(m.ready());
  EXPECT_TRUE(m.rig.sent().empty());  // outside slave mode nothing else is ever sent
  EXPECT_EQ(m.program_status(), ProgStatus::invalid);
  EXPECT_EQ(m.message(), "prog_min_rpm is not set");
  for (const auto& [key, value] : kStandard) {
    ASSERT_EQ(m.write_point("prog_" + key, value), Outcome::ok) << key;
  }
  EXPECT_TRUE(m.rig.sent().empty());  // the fields are only stored
  EXPECT_EQ(m.program_status(), ProgStatus::idle);
  EXPECT_EQ(m.message(), "");
  const TimePoint asked = m.rig.now();
  const auto commit = m.start_point_write("prog_commit", {1});
  m.rig.run_for(1ms);
  EXPECT_EQ(m.program_status(), ProgStatus::pending);
  EXPECT_EQ(m.rig.wait(commit), Outcome::ok);
  ASSERT_EQ(m.rig.sent().size(), 1u);
  EXPECT_EQ(m.rig.sent()[0].bytes, kProgramStandard);
  EXPECT_EQ(m.rig.sent()[0].at, asked);
  // Confirmed by the echo: 22 bytes out, the controller's turnaround, 22 bytes back.
  EXPECT_EQ(m.rig.now() - asked, m.on_wire(22) + m.rig.line().turnaround + m.on_wire(22));
  EXPECT_EQ(m.program_status(), ProgStatus::ok);
  EXPECT_EQ(m.message(), "");
  EXPECT_TRUE(m.sim_has("programs=1"));
  EXPECT_TRUE(m.sim_has("mode=2"));  // the controller applied the stored mode
  EXPECT_EQ(m.read("prog_min_rpm"), 2000u);
  EXPECT_EQ(m.read("prog_cut_out_12v"), 1050u);  // 0.01 V registers
}

TEST(Fdc1ProgramAction, TheActionAsTheToolRunsIt) {
  Maintenance m;
  ASSERT_TRUE(m.ready());
  EXPECT_EQ(m.action(kStandard), Outcome::ok);
  EXPECT_EQ(m.rig.sent().back().bytes, kProgramStandard);
  EXPECT_TRUE(m.sim_has("programs=1"));
}

TEST(Fdc1ProgramAction, AViolatedLimitIsInvalidNamedAndNothingIsSent) {
  Maintenance m;
  ASSERT_TRUE(m.ready());
  auto params = kStandard;
  params[3].second = 13;  // cut_out_12v 13 V, not below cut_in_12v 12.5 V
  EXPECT_EQ(m.action(params), Outcome::invalid_value);
  // What `drivegate action` prints after "value refused (0x03)".
  EXPECT_EQ(m.message(), "cut_out_12v 13.00 V must be below cut_in_12v 12.50 V");
  EXPECT_EQ(m.program_status(), ProgStatus::invalid);
  m.rig.run_for(3s);
  EXPECT_TRUE(m.rig.sent().empty());
  EXPECT_TRUE(m.sim_has("programs=0"));
  // One field written again, and it goes.
  EXPECT_EQ(m.write_point("prog_cut_out_12v", 10.5), Outcome::ok);
  EXPECT_EQ(m.message(), "");
  EXPECT_EQ(m.write_point("prog_commit", 1), Outcome::ok);
  EXPECT_TRUE(m.sim_has("programs=1"));
}

TEST(Fdc1ProgramAction, AFieldNeverWrittenIsInvalidAndNamed) {
  Maintenance m;
  ASSERT_TRUE(m.ready());
  EXPECT_EQ(m.write_point("prog_commit", 1), Outcome::invalid_value);
  EXPECT_EQ(m.message(), "prog_min_rpm is not set");
  auto special = kStandard;
  special[2].second = 34;  // slave + special battery system: other fields
  EXPECT_EQ(m.action(special), Outcome::invalid_value);
  EXPECT_EQ(m.message(), "prog_cut_out_special is not set (special battery system)");
  EXPECT_TRUE(m.rig.sent().empty());
}

TEST(Fdc1ProgramAction, AValueOutsideThePointsLimitsIsRefusedByTheGateway) {
  Maintenance m;
  ASSERT_TRUE(m.ready());
  EXPECT_EQ(m.write_point("prog_min_rpm", 1499), Outcome::invalid_value);
  EXPECT_EQ(m.write_point("prog_mode", 256), Outcome::invalid_value);
  EXPECT_EQ(m.write_point("prog_commit", 0), Outcome::invalid_value);
  EXPECT_EQ(m.read("prog_min_rpm"), 0u);  // never stored
}

// A PLC writes the fields and the commit in one request: judged whole, so a broken field stores
// nothing and sends nothing.
TEST(Fdc1ProgramAction, OneRequestOfFieldsAndCommitIsAllOrNothing) {
  Maintenance m;
  ASSERT_TRUE(m.ready());
  // prog_min_rpm .. prog_commit: the standard fields, the (unused) special ones, the commit.
  std::vector<double> all = {2000, 3000, 2, 10.5, 12.5, 21, 25, 36, 44, 0, 0, 0, 1};
  all[8] = 46;  // cut_in_42v must be below 46 V
  EXPECT_EQ(m.rig.wait(m.start_point_write("prog_min_rpm", all)), Outcome::invalid_value);
  EXPECT_EQ(m.read("prog_min_rpm"), 0u);
  EXPECT_EQ(m.read("prog_cut_in_42v"), 0u);
  EXPECT_TRUE(m.rig.sent().empty());
  all[8] = 44;
  EXPECT_EQ(m.rig.wait(m.start_point_write("prog_min_rpm", all)), Outcome::ok);
  EXPECT_EQ(m.frames(), std::vector<Bytes>{kProgramStandard});
}

TEST(Fdc1ProgramAction, AMismatchedEchoIsRefused) {
  Maintenance m;
  ASSERT_TRUE(m.ready());
  m.control("mangle 1");
  EXPECT_EQ(m.action(kStandard), Outcome::refused);
  EXPECT_EQ(m.program_status(), ProgStatus::refused);
  EXPECT_EQ(m.message(), "the controller's echo differs from the frame sent");
  // Committed again as it is, it goes again.
  EXPECT_EQ(m.write_point("prog_commit", 1), Outcome::ok);
  EXPECT_EQ(m.program_status(), ProgStatus::ok);
}

// The controller does not hear the frame (`deaf on`) and keeps streaming: no echo.
TEST(Fdc1ProgramAction, NoEchoIsNoResponseAfterAsManyAttemptsAsTheBudgetHolds) {
  {
    Maintenance m;  // budget_ms 1000: one attempt of 2 s
    ASSERT_TRUE(m.ready());
    m.control("deaf on");
    const TimePoint asked = m.rig.now();
    EXPECT_EQ(m.action(kStandard), Outcome::no_response);
    EXPECT_EQ(m.times_of(kProgramStandard), std::vector<TimePoint>{asked});
    EXPECT_EQ(m.rig.now() - asked, kEchoTimeout + std::chrono::floor<Millis>(m.on_wire(22)));
    EXPECT_EQ(m.program_status(), ProgStatus::no_response);
    EXPECT_EQ(m.message(), "the controller did not echo the programming frame");
  }
  {
    Maintenance m(5000ms);  // room for both attempts
    ASSERT_TRUE(m.ready());
    m.control("deaf on");
    const TimePoint asked = m.rig.now();
    EXPECT_EQ(m.action(kStandard), Outcome::no_response);
    const auto sends = m.times_of(kProgramStandard);
    ASSERT_EQ(sends.size(), kEchoAttempts);
    EXPECT_EQ(sends[0], asked);
    EXPECT_EQ(sends[1] - sends[0], kEchoTimeout + std::chrono::floor<Millis>(m.on_wire(22)));
    EXPECT_EQ(m.read("retries"), 1u);
  }
}

// Late replies (docs/safety.md): the FDC1 streams its status, so no poll can be answered late;
// what is awaited is the echo of a programming frame. One that comes after its 2 s timeout is not
// taken for the programming's confirmation: the action has failed (no_response) and stays so,
// the late echo counted as a frame for nobody, and the status stream goes on.
TEST(Fdc1ProgramAction, AnEchoAfterItsTimeoutIsNeverTakenForTheConfirmation) {
  Maintenance m;  // budget_ms 1000: one attempt of 2 s
  ASSERT_TRUE(m.ready());
  m.rig.line().turnaround = kEchoTimeout + 500ms;
  EXPECT_EQ(m.action(kStandard), Outcome::no_response);
  EXPECT_EQ(m.program_status(), ProgStatus::no_response);
  const std::uint32_t foreign = m.read("foreign_frames");
  m.rig.run_for(2s);  // the echo arrives now, late
  EXPECT_EQ(m.program_status(), ProgStatus::no_response);
  EXPECT_EQ(m.message(), "the controller did not echo the programming frame");
  EXPECT_EQ(m.read("foreign_frames"), foreign + 1);
  EXPECT_NE(m.status() & kOnline, 0u);
}

TEST(Fdc1ProgramAction, ACorruptedEchoIsSentAgainWhenTheBudgetHoldsIt) {
  Maintenance m(5000ms);
  ASSERT_TRUE(m.ready());
  for (const auto& [key, value] : kStandard) {
    ASSERT_EQ(m.write_point("prog_" + key, value), Outcome::ok);
  }
  // Right after a status, so that the next frame the controller sends is the echo.
  ASSERT_TRUE(m.next_status());
  m.control("corrupt 1");
  EXPECT_EQ(m.write_point("prog_commit", 1), Outcome::ok);
  EXPECT_EQ(m.read("bad_checksum"), 1u);
  EXPECT_EQ(m.times_of(kProgramStandard).size(), 2u);
  EXPECT_TRUE(m.sim_has("programs=2"));  // rewriting identical parameters is harmless
}

TEST(Fdc1ProgramAction, RefusedWhileTheControllerIsNotStreamingOrBusy) {
  Maintenance m;
  for (const auto& [key, value] : kStandard) {
    ASSERT_EQ(m.write_point("prog_" + key, value), Outcome::ok);  // stored before heard
  }
  EXPECT_EQ(m.message(), "the controller is not streaming");
  EXPECT_EQ(m.write_point("prog_commit", 1), Outcome::refused);
  ASSERT_TRUE(m.ready());
  EXPECT_EQ(m.message(), "");
  const auto first = m.start_point_write("prog_commit", {1});
  const auto second = m.start_point_write("prog_commit", {1});  // one at a time
  EXPECT_EQ(second->result, Outcome::refused);
  EXPECT_EQ(m.message(), "a programming frame is on its way already");
  EXPECT_EQ(m.rig.wait(first), Outcome::ok);
  EXPECT_EQ(m.frames(), std::vector<Bytes>{kProgramStandard});
}

}  // namespace
}  // namespace drivegate::fdc1
