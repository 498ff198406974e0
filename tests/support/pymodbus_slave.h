// A Modbus RTU / ASCII slave nobody here wrote, for end-to-end tests: pymodbus's serial server
// (Debian's python3-pymodbus, tests/e2e/pymodbus_serial_slave.py) on one end of a pseudo-terminal
// pair made by socat; the program under test opens the other. (adapters/modbus/tests/e2e_test.cpp
// has its own copy of this class from before it was shared.)
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "e2e.h"
#include "serial_master.h"

namespace drivegate::test {

inline std::filesystem::path pymodbus_slave_script() {
  return std::filesystem::path(DRIVEGATE_SOURCE_DIR) / "tests/e2e/pymodbus_serial_slave.py";
}

// Whether socat and python3-pymodbus are installed (tools/deps.sh test installs them).
inline bool have_pymodbus_tools() {
  return std::filesystem::exists("/usr/bin/socat") && std::filesystem::exists(kSystemPython) &&
         std::filesystem::exists("/usr/lib/python3/dist-packages/pymodbus");
}

// socat's two linked pseudo-terminals, `a` (the tested program's) and `b` (the slave's), and the
// slave on `b` with `args` (pymodbus_serial_slave.py's options).
class PymodbusSlave {
 public:
  PymodbusSlave(const TempDir& dir, const std::vector<std::string>& args)
      : a_(dir / "a"), out_(dir / "slave.out"), line_(dir / "a", dir / "b", dir / "socat.err") {
    using namespace std::chrono_literals;
    std::vector<std::string> argv = {"/bin/sh", "-c",
                                     "exec " + kSystemPython + " " +
                                         pymodbus_slave_script().string() + " --port " +
                                         (dir / "b").string()};
    for (const auto& x : args) argv[2] += " " + x;
    argv[2] += " > " + out_.string();
    slave_ = std::make_unique<Child>(argv, dir / "slave.err");
    for (int i = 0; i < 200 && slurp(out_).find("ready") == std::string::npos; ++i) {
      std::this_thread::sleep_for(20ms);
    }
  }
  [[nodiscard]] const std::filesystem::path& port() const { return a_; }
  // What reached the slave: its `write TABLE ADDRESS VALUE...` lines.
  [[nodiscard]] std::string writes() const { return slurp(out_); }
  void kill() { slave_.reset(); }

 private:
  std::filesystem::path a_;
  std::filesystem::path out_;
  PtyPair line_;
  std::unique_ptr<Child> slave_;
};

}  // namespace drivegate::test
