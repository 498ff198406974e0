#include "transport/port_lock.h"

#include <fcntl.h>
#include <signal.h>  // NOLINT(modernize-deprecated-headers): POSIX kill(), not in <csignal>
#include <sys/ioctl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <optional>
#include <sstream>

#include "base/read_file.h"

namespace drivegate {

namespace {

class PortCategory final : public std::error_category {
 public:
  const char* name() const noexcept override { return "drivegate.port"; }
  std::string message(int) const override { return "in use by another program"; }
};

// The PID a lock file names (HDB UUCP: ten ASCII digits and a newline; binary locks of the old
// kind are not written on Linux), or 0. The lock directory is everyone's (/run/lock is sticky and
// world-writable): what has the lock file's name is read without blocking or following a link,
// and only when it is a regular file (a FIFO there would block the open, and the daemon with it).
pid_t read_pid(const std::filesystem::path& file) {
  std::string error;
  const auto text = read_regular_file(file, 64, error, Links::refuse);
  if (!text) return 0;
  long pid = 0;
  if (!(std::istringstream(*text) >> pid) || pid <= 0) return 0;
  return static_cast<pid_t>(pid);
}

// When process `pid` started, in seconds since the epoch (/proc/PID/stat field 22, in clock
// ticks since boot), or nothing when it cannot be read.
std::optional<double> started_at(pid_t pid) {
  std::ifstream stat("/proc/" + std::to_string(pid) + "/stat");
  std::string line;
  if (!std::getline(stat, line)) return std::nullopt;
  const auto paren = line.rfind(')');  // the command name may hold spaces and parentheses
  if (paren == std::string::npos) return std::nullopt;
  std::istringstream fields(line.substr(paren + 2));
  std::string field;
  for (int i = 3; i <= 22 && fields >> field; ++i) {
    if (i < 22) continue;
    std::ifstream uptime_file("/proc/uptime");
    double uptime = 0;
    if (!(uptime_file >> uptime)) return std::nullopt;
    const double boot = static_cast<double>(std::time(nullptr)) - uptime;
    return boot + std::stod(field) / static_cast<double>(::sysconf(_SC_CLK_TCK));
  }
  return std::nullopt;
}

// Whether the process that wrote the lock file `file` naming `pid` is still there: it exists
// (EPERM: as another user's) and started before the file was written (after, it is another
// process that was given the same PID).
bool holder_alive(pid_t pid, const std::filesystem::path& file) {
  if (pid <= 0 || (::kill(pid, 0) != 0 && errno != EPERM)) return false;
  struct stat st {};
  const auto started = started_at(pid);
  if (!started || ::stat(file.c_str(), &st) != 0) return true;
  return *started <= static_cast<double>(st.st_mtime) + 1.0;
}

// "drivegated (pid 1234)", from /proc when it can be read.
std::string describe(pid_t pid) {
  std::ifstream comm("/proc/" + std::to_string(pid) + "/comm");
  std::string name;
  std::getline(comm, name);
  return (name.empty() ? std::string("a process") : name) + " (pid " + std::to_string(pid) + ")";
}

}  // namespace

const std::error_category& port_category() noexcept {
  static const PortCategory category;
  return category;
}

std::filesystem::path PortLock::default_dir() {
  if (const char* dir = std::getenv("DRIVEGATE_LOCK_DIR"); dir != nullptr && *dir != '\0') {
    return dir;
  }
  return "/run/lock";
}

std::filesystem::path PortLock::lock_file(const std::string& device) const {
  std::error_code ec;
  std::filesystem::path real = std::filesystem::canonical(device, ec);
  if (ec) real = device;
  std::string name = real.string();
  if (name.starts_with("/dev/")) name.erase(0, 5);
  for (char& c : name) {
    if (c == '/') c = '_';
  }
  return dir_ / ("LCK.." + name);
}

std::error_code PortLock::acquire(const std::string& device) {
  release();
  owner_.clear();
  note_.clear();
  const std::filesystem::path file = lock_file(device);
  char content[16];
  std::snprintf(content, sizeof content, "%10d\n", static_cast<int>(::getpid()));
  for (int attempt = 0; attempt < 2; ++attempt) {
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0) {
      const auto n = static_cast<ssize_t>(std::char_traits<char>::length(content));
      const bool written = ::write(fd, content, static_cast<std::size_t>(n)) == n;
      ::close(fd);
      if (!written) {
        std::filesystem::remove(file);
        return {};  // an unwritable lock directory: TIOCEXCL alone
      }
      held_ = file;
      return {};
    }
    if (errno != EEXIST) return {};  // no lock directory we may use: TIOCEXCL alone
    const pid_t pid = read_pid(file);
    if (pid == ::getpid()) return {};  // ours already (the CLI took it before its gateway)
    if (holder_alive(pid, file)) {
      owner_ = describe(pid);
      return PortError::in_use;
    }
    // Stale: its process is gone. Taken over once; a second failure means someone else won.
    std::error_code removed;
    std::filesystem::remove(file, removed);
    if (removed) {
      // Gone, but not ours to remove: another user's file in the sticky lock directory (a
      // process of root's killed there). Its holder is provably gone, so the port is free; a
      // program that honours lock files sees the stale one and judges it as this did.
      note_ = "stale lock " + file.string() + " of pid " + std::to_string(pid) +
              " kept (cannot remove it: " + removed.message() + "); TIOCEXCL alone guards the port";
      return {};
    }
  }
  owner_ = "another program";
  return PortError::in_use;
}

void PortLock::release() {
  if (held_.empty()) return;
  if (read_pid(held_) == ::getpid()) {
    std::error_code ignored;
    std::filesystem::remove(held_, ignored);
  }
  held_.clear();
}

std::error_code make_exclusive(int fd) {
  if (::ioctl(fd, TIOCEXCL) != 0) return {errno, std::generic_category()};
  return {};
}

}  // namespace drivegate
