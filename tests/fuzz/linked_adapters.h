// Every adapter's real plugin descriptor, linked into one program. Each adapters/<id>/plugin.cpp
// is compiled with its `drivegate_adapter` symbol renamed (tests/fuzz/CMakeLists.txt), so that all
// of them fit one binary; the generated linked_adapters.cpp lists them. The core's fake adapters
// (tests/support/fake_adapter.h: one option of every type, and a streamer) are added as well.
#pragma once

#include "plugin/plugins.h"

namespace drivegate::fuzz {

// A registry holding every built adapter plus "fake" and "streamer".
PluginRegistry linked_plugins();

}  // namespace drivegate::fuzz
