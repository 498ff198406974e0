// The adapters a native protocol's end-to-end scenarios run under: its C++ adapter, and the framed
// adapter with the protocol's shipped description (adapters/framed/protocols/<id>.toml), against
// the same simulator, so that each scenario proves both (adapters/framed/README.md). The
// scenario's fixture takes one as its parameter:
//
//   class NidecE2E : public ::testing::TestWithParam<ProtocolAdapter> { ... };
//   INSTANTIATE_TEST_SUITE_P(, NidecE2E, ::testing::ValuesIn(protocol_adapters("nidec-washer")),
//                            adapter_name);
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "e2e.h"

namespace drivegate::test {

struct ProtocolAdapter {
  std::string adapter;  // the [[device]]'s adapter
  std::string options;  // [device.options] lines before the protocol's own
};

inline void PrintTo(const ProtocolAdapter& a, std::ostream* os) {
  *os << a.adapter;
}

// The C++ adapter `id`, and framed with the description of that name when its plugin is built.
inline std::vector<ProtocolAdapter> protocol_adapters(const std::string& id) {
  std::vector<ProtocolAdapter> out = {{id, ""}};
  if (std::filesystem::exists(plugin_dir() / "drivegate-framed.so")) {
    out.push_back({"framed", "protocol = \"" + id + "\"\n"});
  }
  return out;
}

// Native/..., Framed/... in the test names.
inline std::string adapter_name(const ::testing::TestParamInfo<ProtocolAdapter>& info) {
  return info.param.adapter == "framed" ? "Framed" : "Native";
}

// The [[device]] lines of the adapter, with the protocol's own [device.options] after them.
inline std::string device_adapter(const ProtocolAdapter& a, const std::string& own_options = "") {
  std::string out = "adapter = \"" + a.adapter + "\"\n";
  std::string options = a.options + own_options;
  return options.empty() ? out : out + "[device.options]\n" + options;
}

}  // namespace drivegate::test
