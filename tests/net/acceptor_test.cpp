// The one acceptor of the Modbus listeners and the status page (net/acceptor.h), tested once for
// both: the allow list, the server's admission, the counters, the hold-off and the back-off when
// out of descriptors, over loopback on a clock the test moves.
#include "net/acceptor.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "descriptor_limit.h"
#include "server_thread.h"
#include "tcp_client.h"

namespace drivegate::net {
namespace {

using namespace std::chrono_literals;
using boost::asio::ip::tcp;
using test::TcpClient;

// What the server behind the acceptor says (Acceptor::Admit), and the clients it took.
struct Admissions {
  Admission next = Admission::take;
  std::vector<std::shared_ptr<tcp::socket>> taken;
};

// The least server there is: an acceptor on loopback, its clients kept open until it closes.
class AcceptOnly {
 public:
  AcceptOnly(boost::asio::io_context& io, Clock& clock, Admissions& admissions, AllowList allow,
             std::shared_ptr<spdlog::logger> log)
      : admissions_(admissions),
        acceptor_(std::make_shared<Acceptor>(io, clock, std::move(log), "test", std::move(allow))) {
  }
  std::error_code listen() {
    const auto ec = acceptor_->bind("127.0.0.1", 0, 16, AnyAddress::ipv4);
    if (ec) return ec;
    acceptor_->start([this](const boost::asio::ip::address&) { return admissions_.next; },
                     [this](tcp::socket s) {
                       admissions_.taken.push_back(std::make_shared<tcp::socket>(std::move(s)));
                     });
    return {};
  }
  void close() {
    acceptor_->close();
    admissions_.taken.clear();
  }
  // One taken client closed, as a server does when its connection ends.
  void drop_one() {
    admissions_.taken.pop_back();
    acceptor_->left();
  }
  [[nodiscard]] AcceptStats stats() const { return acceptor_->stats(); }
  [[nodiscard]] std::size_t client_count() const { return admissions_.taken.size(); }
  [[nodiscard]] std::uint16_t port() const { return acceptor_->local_endpoint().port(); }

 private:
  Admissions& admissions_;
  std::shared_ptr<Acceptor> acceptor_;
};

class Harness : public test::ServerThread<AcceptOnly, Admissions> {
 public:
  explicit Harness(AllowList allow = {}) : ServerThread(std::move(allow), "acceptor-test") {}
  std::uint16_t port() { return server().port(); }
  void admit(Admission a) {
    on_io([this, a] { source().next = a; });
  }
};

TEST(Acceptor, TakesClientsAndCountsThemInAndOut) {
  Harness h;
  ASSERT_FALSE(h.listen_error());
  TcpClient a(h.port());
  TcpClient b(h.port());
  ASSERT_TRUE(h.wait_clients(2));
  h.on_io([&h] {
    h.server().drop_one();
    return 0;
  });
  const AcceptStats s = h.stats();
  EXPECT_EQ(s.accepted, 2u);
  EXPECT_EQ(s.active, 1u);
  EXPECT_EQ(s.refused, 0u);
  EXPECT_EQ(s.not_allowed, 0u);
}

TEST(Acceptor, AnAddressOutsideTheAllowListIsClosedBeforeTheServerHearsOfIt) {
  std::string error;
  Harness h({*parse_address_range("192.0.2.0/24", error)});
  TcpClient c(h.port());
  ASSERT_TRUE(c.connected());  // the kernel accepts; the acceptor closes
  EXPECT_TRUE(c.closed_by_peer());
  const AcceptStats s = h.stats();
  EXPECT_EQ(s.not_allowed, 1u);
  EXPECT_EQ(s.accepted, 0u);
  EXPECT_EQ(h.clients(), 0u);
}

TEST(Acceptor, ARefusedClientIsClosedAndCountedAndTheNextIsTaken) {
  Harness h;
  h.admit(Admission::refuse);
  TcpClient refused(h.port());
  EXPECT_TRUE(refused.closed_by_peer());
  h.admit(Admission::take);
  TcpClient taken(h.port());
  ASSERT_TRUE(h.wait_clients(1));
  EXPECT_FALSE(taken.closed_by_peer(50ms));
  EXPECT_EQ(h.stats().refused, 1u);
  EXPECT_EQ(h.stats().accepted, 1u);
}

// After a hold-off (a flood rule of the server's), the next client waits in the backlog until
// kHoldOff has passed on the server's clock, then is taken.
TEST(Acceptor, AfterAHoldOffTheNextClientWaitsItsTurn) {
  Harness h;
  h.admit(Admission::hold_off);
  TcpClient flood(h.port());
  EXPECT_TRUE(flood.closed_by_peer());
  h.admit(Admission::take);
  TcpClient next(h.port());
  ASSERT_TRUE(next.connected());  // in the kernel's backlog
  h.advance(kHoldOff - 1ms);
  EXPECT_FALSE(next.closed_by_peer(100ms));
  EXPECT_EQ(h.clients(), 0u);
  h.advance(1ms);
  EXPECT_TRUE(h.wait_clients(1));
  EXPECT_EQ(h.stats().accepted, 1u);
  EXPECT_EQ(h.stats().refused, 0u);  // the server counts its own reasons to hold off
}

// Out of descriptors, accept() fails at once for as long as the connection waits in the backlog.
// The acceptor backs off instead of accepting again straight away (which spun the event loop at
// 100 % CPU, starving everything else on it), and takes the client once descriptors are back and
// the back-off has passed. Both servers (Modbus and HTTP) accept through it.
TEST(Acceptor, OutOfDescriptorsItBacksOffAndRecovers) {
  if (test::kDescriptorsNeededBySanitizer) GTEST_SKIP() << "the sanitizer needs descriptors too";
  Harness h;
  const std::uint16_t port = h.port();
  auto s = test::connect_out_of_descriptors([port] { return std::make_unique<TcpClient>(port); });
  ASSERT_TRUE(s.limited);
  ASSERT_TRUE(s.client->connected());
  EXPECT_LT(s.cpu_seconds, 0.25) << "the acceptor retried EMFILE in a busy loop";
  EXPECT_EQ(h.clients(), 0u);
  h.advance(kAcceptRetry);
  EXPECT_TRUE(h.wait_clients(1));
  EXPECT_EQ(h.stats().accepted, 1u);
}

TEST(Acceptor, BackOffIsOnlyForErrorsThatRepeat) {
  EXPECT_TRUE(accept_needs_back_off(boost::asio::error::no_descriptors));
  EXPECT_TRUE(accept_needs_back_off(boost::asio::error::no_memory));
  EXPECT_TRUE(accept_needs_back_off(boost::asio::error::no_buffer_space));
  EXPECT_TRUE(accept_needs_back_off({ENFILE, boost::system::system_category()}));
  EXPECT_FALSE(accept_needs_back_off(boost::asio::error::connection_aborted));
}

}  // namespace
}  // namespace drivegate::net
