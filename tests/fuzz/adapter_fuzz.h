// The adapter fuzz targets: one binary per adapter, linking its dg_<id> library and its plugin
// descriptor. adapter_fuzz.cpp drives the Driver and the Simulator through the descriptor's
// factories; the adapter's adapters/<id>/fuzz/codec_fuzz.cpp supplies the codec's decoders.
#pragma once

#include "fuzz_input.h"

namespace drivegate::fuzz {

// Runs the adapter's incremental decoders over the rest of `in`.
void fuzz_codec(FuzzInput& in);

}  // namespace drivegate::fuzz
