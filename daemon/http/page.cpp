// The status page: one self-contained HTML document (inline CSS and JS, no external assets, as
// the Content-Security-Policy in http_connection.cpp demands) that polls /api/v1/status every
// second and renders it, with the history from /api/v1/trends (sparklines, charts) and
// /api/v1/events (the events panel), both asked for incrementally in the same round. Its source
// is daemon/http/page/ (page.html, page.css, page.js: open page.html in a browser to work on
// it), made one document at build time by page/embed.cmake.
// Read-only: it only ever GETs JSON; nothing on it writes to a drive.
//
// Test hooks (tests/e2e/status_page_e2e_test.cpp): <body data-refresh-ms> is the poll period and
// data-link the connection state (connecting, live, unreachable); each drive is an <article
// data-device="NAME" data-state=...> whose values sit in elements with data-field="..."
// (speed_rpm, setpoint_rpm, fault_label, fault_code, native_fault, data_age_ms, failsafe, ...);
// each bus is a <tr data-bus="NAME">, each listener a <tr data-listener="ADDRESS">; each sparkline
// an <svg data-spark="device:NAME" data-last=...>, each event a <tr data-seq data-kind ...> in
// #events.
#include "routes.h"

namespace drivegate::http {

namespace {

#include "page_content.inc"  // kPage: daemon/http/page/, inlined by page/embed.cmake

}  // namespace

std::string_view status_page() {
  return kPage;
}

}  // namespace drivegate::http
