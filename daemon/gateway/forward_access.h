// What a pass-through device (Device::forward) makes of a Modbus request PDU before anything is
// queued: whether it may go on the line at all, and the access level it needs.
//
// Only whole, well-formed requests leave for a line. A slave that finds where a frame ends from
// its function code and counts (many real ones do, and so do both of drivegate's simulators)
// takes bytes past that end for a frame of their own, and one that skips a frame it does not
// know byte by byte finds any frame inside it: a write to another slave inside a read. So a
// request is forwarded only when
//   - the codec knows its function's request length (serial_codec.h: request_length); no other
//     function is forwarded, to any client (denied: exception 01, since no level allows it);
//   - it is exactly that long and its counts agree (request_counts_agree); FC 08, whose data the
//     Application Protocol lets be any number of words, carries exactly one
//     (kForwardedDiagnostics), as every sub-function but 0x0000 does;
//   - the RTU frame it makes at the slave's address holds no other request a length-parsing
//     slave would take: none that starts inside it, and no CRC that holds before its end (a
//     slave that delimits by CRC would end it there). Checked whatever the line's framing:
//     an ASCII line cannot carry one, and a request refused for it is rare (a CRC that happens
//     to hold: about one in 65536 per position).
// Anything else is invalid_value (exception 03), and never reaches the line.
//
// The access level: the functions that only read need read; every other one may change
// something in the slave and needs maintain. A pass-through window has no command block, so
// there is nothing of operate's to reach: an operate client reads through it only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "gateway/outcome.h"
#include "gateway/session.h"

namespace drivegate {

// FC 08's PDU as it is forwarded: function, sub-function and one word of data (Application
// Protocol 6.8: every sub-function but 0x0000 has exactly that; 0x0000's echo is held to it).
inline constexpr std::size_t kForwardedDiagnostics = 5;

struct ForwardVerdict {
  AccessLevel needs = AccessLevel::maintain;
  // ok: it may be forwarded to a session of `needs` or more. Else why not, for every session:
  // denied (a function whose length is unknown) or invalid_value (not one whole, well-formed
  // request), and `why` for the audit trail.
  Outcome refusal = Outcome::ok;
  std::string why;
};

// `address`: the slave's, which the frame on the line starts with.
ForwardVerdict judge_forward(std::span<const std::uint8_t> pdu, std::uint8_t address);

}  // namespace drivegate
