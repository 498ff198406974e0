// Debian's ser2net (4.3, YAML configuration) as a serial device server for end-to-end tests: it
// bridges TCP ports on 127.0.0.1 to simulated drives' pseudo-terminals, raw (`tcp` accepter) or
// with RFC 2217 (`telnet(rfc2217),tcp`). Killed and started again on the same ports as a test
// needs. tools/deps.sh installs it.
//
// Found while writing the tests (ser2net 4.3.11):
// - `-c FILE` replaces /etc/ser2net/ser2net.yaml (none of its ports is opened); `-n` stays in the
//   foreground, `-d` also sends its log to stdout (kept in `log()`).
// - `-u`: no UUCP lock in /var/lock (LCK.._tmp_..._ed, named after the device path); one left by
//   a SIGKILL would stay behind, and a user other than root may not write there.
// - The device is opened (with the connector's settings) only when a client connects, and
//   closed when it leaves; a device path that is a symlink (the simulator's --link) is fine.
// - At start-up it prints "Unable to start mdns: Out of memory" when no Avahi daemon runs:
//   harmless.
// - A Linux pty keeps speed, CSTOPB and PARODD but forces CS8 and clears PARENB on every
//   tcsetattr (drivers/tty/pty.c), and ser2net's RFC 2217 answers repeat what was asked (it
//   answers 7 data bits for a pty that stays at 8): only speed, stop bits and odd/even are seen
//   on the pty.
#pragma once

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <sstream>

#include "e2e.h"

namespace drivegate::test {

inline const std::filesystem::path kSer2net = "/usr/sbin/ser2net";

// True when something listens on TCP `port` (/proc/net/tcp and tcp6: no connection is made, so
// ser2net is not made to open its device by the check).
inline bool listening(int port) {
  char hex[8];
  std::snprintf(hex, sizeof hex, ":%04X", port);
  for (const char* table : {"/proc/net/tcp", "/proc/net/tcp6"}) {
    std::ifstream in(table);
    std::string line;
    std::getline(in, line);  // header
    while (std::getline(in, line)) {
      std::istringstream fields(line);
      std::string slot, local, remote, state;
      fields >> slot >> local >> remote >> state;
      if (state == "0A" && local.ends_with(hex)) return true;  // 0A: LISTEN
    }
  }
  return false;
}

// One ser2net connection: 127.0.0.1:`port` to `device` opened at `settings` ("9600e81").
struct Ser2netPort {
  int port = 0;
  std::filesystem::path device;
  std::string settings = "9600n81";
  bool rfc2217 = false;  // a telnet(rfc2217) accepter: the client may change the settings
};

class Ser2net {
 public:
  Ser2net(const TempDir& dir, std::vector<Ser2netPort> ports, const std::string& name = "ser2net")
      : ports_(std::move(ports)), config_(dir / (name + ".yaml")), log_(dir / (name + ".log")) {
    {
      std::ofstream yaml(config_);
      int n = 0;
      for (const auto& p : ports_) {
        yaml << "connection: &con" << n++ << "\n"
             << "  accepter: " << (p.rfc2217 ? "telnet(rfc2217)," : "") << "tcp,127.0.0.1,"
             << p.port << "\n"
             << "  connector: serialdev," << p.device.string() << "," << p.settings << ",local\n"
             << "  options:\n"
             << "    kickolduser: true\n";
      }
    }  // closed: ser2net reads it whole
    start();
  }
  Ser2net(const Ser2net&) = delete;
  Ser2net& operator=(const Ser2net&) = delete;

  // Runs ser2net and returns once every port listens (throws, with its log, if it does not).
  void start() {
    if (!std::filesystem::exists(kSer2net)) {
      throw std::runtime_error(kSer2net.string() + " is missing: run tools/deps.sh");
    }
    // Through sh only for the redirection: `exec` leaves ser2net itself as the child, so a
    // signal reaches it. Appended: a restart keeps the earlier run's lines.
    child_ = std::make_unique<Child>(
        std::vector<std::string>{"/bin/sh", "-c",
                                 "exec " + kSer2net.string() + " -n -d -u -c '" + config_.string() +
                                     "' >>'" + log_.string() + "' 2>&1"});
    const bool up = eventually(
        [&] {
          return !child_->running() || std::all_of(ports_.begin(), ports_.end(),
                                                   [](const auto& p) { return listening(p.port); });
        },
        std::chrono::seconds(5));
    if (!up || !child_->running()) {
      throw std::runtime_error("ser2net did not listen; its log:\n" + log());
    }
  }
  // SIGKILL, as a device server losing power would; returns once it is gone.
  void kill() {
    if (child_) child_->stop(SIGKILL);
  }
  void restart() {
    kill();
    start();
  }
  [[nodiscard]] std::string log() const {
    std::ifstream in(log_);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }
  [[nodiscard]] const std::filesystem::path& config() const { return config_; }

 private:
  std::vector<Ser2netPort> ports_;
  std::filesystem::path config_;
  std::filesystem::path log_;
  std::unique_ptr<Child> child_;
};

}  // namespace drivegate::test
