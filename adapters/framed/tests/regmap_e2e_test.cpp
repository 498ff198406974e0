// A PLC cannot tell which adapter runs a seed protocol: `drivegate regmap` prints the same points
// (names, tables, addresses, references, types, registers, scale, units, access, descriptions and
// labels) for the C++ adapter and for framed with the shipped description, the same options given
// to both; only the adapter column differs.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <sstream>

#include "e2e.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;

struct Seed {
  std::string id;
  std::string options;  // [device.options] lines both get
  std::string address;  // address = N, where the protocol has one
};

void PrintTo(const Seed& s, std::ostream* os) {
  *os << s.id;
}

std::string config(const TempDir& dir, const Seed& s, bool framed) {
  std::string c = "[[bus]]\nname = \"line\"\nport = \"" + (dir / "tty").string() +
                  "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\nunit_id = 3\n" + s.address +
                  "adapter = \"" + (framed ? "framed" : s.id) + "\"\n[device.options]\n";
  if (framed) c += "protocol = \"" + s.id + "\"\n";
  return c + s.options;
}

// `drivegate regmap --format csv`, each line without its third column (the adapter's id).
std::vector<std::string> regmap(const TempDir& dir, const std::string& name,
                                const std::string& toml) {
  const auto path = dir / name;
  std::ofstream(path) << toml;
  Child cli({(bin_dir() / "drivegate").string(), "regmap", "--config", path.string(),
             "--plugin-dir", plugin_dir().string(), "--format", "csv"},
            "/dev/null");
  std::vector<std::string> lines;
  while (auto line = cli.read_line(10s)) {
    std::vector<std::string> cols;
    std::size_t at = 0;
    for (int i = 0; i < 3; ++i) {
      const std::size_t comma = line->find(',', at);
      cols.push_back(line->substr(at, comma - at));
      at = comma == std::string::npos ? line->size() : comma + 1;
    }
    lines.push_back(cols[0] + "," + cols[1] + ",<adapter>," + line->substr(at));
  }
  EXPECT_EQ(cli.wait_exit(10s), 0) << name;
  return lines;
}

class FramedRegmap : public ::testing::TestWithParam<Seed> {};

TEST_P(FramedRegmap, TheSamePointsAsTheCppAdapter) {
  if (!std::filesystem::exists(plugin_dir() / "drivegate-framed.so")) GTEST_SKIP();
  TempDir dir;
  const Seed& s = GetParam();
  const auto native = regmap(dir, "native.toml", config(dir, s, false));
  const auto framed = regmap(dir, "framed.toml", config(dir, s, true));
  ASSERT_GT(native.size(), 30u);  // the header, the common block (28) and the adapter's own points
  EXPECT_EQ(framed, native);
}

INSTANTIATE_TEST_SUITE_P(, FramedRegmap,
                         ::testing::Values(Seed{"nidec-washer", "platform = 8\n", ""},
                                           Seed{"mdriver-2400", "mode = \"continuous\"\n",
                                                "address = 7\n"},
                                           Seed{"fdc1", "slave_mode = true\nrefresh_s = 2\n", ""}),
                         [](const ::testing::TestParamInfo<Seed>& i) {
                           std::string n = i.param.id;
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

}  // namespace
}  // namespace drivegate::test
