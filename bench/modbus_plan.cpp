// dg-modbus-plan: the bus time of one full poll cycle of a Modbus profile, read by its
// plan, against the minimum the wire allows for the same points and against one request per point.
// bench/modbus_plan.sh runs it; docs/performance.md, "Modbus read plans", has the table.
//
// The measured rows run the real bus engine and the modbus adapter's real driver (the descriptor
// of adapters/modbus/plugin.cpp) against its own simulator serving the profile, on simulated time
// and a simulated line (tests/support/bus_rig.h): every byte takes its character time at the
// line's baud, so the numbers are exact and the same on every machine. A cycle's time is read off
// the frames on the wire (SimLine::sent / answers, each with the time its first byte went out).
//
//   dg-modbus-plan [--baud N]... [--profile NAME_OR_PATH]... [--turnaround exact|whole-ms]
//   [--check]
//
// Without --profile: every profile in the shipped folder (adapters/modbus/profiles, whatever it
// holds) and a synthetic larger one written to a temporary file. Without --baud: 19200 and 9600,
// both 8E1 (11 bits a character). --turnaround: the simulated slave answers after exactly 3.5
// characters (exact, the default) or after the fewest whole milliseconds that are as long (as
// the rig could only do before its turnaround was kept in nanoseconds). --check: no table, exit 1
// unless every profile's plan takes at most as many requests, bytes and as much time as one
// request per point, no less time than the floor, and at most 5 % more than the best plan the
// device allows (properties, for ctest). The exit status is also 1 when a cycle could not be
// measured (said on stderr; the other profiles are still measured).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "bus_rig.h"
#include "drivegate/adapter.h"
#include "drivegate/line.h"
#include "line_timing.h"
#include "planner.h"
#include "profile.h"

extern "C" const drivegate::AdapterDescriptor drivegate_adapter;  // adapters/modbus/plugin.cpp

