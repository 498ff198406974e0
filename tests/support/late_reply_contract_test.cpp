// The late-reply contract (late_reply_contract.h), compiled into every adapter's test binary.
#include "late_reply_contract.h"

#include "adapter_bench.h"
#include "adapter_under_test.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;

// Streaming adapters state their own test: nothing to instantiate for them.
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(LateReplyContract);

// The simulator answers every request, but `late` after it: no reply is ever taken for an
// answer (the drive never comes online, no frame counts as good, the speed and fault a PLC reads
// never show a value from a reply), every late reply is dropped and counted, and the drive goes
// comm_lost. Answering in time again, it comes back.
TEST_P(LateReplyContract, ADriveAnsweringAfterItsTimeoutIsNeverBelievedAndGoesCommLost) {
  const LateReplyFacts& f = GetParam();
  ASSERT_EQ(std::string_view(drivegate_adapter.id), f.id);
  AdapterBench b(drivegate_adapter, {.options = f.options});
  b.rig.line().turnaround = f.late;
  for (const auto& c : f.sim_commands) ASSERT_EQ(b.control(c).rfind("ok", 0), 0u) << c;
  bool lost = false;
  for (int i = 0; i < 1000; ++i) {  // 10 s of simulated time
    b.rig.run_for(10ms);
    const std::uint32_t status = b.status();
    ASSERT_EQ(status & common_block::kOnline, 0u) << "online at " << i * 10 << " ms";
    ASSERT_EQ(b.read("frames_good"), 0u) << "a late reply was taken at " << i * 10 << " ms";
    ASSERT_EQ(b.read("speed_rpm"), 0u);
    const std::uint32_t fault = b.read("fault_code");
    ASSERT_TRUE(fault == 0 || fault == static_cast<std::uint32_t>(Fault::comm_lost)) << fault;
    lost = lost || (status & common_block::kCommLost) != 0;
  }
  EXPECT_TRUE(lost);
  EXPECT_FALSE(b.rig.answers().empty());  // the simulator did answer, every time, late
  EXPECT_GT(b.drive->line().counters.late_bytes, 0u);
  EXPECT_EQ(b.drive->line().counters.late_bytes, b.rig.counters().late_bytes);

  b.rig.line().turnaround = 5ms;
  EXPECT_TRUE(b.rig.run_until([&] { return b.drive->online(); }, 15s));
  EXPECT_GT(b.read("frames_good"), 0u);
}

}  // namespace
}  // namespace drivegate::test
