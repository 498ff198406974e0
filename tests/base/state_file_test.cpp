// Files kept in the state directory (daemon/base/state_file.h) and files read without being
// trapped (daemon/base/read_file.h), on a real directory: whatever has a name the daemon uses (a
// FIFO, a hard or symbolic link, a directory) neither blocks it nor is written through.
#include "base/state_file.h"

#include <fcntl.h>
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

#include "base/read_file.h"
#include "fifo_trap.h"
#include "temp_dir.h"

namespace drivegate {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using ::testing::HasSubstr;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class StateFileTest : public ::testing::Test {
 protected:
  // How long `f` took.
  template <typename F>
  static std::chrono::milliseconds took(F&& f) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() -
                                                                 t0);
  }
  test::TempDir tmp_;
  const fs::path file_ = tmp_ / "fact";
  const fs::path temporary_ = tmp_ / "fact.tmp";
};

TEST_F(StateFileTest, AFifoAtTheTemporaryNameNeitherBlocksNorStays) {
  std::error_code ec;
  {
    test::FifoTrap trap({temporary_});
    EXPECT_LT(took([&] { ec = replace_file(file_, "17\n"); }), 1s) << "blocked on the FIFO";
  }
  EXPECT_FALSE(ec) << ec.message();
  EXPECT_EQ(slurp(file_), "17\n");
  EXPECT_FALSE(fs::exists(fs::symlink_status(temporary_)));
}

TEST_F(StateFileTest, AHardLinkAtTheTemporaryNameIsNotWrittenThrough) {
  const fs::path elsewhere = tmp_ / "someone-elses";
  std::ofstream(elsewhere) << "precious\n";
  fs::create_hard_link(elsewhere, temporary_);
  ASSERT_FALSE(replace_file(file_, "3\n"));
  EXPECT_EQ(slurp(file_), "3\n");
  EXPECT_EQ(slurp(elsewhere), "precious\n") << "written through the hard link";
  EXPECT_EQ(fs::hard_link_count(elsewhere), 1u);
}

TEST_F(StateFileTest, ASymbolicLinkAtEitherNameIsNotWrittenThrough) {
  const fs::path elsewhere = tmp_ / "someone-elses";
  std::ofstream(elsewhere) << "precious\n";
  fs::create_symlink(elsewhere, temporary_);
  ASSERT_FALSE(replace_file(file_, "4\n"));
  EXPECT_EQ(slurp(elsewhere), "precious\n");
  fs::create_symlink(elsewhere, tmp_ / "other");
  ASSERT_FALSE(replace_file(tmp_ / "other", "5\n"));
  EXPECT_FALSE(fs::is_symlink(tmp_ / "other")) << "the name is replaced, not what it points to";
  EXPECT_EQ(slurp(tmp_ / "other"), "5\n");
  EXPECT_EQ(slurp(elsewhere), "precious\n");
}

TEST_F(StateFileTest, ADirectoryAtTheTemporaryNameIsSetAside) {
  fs::create_directories(temporary_ / "inside");
  ASSERT_FALSE(replace_file(file_, "6\n"));
  EXPECT_EQ(slurp(file_), "6\n");
  EXPECT_TRUE(fs::is_directory(tmp_ / "fact.tmp.bad" / "inside")) << "kept, out of the way";
}

// A write that fails (here: past the process's file size limit, which binds root too) leaves the
// old content and no temporary.
TEST_F(StateFileTest, AFailedReplaceLeavesTheOldContent) {
  ASSERT_FALSE(replace_file(file_, "9\n"));
  struct rlimit old {};
  ASSERT_EQ(::getrlimit(RLIMIT_FSIZE, &old), 0);
  const auto previous = ::signal(SIGXFSZ, SIG_IGN);
  struct rlimit tiny = old;
  tiny.rlim_cur = 1;
  ASSERT_EQ(::setrlimit(RLIMIT_FSIZE, &tiny), 0);
  const auto ec = replace_file(file_, "1000\n");
  ::setrlimit(RLIMIT_FSIZE, &old);
  ::signal(SIGXFSZ, previous);
  EXPECT_TRUE(ec);
  EXPECT_EQ(slurp(file_), "9\n");
  EXPECT_FALSE(fs::exists(temporary_));
}

TEST_F(StateFileTest, SetAsideTakesTheFirstFreeBadName) {
  std::string error;
  ::mkfifo(file_.c_str(), 0600);
  EXPECT_EQ(set_aside(AT_FDCWD, file_.string(), error), file_.string() + ".bad");
  fs::create_directory(file_);
  EXPECT_EQ(set_aside(AT_FDCWD, file_.string(), error), file_.string() + ".bad-2");
  EXPECT_TRUE(fs::is_fifo(file_.string() + ".bad")) << "the first one kept";
  for (int n = 3; n <= 9; ++n) std::ofstream(file_.string() + ".bad-" + std::to_string(n)) << n;
  std::ofstream(file_) << "x";
  EXPECT_FALSE(set_aside(AT_FDCWD, file_.string(), error));
  EXPECT_THAT(error, HasSubstr("are all taken"));
  EXPECT_EQ(slurp(file_), "x") << "left where it was";
  EXPECT_FALSE(set_aside(AT_FDCWD, (tmp_ / "absent").string(), error));
  EXPECT_THAT(error, HasSubstr("No such file"));
}

TEST_F(StateFileTest, AStateFileIsReadWithoutFollowingALinkOrBlocking) {
  std::ofstream(tmp_ / "real") << "42\n";
  fs::create_symlink(tmp_ / "real", file_);
  std::string error;
  EXPECT_EQ(read_regular_file(file_, 64, error, Links::follow), "42\n") << "configuration files";
  EXPECT_FALSE(read_regular_file(file_, 64, error, Links::refuse));
  EXPECT_THAT(error, HasSubstr("fact: a symbolic link, not followed"));
  fs::remove(file_);
  test::FifoTrap trap({file_});
  EXPECT_LT(took([&] { EXPECT_FALSE(read_regular_file(file_, 64, error, Links::refuse)); }), 1s);
  EXPECT_THAT(error, HasSubstr("fact: a FIFO, not a regular file"));
}

}  // namespace
}  // namespace drivegate
