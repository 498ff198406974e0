// open_serial() reports every failure as an error code and leaves the port closed: the bus engine
// retries on a timer, and an exception there would take the whole gateway down.
#include "transport/serial_line.h"

#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <stdexcept>
#include <string>

#include "fifo_trap.h"

namespace drivegate {
namespace {

BusConfig bus_on(std::string port) {
  BusConfig bus;
  bus.name = "b";
  bus.port = std::move(port);
  bus.baud = 9600;
  return bus;
}

// A pseudo-terminal: a tty that takes termios settings but is no UART.
class Pty {
 public:
  Pty() : master_(::posix_openpt(O_RDWR | O_NOCTTY)) {
    if (master_ >= 0 && ::grantpt(master_) == 0 && ::unlockpt(master_) == 0) {
      if (const char* name = ::ptsname(master_)) path_ = name;
    }
  }
  ~Pty() {
    if (master_ >= 0) ::close(master_);
  }
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  int master_;
  std::string path_;
};

// A fresh directory for the test's port lock files.
std::filesystem::path make_lock_dir() {
  std::string tmpl = (std::filesystem::temp_directory_path() / "drivegate-lock-XXXXXX").string();
  if (::mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("mkdtemp failed");
  return tmpl;
}

class SerialLine : public ::testing::Test {
 protected:
  ~SerialLine() override {
    std::error_code ec;
    std::filesystem::remove_all(lock_dir_, ec);
  }
  std::filesystem::path lock_dir_ = make_lock_dir();  // before lock_, which uses it
  boost::asio::io_context io_;
  boost::asio::serial_port port_{io_};
  PortLock lock_{lock_dir_};
};

TEST_F(SerialLine, AMissingDeviceIsAnErrorCode) {
  std::error_code ec;
  EXPECT_NO_THROW(ec = open_serial(port_, bus_on("/nonexistent/ttyUSB9"), lock_));
  EXPECT_EQ(ec, std::errc::no_such_file_or_directory) << ec.message();
  EXPECT_EQ(ec.category(), std::generic_category());
  EXPECT_FALSE(port_.is_open());
}

TEST_F(SerialLine, ANonTtyIsAnErrorCodeNotAnException) {
  const auto file = std::filesystem::temp_directory_path() /
                    ("drivegate-serial-test-" + std::to_string(::getpid()));
  std::ofstream(file) << "not a tty\n";
  for (const std::string& path : {std::string("/dev/null"), file.string()}) {
    std::error_code ec;
    EXPECT_NO_THROW(ec = open_serial(port_, bus_on(path), lock_)) << path;
    EXPECT_TRUE(ec) << path;
    EXPECT_FALSE(port_.is_open()) << path;
  }
  std::filesystem::remove(file);
}

TEST_F(SerialLine, AFailedSettingClosesThePortAndReportsIt) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  ASSERT_FALSE(open_serial(port_, bus_on(pty.path()), lock_));  // the pty itself is fine
  port_.close();
  BusConfig bus = bus_on(pty.path());
  bus.baud = 12345;  // no such standard rate: asio refuses it in set_option
  std::error_code ec;
  EXPECT_NO_THROW(ec = open_serial(port_, bus, lock_));
  EXPECT_EQ(ec, std::errc::invalid_argument) << ec.message();
  EXPECT_FALSE(port_.is_open());
}

// Asio's own errors are not errno values: "already open" is 1 in asio.misc, not EPERM.
TEST_F(SerialLine, AsioErrorsKeepTheirMeaning) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  ASSERT_FALSE(open_serial(port_, bus_on(pty.path()), lock_));
  const std::error_code ec = open_serial(port_, bus_on(pty.path()), lock_);
  EXPECT_TRUE(ec);
  EXPECT_NE(ec, std::errc::operation_not_permitted);
  EXPECT_STREQ(ec.category().name(), "asio.misc");
  EXPECT_THAT(ec.message(), ::testing::HasSubstr("lready open"));
}

// A pseudo-terminal keeps the baud rate and the stop bits it is given, but has no parity: the
// kernel drops it without an error. The port still opens (a pty is a fine test line), and what it
// refused is named, read back from the port. (It has always 8 data bits too, but 7 is refused
// outright: glibc's tcsetattr reads CSIZE back and says EINVAL.)
TEST_F(SerialLine, SettingsThePortDroppedAreNamedAndThePortStillOpens) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  BusConfig bus = bus_on(pty.path());
  bus.parity = Parity::even;
  std::string refused = "not set";
  ASSERT_FALSE(open_serial(port_, bus, lock_, &refused));
  EXPECT_TRUE(port_.is_open());
  EXPECT_EQ(refused, "parity even (the port has none)");
  port_.close();
  lock_.release();
  bus.parity = Parity::odd;
  bus.stop_bits = 2;
  ASSERT_FALSE(open_serial(port_, bus, lock_, &refused));
  EXPECT_EQ(refused, "parity odd (the port has none)");
  port_.close();
  lock_.release();
  bus.data_bits = 7;
  EXPECT_EQ(open_serial(port_, bus, lock_, &refused), std::errc::invalid_argument);
  EXPECT_FALSE(port_.is_open());
  // What a pty takes is not refused: 8N1, 8N2, any standard rate.
  bus = bus_on(pty.path());
  bus.baud = 115200;
  bus.stop_bits = 2;
  ASSERT_FALSE(open_serial(port_, bus, lock_, &refused));
  EXPECT_EQ(refused, "");
}

