// What `drivegate scan` shows on stderr while it runs: the addresses probed, the slaves found
// and the most time left, redrawn at most once a second (as `drivegate capture` does,
// capture_progress.h). In a terminal the line is redrawn in place; elsewhere (--progress into a
// log) each update is a line of its own.
#pragma once

#include <chrono>
#include <cstddef>
#include <ostream>

namespace drivegate::cli {

struct ScanCounts {
  std::size_t probed = 0;
  std::size_t total = 0;
  std::size_t found = 0;
  std::chrono::nanoseconds left{0};  // at most, if no other address answers
};

class ScanProgress {
 public:
  using Clock = std::chrono::steady_clock;
  // `in_place`: `out` is a terminal, so the line is redrawn where it is.
  ScanProgress(std::ostream& out, bool in_place) : out_(out), in_place_(in_place) {}

  // Draws the first line.
  void start(Clock::time_point now, const ScanCounts& counts);
  // Redraws the line if a second has passed since the last time.
  void tick(Clock::time_point now, const ScanCounts& counts);
  // Draws the final counts and ends the line, so that what follows starts on a line of its own.
  void finish(Clock::time_point now, const ScanCounts& counts);

 private:
  void draw(Clock::time_point now, const ScanCounts& counts);

  std::ostream& out_;
  bool in_place_;
  bool running_ = false;
  Clock::time_point drawn_{};
};

}  // namespace drivegate::cli
