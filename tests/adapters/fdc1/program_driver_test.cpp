// Non-volatile programming through the driver: only in maintenance or with
// allow_nv_programming; every limit checked before anything is sent; the echo completes it.
#include <gtest/gtest.h>

#include "driver.h"
#include "fixture.h"
#include "points.h"

namespace drivegate::fdc1 {
namespace {

using namespace test_support;
using namespace std::chrono_literals;

// The codec test's standard vector (INPUT programming): 2000..3000 rpm, mode 2, 10.5/12.5,
// 21/25, 36/44 V.
const Bytes kProgramStandard = {0x48, 0x50, 0x07, 0xD0, 0x0B, 0xB8, 0x00, 0x02, 0x30, 0xB0, 0x39,
                                0xF6, 0x61, 0x5F, 0x73, 0xEB, 0xA6, 0xEC, 0xCC, 0x04, 0x35, 0x20};

void write_standard(Rig& rig) {
  const std::pair<std::size_t, Value> fields[] = {{pt::prog_min_rpm, std::int64_t{2000}},
                                                  {pt::prog_max_rpm, std::int64_t{3000}},
                                                  {pt::prog_mode, std::int64_t{2}},
                                                  {pt::prog_cut_out_12v, 10.5},
                                                  {pt::prog_cut_in_12v, 12.5},
                                                  {pt::prog_cut_out_24v, 21.0},
                                                  {pt::prog_cut_in_24v, 25.0},
                                                  {pt::prog_cut_out_42v, 36.0},
                                                  {pt::prog_cut_in_42v, 44.0}};
  for (const auto& [point, value] : fields) {
    ASSERT_EQ(rig.driver->write(point, value, 0, rig.now()), WriteStatus::done) << point;
  }
}

std::string message(const Rig& rig) {
  return std::get<std::string>(rig.value(pt::prog_message));
}
std::int64_t status(const Rig& rig) {
  return std::get<std::int64_t>(rig.value(pt::prog_status));
}

TEST(Fdc1Programming, NotReachableByDefault) {
  Rig rig;
  EXPECT_EQ(rig.driver->points().size(), pt::status_count);
  EXPECT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 1, rig.now()),
            WriteStatus::invalid_value);
}

TEST(Fdc1Programming, ExposedInMaintenanceOrByOption) {
  Rig maintenance(slave_options(), true);
  ASSERT_EQ(maintenance.driver->points().size(), pt::all_count);
  EXPECT_EQ(maintenance.driver->points()[pt::prog_commit].name, "prog_commit");
  EXPECT_EQ(maintenance.driver->points()[pt::prog_commit].table, Table::holding);
  EXPECT_EQ(maintenance.driver->points()[pt::prog_min_rpm].min, 1500);
  EXPECT_EQ(maintenance.driver->points()[pt::prog_min_rpm].max, 3500);
  auto options = slave_options();
  options["allow_nv_programming"] = true;
  Rig allowed(options);
  EXPECT_EQ(allowed.driver->points().size(), pt::all_count);
}

TEST(Fdc1Programming, CommitSendsThe22BytesAndTheEchoConfirms) {
  Rig rig(slave_options(), true);
  rig.bus->run_for(600ms);
  write_standard(rig);
  ASSERT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 7, rig.now()),
            WriteStatus::pending);
  EXPECT_EQ(status(rig), static_cast<std::int64_t>(ProgStatus::pending));
  ASSERT_TRUE(rig.settle(7));
  EXPECT_EQ(rig.result(7), WriteResult::ok);
  EXPECT_EQ(rig.bus->sent.back(), kProgramStandard);
  EXPECT_EQ(status(rig), static_cast<std::int64_t>(ProgStatus::ok));
  EXPECT_NE(rig.state().find("programs=1"), std::string::npos);
  EXPECT_NE(rig.state().find("mode=2"), std::string::npos);
}

TEST(Fdc1Programming, AViolatedLimitIsInvalidAndNothingIsSent) {
  Rig rig(slave_options(), true);
  rig.bus->run_for(600ms);
  write_standard(rig);
  ASSERT_EQ(rig.driver->write(pt::prog_cut_in_24v, 33.0, 0, rig.now()), WriteStatus::done);
  const auto sent = rig.bus->sent.size();
  EXPECT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 7, rig.now()),
            WriteStatus::invalid_value);
  rig.bus->run_for(3s);
  EXPECT_EQ(rig.bus->sent.size(), sent);
  EXPECT_EQ(message(rig), "cut_in_24v 33.00 V must be below 33 V");
  EXPECT_EQ(status(rig), static_cast<std::int64_t>(ProgStatus::invalid));
}

