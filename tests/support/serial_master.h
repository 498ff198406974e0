// A serial line between a program under test and one nobody here wrote, for end-to-end tests:
// socat's two linked pseudo-terminals, and pymodbus's serial master
// (tests/e2e/pymodbus_serial_master.py) run on one end with a list of steps.
#pragma once

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include "e2e.h"

namespace drivegate::test {

// Two pseudo-terminals linked at `a` and `b`, joined by socat: what is written to one is read
// from the other. Both go away with it (a USB adapter unplugged).
class PtyPair {
 public:
  PtyPair(const std::filesystem::path& a, const std::filesystem::path& b,
          const std::filesystem::path& err)
      : socat_({"/usr/bin/socat", "pty,raw,echo=0,link=" + a.string(),
                "pty,raw,echo=0,link=" + b.string()},
               err) {
    using namespace std::chrono_literals;
    for (int i = 0; i < 100 && !std::filesystem::exists(b); ++i) {
      std::this_thread::sleep_for(20ms);
    }
  }
  // SIGTERM: socat removes its links as it goes.
  ~PtyPair() { socat_.stop(); }
  PtyPair(const PtyPair&) = delete;
  PtyPair& operator=(const PtyPair&) = delete;

 private:
  Child socat_;
};

// pymodbus_serial_master.py on `where` (--port PATH [--framing F], or --tcp HOST:PORT) with
// `steps`, its stderr to `err`: one line of output a step.
inline std::vector<std::string> run_serial_master(const std::vector<std::string>& where,
                                                  const std::vector<std::string>& steps,
                                                  const std::filesystem::path& err) {
  std::vector<std::string> argv = {kSystemPython, (std::filesystem::path(DRIVEGATE_SOURCE_DIR) /
                                                   "tests/e2e/pymodbus_serial_master.py")
                                                      .string()};
  argv.insert(argv.end(), where.begin(), where.end());
  argv.insert(argv.end(), steps.begin(), steps.end());
  Child c(argv, err);
  std::vector<std::string> lines;
  while (auto line = c.read_line(std::chrono::seconds(20))) lines.push_back(*line);
  c.wait_exit(std::chrono::seconds(5));
  return lines;
}

}  // namespace drivegate::test
