#include "scan_progress.h"

namespace drivegate::cli {

void ScanProgress::start(Clock::time_point now, const ScanCounts& counts) {
  running_ = true;
  draw(now, counts);
}

void ScanProgress::tick(Clock::time_point now, const ScanCounts& counts) {
  if (running_ && now - drawn_ >= std::chrono::seconds(1)) draw(now, counts);
}

void ScanProgress::finish(Clock::time_point now, const ScanCounts& counts) {
  if (!running_) return;
  draw(now, counts);
  running_ = false;
  if (in_place_) out_ << "\n" << std::flush;
}

void ScanProgress::draw(Clock::time_point now, const ScanCounts& counts) {
  // Whole seconds, rounded up: "1 s left" until the very end.
  const auto left_s = std::chrono::ceil<std::chrono::seconds>(counts.left).count();
  out_ << (in_place_ ? "\r" : "") << "drivegate scan: " << counts.probed << " of " << counts.total
       << " addresses, " << counts.found << (counts.found == 1 ? " slave" : " slaves")
       << " found, at most " << left_s << " s left" << (in_place_ ? "\033[K" : "\n") << std::flush;
  drawn_ = now;
}

}  // namespace drivegate::cli