TEST(Fdc1Programming, AFieldNeverWrittenIsInvalid) {
  Rig rig(slave_options(), true);
  rig.bus->run_for(600ms);
  EXPECT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 7, rig.now()),
            WriteStatus::invalid_value);
  EXPECT_EQ(message(rig), "prog_min_rpm is not set");
  write_standard(rig);
  rig.driver->write(pt::prog_mode, std::int64_t{34}, 0, rig.now());  // special: other fields
  EXPECT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 8, rig.now()),
            WriteStatus::invalid_value);
  EXPECT_EQ(message(rig), "prog_cut_out_special is not set (special battery system)");
}

TEST(Fdc1Programming, OutOfRangePointWritesAreInvalid) {
  Rig rig(slave_options(), true);
  EXPECT_EQ(rig.driver->write(pt::prog_min_rpm, std::int64_t{1499}, 1, rig.now()),
            WriteStatus::invalid_value);
  EXPECT_EQ(rig.driver->write(pt::prog_status, std::int64_t{0}, 2, rig.now()),
            WriteStatus::invalid_value);
  EXPECT_EQ(rig.driver->write(pt::motor_on, std::int64_t{1}, 3, rig.now()),
            WriteStatus::invalid_value);
}

TEST(Fdc1Programming, AMismatchedEchoIsRefused) {
  Rig rig(slave_options(), true);
  rig.bus->run_for(600ms);
  write_standard(rig);
  rig.sim->control("mangle 1", rig.now());
  ASSERT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 7, rig.now()),
            WriteStatus::pending);
  ASSERT_TRUE(rig.settle(7));
  EXPECT_EQ(rig.result(7), WriteResult::refused);
  EXPECT_EQ(status(rig), static_cast<std::int64_t>(ProgStatus::refused));
  EXPECT_EQ(message(rig), "the controller's echo differs from the frame sent");
}

TEST(Fdc1Programming, NoEchoIsNoResponseAfterTwoIdenticalSends) {
  Rig rig(slave_options(), true);
  rig.bus->run_for(600ms);
  write_standard(rig);
  rig.sim->control("silent on", rig.now());
  ASSERT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 7, rig.now()),
            WriteStatus::pending);
  ASSERT_TRUE(rig.settle(7));
  EXPECT_EQ(rig.result(7), WriteResult::no_response);
  ASSERT_GE(rig.bus->sent.size(), 2u);
  EXPECT_EQ(rig.bus->sent[rig.bus->sent.size() - 1], kProgramStandard);
  EXPECT_EQ(rig.bus->sent[rig.bus->sent.size() - 2], kProgramStandard);
  EXPECT_EQ(rig.bus->timeouts, 2);
}

TEST(Fdc1Programming, ACorruptedEchoIsResentOnce) {
  Rig rig(slave_options(), true);
  rig.bus->run_for(600ms);
  write_standard(rig);
  rig.sim->control("corrupt 1", rig.now());
  ASSERT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 7, rig.now()),
            WriteStatus::pending);
  ASSERT_TRUE(rig.settle(7));
  EXPECT_EQ(rig.result(7), WriteResult::ok);
  EXPECT_EQ(rig.bus->retries, 1);
}

TEST(Fdc1Programming, AnUnexpectedEchoIsForeign) {
  Rig rig(slave_options(), true);
  Bytes echo = kProgramStandard;
  echo[0] = 27;
  const RxVerdict v = rig.driver->on_receive(echo, rig.now());
  EXPECT_EQ(v.kind, RxKind::foreign);
  EXPECT_EQ(v.consumed, 22u);
}

TEST(Fdc1Programming, RefusedWhileTheControllerIsSilentOrBusy) {
  Rig rig(slave_options(), true);
  write_standard(rig);
  EXPECT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 7, rig.now()),
            WriteStatus::refused);  // not heard yet
  rig.bus->run_for(600ms);
  EXPECT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 8, rig.now()),
            WriteStatus::pending);
  EXPECT_EQ(rig.driver->write(pt::prog_commit, std::int64_t{1}, 9, rig.now()),
            WriteStatus::refused);  // one at a time
}

}  // namespace
}  // namespace drivegate::fdc1
