// FIFOs put where the code under test expects a file, for the tests that a FIFO cannot hang the
// daemon (docs/security.md). Opening a FIFO blocks until its other end is opened: code that opens
// one without O_NONBLOCK waits for ever. So that such a test fails instead of hanging, a watchdog
// opens both ends of every FIFO it made (those still there) once `patience` has passed, which
// lets a blocked open return; the test asserts that what it did took far less than that.
#pragma once

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

namespace drivegate::test {

class FifoTrap {
 public:
  explicit FifoTrap(std::vector<std::filesystem::path> fifos,
                    std::chrono::milliseconds patience = std::chrono::seconds(3))
      : fifos_(std::move(fifos)) {
    for (const auto& f : fifos_) {
      if (::mkfifo(f.c_str(), 0600) != 0) throw std::runtime_error("mkfifo " + f.string());
    }
    watchdog_ = std::thread([this, patience] {
      std::unique_lock lock(mutex_);
      if (stop_cv_.wait_for(lock, patience, [this] { return stopping_; })) return;
      for (const auto& f : fifos_) {
        // A reader first (non-blocking, it always opens), then a writer (it opens once a reader
        // has): whichever end the code under test waits on is then there. The reader stays open
        // until the trap goes, so that what the code then writes fills the pipe instead of
        // raising SIGPIPE; the writer closes at once, so that what it reads ends.
        const int r = ::open(f.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
        const int w = ::open(f.c_str(), O_WRONLY | O_NONBLOCK | O_CLOEXEC);
        if (w >= 0) ::close(w);
        if (r >= 0) readers_.push_back(r);
      }
    });
  }
  ~FifoTrap() {
    {
      std::lock_guard lock(mutex_);
      stopping_ = true;
    }
    stop_cv_.notify_all();
    watchdog_.join();
    for (const int r : readers_) ::close(r);
  }
  FifoTrap(const FifoTrap&) = delete;
  FifoTrap& operator=(const FifoTrap&) = delete;

 private:
  std::vector<std::filesystem::path> fifos_;
  std::mutex mutex_;
  std::condition_variable stop_cv_;
  bool stopping_ = false;
  std::vector<int> readers_;  // opened by the watchdog
  std::thread watchdog_;
};

}  // namespace drivegate::test
