// The bdSeq kept across restarts (daemon/mqtt/bd_seq_file.h) and the atomic replacement under it
// (daemon/base/state_file.h), on a real directory.
#include "mqtt/bd_seq_file.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "base/state_file.h"
#include "temp_dir.h"

namespace drivegate::mqtt {
namespace {

namespace fs = std::filesystem;

class BdSeqFileTest : public ::testing::Test {
 protected:
  static std::string read(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  test::TempDir tmp_;
  const fs::path& dir_ = tmp_.path();
};

TEST(ParseBdSeq, ANumber0To255AndAtMostOneNewline) {
  EXPECT_EQ(parse_bd_seq("0\n"), 0);
  EXPECT_EQ(parse_bd_seq("17"), 17);
  EXPECT_EQ(parse_bd_seq("255\n"), 255);
  for (const char* bad : {"", "\n", "256\n", "-1\n", "+1\n", " 1\n", "1 \n", "1\n\n", "0x10",
                          "1000", "abc", "12a\n"}) {
    EXPECT_FALSE(parse_bd_seq(bad).has_value()) << '"' << bad << '"';
  }
}

// An edge node id changed in the configuration: the store kept under the old one is found (and
// named in the log by the northbound), the node's own and anything else are not.
TEST_F(BdSeqFileTest, OtherEdgeNodesStateIsFoundByItsKind) {
  const fs::path own = edge_node_state_path(dir_, "plant1", "gw01", ".store");
  EXPECT_EQ(own, dir_ / "sparkplug-plant1-gw01.store");
  fs::create_directories(own);
  fs::create_directories(dir_ / "sparkplug-plant1-gw00.store");
  fs::create_directories(dir_ / "sparkplug-line2-gw01.store");
  std::ofstream(dir_ / "sparkplug-plant1-gw00.bdseq") << "3\n";
  std::ofstream(dir_ / "sparkplug-.store") << "";  // no group or node: not an edge node's
  std::ofstream(dir_ / "notes.store") << "";
  EXPECT_EQ(other_edge_node_state(own),
            (std::vector<fs::path>{dir_ / "sparkplug-line2-gw01.store",
                                   dir_ / "sparkplug-plant1-gw00.store"}));
  EXPECT_EQ(other_edge_node_state(edge_node_state_path(dir_, "plant1", "gw01", ".bdseq")),
            std::vector<fs::path>{dir_ / "sparkplug-plant1-gw00.bdseq"});
  EXPECT_TRUE(
      other_edge_node_state(edge_node_state_path(dir_ / "missing", "plant1", "gw01", ".store"))
          .empty());
}

TEST_F(BdSeqFileTest, NoFileYetIsNothingAndNoError) {
  const BdSeqFile f(dir_, "plant1", "gw01");
  EXPECT_TRUE(f.enabled());
  EXPECT_EQ(f.path(), dir_ / "sparkplug-plant1-gw01.bdseq");
  std::string error = "left over";
  EXPECT_FALSE(f.load(error).has_value());
  EXPECT_EQ(error, "");
}

TEST_F(BdSeqFileTest, SavedThenLoadedAndReplacedWhole) {
  const BdSeqFile f(dir_, "plant1", "gw01");
  ASSERT_FALSE(f.save(7));
  EXPECT_EQ(read(f.path()), "7\n");
  std::string error;
  EXPECT_EQ(f.load(error), 7);
  EXPECT_EQ(error, "");
  ASSERT_FALSE(f.save(255));
  EXPECT_EQ(read(f.path()), "255\n");
  EXPECT_EQ(f.load(error), 255);
  // Only the file itself: no temporary left beside it, and readable by the service alone.
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_)) ++n;
  EXPECT_EQ(n, 1u);
  struct stat st {};
  ASSERT_EQ(::stat(f.path().c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0600u);
  // Another edge node keeps its own.
  const BdSeqFile other(dir_, "plant1", "gw02");
  EXPECT_FALSE(other.load(error).has_value());
  EXPECT_EQ(error, "");
}

TEST_F(BdSeqFileTest, AFileWithoutABdSeqIsAnErrorNamingIt) {
  const BdSeqFile f(dir_, "plant1", "gw01");
  for (const char* content : {"", "banana\n", "300\n"}) {
    std::ofstream(f.path()) << content;
    std::string error;
    EXPECT_FALSE(f.load(error).has_value()) << content;
    EXPECT_NE(error.find(f.path().string()), std::string::npos) << error;
  }
  // A directory where the file should be: refused as not a regular file, and a save fails
  // without touching it.
  fs::remove(f.path());
  fs::create_directory(f.path());
  std::string error;
  EXPECT_FALSE(f.load(error).has_value());
  EXPECT_NE(error, "");
  EXPECT_TRUE(f.save(3));
  EXPECT_TRUE(fs::is_directory(f.path()));
  EXPECT_FALSE(fs::exists(f.path().string() + ".tmp"));
}

TEST_F(BdSeqFileTest, AFailedSaveLeavesTheOldValue) {
  const BdSeqFile f(dir_, "plant1", "gw01");
  ASSERT_FALSE(f.save(9));
  // The temporary file cannot be made (a directory has its name; root included): the save fails
  // before anything is renamed.
  fs::create_directory(f.path().string() + ".tmp");
  EXPECT_TRUE(f.save(10));
  std::string error;
  EXPECT_EQ(f.load(error), 9);
  EXPECT_EQ(error, "");
}

TEST_F(BdSeqFileTest, NoStateDirectoryKeepsNothing) {
  const BdSeqFile f({}, "plant1", "gw01");
  EXPECT_FALSE(f.enabled());
  EXPECT_FALSE(f.save(5));
  std::string error;
  EXPECT_FALSE(f.load(error).has_value());
  EXPECT_EQ(error, "");
}

TEST_F(BdSeqFileTest, AMissingDirectoryIsAnError) {
  const BdSeqFile f(dir_ / "absent", "plant1", "gw01");
  EXPECT_TRUE(f.save(1));
  EXPECT_FALSE(fs::exists(dir_ / "absent"));
}

}  // namespace
}  // namespace drivegate::mqtt