namespace {

using namespace drivegate;
using namespace drivegate::modbus_device;
using namespace std::chrono_literals;
using Nanos = std::chrono::nanoseconds;

// RTU frame overhead around a read (Serial Line 2.5.1.1, Application Protocol 6.1 - 6.4):
// request = address, function, start (2), quantity (2), CRC (2); reply = address, function,
// byte count, the data, CRC (2).
constexpr std::size_t kRequestBytes = 8;
constexpr std::size_t kReplyOverhead = 5;
constexpr std::uint8_t kSlave = 1;
// Long enough for the slowest cycle here (60 requests at 9600 baud, about 1.7 s) to end with the
// line idle before the next one starts: cycles are then told apart by the idle time between them.
// The device's comm_timeout_ms is longer than that, so that it stays online between cycles (a
// device with no good reply for its comm_timeout is comm_lost, and then polled again at once).
constexpr Millis kPollInterval{10'000};
constexpr const char* kCommTimeoutMs = "60000";
constexpr Millis kIdleBetweenCycles{1'000};

double ms(Nanos t) {
  return std::chrono::duration<double, std::milli>(t).count();
}

std::string fmt(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof b, f, v);
  return b;
}

std::string us(Nanos t) {
  return fmt("%.0f", std::chrono::duration<double, std::micro>(t).count());
}

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read " + path.string());
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

Profile parse(const std::filesystem::path& path) {
  auto r = parse_profile(read_text(path), path.string());
  if (auto* errors = std::get_if<std::vector<std::string>>(&r)) {
    std::string all;
    for (const auto& e : *errors) all += e + "\n";
    throw std::runtime_error(all);
  }
  return std::get<Profile>(std::move(r));
}

std::string_view table_name(Table t) {
  switch (t) {
    case Table::coil:
      return "coil";
    case Table::discrete:
      return "discrete";
    case Table::input:
      return "input";
    case Table::holding:
      return "holding";
  }
  return "holding";
}

// --- the profiles ---

// The shipped profiles, by name.
std::vector<std::filesystem::path> shipped_profiles() {
  std::vector<std::filesystem::path> all;
  for (const auto& e : std::filesystem::directory_iterator(DRIVEGATE_PROFILE_DIR)) {
    if (e.is_regular_file() && e.path().extension() == ".toml") all.push_back(e.path());
  }
  std::sort(all.begin(), all.end());
  return all;
}

// The synthetic larger profile: 48 holding u16 points with small gaps (a gap of 6 now and then,
// beyond max_gap, so that the plan splits there too) and 12 f32 input points, max_registers 32,
// max_gap 4.
std::string synthetic_profile() {
  std::ostringstream o;
  o << "[profile]\nname = \"bench-synthetic\"\n"
       "source = \"generated by bench/modbus_plan.cpp\"\n\n"
       "[line]\nbaud = 19200\nparity = \"even\"\nstop_bits = 1\nframing = \"rtu\"\n\n"
       "[modbus]\nmax_registers = 32\nmax_gap = 4\ntimeout_ms = 100\n";
  constexpr int kHoldingGaps[] = {0, 1, 0, 0, 2, 0, 3, 0, 0, 6, 0, 1};  // after each point
  unsigned address = 0;
  for (int i = 0; i < 48; ++i) {
    o << "\n[[point]]\nname = \"h" << i << "\"\ntable = \"holding\"\naddress = " << address
      << "\ntype = \"u16\"\n";
    address += 1 + kHoldingGaps[i % 12];
  }
  constexpr int kInputGaps[] = {0, 0, 2, 0, 5, 0};
  address = 1000;
  for (int i = 0; i < 12; ++i) {
    o << "\n[[point]]\nname = \"f" << i << "\"\ntable = \"input\"\naddress = " << address
      << "\ntype = \"f32\"\nword_order = \"" << (i % 2 != 0 ? "little" : "big") << "\"\n";
    address += 2 + kInputGaps[i % 6];
  }
  return o.str();
}

// The same points, each read by a request of its own: max_gap = 0 and every point moved up by
// the number of points before it in its table, so that one unused register lies between any two
// of them and the planner can join none. The frames keep their lengths (an address is two bytes
// whatever its value): only which registers they name differs. The points are renamed p_NAME:
// with no [common] every point is the device's own, and a name like "command" is the common
// block's.
std::string per_point_profile(const Profile& p) {
  std::ostringstream o;
  o << "[profile]\nname = \"" << p.name << "-per-point\"\nsource = \"" << p.name
    << ", each point alone (bench/modbus_plan.cpp)\"\n\n"
    << "[modbus]\nmax_registers = " << p.modbus.max_registers
    << "\nmax_gap = 0\ntimeout_ms = " << p.modbus.timeout_ms << "\n";
  std::vector<std::size_t> order(p.points.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::tie(p.points[a].table, p.points[a].address) <
           std::tie(p.points[b].table, p.points[b].address);
  });
  std::map<Table, unsigned> before;
  for (const std::size_t i : order) {
    const ProfilePoint& q = p.points[i];
    const unsigned moved = q.address + before[q.table]++;
    if (moved + q.width() > 65536) throw std::runtime_error(p.name + ": no room to spread");
    o << "\n[[point]]\nname = \"p_" << q.name << "\"\ntable = \"" << table_name(q.table)
      << "\"\naddress = " << moved << "\ntype = \""
      << modbus_device::kValueTypeNames.at(static_cast<std::size_t>(q.type)) << "\"\n";
    if (q.width() == 2) {
      o << "word_order = \""
        << modbus_device::kWordOrderNames.at(static_cast<std::size_t>(q.word_order)) << "\"\n";
    }
  }
  return o.str();
}

// The profile's text with its [line] set to `baud`, 8E1: the device is polled on the bench's
// line, which the adapter refuses unless the profile says the same (settings.h, line_agrees).
// A point's own poll_ms is dropped, so that every block falls due in the one cycle measured (and
// the plan is plan_reads() over all the points). The framing and everything else stay as the
// profile has them.
std::string on_line(const std::string& text, std::uint32_t baud) {
  std::istringstream in(text);
  std::ostringstream out;
  const std::string keys =
      "baud = " + std::to_string(baud) + "\nparity = \"even\"\nstop_bits = 1\n";
  bool in_line = false;
  bool written = false;
  for (std::string row; std::getline(in, row);) {
    if (!row.empty() && row[0] == '[') in_line = row.rfind("[line]", 0) == 0;
    const bool setting =
        row.rfind("baud", 0) == 0 || row.rfind("parity", 0) == 0 || row.rfind("stop_bits", 0) == 0;
    if (in_line && setting) continue;
    if (row.rfind("poll_ms", 0) == 0) continue;
    out << row << "\n";
    if (in_line && !written) {
      out << keys;
      written = true;
    }
  }
  if (!written) out << "\n[line]\n" << keys;
  return out.str();
}

// --- the line ---

struct Line {
  std::uint32_t baud = 19200;
  Nanos c{};           // one character: 11 bits (8E1)
  Nanos silence{};     // Serial Line 2.5.1.1: 3.5 characters; 1.75 ms above 19200 baud
  Nanos engine_gap{};  // what the driver asks the engine to keep (line_timing.h)
  Nanos turnaround{};  // what the simulated slave takes to start its reply
};

Line line_at(std::uint32_t baud, bool whole_ms) {
  Line l;
  l.baud = baud;
  l.c = character_time(baud, Parity::even, 8, 1);
  l.silence = baud > 19200 ? Nanos(1'750'000) : l.c * 7 / 2;
  l.engine_gap = inter_frame_gap(Framing::rtu, l.c);
  // The fastest legal slave answers after the silence; whole_ms: the fewest whole milliseconds
  // that are still one.
  l.turnaround = whole_ms ? Nanos(std::chrono::ceil<Millis>(l.silence)) : l.silence;
  return l;
}

// --- what the wire allows, computed ---

struct Cost {
  std::size_t requests = 0;
  std::size_t bytes = 0;
  Nanos frames{};
  Nanos silent{};
  [[nodiscard]] Nanos total() const { return frames + silent; }
};

Cost cost_of(const Line& l, std::size_t requests, std::size_t data_bytes) {
  Cost k;
  k.requests = requests;
  k.bytes = requests * (kRequestBytes + kReplyOverhead) + data_bytes;
  k.frames = l.c * static_cast<long>(k.bytes);
  k.silent = 2 * static_cast<long>(requests) * l.silence;
  return k;
}

// Points of one table, by address: {start, width}.
std::map<Table, std::vector<std::pair<unsigned, unsigned>>> by_table(const Profile& p) {
  std::map<Table, std::vector<std::pair<unsigned, unsigned>>> t;
  for (const ProfilePoint& q : p.points) t[q.table].emplace_back(q.address, q.width());
  for (auto& [table, v] : t) std::sort(v.begin(), v.end());
  return t;
}

// The data bytes of a read of `units` registers or bits of `table` (Application Protocol 6.1 -
// 6.4), and the most one read may ask there.
std::size_t data_of(Table table, unsigned units) {
  return is_bit_table(table) ? (units + 7u) / 8u : 2u * units;
}
unsigned limit_of(const Profile& p, Table table) {
  return is_bit_table(table) ? p.modbus.max_bits : p.modbus.max_registers;
}

// The floor: the points' own data (no unused register read) in the fewest requests any plan
// needs under max_registers (a request spans at most max_registers, gaps of any length inside
// it), each request with its frame overhead and two silences (before the request, before the
// reply). No plan can do better: every plan reads at least the points' registers and needs at
// least that many requests; it is reached only where the fewest requests need no gap.
Cost floor_of(const Profile& p, const Line& l) {
  std::size_t requests = 0;
  std::size_t data = 0;
  for (const auto& [table, points] : by_table(p)) {
    unsigned start = 0;
    unsigned units = 0;  // of the points in the request open
    bool open = false;
    for (const auto& [address, width] : points) {
      if (!open || address + width - start > limit_of(p, table)) {
        if (open) data += data_of(table, units);
        ++requests;
        start = address;
        units = 0;
        open = true;
      }
      units += width;
    }
    if (open) data += data_of(table, units);
  }
  return cost_of(l, requests, data);
}

// The best plan the device allows: spans of at most max_registers with no gap over max_gap inside
// (what the planner may join), chosen to take the least line time (not merely the fewest
// requests): a dynamic program over each table's points.
Cost best_plan_of(const Profile& p, const Line& l) {
  Cost all;
  for (const auto& [table, pts] : by_table(p)) {
    const std::size_t n = pts.size();
    std::vector<Nanos> best(n + 1, Nanos::max());
    std::vector<std::size_t> from(n + 1, 0);
    best[0] = Nanos(0);
    for (std::size_t j = 1; j <= n; ++j) {
      for (std::size_t i = j; i >= 1; --i) {  // points i..j (1-based) in one request
        if (i < j) {
          const unsigned gap = pts[i].first - (pts[i - 1].first + pts[i - 1].second);
          if (gap > p.modbus.max_gap) break;
        }
        const unsigned span = pts[j - 1].first + pts[j - 1].second - pts[i - 1].first;
        if (span > limit_of(p, table)) break;
        const Nanos t = best[i - 1] + cost_of(l, 1, data_of(table, span)).total();
        if (t < best[j]) {
          best[j] = t;
          from[j] = i;
        }
      }
    }
    for (std::size_t j = n; j > 0; j = from[j] - 1) {
      const unsigned span = pts[j - 1].first + pts[j - 1].second - pts[from[j] - 1].first;
      const Cost one = cost_of(l, 1, data_of(table, span));
      all.requests += 1;
      all.bytes += one.bytes;
      all.frames += one.frames;
      all.silent += one.silent;
    }
  }
  return all;
}

// --- measured on the rig ---

struct Measured {
  Cost cost;      // requests, bytes, frames, silent = the cycle's time minus its frames
  Nanos model{};  // frames + requests x (turnaround + the engine's gap): what the rig allows
  Nanos gap_min{}, gap_max{};                // reply end -> next request, inside the cycle
  Nanos turnaround_min{}, turnaround_max{};  // request end -> reply start
  std::size_t cycles = 0;                    // complete cycles seen
  std::string error;
};

Measured measure(const std::filesystem::path& profile, const Line& l, std::size_t blocks) {
  Measured m;
  BusConfig bus;
  bus.name = "bench";
  bus.port = "simulated";
  bus.baud = l.baud;
  bus.parity = Parity::even;
  bus.data_bits = 8;
  bus.stop_bits = 1;
  test::BusRig rig(drivegate_adapter, bus);
  const test::OptionText options = {{"profile", profile.string()}};
  DeviceConfig config = rig.device_config(
      "device", kSlave, {{"profile", profile.string()}, {"comm_timeout_ms", kCommTimeoutMs}});
  config.poll_interval = kPollInterval;
  Device& device = rig.add_device(config);
  rig.add_simulator(kSlave, options);
  rig.line().turnaround = l.turnaround;
  rig.start();
  if (!rig.run_until([&] { return device.online(); }, 30s)) {
    m.error = "never online";
    return m;
  }
  // Three cycles, at the start and one and two poll intervals later; the second is measured (the
  // first shares its time with the device coming up).
  rig.run_for(kPollInterval * 2 + kPollInterval / 2);
  if (!device.online()) {
    m.error = "offline at the end";
    return m;
  }

  const auto& sent = rig.sent();
  const auto& answers = rig.answers();
  const auto end_of = [&](const test::SimLine::Frame& f) {
    return f.at + l.c * static_cast<long>(f.bytes.size());
  };
  if (std::getenv("DG_MODBUS_PLAN_TRACE") != nullptr) {  // every frame, for a look by hand
    const auto dump = [&](const char* dir, const test::SimLine::Frame& f) {
      std::fprintf(stderr, "%s %12.3f ms %zu B:", dir, ms(f.at - sent.front().at), f.bytes.size());
      for (const auto b : f.bytes) std::fprintf(stderr, " %02X", b);
      std::fprintf(stderr, "\n");
    };
    for (const auto& f : sent) dump("tx", f);
    for (const auto& f : answers) dump("rx", f);
  }
  // Cycles: runs of requests with less than kIdleBetweenCycles between one and the next.
  std::vector<std::pair<std::size_t, std::size_t>> cycles;  // [first, last] request indices
  for (std::size_t i = 0; i < sent.size(); ++i) {
    if (cycles.empty() || sent[i].at - end_of(sent[i - 1]) > kIdleBetweenCycles) {
      cycles.emplace_back(i, i);
    } else {
      cycles.back().second = i;
    }
  }
  m.cycles = cycles.size();
  if (cycles.size() < 2) {
    m.error = "fewer than two cycles";
    return m;
  }
  // Steady polling: the measured cycle started one poll interval after the first.
  const Nanos period = sent[cycles[1].first].at - sent[cycles[0].first].at;
  if (period < kPollInterval - 50ms || period > kPollInterval + 50ms) {
    m.error = "cycles " + us(period) + " us apart, not one poll interval";
    return m;
  }
  const auto [first, last] = cycles[1];
  const std::size_t n = last - first + 1;
  if (n != blocks) {
    m.error = "cycle of " + std::to_string(n) + " requests, the plan has " + std::to_string(blocks);
    return m;
  }
  // Every request's reply: the first frame that started after it and before the next request.
  std::vector<const test::SimLine::Frame*> reply(n, nullptr);
  for (const auto& a : answers) {
    for (std::size_t k = 0; k < n; ++k) {
      const std::size_t i = first + k;
      const bool after = a.at >= end_of(sent[i]);
      const bool before_next = i + 1 >= sent.size() || a.at < sent[i + 1].at;
      if (after && before_next && reply[k] == nullptr) reply[k] = &a;
    }
  }
  m.gap_min = m.turnaround_min = Nanos::max();
  m.gap_max = m.turnaround_max = Nanos(0);
  for (std::size_t k = 0; k < n; ++k) {
    const auto& rq = sent[first + k];
    if (reply[k] == nullptr || reply[k]->bytes.size() < 2 || reply[k]->bytes[1] != rq.bytes[1]) {
      m.error = "request " + std::to_string(k) + " of the cycle got no good reply";
      return m;
    }
    m.cost.bytes += rq.bytes.size() + reply[k]->bytes.size();
    const Nanos ta = reply[k]->at - end_of(rq);
    m.turnaround_min = std::min(m.turnaround_min, ta);
    m.turnaround_max = std::max(m.turnaround_max, ta);
    if (k + 1 < n) {
      const Nanos gap = sent[first + k + 1].at - end_of(*reply[k]);
      m.gap_min = std::min(m.gap_min, gap);
      m.gap_max = std::max(m.gap_max, gap);
    }
  }
  if (n == 1) m.gap_min = m.gap_max = l.engine_gap;
  m.cost.requests = n;
  m.cost.frames = l.c * static_cast<long>(m.cost.bytes);
  // The cycle holds the line from its first request's first byte to its last reply's last byte,
  // and then for the silence the engine keeps before the next frame (the one before the first
  // request, in the cycle's own count).
  const Nanos span = end_of(*reply[n - 1]) - sent[first].at + l.engine_gap;
  m.cost.silent = span - m.cost.frames;
  m.model = m.cost.frames + static_cast<long>(n) * (l.turnaround + l.engine_gap);
  return m;
}

// --- the table ---

struct Row {
  std::string profile;
  std::size_t points = 0;
  std::uint32_t baud = 0;
  std::string read;
  Cost cost;
  double vs_floor = 0;
  std::string note;
};

int run(int argc, char** argv) {
  std::vector<std::uint32_t> bauds;
  std::vector<std::string> names;
  bool check = false;
  bool whole_ms = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--baud" && i + 1 < argc) {
      bauds.push_back(static_cast<std::uint32_t>(std::stoul(argv[++i])));
    } else if (a == "--profile" && i + 1 < argc) {
      names.emplace_back(argv[++i]);
    } else if (a == "--turnaround" && i + 1 < argc &&
               (argv[i + 1] == std::string("exact") || argv[i + 1] == std::string("whole-ms"))) {
      whole_ms = argv[++i] == std::string("whole-ms");
    } else if (a == "--check") {
      check = true;
    } else {
      std::fprintf(stderr,
                   "usage: dg-modbus-plan [--baud N]... [--profile NAME_OR_PATH]... "
                   "[--turnaround exact|whole-ms] [--check]\n");
      return 2;
    }
  }
  if (bauds.empty()) bauds = {19200, 9600};

  namespace fs = std::filesystem;
  std::string pattern = (fs::temp_directory_path() / "dg-modbus-plan-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) {
    std::perror("mkdtemp");
    return 1;
  }
  const fs::path dir = pattern;
  struct Cleanup {
    fs::path d;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(d, ec);
    }
  } cleanup{dir};

  std::vector<fs::path> profiles;
  if (names.empty()) {
    profiles = shipped_profiles();
    profiles.push_back(dir / "bench-synthetic.toml");
    std::ofstream(profiles.back()) << synthetic_profile();
  } else {
    for (const auto& n : names) {
      profiles.push_back(n.find('/') != std::string::npos
                             ? fs::path(n)
                             : fs::path(DRIVEGATE_PROFILE_DIR) / (n + ".toml"));
    }
  }

  std::vector<Row> rows;
  int failures = 0;
  const auto fail = [&](const std::string& what) {
    std::fprintf(stderr, "%s\n", what.c_str());
    ++failures;
  };
  for (const fs::path& path : profiles) {
    Profile planned;
    try {
      planned = parse(path);
    } catch (const std::exception& e) {
      fail(path.string() + ": " + e.what());
      continue;
    }
    // One request per point, where the profile's points can be written again on their own (a
    // type the variant cannot say, a string of N registers, leaves the row out).
    std::optional<Profile> alone;
    const fs::path alone_path = dir / (planned.name + "-per-point.toml");
    try {
      std::ofstream(alone_path) << per_point_profile(planned);
      alone = parse(alone_path);
      if (plan_reads(*alone).size() != planned.points.size()) alone.reset();
    } catch (const std::exception&) {
      alone.reset();
    }
    const std::size_t planned_blocks = plan_reads(planned).size();
    for (const std::uint32_t baud : bauds) {
      const Line l = line_at(baud, whole_ms);
      const Cost floor = floor_of(planned, l);
      const Cost best = best_plan_of(planned, l);
      const fs::path planned_here = dir / (planned.name + "-" + std::to_string(baud) + ".toml");
      std::ofstream(planned_here) << on_line(read_text(path), baud);
      const Measured a = measure(planned_here, l, planned_blocks);
      std::optional<Measured> b;
      if (alone) {
        const fs::path alone_here =
            dir / (planned.name + "-per-point-" + std::to_string(baud) + ".toml");
        std::ofstream(alone_here) << on_line(read_text(alone_path), baud);
        b = measure(alone_here, l, planned.points.size());
      }
      const std::string at = planned.name + " at " + std::to_string(baud) + " baud: ";
      if (!a.error.empty()) {
        fail(at + a.error);
        continue;
      }
      if (b && !b->error.empty()) {
        fail(at + "one per point: " + b->error);
        b.reset();
      }
      const auto ratio = [&](const Cost& k) { return ms(k.total()) / ms(floor.total()); };
      const auto note = [&](const Measured& m) {
        const auto range = [](Nanos lo, Nanos hi) {
          return us(lo) + (hi != lo ? "-" + us(hi) : std::string()) + " us";
        };
        std::string s = "turnaround " + range(m.turnaround_min, m.turnaround_max) + ", gap " +
                        range(m.gap_min, m.gap_max);
        const Nanos off = m.cost.total() - m.model;
        if (off != Nanos(0)) s += "; " + us(off) + " us beyond frames + silences";
        return s;
      };
      const std::string name = planned.name;
      const std::size_t np = planned.points.size();
      const double vs_best = ms(a.cost.total()) / ms(best.total());
      rows.push_back({name, np, baud, "floor (computed)", floor, 1.0,
                      "data " + std::to_string(floor.bytes - floor.requests * 13) + " B"});
      rows.push_back({name, np, baud, "best plan (computed)", best, ratio(best),
                      "max_gap " + std::to_string(planned.modbus.max_gap)});
      rows.push_back({name, np, baud, "**planned**", a.cost, ratio(a.cost),
                      fmt("%.3fx of best; ", vs_best) + note(a)});
      if (b) rows.push_back({name, np, baud, "one per point", b->cost, ratio(b->cost), note(*b)});
      if (a.cost.total() < floor.total() || vs_best > 1.05 ||
          (b && (a.cost.requests > b->cost.requests || a.cost.bytes > b->cost.bytes ||
                 a.cost.total() > b->cost.total()))) {
        fail(at + "planned " + std::to_string(a.cost.requests) + " requests " +
             std::to_string(a.cost.bytes) + " B " + fmt("%.3f ms", ms(a.cost.total())) +
             (b ? ", per point " + std::to_string(b->cost.requests) + " requests " +
                      std::to_string(b->cost.bytes) + " B " + fmt("%.3f ms", ms(b->cost.total()))
                : std::string()) +
             fmt(", best %.3f ms", ms(best.total())) + fmt(", floor %.3f ms", ms(floor.total())));
      }
    }
  }
  if (check) {
    std::printf("%s\n", failures == 0 ? "ok: every plan within one request per point, above the "
                                        "floor, within 5 % of the best plan"
                                      : "FAILED");
    return failures == 0 ? 0 : 1;
  }

  std::printf(
      "RTU, 8E1 (11 bits a character), c = one character; Ts = 3.5 c (1.75 ms above 19200).\n"
      "floor = c x (R x (%zu + %zu) + the points' data bytes) + 2 x R x Ts, R = fewest "
      "requests under max_registers.\n"
      "measured: one poll cycle on simulated time, first request byte to last reply byte + the "
      "engine's gap after it;\n"
      "the rig's slave answers after %s; the engine keeps the driver's gap.\n",
      kRequestBytes, kReplyOverhead, whole_ms ? "ceil(Ts) whole ms" : "Ts");
  for (const std::uint32_t baud : bauds) {
    const Line l = line_at(baud, whole_ms);
    std::printf("%u baud: c = %.1f us, Ts = %.3f ms, rig turnaround %s us, engine gap %s us\n",
                baud, std::chrono::duration<double, std::micro>(l.c).count(), ms(l.silence),
                us(l.turnaround).c_str(), us(l.engine_gap).c_str());
  }
  std::printf(
      "\n| profile | points | baud | read | requests | bytes | frames ms | silent ms | "
      "cycle ms | / floor | notes |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (const Row& r : rows) {
    std::printf("| %s | %zu | %u | %s | %zu | %zu | %.2f | %.2f | %.2f | %.2fx | %s |\n",
                r.profile.c_str(), r.points, r.baud, r.read.c_str(), r.cost.requests, r.cost.bytes,
                ms(r.cost.frames), ms(r.cost.silent), ms(r.cost.total()), r.vs_floor,
                r.note.c_str());
  }
  if (failures != 0) std::fprintf(stderr, "%d profiles or comparisons failed (above)\n", failures);
  return failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dg-modbus-plan: %s\n", e.what());
    return 1;
  }
}
