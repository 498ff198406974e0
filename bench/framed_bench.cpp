// dg-framed-bench: the framed adapter beside the C++ adapters it is proven against, in one run
// (docs/performance.md, "Described protocols"). For each seed protocol:
//
//  - the bus time of a poll cycle, on simulated time and a simulated line
//  (tests/support/bus_rig.h):
//    the real bus engine drives the C++ adapter's driver, then framed's with the shipped
//    description, each against the C++ adapter's own simulator. Every byte takes its character
//    time, so the numbers are exact and the same on every machine. A cycle holds the line from its
//    request's first byte to the last byte of its reply (or of the request, where none comes);
//  - the codec's CPU per frame: the C++ codec's decoder and encoder, then framed's, over the same
//    frames, on this machine (nanoseconds, best of several runs).
//
//   dg-framed-bench [--check] [--plugin-dir DIR] [--frames N]
//
// --check: no CPU figures; exit 1 unless every seed's poll cycle takes within 2 % of the C++
// adapter's bus time (the bound; simulated time, so exact) and the framed driver was
// polled as often. The plugins come from the build tree (DRIVEGATE_BUILD_PLUGIN_DIR).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bus_rig.h"
#include "fdc1/codec.h"
#include "framed/codec.h"
#include "framed/settings.h"
#include "mdriver-2400/codec.h"
#include "nidec-washer/codec.h"
#include "plugin/plugins.h"

namespace {

using namespace drivegate;
using namespace std::chrono_literals;
using Nanos = std::chrono::nanoseconds;

struct Seed {
  std::string id;
  test::OptionText options;  // both devices'
  test::OptionText sim_options;
  Millis poll;
};

// One cycle's bus time, and how many cycles were seen, for one adapter's device.
struct Cycle {
  double mean_ms = 0;
  std::size_t cycles = 0;
  std::string error;
};

Cycle measure(const AdapterDescriptor& device_adapter, const AdapterDescriptor& sim_adapter,
              const Seed& s) {
  Cycle c;
  test::BusRig rig(device_adapter);
  DeviceConfig dc = rig.device_config("drive", device_adapter.default_address, s.options);
  dc.poll_interval = s.poll;
  Device& d = rig.add_device(dc);
  SimEnv env;
  env.address = sim_adapter.default_address;
  env.options = test::options_of(sim_adapter, s.sim_options);
  std::string why;
  auto sim = sim_adapter.create_simulator(env, why);
  if (!sim) throw std::runtime_error(s.id + " simulator: " + why);
  rig.add_simulator(std::move(sim));
  rig.start();
  if (!rig.run_until([&] { return d.online(); }, 10s)) {
    c.error = "never online";
    return c;
  }
  rig.run_for(2s);  // past the handshake
  const TimePoint from = rig.now();
  rig.run_for(30s);
  const auto& line = rig.line();
  const Nanos ch = character_time(device_adapter.line.baud, device_adapter.line.parity,
                                  device_adapter.line.data_bits, device_adapter.line.stop_bits);
  const auto end_of = [&](const test::SimLine::Frame& f) {
    return f.at + ch * static_cast<long>(f.bytes.size());
  };
  Nanos total{0};
  for (std::size_t i = 0; i < line.sent.size(); ++i) {
    const auto& req = line.sent[i];
    if (req.at < from) continue;
    TimePoint end = end_of(req);
    // Its reply, where one comes: what the device sends before the master's next frame. A
    // streaming device's frames are its own, not answers: the cycle is the request alone.
    const TimePoint next = i + 1 < line.sent.size() ? line.sent[i + 1].at : TimePoint::max();
    for (const auto& a :
         device_adapter.streaming ? std::vector<test::SimLine::Frame>{} : line.answers) {
      if (a.at >= req.at && a.at < next) end = std::max(end, end_of(a));
    }
    total += end - req.at;
    ++c.cycles;
  }
  if (c.cycles == 0) {
    c.error = "no poll";
    return c;
  }
  c.mean_ms =
      std::chrono::duration<double, std::milli>(total).count() / static_cast<double>(c.cycles);
  return c;
}

// One run of `n` calls, in ns per call.
double ns_per(std::size_t n, const std::function<void()>& one) {
  const auto t0 = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < n; ++i) one();
  const auto t1 = std::chrono::steady_clock::now();
  return std::chrono::duration<double, std::nano>(t1 - t0).count() / static_cast<double>(n);
}

