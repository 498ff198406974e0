// The standard process metrics (status/process_metrics.h): proc(5)'s files parsed from sample
// text, the metrics composed from them, and this test's own process read from /proc.
#include "status/process_metrics.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>

namespace drivegate {
namespace {

// A process named "drive gate (x)": spaces and parentheses in field 2, as a name may have.
constexpr std::string_view kStat =
    "4242 (drive gate (x)) S 1 4242 4242 0 -1 4194560 1234 0 0 0 "
    "350 150 0 0 20 0 3 0 987654 123456789 2048 18446744073709551615 1 1 0 0 0 0 0 4096 0 0 0 "
    "17 1 0 0 0 0 0 0 0 0 0 0 0 0 0\n";

TEST(ProcStat, ReadsTheFieldsPastTheCommandName) {
  const auto s = parse_proc_stat(kStat);
  ASSERT_TRUE(s.has_value());
  EXPECT_EQ(s->utime_ticks, 350u);        // field 14
  EXPECT_EQ(s->stime_ticks, 150u);        // field 15
  EXPECT_EQ(s->start_ticks, 987654u);     // field 22
  EXPECT_EQ(s->vsize_bytes, 123456789u);  // field 23
  EXPECT_EQ(s->rss_pages, 2048u);         // field 24
}

TEST(ProcStat, NoneForWhatIsNotTheLine) {
  EXPECT_FALSE(parse_proc_stat(""));
  EXPECT_FALSE(parse_proc_stat("4242 drivegated S 1 2 3"));                       // no parentheses
  EXPECT_FALSE(parse_proc_stat("4242 (drivegated) S 1 4242 4242 0 -1 4194560"));  // cut short
  EXPECT_FALSE(
      parse_proc_stat("4242 (drivegated) S 1 4242 4242 0 -1 4194560 1234 0 0 0 "
                      "x 150 0 0 20 0 3 0 987654 123456789 2048"));  // not a number
}

TEST(BootTime, IsTheBtimeLine) {
  EXPECT_EQ(parse_boot_time("cpu  1 2 3\nintr 5\nctxt 77\nbtime 1700000000\nprocesses 9\n"),
            1700000000u);
  EXPECT_FALSE(parse_boot_time("cpu  1 2 3\nctxt 77\n"));
  EXPECT_FALSE(parse_boot_time("xbtime 17\n"));
}

TEST(MaxOpenFiles, IsTheSoftLimit) {
  constexpr std::string_view kLimits =
      "Limit                     Soft Limit           Hard Limit           Units     \n"
      "Max cpu time              unlimited            unlimited            seconds   \n"
      "Max open files            1024                 524288               files     \n"
      "Max locked memory         8388608              8388608              bytes     \n";
  EXPECT_EQ(parse_max_open_files(kLimits), 1024u);
  EXPECT_FALSE(parse_max_open_files(
      "Limit                     Soft Limit           Hard Limit           Units     \n"
      "Max open files            unlimited            unlimited            files     \n"));
  EXPECT_FALSE(parse_max_open_files("Max cpu time              unlimited            unlimited\n"));
}

TEST(ProcessMetrics, ComposedInSecondsAndBytes) {
  const auto m = process_metrics(parse_proc_stat(kStat), 1700000000, 1024, 12, 100.0, 4096.0);
  EXPECT_EQ(m.cpu_seconds, 5.0);  // (350 + 150) / 100
  EXPECT_EQ(m.start_time_seconds, 1700000000.0 + 9876.54);
  EXPECT_EQ(m.virtual_memory_bytes, 123456789.0);
  EXPECT_EQ(m.resident_memory_bytes, 2048.0 * 4096.0);
  EXPECT_EQ(m.max_fds, 1024.0);
  EXPECT_EQ(m.open_fds, 12.0);
}

TEST(ProcessMetrics, WhatCouldNotBeReadIsLeftOut) {
  const auto m = process_metrics(std::nullopt, std::nullopt, std::nullopt, std::nullopt, 100, 4096);
  EXPECT_FALSE(m.cpu_seconds || m.start_time_seconds || m.virtual_memory_bytes ||
               m.resident_memory_bytes || m.max_fds || m.open_fds);
  // Without the boot time the start time cannot be told; the rest can.
  const auto n = process_metrics(parse_proc_stat(kStat), std::nullopt, 1024, 3, 100, 4096);
  EXPECT_FALSE(n.start_time_seconds);
  EXPECT_TRUE(n.cpu_seconds);
}

TEST(ProcessMetrics, ThisProcessFromProc) {
  const auto before = read_process_metrics();
  ASSERT_TRUE(before.open_fds && before.max_fds && before.cpu_seconds &&
              before.start_time_seconds && before.resident_memory_bytes &&
              before.virtual_memory_bytes);
  rlimit nofile{};
  ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &nofile), 0);
  EXPECT_EQ(*before.max_fds, static_cast<double>(nofile.rlim_cur));
  // One descriptor more is one more counted: the listing's own is not among them.
  const int fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  ASSERT_GE(fd, 0);
  const auto after = read_process_metrics();
  ::close(fd);
  EXPECT_EQ(*after.open_fds, *before.open_fds + 1);
  // Started a little while ago, this boot.
  const double now =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  EXPECT_LE(*before.start_time_seconds, now + 1);
  EXPECT_GT(*before.start_time_seconds, now - 3600);
  EXPECT_GT(*before.resident_memory_bytes, 0);
  EXPECT_GE(*before.virtual_memory_bytes, *before.resident_memory_bytes);
}

TEST(ProcessMetrics, NothingFromAProcThatIsNotThere) {
  const auto m = read_process_metrics("/nonexistent/proc");
  EXPECT_FALSE(m.cpu_seconds || m.start_time_seconds || m.virtual_memory_bytes ||
               m.resident_memory_bytes || m.max_fds || m.open_fds);
}

}  // namespace
}  // namespace drivegate
