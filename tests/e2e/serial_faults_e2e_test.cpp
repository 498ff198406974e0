// Serial faults end to end: the real daemon against simulated drives of the tests' own
// (test-drive, tests/support/test_adapter) while the line misbehaves. The port vanishes and
// returns; noise and truncated frames arrive between good replies; a drive answers late; a reply
// for another address; a NACK storm; a silent drive beside a good one. Nothing crashes, the
// counters a PLC reads (input registers 9..18) count it, and the good drive keeps its poll rate.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <termios.h>

#include <array>
#include <atomic>
#include <iostream>
#include <mutex>
#include <random>

#include "e2e.h"
#include "test_adapter/codec.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;

std::string one_device(const std::filesystem::path& port, const std::string& bus_extra = "") {
  return "[[bus]]\nname = \"line\"\nport = \"" + port.string() + "\"\nreopen_max_ms = 1000\n" +
         bus_extra +
         "\n[[device]]\nname = \"drive\"\nbus = \"line\"\nadapter = \"test-drive\"\n"
         "unit_id = 1\n";
}

// The common block's status and counters, as a PLC reads them.
struct Snapshot {
  std::uint16_t status = 0;
  std::uint32_t frames_good = 0, bad_checksum = 0, timeouts = 0, retries = 0, nacks = 0;
};
Snapshot snapshot(Plc& plc) {
  const auto r = plc.input(reg::status, 19);
  EXPECT_TRUE(r.ok()) << "exception " << r.exception;
  if (!r.ok()) return {};
  return {
      r.regs[0],           r.u32(reg::frames_good), r.u32(reg::bad_checksum), r.u32(reg::timeouts),
      r.u32(reg::retries), r.u32(reg::nacks)};
}
bool online(Plc& plc) {
  return (snapshot(plc).status & reg::online) != 0;
}

// One whole test-drive reply (a refusal too), as the simulator writes it.
bool whole_reply(const std::vector<std::uint8_t>& f) {
  const auto d = testdrive::decode_reply(f);
  return d.status == DecodeStatus::frame && d.consumed == f.size();
}

int open_raw(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) throw std::runtime_error("cannot open " + path);
  termios t{};
  ::tcgetattr(fd, &t);
  ::cfmakeraw(&t);
  ::tcsetattr(fd, TCSANOW, &t);
  return fd;
}

// A man in the middle of a test-drive line: the daemon opens the tap's pty at `link`, the tap
// opens the simulator's, and a thread copies bytes both ways, damaging every third reply of the
// drive as told.
class LineTap {
 public:
  enum class Damage : std::uint8_t {
    none,
    noise,      // random bytes before the reply, and now and then on an idle line
    truncated,  // half the reply alone (lost), or half then the whole reply
    foreign,    // the reply re-addressed to another drive (good sum) before the real one
  };