// The C++ codec's call and framed's, side by side: rounds alternating which goes first, the best
// of each (the least disturbed by the rest of the machine), ns per call.
std::pair<double, double> side_by_side(std::size_t n, const std::function<void()>& native,
                                       const std::function<void()>& framed) {
  double a = 1e30;
  double b = 1e30;
  for (int round = 0; round < 9; ++round) {
    if (round % 2 == 0) {
      a = std::min(a, ns_per(n, native));
      b = std::min(b, ns_per(n, framed));
    } else {
      b = std::min(b, ns_per(n, framed));
      a = std::min(a, ns_per(n, native));
    }
  }
  return {a, b};
}

volatile std::size_t g_sink = 0;  // keeps the decoders' work from being optimised away

struct CodecRow {
  std::string what;
  std::pair<double, double> ns;  // C++, framed
};

std::vector<CodecRow> codec_rows(std::size_t n) {
  std::vector<CodecRow> rows;
  const auto description = [](const std::string& name) {
    std::string error;
    auto d = framed::load_description(name, error);
    if (!d) throw std::runtime_error(error);
    return d;
  };
  const auto decode = [&](const framed::Codec& c, const Bytes& b) {
    return [&c, &b] { g_sink = g_sink + c.decode(framed::Direction::reply, b).consumed; };
  };
  {
    const auto d = description("nidec-washer");
    const framed::Codec fc(*d);
    const Bytes ack = {0xA5, 0x05, 0x00, 0x03, 0x20, 0x23, 0xA0};
    rows.push_back(
        {"nidec-washer decode request ACK",
         side_by_side(
             n, [&] { g_sink = g_sink + nidec::decode_reply(ack).consumed; }, decode(fc, ack))});
    const std::size_t cw = *d->message("cw");
    const double values[] = {800, 30};
    rows.push_back({"nidec-washer encode CW 800 rpm",
                    side_by_side(
                        n,
                        [&] {
                          g_sink = g_sink +
                                   nidec::encode(nidec::make_run(nidec::Mode::cw, 800, 30)).size();
                        },
                        [&] { g_sink = g_sink + fc.encode(cw, values).size(); })});
  }
  {
    const auto d = description("mdriver-2400");
    const framed::Codec fc(*d);
    const Bytes reply = {0x01, 0x00, 0x10, 0x07, 0x1C, 0x1C, 0x00,
                         0x00, 0x1A, 0x00, 0x00, 0x00, 0xEB};
    rows.push_back(
        {"mdriver-2400 decode run reply",
         side_by_side(
             n, [&] { g_sink = g_sink + mdriver::decode(reply).consumed; }, decode(fc, reply))});
    const std::size_t run = *d->message("run");
    // run's fields: master, address, n, code, change (framed/protocols/mdriver-2400.toml)
    const double values[] = {0, 1, 0, 0x1C, 0x01};
    rows.push_back({"mdriver-2400 encode run 504 rpm",
                    side_by_side(
                        n, [&] { g_sink = g_sink + mdriver::encode_run(0, 1, 0x1C, 0x01).size(); },
                        [&] { g_sink = g_sink + fc.encode(run, values).size(); })});
  }
  {
    const auto d = description("fdc1");
    const framed::Codec fc(*d);
    const Bytes on = {0x1B, 0x4C, 0x09, 0xC4, 0x1E, 0xDC, 0x0C, 0x54};
    rows.push_back(
        {"fdc1 decode ON status",
         side_by_side(
             n, [&] { g_sink = g_sink + fdc1::decode_device(on).consumed; }, decode(fc, on))});
    const std::size_t speed = *d->message("speed");
    const double values[] = {2000, 3000};
    rows.push_back({"fdc1 encode speed 2000..3000",
                    side_by_side(
                        n,
                        [&] {
                          g_sink = g_sink + fdc1::encode_speed({2000, 3000}).size();
                        },
                        [&] { g_sink = g_sink + fc.encode(speed, values).size(); })});
  }
  return rows;
}

}  // namespace

