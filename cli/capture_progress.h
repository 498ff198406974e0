// What `drivegate capture` shows on stderr while it runs: the frames and bytes received so far
// and the seconds left, redrawn at most once a second (a capture is seconds to minutes long; a
// faster display would only flicker). In a terminal the line is redrawn in place; elsewhere
// (--progress into a log) each update is a line of its own.
#pragma once

#include <chrono>
#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>

namespace drivegate::cli {

// Counts the records of a pcap stream as its bytes pass (docs/capture.md: the 24-byte global
// header, then per frame a 16-byte record header whose captured length, little-endian at offset
// 8, says how many bytes of frame follow).
class PcapCounter {
 public:
  void feed(std::string_view bytes);
  [[nodiscard]] std::uint64_t frames() const { return frames_; }
  [[nodiscard]] std::uint64_t bytes() const { return bytes_; }

 private:
  std::uint64_t bytes_ = 0;
  std::uint64_t frames_ = 0;
  std::size_t skip_ = 24;  // of the global header, then of each frame
  std::string header_;     // the record header being read
};

class CaptureProgress {
 public:
  using Clock = std::chrono::steady_clock;
  // `in_place`: `out` is a terminal, so the line is redrawn where it is.
  CaptureProgress(std::ostream& out, bool in_place, std::string bus, std::chrono::seconds length);

  // The daemon accepted the capture: the countdown starts.
  void started(Clock::time_point now);
  void feed(std::string_view pcap) { counter_.feed(pcap); }
  // Redraws the line if a second has passed since the last time.
  void tick(Clock::time_point now);
  // Draws the final counts and ends the line, so what follows starts on a line of its own.
  // `ended`: the daemon ended the capture, so nothing is left whatever this side's clock says
  // (the daemon's countdown began before the answer reached here).
  void finish(Clock::time_point now, bool ended);

  [[nodiscard]] const PcapCounter& counter() const { return counter_; }

 private:
  void draw(Clock::time_point now, bool ended = false);

  std::ostream& out_;
  bool in_place_;
  std::string bus_;
  std::chrono::seconds length_;
  Clock::time_point started_{};
  Clock::time_point drawn_{};
  bool running_ = false;
  PcapCounter counter_;
};

}  // namespace drivegate::cli
