// The bdSeq kept across restarts (daemon/mqtt/bd_seq_file.h) and the atomic replacement under it
// (daemon/base/state_file.h), on a real directory, with FIFOs and links where its files should be.
#include "mqtt/bd_seq_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "base/state_file.h"
#include "fifo_trap.h"
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
  // A directory where the file should be: refused as not a regular file and set aside, so that
  // the next save can put the file there.
  fs::remove(f.path());
  fs::create_directory(f.path());
  std::string error;
  EXPECT_FALSE(f.load(error).has_value());
  EXPECT_EQ(error, f.path().string() + ": a directory, not a regular file; set aside as " +
                       f.path().string() + ".bad");
  EXPECT_TRUE(fs::is_directory(f.path().string() + ".bad"));
  EXPECT_FALSE(f.save(3));
  EXPECT_EQ(f.load(error), 3);
}

// Nothing at the file's or its temporary's name can hang the daemon or redirect the write: a
// FIFO (whose open would block the event loop, Modbus, HTTP and the failsafe timers with it), a
// hard link (written through with O_TRUNC), a symbolic link (read and written elsewhere).
TEST_F(BdSeqFileTest, NoFifoOrLinkIsOpenedOrWrittenThrough) {
  const BdSeqFile f(dir_, "plant1", "gw01");
  const fs::path tmp = f.path().string() + ".tmp";
  const auto took = [](auto&& op) {
    const auto t0 = std::chrono::steady_clock::now();
    op();
    return std::chrono::steady_clock::now() - t0;
  };
  {
    test::FifoTrap trap({tmp});
    std::error_code ec;
    EXPECT_LT(took([&] { ec = f.save(1); }), std::chrono::seconds(1)) << "blocked on the FIFO";
    EXPECT_FALSE(ec) << ec.message();
  }
  EXPECT_EQ(read(f.path()), "1\n");
  EXPECT_FALSE(fs::exists(fs::symlink_status(tmp)));

  const fs::path elsewhere = tmp_ / "someone-elses";
  std::ofstream(elsewhere) << "precious\n";
  fs::create_hard_link(elsewhere, tmp);
  ASSERT_FALSE(f.save(2));
  EXPECT_EQ(read(elsewhere), "precious\n") << "written through the hard link";
  EXPECT_EQ(read(f.path()), "2\n");

  fs::remove(f.path());
  std::ofstream(tmp_ / "planted") << "200\n";
  fs::create_symlink(tmp_ / "planted", f.path());
  std::string error;
  EXPECT_FALSE(f.load(error).has_value()) << "read through the link";
  EXPECT_EQ(error, f.path().string() + ": a symbolic link, not a regular file; set aside as " +
                       f.path().string() + ".bad");
  ASSERT_FALSE(f.save(4));
  EXPECT_EQ(read(tmp_ / "planted"), "200\n");

  fs::remove(f.path());
  {
    test::FifoTrap trap({f.path()});
    EXPECT_LT(took([&] { EXPECT_FALSE(f.load(error).has_value()); }), std::chrono::seconds(1));
  }
  EXPECT_THAT(error, ::testing::HasSubstr("a FIFO, not a regular file; set aside as"));
}

// A write that fails (past the file size limit, which binds root too) leaves the old value.
TEST_F(BdSeqFileTest, AFailedSaveLeavesTheOldValue) {
  const BdSeqFile f(dir_, "plant1", "gw01");
  ASSERT_FALSE(f.save(9));
  struct rlimit old {};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  const auto previous = ::signal(SIGXFSZ, SIG_IGN);
  struct rlimit tiny = old;
  tiny.rlim_cur = 1;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &tiny), 0);
  const auto ec = f.save(100);
  ::setrlimit(RLIMIT_FSIZE, &old);
  ::signal(SIGXFSZ, previous);
  EXPECT_TRUE(ec);
  std::string error;
  EXPECT_EQ(f.load(error), 9);
  EXPECT_EQ(error, "");
  EXPECT_FALSE(fs::exists(f.path().string() + ".tmp"));
}

TEST_F(BdSeqFileTest, NoStateDirectoryKeepsNothing) {
  const BdSeqFile f({}, "plant1", "gw01");
  EXPECT_FALSE(f.enabled());
  EXPECT_FALSE(f.save(5));
  std::string error;
  EXPECT_FALSE(f.load(error).has_value());
  EXPECT_EQ(error, "");
}

// The state directory removed while the daemon runs: made again by the next save.
TEST_F(BdSeqFileTest, AMissingDirectoryIsMadeAgain) {
  const BdSeqFile f(dir_ / "absent", "plant1", "gw01");
  EXPECT_FALSE(f.save(1));
  std::string error;
  EXPECT_EQ(f.load(error), 1);
}

}  // namespace
}  // namespace drivegate::mqtt
