// What the HTTP side serves, and the one seam with the rest of the daemon (as backend.h is for
// Modbus): the daemon renders each document from the same register image and counters a Modbus
// client sees, at the moment it is asked for, on the event loop. Read-only: nothing here writes.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>

namespace drivegate::http {

// A capture of one bus in progress (GET /api/v1/capture, docs/capture.md): a pcap stream. The tap
// on the bus goes when this does.
class CaptureStream {
 public:
  virtual ~CaptureStream() = default;
  // The pcap bytes produced since the last call (the global header first), moved out.
  virtual std::string take() = 0;
  // It has reached its size cap: nothing more will come.
  [[nodiscard]] virtual bool full() const = 0;
};

// A document made a slice at a time (GET /api/v1/events: its largest page is about 330 KB of JSON,
// milliseconds of work at once). The server renders one slice of one such document per turn of
// the event loop, whoever asked for it, so the loop serves the PLCs between two slices; a
// document many requests ask for at once is rendered once for all of them.
class SlicedDocument {
 public:
  virtual ~SlicedDocument() = default;
  // Renders about `bytes` more of it unless it is whole: whether it is whole now.
  virtual bool render_slice(std::size_t bytes) = 0;
  [[nodiscard]] virtual bool whole() const = 0;
  // The document, once whole.
  [[nodiscard]] virtual std::shared_ptr<const std::string> document() const = 0;
};

// GET /api/v1/events: which entries of the history (docs/http.md); the route parses the query,
// the daemon judges the names.
struct EventsQuery {
  std::string device;          // ?device=NAME; empty: any
  std::string kind;            // ?kind=fault_raised; empty: any
  std::int64_t since_ms = 0;   // ?since=UNIX_SECONDS (a fraction allowed)
  std::uint64_t after = 0;     // ?after=SEQ: only entries newer than that one
  std::size_t limit = 100;     // ?limit=N (the history returns at most its maximum)
};

// GET /api/v1/trends: ?device=NAME or ?bus=NAME (else all) and ?since=UNIX_SECONDS.
struct TrendsQuery {
  std::string name;  // "device:NAME", "bus:NAME" or empty
  std::int64_t since_ms = 0;
};

class Content {
 public:
  virtual ~Content() = default;
  // GET /api/v1/status: devices, buses, listeners and clients (docs/http.md).
  virtual std::string status_json() = 0;
  // GET /metrics: Prometheus text exposition format 0.0.4.
  virtual std::string metrics() = 0;
  // GET /api/v1/regmap: the register map, as `drivegate regmap --format json` prints it.
  virtual std::string regmap_json() = 0;
  // GET /api/v1/events (JSON, made a slice at a time), or nullptr for a kind that is not one
  // (400).
  virtual std::shared_ptr<SlicedDocument> events_page(const EventsQuery& /*query*/) {
    return nullptr;
  }
  // GET /api/v1/trends (JSON).
  virtual std::string trends_json(const TrendsQuery& /*query*/) { return "{\"trends\":[]}"; }
  // Whether a bus of that name runs now.
  virtual bool has_bus(std::string_view /*name*/) { return false; }
  // Starts capturing bus `name`, at most `max_bytes` of pcap in all; `on_data` is called (on the
  // event loop, from inside the bus's own handling) whenever there is something to take() or it
  // became full. nullptr when there is no such bus.
  virtual std::unique_ptr<CaptureStream> start_capture(std::string_view /*name*/,
                                                       std::size_t /*max_bytes*/,
                                                       std::function<void()> /*on_data*/) {
    return nullptr;
  }
};

}  // namespace drivegate::http
