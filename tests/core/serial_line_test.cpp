// open_serial() reports every failure as an error code and leaves the port closed: the bus engine
// retries on a timer, and an exception there would take the whole gateway down.
#include "line/serial_line.h"

#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <boost/asio/io_context.hpp>
#include <filesystem>
#include <fstream>
#include <string>

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

class SerialLine : public ::testing::Test {
 protected:
  boost::asio::io_context io_;
  boost::asio::serial_port port_{io_};
};

TEST_F(SerialLine, AMissingDeviceIsAnErrorCode) {
  std::error_code ec;
  EXPECT_NO_THROW(ec = open_serial(port_, bus_on("/nonexistent/ttyUSB9")));
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
    EXPECT_NO_THROW(ec = open_serial(port_, bus_on(path))) << path;
    EXPECT_TRUE(ec) << path;
    EXPECT_FALSE(port_.is_open()) << path;
  }
  std::filesystem::remove(file);
}

TEST_F(SerialLine, AFailedSettingClosesThePortAndReportsIt) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  ASSERT_FALSE(open_serial(port_, bus_on(pty.path())));  // the pty itself is fine
  port_.close();
  BusConfig bus = bus_on(pty.path());
  bus.baud = 12345;  // no such standard rate: asio refuses it in set_option
  std::error_code ec;
  EXPECT_NO_THROW(ec = open_serial(port_, bus));
  EXPECT_EQ(ec, std::errc::invalid_argument) << ec.message();
  EXPECT_FALSE(port_.is_open());
}

// Asio's own errors are not errno values: "already open" is 1 in asio.misc, not EPERM.
TEST_F(SerialLine, AsioErrorsKeepTheirMeaning) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  ASSERT_FALSE(open_serial(port_, bus_on(pty.path())));
  const std::error_code ec = open_serial(port_, bus_on(pty.path()));
  EXPECT_TRUE(ec);
  EXPECT_NE(ec, std::errc::operation_not_permitted);
  EXPECT_STREQ(ec.category().name(), "asio.misc");
  EXPECT_THAT(ec.message(), ::testing::HasSubstr("lready open"));
}

TEST_F(SerialLine, AFailedRs485SwitchClosesThePortAndReportsIt) {
  Pty pty;
  if (pty.path().empty()) GTEST_SKIP() << "no pseudo-terminals here";
  BusConfig bus = bus_on(pty.path());
  bus.rs485 = true;  // a pty has no RS-485 mode
  std::error_code ec;
  EXPECT_NO_THROW(ec = open_serial(port_, bus));
  EXPECT_TRUE(ec);
  EXPECT_FALSE(port_.is_open());
}

}  // namespace
}  // namespace drivegate
