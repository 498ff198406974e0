// What the adapters' file readers share (include/drivegate/toml_reader.h): a name that must also
// be a file's name, and finding a declared entry by its name.
#include "drivegate/toml_reader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace drivegate {
namespace {

using ::testing::ElementsAre;

// The errors a [profile] table's name gives, and the name read.
std::pair<std::optional<std::string>, std::vector<std::string>> read_name(const char* text) {
  const toml::table root = toml::parse(text);
  Diagnostics diag("p.toml");
  std::optional<std::string> name;
  {
    TableReader r(*root["profile"].as_table(), "profile", diag);
    name = r.file_name("name");
  }
  return {name, diag.errors};
}

TEST(TomlReader, AFileNameIsReadAsWritten) {
  const auto [name, errors] = read_name("[profile]\nname = \"example-vfd_2\"\n");
  EXPECT_EQ(name, "example-vfd_2");
  EXPECT_TRUE(errors.empty());
}

TEST(TomlReader, ANameThatIsNoFileNameIsAnErrorAtItsLine) {
  const auto [name, errors] = read_name("[profile]\n\nname = \"Bad Name\"\n");
  EXPECT_EQ(name, "Bad Name");  // read all the same: the file fails on the error
  EXPECT_THAT(errors, ElementsAre("p.toml:3: profile.name: must be 1..64 characters of a-z, 0-9, "
                                  "'-' and '_' (got 'Bad Name')"));
  for (const char* bad : {"", "a/b", "../x", "UPPER", "dot.toml", " x"}) {
    EXPECT_FALSE(valid_file_name(bad)) << bad;
  }
  EXPECT_TRUE(valid_file_name(std::string(64, 'a')));
  EXPECT_FALSE(valid_file_name(std::string(65, 'a')));
}

TEST(TomlReader, AMissingNameIsTheMissingKeysError) {
  const auto [name, errors] = read_name("[profile]\n");
  EXPECT_FALSE(name.has_value());
  EXPECT_THAT(errors, ElementsAre("p.toml:1: profile.name: required key is missing"));
}

struct Named {
  std::string name;
};

TEST(TomlReader, AnEntryIsFoundByItsNameTheFirstOfTwo) {
  const std::vector<Named> entries = {{"run"}, {"stop"}, {"run"}};
  EXPECT_EQ(index_of(entries, "run"), 0u);
  EXPECT_EQ(index_of(entries, "stop"), 1u);
  EXPECT_FALSE(index_of(entries, "Run").has_value());
  EXPECT_FALSE(index_of(std::vector<Named>{}, "run").has_value());
}

}  // namespace
}  // namespace drivegate
