// The status page end to end (issue: "Status page"): drivegated on every adapter's simulated
// drive with [http] on, each drive started from Modbus TCP as a PLC would, and the page rendered by Debian's
// headless chromium (tools/deps.sh chromium). The assertions read the DOM chromium dumps after
// the page's own script has fetched /api/v1/status and rendered it.
//
// Timing, honestly: each `chromium --dump-dom` run is a fresh browser (start-up, load, first fetch,
// render), so "the fault shows within 2 s" is checked as (a) the page polls at least once a second
// (its data-refresh-ms, and more than one poll inside a 3 s virtual-time budget), (b) the fault
// reaches the JSON the page polls within `kFaultToJson`, and (c) a dump started right after shows
// it, its wall time minus the start-up overhead measured on an identical dump before the fault
// staying under 2 s.
//
// DRIVEGATE_STATUS_SCREENSHOT=PATH also writes a 1280x900 screenshot of the page with the fault
// standing, at 80 % zoom (docs/status-page.png was made that way).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <map>

#include "e2e.h"
#include "e2e_adapters.h"
#include "http_get.h"

namespace drivegate::test {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr const char* kChromium = "/usr/bin/chromium";
constexpr auto kFaultToJson = 1000ms;  // each drive is polled every few hundred ms

// Every drive whose adapter's scenario registered itself (support/e2e_adapters.h), unit 1, 2...
// by adapter id; each runs at its registered speed. The fault is shown on unicla-edrive beside
// ed3100 (tests/e2e/CMakeLists.txt builds this scenario when both are enabled).
struct Drive {
  std::string adapter;
  int unit;
  int rpm;
  E2eAdapter setup;
};

const std::vector<Drive>& drives() {
  static const std::vector<Drive> d = [] {
    std::vector<Drive> out;
    for (const auto& a : e2e_adapters()) {
      out.push_back({a.id, static_cast<int>(out.size()) + 1, a.rpm, a});
    }
    return out;
  }();
  return d;
}

// The text of the element with data-field="field" inside the card of `device`; "<none>" if absent.
std::string field(const std::string& dom, const std::string& device, const std::string& name) {
  const auto card = dom.find("data-device=\"" + device + "\"");
  if (card == std::string::npos) return "<none>";
  const auto end = dom.find("</article>", card);
  const auto at = dom.find("data-field=\"" + name + "\"", card);
  if (at == std::string::npos || at > end) return "<none>";
  const auto open = dom.find('>', at);
  return dom.substr(open + 1, dom.find('<', open) - open - 1);
}

// An attribute of <body> in the dumped DOM.
std::string body_attr(const std::string& dom, const std::string& name) {
  const auto body = dom.find("<body");
  const auto at = dom.find(name + "=\"", body);
  if (body == std::string::npos || at == std::string::npos || at > dom.find('>', body)) return "";
  const auto from = at + name.size() + 2;
  return dom.substr(from, dom.find('"', from) - from);
}

// A stand-in for the daemon: serves `page` at / and `status` once at /api/v1/status, then closes
// every further status request unanswered, as a daemon that has gone away would.
class OneAnswerServer {
 public:
  OneAnswerServer(std::string page, std::string status)
      : page_(std::move(page)), status_(std::move(status)) {
    fd_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    ::listen(fd_, 16);
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
    thread_ = std::thread([this] { run(); });
  }
  ~OneAnswerServer() {
    stop_ = true;
    thread_.join();
    ::close(fd_);
  }
  OneAnswerServer(const OneAnswerServer&) = delete;
  OneAnswerServer& operator=(const OneAnswerServer&) = delete;
  [[nodiscard]] int port() const { return port_; }
  [[nodiscard]] int refused() const { return refused_; }

 private:
  void run() {
    while (!stop_) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 50) <= 0) continue;
      const int c = ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC);
      if (c < 0) continue;
      std::string req;
      char buf[2048];
      while (req.find("\r\n\r\n") == std::string::npos) {
        pollfd q{c, POLLIN, 0};
        if (::poll(&q, 1, 2000) <= 0) break;
        const ssize_t n = ::read(c, buf, sizeof buf);
        if (n <= 0) break;
        req.append(buf, static_cast<std::size_t>(n));
      }
      const bool is_status = req.rfind("GET /api/v1/status", 0) == 0;
      if (is_status && answered_) {
        ++refused_;
      } else {
        answered_ = answered_ || is_status;
        const std::string& body = is_status ? status_ : page_;
        const std::string head = "HTTP/1.1 200 OK\r\nContent-Type: " +
                                 std::string(is_status ? "application/json" : "text/html") +
                                 "\r\nCache-Control: no-store\r\nConnection: close\r\n"
                                 "Content-Length: " +
                                 std::to_string(body.size()) + "\r\n\r\n";
        const std::string out = head + body;
        std::size_t sent = 0;
        while (sent < out.size()) {
          const ssize_t n = ::write(c, out.data() + sent, out.size() - sent);
          if (n <= 0) break;
          sent += static_cast<std::size_t>(n);
        }
      }
      ::close(c);
    }
  }
  std::string page_;
  std::string status_;
  int fd_ = -1;
  int port_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<int> refused_{0};
  bool answered_ = false;
  std::thread thread_;
};

