#include "status/process_metrics.h"

#include <dirent.h>
#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <string>

namespace drivegate {

namespace {

// The next whitespace-separated word of `text` from `at` on (moved past it); "" at the end.
std::string_view next_word(std::string_view text, std::size_t& at) {
  while (at < text.size() && (text[at] == ' ' || text[at] == '\t' || text[at] == '\n')) ++at;
  const std::size_t begin = at;
  while (at < text.size() && text[at] != ' ' && text[at] != '\t' && text[at] != '\n') ++at;
  return text.substr(begin, at - begin);
}

std::optional<std::uint64_t> to_u64(std::string_view word) {
  std::uint64_t v = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
  if (ec != std::errc() || end != word.data() + word.size() || word.empty()) return std::nullopt;
  return v;
}

// The whole file, read with plain read(2): a stream's machinery costs more than these few reads
// (the scrape renders on the event loop).
std::optional<std::string> slurp(const std::filesystem::path& file) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return std::nullopt;
  std::string out;
  char buf[4096];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    out.append(buf, static_cast<std::size_t>(n));
  }
  ::close(fd);
  return out;
}

// Entries of the directory of this process's descriptors, less the one the listing itself holds
// open (it is listed too).
std::optional<std::uint64_t> count_fds(const std::filesystem::path& dir) {
  DIR* d = ::opendir(dir.c_str());
  if (d == nullptr) return std::nullopt;
  const std::string own = std::to_string(::dirfd(d));
  const bool self = dir.filename() == "fd" && dir.parent_path().filename() == "self";
  std::uint64_t n = 0;
  while (const dirent* e = ::readdir(d)) {
    const std::string_view name = e->d_name;
    if (name == "." || name == ".." || (self && name == own)) continue;
    ++n;
  }
  ::closedir(d);
  return n;
}

}  // namespace

std::optional<ProcStat> parse_proc_stat(std::string_view text) {
  const auto close = text.rfind(')');
  if (close == std::string_view::npos || text.find('(') > close) return std::nullopt;
  // Field 3 (state) is the first word after the name; field n is word n - 3 from there.
  std::size_t at = close + 1;
  ProcStat s;
  for (int field = 3; field <= 24; ++field) {
    const std::string_view w = next_word(text, at);
    if (w.empty()) return std::nullopt;
    if (field == 3) continue;
    const auto v = to_u64(w);
    // Fields 4..24 are numbers; some (priority, nice) may be negative, and none of those is kept.
    if (!v && w.front() != '-') return std::nullopt;
    switch (field) {
      case 14:
        s.utime_ticks = v.value_or(0);
        break;
      case 15:
        s.stime_ticks = v.value_or(0);
        break;
      case 22:
        s.start_ticks = v.value_or(0);
        break;
      case 23:
        s.vsize_bytes = v.value_or(0);
        break;
      case 24:
        s.rss_pages = v.value_or(0);
        break;
      default:
        break;
    }
  }
  return s;
}

std::optional<std::uint64_t> parse_boot_time(std::string_view text) {
  std::size_t line = 0;
  while (line < text.size()) {
    const auto end = std::min(text.find('\n', line), text.size());
    std::string_view l = text.substr(line, end - line);
    if (l.starts_with("btime ")) {
      std::size_t at = 6;
      return to_u64(next_word(l, at));
    }
    line = end + 1;
  }
  return std::nullopt;
}

std::optional<std::uint64_t> parse_max_open_files(std::string_view text) {
  // "Limit                     Soft Limit           Hard Limit           Units"
  // "Max open files            1024                 524288               files"
  constexpr std::string_view kName = "Max open files";
  const auto at = text.find(kName);
  if (at == std::string_view::npos || (at > 0 && text[at - 1] != '\n')) return std::nullopt;
  std::size_t from = at + kName.size();
  return to_u64(next_word(text, from));  // "unlimited" is no number
}

ProcessMetrics process_metrics(const std::optional<ProcStat>& stat,
                               std::optional<std::uint64_t> boot_time,
                               std::optional<std::uint64_t> max_open_files,
                               std::optional<std::uint64_t> open_fds, double ticks_per_second,
                               double page_size) {
  ProcessMetrics m;
  if (stat && ticks_per_second > 0) {
    m.cpu_seconds = static_cast<double>(stat->utime_ticks + stat->stime_ticks) / ticks_per_second;
    if (boot_time) {
      m.start_time_seconds = static_cast<double>(*boot_time) +
                             static_cast<double>(stat->start_ticks) / ticks_per_second;
    }
  }
  if (stat) {
    m.virtual_memory_bytes = static_cast<double>(stat->vsize_bytes);
    m.resident_memory_bytes = static_cast<double>(stat->rss_pages) * page_size;
  }
  if (max_open_files) m.max_fds = static_cast<double>(*max_open_files);
  if (open_fds) m.open_fds = static_cast<double>(*open_fds);
  return m;
}

ProcessMetrics read_process_metrics(const std::filesystem::path& proc) {
  const auto self = proc / "self";
  const auto stat = slurp(self / "stat");
  const auto boot = slurp(proc / "stat");
  const auto limits = slurp(self / "limits");
  return process_metrics(
      stat ? parse_proc_stat(*stat) : std::nullopt, boot ? parse_boot_time(*boot) : std::nullopt,
      limits ? parse_max_open_files(*limits) : std::nullopt, count_fds(self / "fd"),
      static_cast<double>(::sysconf(_SC_CLK_TCK)), static_cast<double>(::sysconf(_SC_PAGESIZE)));
}

}  // namespace drivegate
