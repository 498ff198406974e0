// A fuzz target as an ordinary test: feeds it every file of its seed corpus and of its crash
// regressions (replay_dirs.h: tests/fuzz/corpus/<target>/ and tests/fuzz/regressions/<target>/,
// or an adapter's adapters/<id>/fuzz/corpus/ and regressions/). Compiled once for every replay
// binary; each binary links the directories of its own target.
// A regression input that crashes again aborts the test binary, which ctest reports as a failure.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "replay_dirs.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace {

namespace fs = std::filesystem;

std::vector<fs::path> files_in(const fs::path& dir) {
  std::vector<fs::path> out;
  if (!fs::is_directory(dir)) return out;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (e.is_regular_file() && e.path().filename().string().front() != '.') out.push_back(e.path());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::size_t replay(const fs::path& dir) {
  const auto files = files_in(dir);
  for (const auto& f : files) {
    SCOPED_TRACE(f.string());
    std::ifstream in(f, std::ios::binary);
    const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), {}};
    // libFuzzer never passes a null pointer; neither does the replay.
    const std::uint8_t empty = 0;
    EXPECT_EQ(LLVMFuzzerTestOneInput(bytes.empty() ? &empty : bytes.data(), bytes.size()), 0);
  }
  return files.size();
}

TEST(FuzzReplay, SeedCorpus) {
  // The seeds are the golden vectors; a target without any would start blind.
  EXPECT_GT(replay(drivegate::fuzz::kCorpusDir), 0u) << drivegate::fuzz::kCorpusDir;
}

TEST(FuzzReplay, CrashRegressions) {
  replay(drivegate::fuzz::kRegressionDir);
}

TEST(FuzzReplay, EmptyAndTinyInputs) {
  const std::uint8_t bytes[4] = {0, 1, 2, 0xFF};
  for (std::size_t n = 0; n <= sizeof bytes; ++n) EXPECT_EQ(LLVMFuzzerTestOneInput(bytes, n), 0);
}

}  // namespace
