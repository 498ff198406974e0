// The register map: the common block sits at the same addresses for every adapter; adapter
// points follow it without overlap.
#include "gateway/register_map.h"

#include <gtest/gtest.h>

#include "drivegate/common.h"

namespace drivegate {
namespace {

const MappedPoint& named(const RegisterMap& m, const std::string& name) {
  for (const auto& p : m.points()) {
    if (p.spec.name == name) return p;
  }
  throw std::runtime_error("no point " + name);
}

TEST(RegisterMap, CommonBlockIsFixed) {
  const RegisterMap m({});
  const std::pair<const char*, int> input[] = {
      {"status", 0},        {"fault_code", 1},       {"fault_mask", 2},
      {"native_fault", 4},  {"speed_rpm", 6},        {"data_age_ms", 7},
      {"frames_good", 9},   {"bad_checksum", 11},    {"timeouts", 13},
      {"retries", 15},      {"nacks", 17},           {"bus_exchanges", 19},
      {"bus_timeouts", 21}, {"bus_echo_errors", 23}, {"bus_noise_bytes", 25},
      {"bus_reopens", 27},  {"foreign_frames", 29}};
  for (const auto& [name, address] : input) {
    EXPECT_EQ(named(m, name).address, address) << name;
    EXPECT_EQ(named(m, name).spec.table, Table::input) << name;
  }
  EXPECT_EQ(named(m, "command").address, 0);
  EXPECT_EQ(named(m, "setpoint_rpm").address, 1);
  EXPECT_EQ(named(m, "heartbeat").address, 2);
  EXPECT_EQ(named(m, "command").spec.table, Table::holding);
  EXPECT_EQ(named(m, "status_comm_lost").address, 4);
  EXPECT_EQ(named(m, "status_comm_lost").spec.table, Table::discrete);
  // Labels carry the unified vocabulary.
  const auto& fault = named(m, "fault_code").spec.labels;
  ASSERT_EQ(fault.size(), kFaultCount);
  EXPECT_EQ(fault[7].name, "stall");
  EXPECT_EQ(fault[7].value, 7u);
  EXPECT_TRUE(named(m, "status").spec.bit_labels);
}

TEST(RegisterMap, AdapterPointsFollowTheCommonBlock) {
  PointSpec a{.name = "a", .table = Table::input, .type = PointType::f32};
  PointSpec b{.name = "b", .table = Table::input, .type = PointType::u16};
  PointSpec s{.name = "s", .table = Table::input, .type = PointType::string, .string_registers = 8};
  PointSpec h{.name = "h", .table = Table::holding, .type = PointType::u32};
  PointSpec d{.name = "d", .table = Table::discrete};
  const RegisterMap m({a, b, s, h, d});
  EXPECT_EQ(named(m, "a").address, kAdapterInputBase);
  EXPECT_EQ(named(m, "b").address, kAdapterInputBase + 2);
  EXPECT_EQ(named(m, "s").address, kAdapterInputBase + 3);
  EXPECT_EQ(m.size(Table::input), kAdapterInputBase + 11);
  EXPECT_EQ(named(m, "h").address, kAdapterHoldingBase);
  EXPECT_EQ(named(m, "d").address, kAdapterDiscreteBase);
  EXPECT_EQ(m.at(Table::input, kAdapterInputBase + 1)->spec.name, "a");
  EXPECT_EQ(m.at(Table::input, 31), nullptr);  // the reserved gap
  EXPECT_EQ(m.at(Table::input, 60000), nullptr);
}

// mapped_from (one lookup per read) agrees with at() (one per register) at every address.
TEST(RegisterMap, MappedFromCountsTheMappedRunAtEveryAddress) {
  PointSpec a{.name = "a", .table = Table::input, .type = PointType::f32};
  PointSpec h{.name = "h", .table = Table::holding, .type = PointType::u32};
  PointSpec c{.name = "c", .table = Table::coil};
  const RegisterMap m({a, h, c});
  for (const Table t : {Table::input, Table::holding, Table::discrete, Table::coil}) {
    for (std::uint32_t address = 0; address <= 0xFFFF; ++address) {
      std::size_t expected = 0;
      while (address + expected <= 0xFFFF &&
             m.at(t, static_cast<std::uint16_t>(address + expected)) != nullptr) {
        ++expected;
      }
      ASSERT_EQ(m.mapped_from(t, static_cast<std::uint16_t>(address)), expected)
          << "table " << static_cast<int>(t) << " address " << address;
    }
  }
  EXPECT_EQ(m.mapped_from(Table::input, 0), 31u);  // the common block up to the reserved gap
  EXPECT_EQ(m.mapped_from(Table::input, 31), 0u);
  EXPECT_EQ(m.mapped_from(Table::input, kAdapterInputBase), 2u);
  EXPECT_EQ(m.mapped_from(Table::holding, 0), 3u);
  EXPECT_EQ(m.mapped_from(Table::holding, kAdapterHoldingBase + 1), 1u);
  EXPECT_EQ(m.mapped_from(Table::coil, 0), 1u);
}

TEST(RegisterMap, DuplicateStringOfZeroRegistersIsRefused) {
  PointSpec s{.name = "s", .table = Table::input, .type = PointType::string};
  EXPECT_THROW(RegisterMap({s}), std::invalid_argument);
}

TEST(RegisterMap, EveryNameIsOneAndOnlyOnePoint) {
  PointSpec a{.name = "a", .table = Table::input, .type = PointType::u16};
  EXPECT_THROW(RegisterMap({a, a}), std::invalid_argument);
  PointSpec clash{.name = "fault_code", .table = Table::input, .type = PointType::u16};
  EXPECT_THROW(RegisterMap({clash}), std::invalid_argument);  // the common block's
  PointSpec nameless{.table = Table::input, .type = PointType::u16};
  EXPECT_THROW(RegisterMap({nameless}), std::invalid_argument);
  const RegisterMap m({a});
  EXPECT_EQ(m.find("a")->address, kAdapterInputBase);
  EXPECT_EQ(m.find("missing"), nullptr);
}

}  // namespace
}  // namespace drivegate