int main(int argc, char** argv) {
  bool check = false;
  std::string plugin_dir = DRIVEGATE_BUILD_PLUGIN_DIR;
  std::size_t frames = 200'000;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--check") {
      check = true;
    } else if (a == "--plugin-dir" && i + 1 < argc) {
      plugin_dir = argv[++i];
    } else if (a == "--frames" && i + 1 < argc) {
      frames = std::strtoul(argv[++i], nullptr, 10);
    } else {
      std::fprintf(stderr, "usage: dg-framed-bench [--check] [--plugin-dir DIR] [--frames N]\n");
      return 2;
    }
  }
  PluginRegistry plugins;
  for (const char* id : {"framed", "nidec-washer", "mdriver-2400", "fdc1"}) {
    const std::string why = plugins.load_file(std::string(plugin_dir) + "/drivegate-" + id + ".so");
    if (!why.empty()) {
      std::fprintf(stderr, "dg-framed-bench: %s\n", why.c_str());
      return 1;
    }
  }
  const std::vector<Seed> seeds = {
      {"nidec-washer", {{"platform", "8"}}, {{"platform", "8"}}, 500ms},
      {"mdriver-2400", {}, {}, 500ms},
      {"fdc1", {{"slave_mode", "true"}, {"refresh_s", "1"}}, {{"slave_mode", "true"}}, 500ms},
  };
  bool ok = true;
  std::printf(
      "| protocol | C++ adapter, ms a cycle | framed, ms a cycle | framed / C++ | cycles in 30 s "
      "(C++, framed) |\n"
      "|---|---|---|---|---|\n");
  for (const Seed& s : seeds) {
    const AdapterDescriptor& native = *plugins.find(s.id);
    test::OptionText framed_options = {{"protocol", s.id}};
    framed_options.insert(framed_options.end(), s.options.begin(), s.options.end());
    Options base;
    base.set("protocol", s.id);
    std::string why;
    const AdapterDescriptor* framed = specialised(*plugins.find("framed"), base, why);
    if (framed == nullptr) {
      std::fprintf(stderr, "dg-framed-bench: %s\n", why.c_str());
      return 1;
    }
    const Cycle n = measure(native, native, s);
    Seed fs = s;
    fs.options = framed_options;
    const Cycle f = measure(*framed, native, fs);
    if (!n.error.empty() || !f.error.empty()) {
      std::fprintf(stderr, "dg-framed-bench: %s: %s%s\n", s.id.c_str(), n.error.c_str(),
                   f.error.c_str());
      ok = false;
      continue;
    }
    const double ratio = f.mean_ms / n.mean_ms;
    std::printf("| %s | %.3f | %.3f | %.4f | %zu, %zu |\n", s.id.c_str(), n.mean_ms, f.mean_ms,
                ratio, n.cycles, f.cycles);
    if (ratio > 1.02 || ratio < 0.98 || f.cycles < n.cycles) ok = false;
  }
  if (check) return ok ? 0 : 1;
  std::printf(
      "\n| codec, this machine | C++ adapter, ns a frame | framed, ns a frame | framed / C++ |\n"
      "|---|---|---|---|\n");
  for (const CodecRow& r : codec_rows(frames)) {
    std::printf("| %s | %.1f | %.1f | %.2f |\n", r.what.c_str(), r.ns.first, r.ns.second,
                r.ns.second / r.ns.first);
  }
  return ok ? 0 : 1;
}
