// Running out of descriptors on purpose: the process's soft RLIMIT_NOFILE lowered so that exactly
// one more descriptor can be opened, put back however the test ends; and the process's CPU time
// over a wait, to tell a busy loop from a wait.
#pragma once

#include <fcntl.h>
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <thread>

namespace drivegate::test {

// UndefinedBehaviorSanitizer's vptr check needs descriptors of its own (a pipe, to probe memory
// the first time it meets a type): with none left it reports valid objects as invalid. A test
// that takes the last descriptor skips itself in that build; the README's pass and the
// ThreadSanitizer pass run it.
#ifdef DRIVEGATE_UBSAN
inline constexpr bool kDescriptorsNeededBySanitizer = true;
#else
inline constexpr bool kDescriptorsNeededBySanitizer = false;
#endif

class OneDescriptorLeft {
 public:
  OneDescriptorLeft() {
    // With the soft limit at the lowest number not in use + 1, one more can be opened.
    const int fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);  // the lowest free number
    if (fd < 0) return;
    ::close(fd);
    ::getrlimit(RLIMIT_NOFILE, &saved_);
    rlimit lowered = saved_;
    lowered.rlim_cur = static_cast<rlim_t>(fd) + 1;
    ok_ = ::setrlimit(RLIMIT_NOFILE, &lowered) == 0;
  }
  ~OneDescriptorLeft() { restore(); }
  OneDescriptorLeft(const OneDescriptorLeft&) = delete;
  OneDescriptorLeft& operator=(const OneDescriptorLeft&) = delete;
  [[nodiscard]] bool ok() const { return ok_; }
  void restore() {
    if (ok_) ::setrlimit(RLIMIT_NOFILE, &saved_);
    ok_ = false;
  }

 private:
  rlimit saved_{};
  bool ok_ = false;
};

// Waits `wait`; the CPU seconds the whole process used meanwhile.
inline double cpu_seconds_over(std::chrono::milliseconds wait) {
  const auto now = [] {
    rusage u{};
    ::getrusage(RUSAGE_SELF, &u);
    const auto s = [](const timeval& v) {
      return static_cast<double>(v.tv_sec) + static_cast<double>(v.tv_usec) / 1e6;
    };
    return s(u.ru_utime) + s(u.ru_stime);
  };
  const double before = now();
  std::this_thread::sleep_for(wait);
  return now() - before;
}

// A client connected by `connect` (a callable returning it: its socket takes the last
// descriptor, so the server's accept() gets EMFILE for as long as it waits in the backlog), and
// the CPU seconds the process used over the `wait` that follows; the limit is back on return.
template <class Connect>
auto connect_out_of_descriptors(Connect connect,
                                std::chrono::milliseconds wait = std::chrono::milliseconds(500)) {
  struct Starved {
    decltype(connect()) client;
    double cpu_seconds = 0;
    bool limited = false;
  };
  OneDescriptorLeft starved;
  Starved out{connect(), 0, starved.ok()};
  out.cpu_seconds = cpu_seconds_over(wait);
  return out;
}

}  // namespace drivegate::test