class StatusPage : public ::testing::Test {
 protected:
  void SetUp() override {
    if (::access(kChromium, X_OK) != 0) {
      GTEST_SKIP() << kChromium << " is not installed (tools/deps.sh chromium)";
    }
    http_port_ = free_port();
    std::string toml = "[http]\nlisten = \"127.0.0.1:" + std::to_string(http_port_) +
                       "\"\nallow = [\"127.0.0.1\"]\n";
    for (const auto& d : drives()) {
      sims_[d.adapter] = std::make_unique<Sim>(d.adapter, dir_ / d.adapter, d.setup.sim_args);
      toml += "\n[[bus]]\nname = \"" + d.adapter + "\"\nport = \"" + (dir_ / d.adapter).string() +
              "\"\n" + d.setup.bus_extra + "\n[[device]]\nname = \"" + d.adapter +
              "\"\nbus = \"" + d.adapter + "\"\nadapter = \"" + d.adapter +
              "\"\nunit_id = " + std::to_string(d.unit) + "\n" + d.setup.device_extra;
    }
    daemon_ =
        std::make_unique<Daemon>(dir_, toml, std::vector<std::string>{}, dir_ / "drivegated.log");
    plc_ = std::make_unique<Plc>(daemon_->port());
    ASSERT_TRUE(plc_->connect());
  }

  std::uint16_t in(int unit, int address) {
    plc_->unit(unit);
    const auto r = plc_->input(address, 1);
    return r.ok() ? r.regs[0] : 0xFFFF;
  }
  int speed(int unit) { return static_cast<std::int16_t>(in(unit, reg::speed)); }

  // chromium's DOM of the page after `budget_ms` of virtual time; wall time in `took`.
  std::string dump(int budget_ms, std::chrono::milliseconds* took = nullptr) {
    const auto start = Clock::now();
    Child c({kChromium, "--headless", "--disable-gpu", "--no-sandbox", "--no-first-run",
             "--disable-extensions", "--disable-background-networking", "--disable-sync",
             "--mute-audio", "--user-data-dir=" + (dir_ / "chromium").string(),
             "--virtual-time-budget=" + std::to_string(budget_ms), "--dump-dom", url()},
            dir_ / "chromium.log");
    std::string dom;
    while (auto line = c.read_line(15s)) dom += *line + "\n";
    c.wait_exit(5s);
    if (took != nullptr) {
      *took = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - start);
    }
    return dom;
  }
  [[nodiscard]] std::string url() const {
    return "http://127.0.0.1:" + std::to_string(http_port_) + "/";
  }

  TempDir dir_;
  int http_port_ = 0;
  std::map<std::string, std::unique_ptr<Sim>> sims_;
  std::unique_ptr<Daemon> daemon_;
  std::unique_ptr<Plc> plc_;
};

