// The daemon's side of the systemd service protocol (sd_notify(3)), against a fake notification
// socket: what systemd would receive from the unit (Type=notify, WatchdogSec=) at start, while it
// runs, at `systemctl reload` and at `systemctl stop`.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include "e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;

// What systemd's end of NOTIFY_SOCKET would read: one datagram per sd_notify() call.
class NotifySocket {
 public:
  explicit NotifySocket(const std::filesystem::path& path) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    const std::string name = path.string();
    if (fd_ < 0 || name.size() >= sizeof addr.sun_path) throw std::runtime_error("notify socket");
    std::copy(name.begin(), name.end(), addr.sun_path);
    if (::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      throw std::runtime_error("bind notify socket");
    }
    const timeval tv{0, 50'000};
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  }
  ~NotifySocket() { ::close(fd_); }
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;

  // Reads datagrams until one contains `what` (true) or `timeout` passes (false).
  bool await(const std::string& what, std::chrono::milliseconds timeout = 5s) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      char buf[4096];
      const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) continue;
      received.emplace_back(buf, static_cast<std::size_t>(n));
      if (received.back().find(what) != std::string::npos) return true;
    }
    return false;
  }
  // Everything received, one datagram per line, for failure messages.
  [[nodiscard]] std::string dump() const {
    std::string out;
    for (auto m : received) {
      std::replace(m.begin(), m.end(), '\n', ' ');
      out += "\n  " + m;
    }
    return out;
  }
  [[nodiscard]] std::size_t count(const std::string& what) const {
    std::size_t c = 0;
    for (const auto& m : received) c += m.find(what) != std::string::npos ? 1 : 0;
    return c;
  }
  std::vector<std::string> received;

 private:
  int fd_ = -1;
};

// The environment systemd gives a Type=notify unit with WatchdogSec=, for the child only.
class SystemdEnvironment {
 public:
  SystemdEnvironment(const std::filesystem::path& socket, std::chrono::microseconds watchdog) {
    ::setenv("NOTIFY_SOCKET", socket.c_str(), 1);
    ::setenv("WATCHDOG_USEC", std::to_string(watchdog.count()).c_str(), 1);
  }
  ~SystemdEnvironment() {
    ::unsetenv("NOTIFY_SOCKET");
    ::unsetenv("WATCHDOG_USEC");
  }
  SystemdEnvironment(const SystemdEnvironment&) = delete;
  SystemdEnvironment& operator=(const SystemdEnvironment&) = delete;
};

std::string drive(const std::filesystem::path& port) {
  return "[[bus]]\nname = \"line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\nadapter = \"test-drive\"\n"
         "unit_id = 1\n";
}

TEST(SystemdNotifyE2E, ReadyWatchdogReloadingAndStopping) {
  TempDir dir;
  NotifySocket systemd(dir / "notify");
  Sim sim("test-drive", dir / "drive");
  std::optional<Daemon> daemon;
  {
    const SystemdEnvironment env(dir / "notify", 400ms);  // WatchdogSec=0.4s: pings every 200 ms
    daemon.emplace(dir, drive(dir / "drive"));
  }

  ASSERT_TRUE(systemd.await("READY=1")) << systemd.dump();
  EXPECT_NE(systemd.received.back().find("STATUS="), std::string::npos) << systemd.dump();
  EXPECT_EQ(systemd.count("READY=1"), 1u) << systemd.dump();

  // The watchdog is pinged from the event loop, at half the interval systemd expects (about ten
  // pings in 2 s; a loaded machine may delay some).
  const std::size_t before = systemd.count("WATCHDOG=1");
  systemd.await("never sent", 2s);
  EXPECT_GE(systemd.count("WATCHDOG=1") - before, 3u) << systemd.dump();

  // systemctl reload: RELOADING=1, then READY=1 again once the new configuration runs.
  daemon->process().signal(SIGHUP);
  ASSERT_TRUE(systemd.await("RELOADING=1")) << systemd.dump();
  ASSERT_TRUE(systemd.await("READY=1")) << systemd.dump();
  EXPECT_EQ(systemd.count("READY=1"), 2u) << systemd.dump();

  // systemctl stop: STOPPING=1 before the drives are stopped, then a clean exit (one SIGTERM,
  // as systemd sends it: a second one after the daemon let go of its signals would kill it).
  daemon->process().signal(SIGTERM);
  ASSERT_TRUE(systemd.await("STOPPING=1")) << systemd.dump();
  EXPECT_EQ(daemon->process().wait_exit(), 0);
}

// `systemctl reload` as the unit file runs it: its ExecReload= commands in order, the first that
// fails failing the reload (systemd.service(5)), with the installed paths replaced by the
// build's. A file that does not validate fails the reload (non-zero, the reasons on its output)
// and never reaches the daemon; a good one reaches it, and it reloads.
int exec_reload(const Daemon& daemon_config, pid_t pid, std::string& output) {
  std::ifstream unit(std::filesystem::path(DRIVEGATE_SOURCE_DIR) / "systemd" / "drivegate.service");
  std::string line;
  int commands = 0;
  while (std::getline(unit, line)) {
    if (!line.starts_with("ExecReload=")) continue;
    std::string cmd = line.substr(std::string("ExecReload=").size());
    const auto replace = [&](const std::string& from, const std::string& to) {
      for (auto at = cmd.find(from); at != std::string::npos; at = cmd.find(from, at + to.size())) {
        cmd.replace(at, from.size(), to);
      }
    };
    replace("/usr/sbin/drivegated", (bin_dir() / "drivegated").string());
    replace("/etc/drivegate/drivegate.toml",
            daemon_config.config().string() + " --plugin-dir " + plugin_dir().string());
    replace("$MAINPID", std::to_string(pid));
    ++commands;
    Child c({"/bin/sh", "-c", cmd + " 2>&1"});
    while (auto out = c.read_line(10s)) output += *out + "\n";
    if (const int status = c.wait_exit(); status != 0) return status;
  }
  return commands >= 2 ? 0 : -1;  // the unit validates, then signals
}

TEST(SystemdNotifyE2E, ReloadFailsForAFileThatDoesNotValidate) {
  TempDir dir;
  NotifySocket systemd(dir / "notify");
  Sim sim("test-drive", dir / "drive");
  std::optional<Daemon> daemon;
  {
    const SystemdEnvironment env(dir / "notify", 0us);
    daemon.emplace(dir, drive(dir / "drive"));
  }
  ASSERT_TRUE(systemd.await("READY=1")) << systemd.dump();

  std::ofstream(daemon->config()) << drive(dir / "drive") << "poll_ms = \"fast\"\n";
  std::string out;
  EXPECT_EQ(exec_reload(*daemon, daemon->process().pid(), out), 1) << out;
  EXPECT_NE(out.find("drivegate.toml:"), std::string::npos) << out;  // names the line
  EXPECT_FALSE(systemd.await("RELOADING=1", 1s)) << "the bad file reached the daemon";
  EXPECT_TRUE(daemon->process().running());

  std::ofstream(daemon->config()) << drive(dir / "drive");
  out.clear();
  EXPECT_EQ(exec_reload(*daemon, daemon->process().pid(), out), 0) << out;
  EXPECT_TRUE(systemd.await("RELOADING=1")) << systemd.dump();
  EXPECT_TRUE(systemd.await("READY=1")) << systemd.dump();
}

}  // namespace
}  // namespace drivegate::test
