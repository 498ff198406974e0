// What drivegated put on and read from one bus, from its `--log-level trace` log: every "tx"
// line is one frame as written; the "rx" lines are the chunks as read, joined into one stream.
// End-to-end tests compare them with the frames the vendors' documents print.
#pragma once

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace drivegate::test {

// Hex bytes as "1F 03 ..." whatever spacing and case the log used.
inline std::string normalise_hex(const std::string& hex) {
  std::istringstream in(hex);
  std::string out;
  for (std::string b; in >> b;) {
    std::transform(b.begin(), b.end(), b.begin(), [](unsigned char c) { return std::toupper(c); });
    out += (out.empty() ? "" : " ") + b;
  }
  return out;
}

struct Wire {
  std::vector<std::string> tx;  // frames sent, in order
  std::vector<long> tx_ms;      // the log's time of day of each, in ms
  std::string rx;               // every byte received, as one stream
};

inline Wire read_wire(const std::filesystem::path& log, std::string_view bus) {
  const std::string tx = "bus " + std::string(bus) + ": tx ";
  const std::string rx = "bus " + std::string(bus) + ": rx ";
  Wire w;
  std::ifstream in(log);
  for (std::string line; std::getline(in, line);) {
    if (const auto p = line.find(tx); p != std::string::npos) {
      w.tx.push_back(normalise_hex(line.substr(p + tx.size())));
      int h = 0, m = 0, s = 0, milli = 0;  // "YYYY-MM-DD HH:MM:SS.mmm ..."
      std::sscanf(line.c_str(), "%*d-%*d-%*d %d:%d:%d.%d", &h, &m, &s, &milli);
      w.tx_ms.push_back(((h * 60L + m) * 60L + s) * 1000L + milli);
    } else if (const auto q = line.find(rx); q != std::string::npos) {
      w.rx += (w.rx.empty() ? "" : " ") + normalise_hex(line.substr(q + rx.size()));
    }
  }
  return w;
}

}  // namespace drivegate::test
