// End-to-end test support: the real programs as child processes (`drivegate sim` on a pty,
// `drivegated` on a generated configuration) and libmodbus's Modbus TCP client, as a PLC would
// use it. Paths to the built programs come from the build (DRIVEGATE_TEST_BIN_DIR).
#pragma once

#include <fcntl.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "free_port.h"
#include "temp_dir.h"

extern char** environ;

namespace drivegate::test {

inline std::filesystem::path bin_dir() {
  return DRIVEGATE_TEST_BIN_DIR;
}
// Debian's python3-pymodbus lives with the system interpreter (`python3` may be a pyenv shim).
inline const std::string kSystemPython = "/usr/bin/python3";

inline std::filesystem::path plugin_dir() {
  return DRIVEGATE_TEST_PLUGIN_DIR;
}

// Whether production adapter `id`'s plugin is built: the few core scenarios whose subject is an
// adapter's own (a profile file, the shipped examples) skip without it; the rest run on test-drive.
inline bool adapter_built(const std::string& id) {
  return std::filesystem::exists(plugin_dir() / ("drivegate-" + id + ".so"));
}
#define REQUIRE_ADAPTER(id) \
  if (!::drivegate::test::adapter_built(id)) GTEST_SKIP() << (id) << " is not built"

// The serial port lock files (daemon/transport/port_lock.h) of the programs a test starts go to a
// directory of the test process's own, not /run/lock: a daemon killed with SIGKILL leaves its
// lock behind, and the next test must not meet it. Set once, before any child starts, and
// removed when the test process ends.
class LockDir {
 public:
  LockDir() {
    if (std::getenv("DRIVEGATE_LOCK_DIR") != nullptr) return;  // the caller chose one
    std::string tmpl = (std::filesystem::temp_directory_path() / "drivegate-locks-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) return;
    path_ = tmpl;
    ::setenv("DRIVEGATE_LOCK_DIR", path_.c_str(), 1);
  }
  ~LockDir() {
    std::error_code ec;
    if (!path_.empty()) std::filesystem::remove_all(path_, ec);
  }
  LockDir(const LockDir&) = delete;
  LockDir& operator=(const LockDir&) = delete;

 private:
  std::filesystem::path path_;
};
inline const LockDir kLockDir;

// A child process with its stdin and stdout on pipes; stderr is inherited (test log).
class Child {
 public:
  // `stderr_file`: where the child's stderr goes (empty: inherited, into the test's log).
  explicit Child(std::vector<std::string> argv, const std::filesystem::path& stderr_file = {}) {
    int in[2];
    int out[2];
    if (::pipe2(in, O_CLOEXEC) != 0 || ::pipe2(out, O_CLOEXEC) != 0) {
      throw std::runtime_error("pipe failed");
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, in[0], STDIN_FILENO);
    posix_spawn_file_actions_adddup2(&fa, out[1], STDOUT_FILENO);
    if (!stderr_file.empty()) {
      posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, stderr_file.c_str(),
                                       O_WRONLY | O_CREAT | O_TRUNC, 0644);
    }
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    const int rc = posix_spawn(&pid_, args[0], &fa, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    ::close(in[0]);
    ::close(out[1]);
    stdin_ = in[1];
    stdout_ = out[0];
    if (rc != 0) throw std::runtime_error("cannot start " + argv[0]);
  }
  ~Child() {
    terminate();
    if (stdin_ >= 0) ::close(stdin_);
    if (stdout_ >= 0) ::close(stdout_);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  void write_line(const std::string& line) {
    const std::string l = line + "\n";
    if (::write(stdin_, l.data(), l.size()) != static_cast<ssize_t>(l.size())) {
      throw std::runtime_error("write to child failed");
    }
  }
  // One line of stdout, or nullopt after `timeout`.
  std::optional<std::string> read_line(std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (true) {
      if (const auto nl = buffer_.find('\n'); nl != std::string::npos) {
        std::string line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        return line;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
          deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return std::nullopt;
      pollfd p{stdout_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
      char buf[4096];
      const ssize_t n = ::read(stdout_, buf, sizeof buf);
      if (n <= 0) return std::nullopt;
      buffer_.append(buf, static_cast<std::size_t>(n));
    }
  }
  // Sends `sig` and waits for the exit; returns the exit status (or 128 + signal).
  int stop(int sig = SIGTERM, std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    if (pid_ <= 0) return status_;
    ::kill(pid_, sig);
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      if (reap(WNOHANG)) return status_;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ::kill(pid_, SIGKILL);
    reap(0);
    return -1;
  }
  // Waits for the exit without sending anything; its status, or -1 after `timeout`.
  int wait_exit(std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (pid_ > 0 && std::chrono::steady_clock::now() < deadline) {
      if (reap(WNOHANG)) return status_;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return pid_ > 0 ? -1 : status_;
  }
  [[nodiscard]] bool running() { return pid_ > 0 && !reap(WNOHANG); }
  [[nodiscard]] pid_t pid() const { return pid_; }
  void signal(int sig) {
    if (pid_ > 0) ::kill(pid_, sig);
  }
  void terminate() {
    if (pid_ > 0) stop(SIGKILL, std::chrono::seconds(5));
  }

 private:
  bool reap(int flags) {
    int status = 0;
    if (::waitpid(pid_, &status, flags) != pid_) return false;
    status_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    pid_ = -1;
    return true;
  }
  pid_t pid_ = -1;
  int stdin_ = -1;
  int stdout_ = -1;
  int status_ = -1;
  std::string buffer_;
};

// `drivegate sim ADAPTER ...` on a pty linked at `link`.
class Sim {
 public:
  Sim(const std::string& adapter, const std::filesystem::path& link,
      std::vector<std::string> extra = {})
      : link_(link), child_(argv(adapter, link, std::move(extra))) {
    const auto path = child_.read_line(std::chrono::seconds(10));
    if (!path) throw std::runtime_error("drivegate sim " + adapter + " did not start");
    path_ = *path;
  }
  // Sends an operator command and returns the first line of its answer.
  std::string control(const std::string& line) {
    child_.write_line(line);
    return child_.read_line(std::chrono::seconds(5)).value_or("<no answer>");
  }
  [[nodiscard]] const std::string& path() const { return path_; }
  Child& process() { return child_; }

 private:
  static std::vector<std::string> argv(const std::string& adapter,
                                       const std::filesystem::path& link,
                                       std::vector<std::string> extra) {
    std::vector<std::string> a = {(bin_dir() / "drivegate").string(),
                                  "sim",
                                  adapter,
                                  "--link",
                                  link.string(),
                                  "--plugin-dir",
                                  plugin_dir().string()};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }
  std::filesystem::path link_;
  Child child_;
  std::string path_;
};

// Two Modbus TCP listeners, as a configuration's first lines: the one the harness moves to a free
// port (Daemon's --listen), where a client may maintain, and one on `read_port` where a client
// may only read.
inline std::string maintain_and_read_listeners(int read_port) {
  return "[[listener]]\naddress = \"127.0.0.1:1\"\naccess = \"maintain\"\n\n"
         "[[listener]]\naddress = \"127.0.0.1:" +
         std::to_string(read_port) + "\"\naccess = \"read\"\n\n";
}

// libmodbus's Modbus TCP client, as a PLC would talk to the gateway.
class Plc {
 public:
  explicit Plc(int port, int unit = 1) : ctx_(modbus_new_tcp("127.0.0.1", port)) {
    modbus_set_response_timeout(ctx_, 10, 0);
    modbus_set_slave(ctx_, unit);
  }
  ~Plc() {
    modbus_close(ctx_);
    modbus_free(ctx_);
  }
  Plc(const Plc&) = delete;
  Plc& operator=(const Plc&) = delete;
  bool connect() { return modbus_connect(ctx_) == 0; }
  void unit(int u) { modbus_set_slave(ctx_, u); }

  // Registers, or the Modbus exception code (negative: a transport error).
  struct Read {
    std::vector<std::uint16_t> regs;
    int exception = 0;
    [[nodiscard]] bool ok() const { return exception == 0; }
    [[nodiscard]] std::uint32_t u32(std::size_t at) const {
      return (std::uint32_t{regs.at(at)} << 16) | regs.at(at + 1);
    }
  };
  Read input(int address, int count) { return read(address, count, false); }
  Read holding(int address, int count) { return read(address, count, true); }
  // 0 on success, else the Modbus exception code (negative: a transport error).
  int write(int address, std::vector<std::uint16_t> values) {
    const int rc =
        values.size() == 1
            ? modbus_write_register(ctx_, address, values[0])
            : modbus_write_registers(ctx_, address, static_cast<int>(values.size()), values.data());
    return rc >= 0 ? 0 : code(errno);
  }

 private:
  static int code(int err) {
    if (err > MODBUS_ENOBASE && err < MODBUS_ENOBASE + 0x20) return err - MODBUS_ENOBASE;
    return -err;
  }
  Read read(int address, int count, bool holding) {
    Read r;
    r.regs.resize(static_cast<std::size_t>(count));
    const int rc = holding ? modbus_read_registers(ctx_, address, count, r.regs.data())
                           : modbus_read_input_registers(ctx_, address, count, r.regs.data());
    if (rc != count) r.exception = code(errno);
    return r;
  }
  modbus_t* ctx_;
};

// A Modbus TCP request ADU: the MBAP header (transaction, protocol 0, length, unit) and `pdu`.
inline std::vector<std::uint8_t> mbap_adu(std::uint16_t transaction, std::uint8_t unit,
                                          const std::vector<std::uint8_t>& pdu) {
  const auto length = static_cast<std::uint16_t>(pdu.size() + 1);
  std::vector<std::uint8_t> adu = {static_cast<std::uint8_t>(transaction >> 8),
                                   static_cast<std::uint8_t>(transaction & 0xFF),
                                   0x00,
                                   0x00,
                                   static_cast<std::uint8_t>(length >> 8),
                                   static_cast<std::uint8_t>(length & 0xFF),
                                   unit};
  adu.insert(adu.end(), pdu.begin(), pdu.end());
  return adu;
}

// Reads one response from `fd` within 10 s: its PDU (empty on a transport failure), and whether
// the server closed the connection right after it (`closed`, when asked for).
inline std::vector<std::uint8_t> read_response_pdu(int fd, bool* closed = nullptr) {
  std::vector<std::uint8_t> in;
  std::vector<std::uint8_t> out;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < deadline) {
    pollfd p{fd, POLLIN, 0};
    if (::poll(&p, 1, 100) <= 0) continue;
    std::uint8_t buf[300];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n <= 0) {
      if (closed != nullptr) *closed = n == 0;
      break;
    }
    in.insert(in.end(), buf, buf + n);
    if (out.empty() && in.size() >= 7 && in.size() >= 6u + ((in[4] << 8) | in[5])) {
      out.assign(in.begin() + 7, in.begin() + 6 + ((in[4] << 8) | in[5]));
      if (closed == nullptr) break;  // not waiting for the close
    }
  }
  return out;
}

// One Modbus TCP request as raw bytes, the way any client puts it on the wire: the MBAP header
// (transaction 1, protocol 0, length, unit) and `pdu`; returns the response PDU as received (empty
// on a transport failure). Tests assert exact bytes with it, not a client library's reading.
inline std::vector<std::uint8_t> raw_request(int port, std::uint8_t unit,
                                             const std::vector<std::uint8_t>& pdu) {
  const int fd = connect_loopback(port);
  if (fd < 0) return {};
  std::vector<std::uint8_t> out;
  const auto adu = mbap_adu(1, unit, pdu);
  if (::write(fd, adu.data(), adu.size()) == static_cast<ssize_t>(adu.size())) {
    out = read_response_pdu(fd);
  }
  ::close(fd);
  return out;
}

// drivegated on a configuration written from `toml`, listening on a free loopback port.
class Daemon {
 public:
  // `log`: where its stderr goes (empty: the test's own stderr). `port`: its Modbus TCP port
  // (0: a free_port()), for a test that hands out the ports of many daemons itself.
  Daemon(const TempDir& dir, const std::string& toml, std::vector<std::string> extra = {},
         const std::filesystem::path& log = {}, int port = 0)
      : port_(port != 0 ? port : free_port()),
        config_(dir / "drivegate.toml"),
        child_(argv(dir, toml, extra), log) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(15);
    while (std::chrono::steady_clock::now() < deadline) {
      Plc probe(port_);
      if (probe.connect()) return;
      if (!child_.running()) throw std::runtime_error("drivegated exited at start-up");
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    throw std::runtime_error("drivegated did not listen");
  }
  [[nodiscard]] int port() const { return port_; }
  [[nodiscard]] const std::filesystem::path& config() const { return config_; }
  Child& process() { return child_; }
  int stop() { return child_.stop(SIGTERM); }

 private:
  std::vector<std::string> argv(const TempDir& dir, const std::string& toml,
                                const std::vector<std::string>& extra) {
    std::ofstream(dir / "drivegate.toml") << toml;
    std::vector<std::string> a = {(bin_dir() / "drivegated").string(),
                                  "--config",
                                  (dir / "drivegate.toml").string(),
                                  "--listen",
                                  "127.0.0.1:" + std::to_string(port_),
                                  "--plugin-dir",
                                  plugin_dir().string()};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }
  int port_;
  std::filesystem::path config_;
  Child child_;
};

// A file's whole content (a log), "" if it cannot be read.
inline std::string slurp(const std::filesystem::path& file) {
  std::ostringstream text;
  text << std::ifstream(file).rdbuf();
  return text.str();
}

// How many times `what` stands in `text` (a log line's words, overlaps counted).
inline std::size_t occurrences(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// One request sent on a new connection whose sending side is then shut down (SHUT_WR) at once:
// the response PDU that came back, and whether the server closed the connection after it.
struct HalfClosedAnswer {
  std::vector<std::uint8_t> reply;
  bool closed_after = false;
};
inline HalfClosedAnswer half_closed_request(int port, std::uint8_t unit,
                                            const std::vector<std::uint8_t>& pdu) {
  HalfClosedAnswer out;
  const int fd = connect_loopback(port);
  if (fd < 0) return out;
  const auto adu = mbap_adu(7, unit, pdu);
  if (::write(fd, adu.data(), adu.size()) == static_cast<ssize_t>(adu.size())) {
    ::shutdown(fd, SHUT_WR);
    out.reply = read_response_pdu(fd, &out.closed_after);
  }
  ::close(fd);
  return out;
}

// One request sent on a new connection that is then reset (SO_LINGER 0) once the server has had
// time to read it, as when a client crashes with a write in flight.
inline void reset_after_request(int port, std::uint8_t unit, const std::vector<std::uint8_t>& pdu) {
  const int fd = connect_loopback(port);
  if (fd < 0) return;
  const auto adu = mbap_adu(8, unit, pdu);
  if (::write(fd, adu.data(), adu.size()) == static_cast<ssize_t>(adu.size())) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  const linger l{1, 0};
  ::setsockopt(fd, SOL_SOCKET, SO_LINGER, &l, sizeof l);
  ::close(fd);
}

// Polls `condition` every 20 ms until it holds or `timeout` passes.
inline bool eventually(const std::function<bool()>& condition,
                       std::chrono::milliseconds timeout = std::chrono::seconds(5)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    if (condition()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return condition();
}

// Addresses of the common block (docs/register-map.md).
namespace reg {
inline constexpr int status = 0, fault_code = 1, fault_mask = 2, native_fault = 4, speed = 6,
                     data_age = 7, frames_good = 9, bad_checksum = 11, timeouts = 13, retries = 15,
                     nacks = 17;
inline constexpr int command = 0, setpoint = 1, heartbeat = 2;
inline constexpr std::uint16_t online = 1 << 0, running = 1 << 1, fault = 1 << 2, warning = 1 << 3,
                               comm_lost = 1 << 4;
}  // namespace reg

// Whether the device `plc` talks to (its unit) reads online in the common block's status within
// `timeout`.
inline bool comes_online(Plc& plc, std::chrono::milliseconds timeout = std::chrono::seconds(10)) {
  return eventually([&] { return (plc.input(reg::status, 1).regs[0] & reg::online) != 0; },
                    timeout);
}

}  // namespace drivegate::test
