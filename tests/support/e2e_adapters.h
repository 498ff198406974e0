// The adapters the core's end-to-end scenarios run on all at once (tests/e2e/capture_e2e_test.cpp),
// found rather than listed: each adapter's own scenario (adapters/<id>/tests/e2e_test.cpp, linked
// into the e2e binary by tests/e2e/CMakeLists.txt for every enabled adapter) registers what those
// scenarios need to know of it with
//
//   const RegisterE2eAdapter kE2eAdapter({.id = "<id>", ...});
//
// A new adapter's folder brings its registration along; nothing outside the folder names it.
#pragma once

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

namespace drivegate::test {

struct E2eAdapter {
  std::string id;
  std::string bus_extra;     // [[bus]] lines past name and port
  std::string device_extra;  // [[device]] lines past name, bus, adapter, unit_id
  std::vector<std::string> sim_args;  // `drivegate sim <id>` arguments past the link
  int rpm = 1000;                     // a speed it runs at in the simulator
  // Its dissector (adapters/<id>/dissector.lua): tshark's Protocol column and the checksum
  // status field(s) it sets (1 = Good).
  std::string protocol;
  std::string checksum_field;
  // The adapter id a capture names its frames with, where it is not `id`: a described protocol's
  // device is "framed/NAME" (AdapterDescriptor::specialise).
  std::string capture_id;
};

// Every registered adapter, by id.
inline std::vector<E2eAdapter>& e2e_adapters() {
  static std::vector<E2eAdapter> all;
  return all;
}

struct RegisterE2eAdapter {
  explicit RegisterE2eAdapter(E2eAdapter a) {
    auto& all = e2e_adapters();
    all.push_back(std::move(a));
    std::sort(all.begin(), all.end(),
              [](const E2eAdapter& x, const E2eAdapter& y) { return x.id < y.id; });
  }
};

}  // namespace drivegate::test