  LineTap(const std::filesystem::path& sim_link, const std::filesystem::path& link) {
    master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);
    if (master_ < 0 || ::grantpt(master_) != 0 || ::unlockpt(master_) != 0) {
      throw std::runtime_error("no pty");
    }
    std::array<char, 128> name{};
    ::ptsname_r(master_, name.data(), name.size());
    slave_ = open_raw(name.data());  // held, so the daemon closing its side is no hang-up
    ::fcntl(master_, F_SETFL, O_NONBLOCK);
    sim_ = open_raw(sim_link.string());
    std::filesystem::create_symlink(name.data(), link);
    thread_ = std::thread([this] { run(); });
  }
  ~LineTap() {
    stop_ = true;
    thread_.join();
    ::close(sim_);
    ::close(slave_);
    ::close(master_);
  }
  LineTap(const LineTap&) = delete;
  LineTap& operator=(const LineTap&) = delete;

  void damage(Damage d) { damage_ = d; }
  [[nodiscard]] int damaged() const { return damaged_; }

 private:
  void run() {
    std::mt19937 rng(8);  // fixed seed: the same noise every run
    std::array<std::uint8_t, 512> buf{};
    int replies = 0;
    auto next_idle_noise = std::chrono::steady_clock::now();
    while (!stop_) {
      std::array<pollfd, 2> p{pollfd{master_, POLLIN, 0}, pollfd{sim_, POLLIN, 0}};
      ::poll(p.data(), p.size(), 20);
      if (p[0].revents & POLLIN) {  // the daemon's requests, untouched
        const ssize_t n = ::read(master_, buf.data(), buf.size());
        if (n > 0) put(sim_, {buf.begin(), buf.begin() + n});
      }
      if (p[1].revents & POLLIN) {
        const ssize_t n = ::read(sim_, buf.data(), buf.size());
        if (n <= 0) continue;
        std::vector<std::uint8_t> reply(buf.begin(), buf.begin() + n);
        const Damage d = damage_;
        if (d == Damage::none || !whole_reply(reply) || ++replies % 3 != 0) {
          put(master_, reply);
          continue;
        }
        ++damaged_;
        std::vector<std::uint8_t> out;
        if (d == Damage::noise) {
          const auto count = 1 + rng() % 12;
          for (unsigned i = 0; i < count; ++i) out.push_back(static_cast<std::uint8_t>(rng()));
          out.insert(out.end(), reply.begin(), reply.end());
        } else if (d == Damage::truncated) {
          out.assign(reply.begin(), reply.begin() + static_cast<long>(reply.size() / 2));
          if (damaged_ % 2 == 0) out.insert(out.end(), reply.begin(), reply.end());
        } else {
          testdrive::Reply other = testdrive::decode_reply(reply).frame;
          other.address = static_cast<std::uint8_t>(other.address + 1);
          out = testdrive::encode(other);
          out.insert(out.end(), reply.begin(), reply.end());
        }
        put(master_, out);
      }
      if (damage_ == Damage::noise && std::chrono::steady_clock::now() >= next_idle_noise) {
        next_idle_noise = std::chrono::steady_clock::now() + 250ms;
        std::vector<std::uint8_t> junk(1 + rng() % 8);
        for (auto& b : junk) b = static_cast<std::uint8_t>(rng());
        put(master_, junk);
      }
    }
  }
  static void put(int fd, const std::vector<std::uint8_t>& bytes) {
    std::size_t done = 0;
    for (int spins = 0; done < bytes.size() && spins < 100; ++spins) {
      const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
      if (n > 0) {
        done += static_cast<std::size_t>(n);
      } else {
        std::this_thread::sleep_for(1ms);
      }
    }
  }

  int master_ = -1;
  int slave_ = -1;
  int sim_ = -1;
  std::atomic<Damage> damage_{Damage::none};
  std::atomic<int> damaged_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Runs `damage` for `period` while sampling the status; true if comm_lost was ever seen.
bool damaged_for(LineTap& tap, LineTap::Damage damage, std::chrono::milliseconds period, Plc& plc) {
  tap.damage(damage);
  bool lost = false;
  const auto end = std::chrono::steady_clock::now() + period;
  while (std::chrono::steady_clock::now() < end) {
    lost = lost || (snapshot(plc).status & reg::comm_lost) != 0;
    std::this_thread::sleep_for(100ms);
  }
  tap.damage(LineTap::Damage::none);
  return lost;
}

class TappedLine : public ::testing::Test {
 protected:
  void SetUp() override {
    sim_.emplace("test-drive", dir_ / "sim");
    tap_.emplace(dir_ / "sim", dir_ / "line");
    // Polled every 100 ms: a reply in three damaged is a dozen in the 4 s of each damage.
    daemon_.emplace(dir_, one_device(dir_ / "line") + "poll_ms = 100\n");
    plc_.emplace(daemon_->port());
    ASSERT_TRUE(plc_->connect());
    ASSERT_TRUE(eventually([&] { return online(*plc_); }, 10s)) << sim_->control("state");
  }
  TempDir dir_;
  std::optional<Sim> sim_;
  std::optional<LineTap> tap_;
  std::optional<Daemon> daemon_;
  std::optional<Plc> plc_;
};

TEST_F(TappedLine, NoiseAndTruncatedFramesBetweenGoodOnes) {
  const Snapshot before = snapshot(*plc_);
  const bool lost_noise = damaged_for(*tap_, LineTap::Damage::noise, 4s, *plc_);
  const int noisy = tap_->damaged();
  const bool lost_trunc = damaged_for(*tap_, LineTap::Damage::truncated, 4s, *plc_);
  std::this_thread::sleep_for(1s);
  const Snapshot after = snapshot(*plc_);
  EXPECT_GE(noisy, 5);
  EXPECT_GE(tap_->damaged() - noisy, 5);
  // One damaged reply in three never costs an exchange all its attempts.
  EXPECT_FALSE(lost_noise);
  EXPECT_FALSE(lost_trunc);
  EXPECT_TRUE(after.status & reg::online);
  EXPECT_GT(after.frames_good, before.frames_good + 10);
  // A lost reply is a timeout and a retry; a damaged one a bad checksum (or a timeout when the
  // noise looked like the start of a longer frame).
  EXPECT_GT(after.timeouts, before.timeouts);
  EXPECT_GT(after.retries, before.retries);
  EXPECT_GT(after.bad_checksum + after.timeouts, before.bad_checksum + before.timeouts + 5);
  EXPECT_TRUE(daemon_->process().running());
  std::cerr << "damaged " << tap_->damaged() << " replies: frames_good +"
            << after.frames_good - before.frames_good << ", bad_checksum +"
            << after.bad_checksum - before.bad_checksum << ", timeouts +"
            << after.timeouts - before.timeouts << ", retries +" << after.retries - before.retries
            << "\n";
}

