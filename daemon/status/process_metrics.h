// The standard process metrics every Prometheus client library exports (process_cpu_seconds_total,
// process_resident_memory_bytes, ...: https://prometheus.io/docs/instrumenting/writing_clientlibs/
// #process-metrics), read where client_golang reads them on Linux: /proc/self/stat (CPU time,
// start time, virtual and resident memory), /proc/stat (the boot time the start time counts
// from), /proc/self/limits (the open-files limit) and /proc/self/fd (open descriptors).
// proc(5) describes each file.
//
// The parsers are pure, tested on sample text; read_process_metrics() is the thin part that opens
// the files, on each scrape (a few small reads: tens of microseconds on the event loop).
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string_view>

namespace drivegate {

// What /proc/PID/stat says of the process, in its own units (proc(5), fields 14, 15, 22, 23, 24).
struct ProcStat {
  std::uint64_t utime_ticks = 0;  // user CPU time, clock ticks
  std::uint64_t stime_ticks = 0;  // system CPU time, clock ticks
  std::uint64_t start_ticks = 0;  // start time, clock ticks after the boot
  std::uint64_t vsize_bytes = 0;  // virtual memory size
  std::uint64_t rss_pages = 0;    // resident set size, pages
};

// /proc/PID/stat's one line; none if it is not one. The command name (field 2) is in parentheses
// and may hold spaces and parentheses itself: the fields are counted from its last ')'.
std::optional<ProcStat> parse_proc_stat(std::string_view text);
// The `btime` line of /proc/stat: the boot time, seconds since the epoch.
std::optional<std::uint64_t> parse_boot_time(std::string_view text);
// The soft limit of "Max open files" in /proc/PID/limits; none if missing or "unlimited".
std::optional<std::uint64_t> parse_max_open_files(std::string_view text);

// The metrics, each one none when its file could not be read.
struct ProcessMetrics {
  std::optional<double> cpu_seconds;
  std::optional<double> resident_memory_bytes;
  std::optional<double> virtual_memory_bytes;
  std::optional<double> open_fds;
  std::optional<double> max_fds;
  std::optional<double> start_time_seconds;  // since the epoch
};

// From what the files said: `ticks_per_second` is sysconf(_SC_CLK_TCK), `page_size`
// sysconf(_SC_PAGESIZE).
ProcessMetrics process_metrics(const std::optional<ProcStat>& stat,
                               std::optional<std::uint64_t> boot_time,
                               std::optional<std::uint64_t> max_open_files,
                               std::optional<std::uint64_t> open_fds, double ticks_per_second,
                               double page_size);

// This process's, read from `proc` (the proc file system's mount point).
ProcessMetrics read_process_metrics(const std::filesystem::path& proc = "/proc");

}  // namespace drivegate
