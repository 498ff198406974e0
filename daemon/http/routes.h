// Which document a request gets: pure (a method and a target in, a response out), so every
// route, refusal and header is tested without a socket.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "content.h"

namespace drivegate::http {

// GET /api/v1/capture: not a document but a stream, which the connection serves (a pcap of the
// bus for `duration`, docs/capture.md).
struct CaptureRequest {
  std::string bus;
  std::chrono::seconds duration{10};
};

inline constexpr std::chrono::seconds kCaptureDefault{10};
inline constexpr std::chrono::seconds kCaptureMax{300};

struct Response {
  unsigned status = 200;
  std::string content_type;
  std::string body;
  std::string allow;                       // for 405: the methods that are
  std::optional<CaptureRequest> capture;   // set: stream this capture instead of `body`
  std::shared_ptr<SlicedDocument> sliced;  // set: this (a slice at a time) instead of `body`
};

struct RouteOptions {
  bool capture = false;  // [http] capture: whether /api/v1/capture is served (else 403)
};

// GET and HEAD only (the server strips HEAD's body). Query strings are ignored except where a
// route reads them. Unknown targets are 404; other methods 405.
// /api/v1/capture?bus=NAME&seconds=N (N 1..300, default 10): 403 unless options.capture, 400 for a
// missing bus or a bad N, 404 for an unknown bus; else a Response whose `capture` says what to
// stream (application/vnd.tcpdump.pcap).
// /api/v1/events?device=&kind=&since=&after=&limit= and /api/v1/trends?device=|bus=&since=:
// 400 for a value that is not a number or out of range, or an unknown kind (content.h).
Response route(std::string_view method, std::string_view target, Content& content,
               const RouteOptions& options = {});

// The status page (page.cpp): HTML, CSS and JavaScript in one document, no external asset.
std::string_view status_page();

}  // namespace drivegate::http