TEST_F(TappedLine, AReplyForAnotherAddressIsDroppedWithoutARetry) {
  const Snapshot before = snapshot(*plc_);
  EXPECT_FALSE(damaged_for(*tap_, LineTap::Damage::foreign, 4s, *plc_));
  const Snapshot after = snapshot(*plc_);
  EXPECT_GE(tap_->damaged(), 5);
  EXPECT_TRUE(after.status & reg::online);
  EXPECT_GT(after.frames_good, before.frames_good + 10);
  // The real reply follows in the same burst: nothing was resent, nothing timed out.
  EXPECT_EQ(after.retries, before.retries);
  EXPECT_EQ(after.timeouts, before.timeouts);
  EXPECT_EQ(after.bad_checksum, before.bad_checksum);
}

TEST(SerialFaults, ADriveThatAnswersLaterThanTheTimeoutIsCommLostAndCounted) {
  TempDir dir;
  // test-drive waits 100 ms per attempt, 3 attempts: a 400 ms turnaround misses all of them.
  Sim sim("test-drive", dir / "sim", {"--turnaround-ms", "400"});
  Daemon daemon(dir, one_device(dir / "sim"));
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return (snapshot(plc).status & reg::comm_lost) != 0; }, 10s));
  const Snapshot s = snapshot(plc);
  EXPECT_FALSE(s.status & reg::online);
  EXPECT_GE(s.timeouts, 3u);
  EXPECT_GE(s.retries, 2u);
  EXPECT_EQ(plc.write(reg::command, {1}), 0x0B);
  EXPECT_TRUE(daemon.process().running());
}

// A port that silently drops a setting (a pseudo-terminal has no parity; some USB adapters do
// the same) is named in the log with what it refused, once per open, and the daemon runs on:
// a pty is a legitimate test line, so a warning, not a refusal. A bus of 8E1 on a pty.
TEST(SerialFaults, APortThatDropsASettingIsWarnedOfAndTheDaemonRunsOn) {
  TempDir dir;
  Sim sim("test-drive", dir / "sim");
  Daemon daemon(dir, one_device(dir / "sim", "parity = \"even\"\n"), {}, dir / "daemon.log");
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return online(plc); }, 10s)) << slurp(dir / "daemon.log");
  const std::string log = slurp(dir / "daemon.log");
  EXPECT_EQ(occurrences(log, "bus line: " + (dir / "sim").string() +
                                 " did not take every setting asked: parity even (the port has "
                                 "none). It runs as the port has it"),
            1u)
      << log;
  EXPECT_NE(log.find("parity even, 1 stop) open"), std::string::npos) << log;
  EXPECT_TRUE(daemon.process().running());
}

TEST(SerialFaults, ThePortVanishesAndReturnsAndTheDriveComesBackByItself) {
  TempDir dir;
  std::optional<Sim> sim(std::in_place, "test-drive", dir / "sim");
  Daemon daemon(dir, one_device(dir / "sim"));
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return online(plc); }, 10s));

  // Unplugged: the simulator dies (its pty closes) and the device node goes away.
  sim->process().stop(SIGKILL);
  sim.reset();
  std::filesystem::remove(dir / "sim");
  ASSERT_TRUE(eventually([&] { return (snapshot(plc).status & reg::comm_lost) != 0; }, 10s));
  std::this_thread::sleep_for(2s);  // several reopen attempts fail meanwhile
  EXPECT_TRUE(daemon.process().running());

  // Plugged in again at the same path: the bus reopens (back-off at most reopen_max_ms = 1 s).
  const auto plugged = std::chrono::steady_clock::now();
  sim.emplace("test-drive", dir / "sim");
  const std::uint32_t frames = snapshot(plc).frames_good;
  ASSERT_TRUE(eventually([&] { return online(plc); }, 10s)) << sim->control("state");
  const auto took = std::chrono::steady_clock::now() - plugged;
  RecordProperty(
      "back_online_ms",
      static_cast<int>(std::chrono::duration_cast<std::chrono::milliseconds>(took).count()));
  std::cerr << "back online " << std::chrono::duration_cast<std::chrono::milliseconds>(took).count()
            << " ms after the port returned\n";
  EXPECT_GT(snapshot(plc).frames_good, frames);
  EXPECT_EQ(plc.write(reg::command, {1}), 0);
}

