// Who owns a serial port. Every opener of a line (the daemon's buses, `drivegate write` and
// `action`, `drivegate sim --port`) takes it exclusively: a lock file in /run/lock, the UUCP /
// FHS convention Debian follows (LCK..<device name>, holding the owner's PID as ten ASCII digits
// and a newline, as minicom, cu and ModemManager read it), and TIOCEXCL on the open tty. A second
// opener fails at once, naming the owner ("in use by drivegated (pid 1234)"), instead of two
// programs sharing a line and garbling each other's frames.
//
// A lock left by a process that is gone (killed, crashed) is stale and taken over. Where the lock
// directory cannot be written (a user without the right), TIOCEXCL alone guards the port.
#pragma once

#include <filesystem>
#include <string>
#include <system_error>

namespace drivegate {

enum class PortError { in_use = 1 };
const std::error_category& port_category() noexcept;
inline std::error_code make_error_code(PortError e) noexcept {
  return {static_cast<int>(e), port_category()};
}

class PortLock {
 public:
  // /run/lock; DRIVEGATE_LOCK_DIR in the environment instead, for tests run without it.
  static std::filesystem::path default_dir();

  explicit PortLock(std::filesystem::path dir = default_dir()) : dir_(std::move(dir)) {}
  ~PortLock() { release(); }
  PortLock(const PortLock&) = delete;
  PortLock& operator=(const PortLock&) = delete;

  // Takes the lock of the tty `device` (a path, symlinks followed). PortError::in_use when a live
  // process other than this one holds it; owner() then names it. Taking a lock this process
  // already holds succeeds (the CLI holds its port before its gateway opens it).
  std::error_code acquire(const std::string& device);
  // Removes the lock file if this holds it.
  void release();
  // "drivegated (pid 1234)": the holder found by the last acquire() that failed.
  [[nodiscard]] const std::string& owner() const { return owner_; }
  // What the last acquire() that succeeded without a lock file of its own has to say (a stale lock
  // it could not remove), for the open's log line; empty otherwise.
  [[nodiscard]] const std::string& note() const { return note_; }
  // The lock file for `device`: dir/LCK..ttyUSB0 (a device below /dev/pts: LCK..pts_3).
  [[nodiscard]] std::filesystem::path lock_file(const std::string& device) const;

 private:
  std::filesystem::path dir_;
  std::filesystem::path held_;  // the lock file this holds, if any
  std::string owner_;
  std::string note_;
};

// TIOCEXCL on an open tty: no further open(2) of it succeeds (but root's).
std::error_code make_exclusive(int fd);

}  // namespace drivegate

template <>
struct std::is_error_code_enum<drivegate::PortError> : std::true_type {};
