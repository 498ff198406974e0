// Where a replay binary finds its target's inputs (replay_test.cpp): defined for each
// fuzz_replay_<target> by a file the build writes (tests/fuzz/CMakeLists.txt, dg_fuzz_target).
#pragma once

namespace drivegate::fuzz {

extern const char* const kCorpusDir;      // the seed corpus
extern const char* const kRegressionDir;  // the crash regressions

}  // namespace drivegate::fuzz