// NACKs (the drive's refusals), then damaged replies: counted, resent, survived. A NACKing drive
// is not backed off like a silent one, so it is back as soon as the NACKs end.
void nacks_then_bad_checksums(int nacks, int corrupt) {
  TempDir dir;
  Sim sim("test-drive", dir / "sim");
  Daemon daemon(dir, one_device(dir / "sim"));
  Plc plc(daemon.port());
  ASSERT_TRUE(plc.connect());
  ASSERT_TRUE(eventually([&] { return online(plc); }, 10s));
  const Snapshot before = snapshot(plc);
  ASSERT_EQ(sim.control("refuse " + std::to_string(nacks)).rfind("ok", 0), 0u);
  ASSERT_TRUE(eventually([&] { return snapshot(plc).nacks >= before.nacks + nacks; }, 30s))
      << sim.control("state");
  ASSERT_EQ(sim.control("corrupt " + std::to_string(corrupt)).rfind("ok", 0), 0u);
  ASSERT_TRUE(
      eventually([&] { return snapshot(plc).bad_checksum >= before.bad_checksum + corrupt; }, 30s));
  // Back: online, with good frames again after the storm (not merely never marked lost).
  ASSERT_TRUE(eventually(
      [&] { return online(plc) && snapshot(plc).frames_good > before.frames_good; }, 15s))
      << sim.control("state");
  EXPECT_GT(snapshot(plc).retries, before.retries);
  EXPECT_TRUE(daemon.process().running());
}

TEST(SerialFaults, ANackBurstAndBadChecksumsAreCountedAndSurvived) {
  nacks_then_bad_checksums(6, 6);
}

// 30 NACKs in a row: the drive refuses every resend, turn after turn, until the storm ends.
TEST(SerialFaults, ANackStormAndBadChecksumsAreCountedAndSurvived) {
  nacks_then_bad_checksums(30, 10);
}

TEST(SerialFaults, ASilentDriveDoesNotSlowTheOtherOneOnTheSameBus) {
  TempDir dir;
  Sim sim("test-drive", dir / "sim", {"--address", "1", "--address", "2"});
  const std::string toml =
      "[[bus]]\nname = \"line\"\nport = \"" + (dir / "sim").string() +
      "\"\n\n[[device]]\nname = \"one\"\nbus = \"line\"\nadapter = \"test-drive\"\n"
      "unit_id = 1\naddress = 1\n\n[[device]]\nname = \"two\"\nbus = \"line\"\n"
      "adapter = \"test-drive\"\nunit_id = 2\naddress = 2\n";
  Daemon daemon(dir, toml);
  Plc one(daemon.port(), 1);
  Plc two(daemon.port(), 2);
  ASSERT_TRUE(one.connect());
  ASSERT_TRUE(two.connect());
  ASSERT_TRUE(eventually([&] { return online(one) && online(two); }, 10s));

  // Good frames of drive one per second over `period`.
  const auto rate = [&](std::chrono::milliseconds period) {
    const auto f0 = snapshot(one).frames_good;
    std::this_thread::sleep_for(period);
    return (snapshot(one).frames_good - f0) * 1000.0 / static_cast<double>(period.count());
  };
  const double both_answer = rate(4s);
  ASSERT_NE(sim.control("@2 silent on").find("ok"), std::string::npos);
  const double two_silent = rate(4s);  // includes drive two's turn into comm_lost
  ASSERT_TRUE(eventually([&] { return (snapshot(two).status & reg::comm_lost) != 0; }, 10s));
  const double two_lost = rate(4s);
  RecordProperty("rate_both", std::to_string(both_answer));
  RecordProperty("rate_two_silent", std::to_string(two_silent));
  RecordProperty("rate_two_lost", std::to_string(two_lost));
  std::cerr << "drive one frames/s: both answering " << both_answer << ", two silent " << two_silent
            << ", two comm_lost " << two_lost << "\n";
  EXPECT_GT(both_answer, 1.0);
  EXPECT_GE(two_silent, 0.75 * both_answer);
  EXPECT_GE(two_lost, 0.75 * both_answer);
  EXPECT_TRUE(online(one));
  EXPECT_GT(snapshot(two).timeouts, 0u);
  EXPECT_TRUE(daemon.process().running());
}

}  // namespace
}  // namespace drivegate::test
