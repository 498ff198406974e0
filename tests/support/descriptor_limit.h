// Running out of descriptors on purpose: the process's soft RLIMIT_NOFILE lowered for a test and
// put back however it ends, and the process's CPU time (to tell a busy loop from a wait).
#pragma once

#include <sys/resource.h>
#include <unistd.h>

namespace drivegate::test {

// The process's soft descriptor limit, lowered for a test and put back however it ends.
class DescriptorLimit {
 public:
  explicit DescriptorLimit(rlim_t soft) {
    ::getrlimit(RLIMIT_NOFILE, &saved_);
    rlimit lowered = saved_;
    lowered.rlim_cur = soft;
    ok_ = ::setrlimit(RLIMIT_NOFILE, &lowered) == 0;
  }
  ~DescriptorLimit() { restore(); }
  DescriptorLimit(const DescriptorLimit&) = delete;
  DescriptorLimit& operator=(const DescriptorLimit&) = delete;
  [[nodiscard]] bool ok() const { return ok_; }
  void restore() {
    if (ok_) ::setrlimit(RLIMIT_NOFILE, &saved_);
    ok_ = false;
  }

 private:
  rlimit saved_{};
  bool ok_ = false;
};

inline double process_cpu_seconds() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  const auto s = [](const timeval& v) {
    return static_cast<double>(v.tv_sec) + static_cast<double>(v.tv_usec) / 1e6;
  };
  return s(u.ru_utime) + s(u.ru_stime);
}

// The lowest descriptor number not in use: with the soft limit at this + 1, exactly one more
// descriptor can be opened. -1 if none can be now.
inline int lowest_free_descriptor() {
  const int fd = ::dup(0);
  if (fd >= 0) ::close(fd);
  return fd;
}

}  // namespace drivegate::test
