// Where the audit trail's lines go besides the history: an entry with structured fields (DEVICE=,
// UNIT=, CLIENT=, ROLE=, RESULT=, ...) at info level. The daemon's writes to the journal over its
// native protocol when it runs under systemd, else logs the message (app/logging.h); tests
// keep what they are given.
#pragma once

#include <span>
#include <string>
#include <string_view>

namespace drivegate {

class JournalWriter {
 public:
  virtual ~JournalWriter() = default;
  // `fields`: "NAME=value" each, MESSAGE= and PRIORITY= not among them.
  virtual void info(std::string_view message, std::span<const std::string> fields) = 0;
};

}  // namespace drivegate