TEST_F(StatusPage, ShowsLiveSpeedsAFaultWithinTwoSecondsAndALostDaemon) {
  const auto t0 = Clock::now();
  // Every drive online, then started as a PLC would: setpoint and run_forward in one request.
  for (const auto& d : drives()) {
    ASSERT_TRUE(eventually([&] { return (in(d.unit, reg::status) & reg::online) != 0; }, 10s))
        << d.adapter << " never online; sim says " << sims_[d.adapter]->control("state");
    plc_->unit(d.unit);
    ASSERT_EQ(plc_->write(reg::command, {1 /*run_forward*/, static_cast<std::uint16_t>(d.rpm)}), 0)
        << d.adapter;
  }
  // Running, each at its setpoint (ramps done), so the page and the register can be compared.
  std::map<std::string, int> settled;
  for (const auto& d : drives()) {
    ASSERT_TRUE(eventually([&] { return speed(d.unit) == d.rpm; }, 10s))
        << d.adapter << " never reached " << d.rpm << " rpm; speed " << speed(d.unit)
        << ", sim says " << sims_[d.adapter]->control("state");
    settled[d.adapter] = speed(d.unit);
  }

  // The page shows each drive's live speed: the register value read before and after the dump.
  std::chrono::milliseconds overhead{};
  const std::string dom = dump(3000, &overhead);
  ASSERT_THAT(dom, HasSubstr("data-device=")) << dom.substr(0, 2000);
  EXPECT_EQ(body_attr(dom, "data-link"), "live");
  for (const auto& d : drives()) {
    const int after = speed(d.unit);
    EXPECT_EQ(after, settled[d.adapter]) << d.adapter << " moved while the page was rendered";
    EXPECT_EQ(field(dom, d.adapter, "speed_rpm"), std::to_string(after)) << d.adapter;
    EXPECT_EQ(field(dom, d.adapter, "setpoint_rpm"), std::to_string(d.rpm)) << d.adapter;
    EXPECT_EQ(field(dom, d.adapter, "fault_label"), "none") << d.adapter;
    EXPECT_EQ(field(dom, d.adapter, "failsafe"), "clear") << d.adapter;
    EXPECT_THAT(dom, HasSubstr("data-device=\"" + d.adapter + "\" data-state=\"running\""))
        << d.adapter;
    EXPECT_THAT(dom, HasSubstr("<tr data-bus=\"" + d.adapter + "\"")) << d.adapter;
  }
  // It polls at least once a second, over and over (3 s of virtual time: several answers).
  const int refresh_ms = std::atoi(body_attr(dom, "data-refresh-ms").c_str());
  EXPECT_GT(refresh_ms, 0);
  EXPECT_LE(refresh_ms, 1000);
  EXPECT_GE(std::atoi(body_attr(dom, "data-updates").c_str()), 2);
  // Read-only: nothing on it to press or fill in, and its script only GETs.
  EXPECT_THAT(dom, Not(HasSubstr("<button")));
  EXPECT_THAT(dom, Not(HasSubstr("<form")));
  EXPECT_THAT(dom, Not(HasSubstr("<input")));
  EXPECT_THAT(dom, Not(HasSubstr("POST")));

  // A motor fault on the eDrive (over_current; sticky, so it stands until the test ends: the
  // washer's own over-current clears itself after 4 s, as the real drive's does): in the JSON
  // within kFaultToJson, on the page in the next dump.
  ASSERT_THAT(sims_["unicla-edrive"]->control("sticky on"), HasSubstr("sticky"));
  const auto fault_at = Clock::now();
  ASSERT_THAT(sims_["unicla-edrive"]->control("fault motor"), HasSubstr("op_state=7"));
  ASSERT_TRUE(eventually(
      [&] {
        return http_get(http_port_, "/api/v1/status").body.find("\"over_current\"") !=
               std::string::npos;
      },
      5s));
  const auto to_json =
      std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - fault_at);
  EXPECT_LE(to_json, kFaultToJson);
  std::chrono::milliseconds took{};
  const std::string faulted = dump(1500, &took);
  const auto to_page =
      std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - fault_at);
  EXPECT_EQ(field(faulted, "unicla-edrive", "fault_label"), "over_current");
  EXPECT_EQ(field(faulted, "unicla-edrive", "fault_code"), "(4)");
  EXPECT_THAT(faulted, HasSubstr("data-device=\"unicla-edrive\" data-state=\"fault\""));
  EXPECT_EQ(field(faulted, "ed3100", "fault_label"), "none");
  // The dump's own cost is browser start-up plus the page's first fetch; the fault must have
  // reached the page within 2 s on top of the start-up overhead measured before the fault, and the
  // page's refresh adds at most refresh_ms to the time it takes to reach the JSON.
  EXPECT_LT(to_page - overhead, 2000ms) << "overhead " << overhead.count() << " ms";
  EXPECT_LE(to_json.count() + refresh_ms, 2000);
  std::cerr << "[ status page ] chromium dump " << overhead.count() << " ms (overhead), fault to "
            << "JSON " << to_json.count() << " ms, fault to dumped page " << to_page.count()
            << " ms (that dump " << took.count() << " ms), page refresh " << refresh_ms << " ms\n";

  if (const char* shot = std::getenv("DRIVEGATE_STATUS_SCREENSHOT"); shot != nullptr) {
    Child c({kChromium, "--headless", "--disable-gpu", "--no-sandbox", "--no-first-run",
             "--hide-scrollbars", "--user-data-dir=" + (dir_ / "chromium").string(),
             "--virtual-time-budget=2500", "--force-device-scale-factor=0.8",
             "--window-size=1600,1125",  // 1280x900 pixels: every card and table in view
             std::string("--screenshot=") + shot, url()},
            dir_ / "chromium.log");
    EXPECT_EQ(c.wait_exit(30s), 0);
  }

  // The daemon gone after one answer: the page says so instead of showing frozen values as live.
  // A stand-in for the daemon serves the page and one status, then drops every request.
  const std::string page = http_get(http_port_, "/").body;
  const std::string status = http_get(http_port_, "/api/v1/status").body;
  ASSERT_FALSE(page.empty());
  OneAnswerServer stand_in(page, status);
  http_port_ = stand_in.port();
  const std::string gone = dump(3000);
  EXPECT_EQ(body_attr(gone, "data-link"), "unreachable");
  EXPECT_THAT(gone, HasSubstr("does not answer"));
  EXPECT_THAT(gone, HasSubstr("they are not live"));
  EXPECT_EQ(field(gone, "unicla-edrive", "fault_label"), "over_current");      // the last values...
  EXPECT_THAT(field(gone, "ed3100", "data_age_ms"), HasSubstr("(not live)"));  // ...not as live
  EXPECT_GE(stand_in.refused(), 1);
  std::cerr << "[ status page ] whole scenario "
            << std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - t0).count()
            << " ms\n";
}

}  // namespace
}  // namespace drivegate::test