TEST_F(SerialLine, AFailedRs485SwitchClosesThePortAndReportsIt) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  BusConfig bus = bus_on(pty.path());
  bus.rs485 = true;  // a pty has no RS-485 mode
  std::error_code ec;
  EXPECT_NO_THROW(ec = open_serial(port_, bus, lock_));
  EXPECT_TRUE(ec);
  EXPECT_FALSE(port_.is_open());
}

// A port has one owner. The lock file of a port another live program holds (here the
// test's parent, started before the file was written) refuses the open at once, naming it; the
// port itself is never opened.
TEST_F(SerialLine, APortAnotherProgramHoldsIsRefusedNamingIt) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  const auto file = lock_.lock_file(pty.path());
  EXPECT_EQ(file.filename().string().rfind("LCK..pts_", 0), 0u) << file;
  std::ofstream(file) << std::setw(10) << ::getppid() << "\n";
  const std::error_code ec = open_serial(port_, bus_on(pty.path()), lock_);
  EXPECT_EQ(ec, PortError::in_use) << ec.message();
  EXPECT_THAT(lock_.owner(), ::testing::HasSubstr("(pid " + std::to_string(::getppid()) + ")"));
  EXPECT_FALSE(port_.is_open());
  EXPECT_TRUE(std::filesystem::exists(file));  // not ours to remove
}

// A lock left by a process that is gone is stale: taken over, then released with the port.
TEST_F(SerialLine, AStaleLockIsTakenOverAndReleasedWithThePort) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  const pid_t gone = ::fork();
  if (gone == 0) ::_exit(0);
  ASSERT_GT(gone, 0);
  int status = 0;
  ::waitpid(gone, &status, 0);  // reaped: no process has that PID now
  const auto file = lock_.lock_file(pty.path());
  std::ofstream(file) << std::setw(10) << gone << "\n";
  ASSERT_FALSE(open_serial(port_, bus_on(pty.path()), lock_));
  std::ifstream in(file);
  long pid = 0;
  in >> pid;
  EXPECT_EQ(pid, ::getpid());  // ours now, in the HDB UUCP form
  lock_.release();
  EXPECT_FALSE(std::filesystem::exists(file));
}

// A stale lock this cannot remove (root's file in the sticky /run/lock, met by the service's
// user: the lock a killed root process left) does not keep the port closed forever: its holder
// is gone, so the port opens under TIOCEXCL alone, and the note says why there is no lock file.
// (Root may remove any file, so a directory in the lock file's place stands in for it here.)
TEST_F(SerialLine, AStaleLockThatCannotBeRemovedStillLetsThePortOpen) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  const auto file = lock_.lock_file(pty.path());
  std::filesystem::create_directories(file / "held");
  const std::error_code ec = open_serial(port_, bus_on(pty.path()), lock_);
  EXPECT_FALSE(ec) << ec.message();
  EXPECT_TRUE(port_.is_open());
  EXPECT_THAT(lock_.note(), ::testing::HasSubstr("stale lock " + file.string()));
  EXPECT_THAT(lock_.note(), ::testing::HasSubstr("TIOCEXCL alone"));
  // Exclusive all the same: a second opener of this process's kind is refused by the tty.
  if (::geteuid() != 0) {
    const int again = ::open(pty.path().c_str(), O_RDWR | O_NOCTTY);
    EXPECT_LT(again, 0);
    if (again >= 0) ::close(again);
  }
  lock_.release();
  EXPECT_TRUE(std::filesystem::exists(file / "held"));  // never ours to remove
}

// /run/lock is everyone's (sticky, world-writable): a FIFO anyone made at a port's lock file name
// would block the daemon's open of it, and with it Modbus, HTTP and every other bus. It is no
// lock (no PID can be read from it): taken over as a stale one, and the port opens at once.
TEST_F(SerialLine, AFifoAtTheLockFilesNameNeitherBlocksNorHoldsThePort) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  const auto file = lock_.lock_file(pty.path());
  std::error_code ec;
  std::chrono::steady_clock::duration took{};
  {
    test::FifoTrap trap({file});
    const auto t0 = std::chrono::steady_clock::now();
    ec = open_serial(port_, bus_on(pty.path()), lock_);
    took = std::chrono::steady_clock::now() - t0;
  }
  EXPECT_LT(took, std::chrono::seconds(1)) << "blocked on the FIFO";
  EXPECT_FALSE(ec) << ec.message();
  EXPECT_TRUE(port_.is_open());
  EXPECT_TRUE(std::filesystem::is_regular_file(std::filesystem::symlink_status(file)))
      << "a lock file of its own";
}

}  // namespace
}  // namespace drivegate
