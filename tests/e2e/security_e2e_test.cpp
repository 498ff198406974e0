// Listeners with access levels, allow lists, word order and Modbus/TCP Security (TLS with
// client certificates and roles), end to end: the real drivegated on a simulated drive of the
// tests' own (test-drive, tests/support/test_adapter), with the clients a plant would use (pymodbus
// over TLS, mbpoll, libmodbus, raw sockets), and what each of them sees on the wire, plus what the
// daemon logs about it.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <set>
#include <sstream>

#include "e2e.h"

namespace drivegate::test::security_e2e_test {
namespace {

using namespace std::chrono_literals;
using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;

const fs::path kSource = DRIVEGATE_SOURCE_DIR;

// `n` different free loopback ports.
std::vector<int> free_ports(std::size_t n) {
  std::set<int> ports;
  while (ports.size() < n) ports.insert(free_port());
  return {ports.begin(), ports.end()};
}

// A program run to its end: exit status, stdout, stderr.
struct Ran {
  int status = -1;
  std::string out;
  std::string err;
};
Ran run(std::vector<std::string> argv, const fs::path& stderr_file,
        std::chrono::milliseconds timeout = 10s) {
  Ran r;
  Child child(std::move(argv), stderr_file);
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < deadline) {
    const auto line = child.read_line(std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now()));
    if (!line) break;  // EOF (or the deadline)
    r.out += *line + "\n";
  }
  r.status = child.wait_exit(1s);
  r.err = slurp(stderr_file);
  return r;
}

// tests/support/make_certs.sh into `dir`: ca, server, viewer/operator/engineer/norole, otherca,
// expired.
void make_certs(const fs::path& dir) {
  const Ran r = run({"/bin/sh", (kSource / "tests/support/make_certs.sh").string(), dir.string()},
                    dir.parent_path() / "make_certs.log", 60s);
  ASSERT_EQ(r.status, 0) << r.err;
  ASSERT_TRUE(fs::exists(dir / "server.key"));
}

// --- configuration ------------------------------------------------------------------------

std::string drive(const fs::path& port) {
  return "[[bus]]\nname = \"line\"\nport = \"" + port.string() +
         "\"\n\n[[device]]\nname = \"drive\"\nbus = \"line\"\nadapter = \"test-drive\"\n"
         "unit_id = 1\npoll_ms = 100\n\n";
}

std::string listener(int port, const std::string& keys = "") {
  return "[[listener]]\naddress = \"127.0.0.1:" + std::to_string(port) + "\"\n" + keys + "\n";
}

std::string tls_keys(const fs::path& certs) {
  const auto at = [&](const char* name) { return "\"" + (certs / name).string() + "\""; };
  return "tls = { cert = " + at("server.pem") + ", key = " + at("server.key") +
         ", ca = " + at("ca.pem") +
         " }\nroles = { viewer = \"read\", operator = \"operate\", engineer = \"maintain\" }\n";
}

bool online(Plc& plc) {
  const auto r = plc.input(reg::status, 1);
  return r.ok() && (r.regs[0] & reg::online) != 0;
}

// drivegated on `toml` as written (no --listen: every listener where the file says), its log in
// `log`; ready once `probe`, a plain listener open to loopback, accepts a connection (all
// listeners are bound before any accepts).
class Gateway {
 public:
  Gateway(const TempDir& dir, const std::string& toml, int probe, const fs::path& log)
      : child_(argv(dir, toml), log) {
    if (!eventually(
            [&] {
              Plc p(probe);
              return p.connect() || !child_.running();
            },
            15s) ||
        !child_.running()) {
      throw std::runtime_error("drivegated did not listen:\n" + slurp(log));
    }
  }
  Child& process() { return child_; }

 private:
  static std::vector<std::string> argv(const TempDir& dir, const std::string& toml) {
    std::ofstream(dir / "drivegate.toml") << toml;
    return {(bin_dir() / "drivegated").string(), "--config", (dir / "drivegate.toml").string(),
            "--plugin-dir", plugin_dir().string()};
  }
  Child child_;
};

// --- clients ------------------------------------------------------------------------------

// A plain TCP connection, for exactly what the daemon puts on the wire (or does not).
class RawSocket {
 public:
  explicit RawSocket(int port) : fd_(connect_loopback(port)), connected_(fd_ >= 0) {}
  ~RawSocket() { ::close(fd_); }
  RawSocket(const RawSocket&) = delete;
  RawSocket& operator=(const RawSocket&) = delete;
  [[nodiscard]] bool connected() const { return connected_; }
  bool send(const std::vector<std::uint8_t>& bytes) {
    return ::send(fd_, bytes.data(), bytes.size(), MSG_NOSIGNAL) ==
           static_cast<ssize_t>(bytes.size());
  }
  struct Received {
    std::vector<std::uint8_t> bytes;
    bool closed = false;  // the daemon closed it (EOF or reset); false: still open at the timeout
  };
  Received until_closed(std::chrono::milliseconds timeout) {
    Received r;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < deadline) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 20) <= 0) continue;
      std::uint8_t buf[512];
      const ssize_t n = ::recv(fd_, buf, sizeof buf, 0);
      if (n <= 0) {
        r.closed = true;
        break;
      }
      r.bytes.insert(r.bytes.end(), buf, buf + n);
    }
    return r;
  }

 private:
  int fd_;
  bool connected_ = false;
};

// Read input register 0, one register, unit 1, as a Modbus TCP ADU (transaction 1).
const std::vector<std::uint8_t> kReadStatusAdu = {0x00, 0x01, 0x00, 0x00, 0x00, 0x06,
                                                  0x01, 0x04, 0x00, 0x00, 0x00, 0x01};

// tests/e2e/pymodbus_tls.py holding one TLS session with the client certificate `name` (none:
// "-"); each action answered by one JSON line, e.g. {"op": "write", "exception": 1}.
class TlsClient {
 public:
  TlsClient(int port, const fs::path& certs, const std::string& name)
      : name_(name),
        child_({kSystemPython, (kSource / "tests/e2e/pymodbus_tls.py").string(), "127.0.0.1",
                std::to_string(port), (certs / "ca.pem").string(), file(certs, name, ".pem"),
                file(certs, name, ".key")}) {}
  // Its first line: {"connect": "ok", ...} or {"connect": "failed", "error": ..., "ssl": ...}.
  const std::string& connected() {
    if (!connect_) connect_ = child_.read_line(30s).value_or(name_ + ": <no answer>");
    return *connect_;
  }
  std::string ask(const std::string& action) {
    connected();
    child_.write_line(action);
    return child_.read_line(15s).value_or(name_ + ": <no answer to " + action + ">");
  }

 private:
  static std::string file(const fs::path& certs, const std::string& name, const char* ext) {
    return name == "-" ? name : (certs / (name + ext)).string();
  }
  std::string name_;
  Child child_;
  std::optional<std::string> connect_;
};

constexpr const char* kConnected = R"({"connect": "ok")";
std::string write_ok() {
  return R"({"op": "write", "ok": true})";
}
std::string write_exception(int code) {
  return R"({"op": "write", "exception": )" + std::to_string(code) + "}";
}
std::string holding(std::initializer_list<int> values) {
  std::string list;
  for (const int v : values) list += (list.empty() ? "" : ", ") + std::to_string(v);
  return R"({"op": "read_holding", "registers": [)" + list + "]}";
}
// The registers of a {"op": "read_...", "registers": [...]} line; empty for anything else.
std::vector<std::uint16_t> registers(const std::string& line) {
  std::vector<std::uint16_t> out;
  const auto open = line.find("\"registers\": [");
  if (open == std::string::npos) return out;
  std::istringstream list(line.substr(open + 14));
  long v = 0;
  char sep = ',';
  while (sep == ',' && list >> v >> sep) out.push_back(static_cast<std::uint16_t>(v));
  return out;
}

// Holding 16: test-drive's accel_time (0.1 s), an adapter point: maintain's to write.
constexpr int kAccelTime = 16;

// --- TLS ----------------------------------------------------------------------------------

// A daemon with a plain maintain listener (the test's own libmodbus PLC) and a TLS listener with
// roles viewer = read, operator = operate, engineer = maintain (and read without a known role).
class SecurityTls : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_NO_FATAL_FAILURE(make_certs(certs_));
    const auto ports = free_ports(2);
    plain_ = ports[0];
    tls_ = ports[1];
    gateway_ = std::make_unique<Gateway>(dir_,
                                         listener(plain_, "access = \"maintain\"") +
                                             listener(tls_, tls_keys(certs_) + tls_extra()) +
                                             drive(dir_ / "drive"),
                                         plain_, log_);
    plc_ = std::make_unique<Plc>(plain_);
    ASSERT_TRUE(plc_->connect());
    ASSERT_TRUE(eventually([&] { return online(*plc_); }, 10s)) << sim_.control("state");
  }
  std::string log() const { return slurp(log_); }
  // More keys for the TLS listener.
  virtual std::string tls_extra() const { return {}; }

  TempDir dir_;
  fs::path certs_ = dir_ / "certs";
  fs::path log_ = dir_ / "drivegated.log";
  Sim sim_{"test-drive", dir_ / "drive"};
  int plain_ = 0;
  int tls_ = 0;
  std::unique_ptr<Gateway> gateway_;
  std::unique_ptr<Plc> plc_;
};

TEST_F(SecurityTls, EachCertificateRoleGetsItsAccessLevel) {
  // All four start together: the interpreter's start-up is the slow part.
  TlsClient viewer(tls_, certs_, "viewer");
  TlsClient op(tls_, certs_, "operator");
  TlsClient engineer(tls_, certs_, "engineer");
  TlsClient norole(tls_, certs_, "norole");
  ASSERT_THAT(viewer.connected(), HasSubstr(kConnected));
  ASSERT_THAT(op.connected(), HasSubstr(kConnected));
  ASSERT_THAT(engineer.connected(), HasSubstr(kConnected));
  ASSERT_THAT(norole.connected(), HasSubstr(kConnected));

  // viewer (read): the common block reads, a setpoint write is exception 01.
  const std::string block = viewer.ask("read_input 0 11");
  const auto regs = registers(block);
  ASSERT_EQ(regs.size(), 11u) << block;
  EXPECT_TRUE(regs[reg::status] & reg::online) << block;
  EXPECT_EQ(regs[reg::fault_code], 0) << block;
  EXPECT_GT((std::uint32_t{regs[reg::frames_good]} << 16) | regs[reg::frames_good + 1], 0u)
      << block;
  EXPECT_EQ(viewer.ask("write 1 999"), write_exception(1));

  // operator (operate): the setpoint is written and read back; an adapter point is not its.
  EXPECT_EQ(op.ask("write 1 1200"), write_ok());
  EXPECT_EQ(op.ask("read_holding 1 1"), holding({1200}));
  EXPECT_EQ(op.ask("write 16 66"), write_exception(1));

  // engineer (maintain): the adapter point too.
  EXPECT_EQ(engineer.ask("write 16 55"), write_ok());
  EXPECT_EQ(engineer.ask("read_holding 16 1"), holding({55}));

  // No role in the certificate: the listener's access, read.
  EXPECT_THAT(registers(norole.ask("read_input 0 1")), ::testing::SizeIs(1));
  EXPECT_EQ(norole.ask("write 1 777"), write_exception(1));
  EXPECT_EQ(norole.ask("write 2 1"), write_exception(1));  // heartbeat: operate's too

  // None of the refused writes reached the drive.
  EXPECT_EQ(viewer.ask("read_holding 1 1"), holding({1200}));
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs.at(0), 1200);
  EXPECT_EQ(plc_->holding(kAccelTime, 1).regs.at(0), 55);

  const std::string text = log();
  EXPECT_THAT(text, HasSubstr("role \"viewer\": access read"));
  EXPECT_THAT(text, HasSubstr("role \"operator\": access operate"));
  EXPECT_THAT(text, HasSubstr("role \"engineer\": access maintain"));
  EXPECT_THAT(text, HasSubstr("CN = norole\", role (none): access read"));
  // Each write is one audit record with the certificate's subject and role (docs/audit.md):
  // accepted, refused by the session's level at the gateway, and refused by the server itself.
  EXPECT_THAT(text, HasSubstr("\", role operator: setpoint_rpm=1200: ok, "));
  EXPECT_THAT(text,
              HasSubstr("\", role operator: holding 16 = 66: denied (beyond access operate)"));
  EXPECT_THAT(text, HasSubstr("\", role engineer: accel_time=5.5: ok, "));
  EXPECT_THAT(text, HasSubstr("\", role viewer: pdu 06 00 01 03 e7: denied (beyond access read)"));
  EXPECT_THAT(text, HasSubstr("from modbus_tls 127.0.0.1:"));
  // Logged once per connection: viewer, operator and norole (twice refused, logged once).
  EXPECT_EQ(occurrences(text, "beyond its access level"), 3u) << text;
  EXPECT_THAT(text, Not(HasSubstr("TLS handshake failed")));
}

TEST_F(SecurityTls, AnotherCaExpiredOrNoCertificateFailsTheHandshakeOnly) {
  TlsClient engineer(tls_, certs_, "engineer");
  ASSERT_THAT(engineer.connected(), HasSubstr(kConnected));
  EXPECT_EQ(engineer.ask("write 1 800"), write_ok());

  // The server's verdict reaches each client as a TLS alert (an ssl.SSLError in Python).
  TlsClient otherca(tls_, certs_, "otherca");
  TlsClient expired(tls_, certs_, "expired");
  TlsClient anonymous(tls_, certs_, "-");
  const auto refused = [](const std::string& alert) {
    return ::testing::AllOf(HasSubstr(R"({"connect": "failed")"), HasSubstr(alert),
                            HasSubstr(R"("ssl": true)"));
  };
  EXPECT_THAT(otherca.connected(), refused("alert unknown ca"));
  EXPECT_THAT(expired.connected(), refused("alert certificate expired"));
  EXPECT_THAT(anonymous.connected(), refused("alert certificate required"));

  // The session opened before them is still served, reads and writes.
  EXPECT_EQ(engineer.ask("read_holding 1 1"), holding({800}));
  EXPECT_EQ(engineer.ask("write 1 900"), write_ok());
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs.at(0), 900);
  EXPECT_TRUE(eventually([&] { return occurrences(log(), "TLS handshake failed") == 3; })) << log();
  EXPECT_TRUE(gateway_->process().running());
}

TEST_F(SecurityTls, PlaintextModbusOnTheTlsPortGetsNoModbusReply) {
  RawSocket raw(tls_);
  ASSERT_TRUE(raw.connected());
  ASSERT_TRUE(raw.send(kReadStatusAdu));
  const auto r = raw.until_closed(5s);
  EXPECT_TRUE(r.closed) << "still open 5 s after a plaintext request";
  // Nothing, or a TLS alert record (content type 21): never an MBAP reply to transaction 1.
  EXPECT_TRUE(r.bytes.empty() || r.bytes[0] == 0x15) << "got " << r.bytes.size() << " bytes";
  EXPECT_TRUE(eventually([&] { return occurrences(log(), "TLS handshake failed") == 1; })) << log();
  // The same request on the plain listener is answered.
  EXPECT_EQ(raw_request(plain_, 1, {0x04, 0x00, 0x00, 0x00, 0x01}).size(), 4u);
}

// Without the per-address handshake limit (tls_handshakes_per_s = 0), so that every connection
// of a flood reaches the handshake.
class SecurityTlsUnlimited : public SecurityTls {
 protected:
  std::string tls_extra() const override { return "tls_handshakes_per_s = 0\n"; }
};

// A client failing its handshake in a loop: the journal gets the first ten failures with their
// reasons, then at most one a second saying how many it left out (journald would otherwise drop
// the service's messages, the ones that matter with the flood); the plain listener is served.
TEST_F(SecurityTlsUnlimited, AHandshakeFloodIsNotLoggedLineByLine) {
  const auto fail_one = [this] {
    RawSocket raw(tls_);
    ASSERT_TRUE(raw.connected());
    ASSERT_TRUE(raw.send(kReadStatusAdu));
    EXPECT_TRUE(raw.until_closed(5s).closed);
  };
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < 100; ++i) ASSERT_NO_FATAL_FAILURE(fail_one());
  std::this_thread::sleep_for(1100ms);  // a token back: the next failure is written
  ASSERT_NO_FATAL_FAILURE(fail_one());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_TRUE(eventually([&] { return log().find("like it not logged)") != std::string::npos; }))
      << log();
  const std::size_t lines = occurrences(log(), "TLS handshake failed");
  EXPECT_GE(lines, 11u) << log();
  EXPECT_LE(static_cast<double>(lines), 10 + std::ceil(seconds)) << log();
  EXPECT_EQ(raw_request(plain_, 1, {0x04, 0x00, 0x00, 0x00, 0x01}).size(), 4u);
}

// With the default limit (5 handshakes a second from one address, bursts of 10), a
// flood from one address reaches the handshake a burst's worth of times; the rest are closed as
// they are accepted, before any cryptography, said in the journal without a line each; the
// plain listener's PLC is answered throughout.
TEST_F(SecurityTls, AHandshakeFloodFromOneAddressIsClosedAtAccept) {
  for (int i = 0; i < 100; ++i) {
    RawSocket raw(tls_);
    ASSERT_TRUE(raw.connected());
    raw.send(kReadStatusAdu);
    EXPECT_TRUE(raw.until_closed(5s).closed);
    if (i % 20 == 0) {
      EXPECT_EQ(raw_request(plain_, 1, {0x04, 0x00, 0x00, 0x00, 0x01}).size(), 4u) << i;
    }
  }
  ASSERT_TRUE(eventually([&] {
    return occurrences(log(), "more than 5 TLS handshakes a second") > 0;
  })) << log();
  // A hundred connections in well under the 18 s the bucket would need to pass them all: most
  // never got to the handshake.
  EXPECT_LE(occurrences(log(), "TLS handshake failed"), 40u) << log();
  EXPECT_LE(occurrences(log(), "more than 5 TLS handshakes a second"), 25u) << log();
  EXPECT_EQ(raw_request(plain_, 1, {0x04, 0x00, 0x00, 0x00, 0x01}).size(), 4u);
}

// A TLS key others may read: refused by --check-config and at start-up, naming the key.
TEST(SecurityKey, WorldReadableKeyIsRefusedAtCheckAndStart) {
  TempDir dir;
  const fs::path certs = dir / "certs";
  ASSERT_NO_FATAL_FAILURE(make_certs(certs));
  Sim sim{"test-drive", dir / "drive"};
  const auto ports = free_ports(2);
  const fs::path config = dir / "drivegate.toml";
  std::ofstream(config) << listener(ports[0], "access = \"maintain\"") +
                               listener(ports[1], tls_keys(certs)) + drive(dir / "drive");
  const std::string key = (certs / "server.key").string();
  const auto check = [&] {
    return run({(bin_dir() / "drivegated").string(), "--check-config", config.string(),
                "--plugin-dir", plugin_dir().string()},
               dir / "check.log");
  };

  const Ran good = check();  // as make_certs.sh left it, 0600: accepted
  ASSERT_EQ(good.status, 0) << good.out << good.err;

  ASSERT_EQ(::chmod(key.c_str(), 0644), 0);
  const Ran bad = check();
  EXPECT_NE(bad.status, 0);
  EXPECT_THAT(bad.err, HasSubstr("key " + key + " is readable by others")) << bad.err;

  const fs::path log = dir / "drivegated.log";
  Child daemon({(bin_dir() / "drivegated").string(), "--config", config.string(), "--plugin-dir",
                plugin_dir().string()},
               log);
  EXPECT_EQ(daemon.wait_exit(10s), 1);
  EXPECT_THAT(slurp(log), HasSubstr("key " + key + " is readable by others")) << slurp(log);
  Plc plain(ports[0]);
  EXPECT_FALSE(plain.connect());  // all or nothing: not even the plain listener
}

// --- plain listeners ----------------------------------------------------------------------

// A daemon with four plain listeners: open with maintain (the test's PLC), read-only, one whose
// allow list leaves loopback out, and one serving 32-bit values low word first.
class SecurityPlain : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto ports = free_ports(4);
    open_ = ports[0];
    read_only_ = ports[1];
    not_allowed_ = ports[2];
    little_ = ports[3];
    gateway_ = std::make_unique<Gateway>(
        dir_,
        listener(open_, "access = \"maintain\"") + listener(read_only_, "access = \"read\"") +
            listener(not_allowed_, "allow = [\"192.0.2.1\"]\naccess = \"maintain\"") +
            listener(little_, "word_order = \"little\"") + drive(dir_ / "drive"),
        open_, log_);
    plc_ = std::make_unique<Plc>(open_);
    ASSERT_TRUE(plc_->connect());
    ASSERT_TRUE(eventually([&] { return online(*plc_); }, 10s)) << sim_.control("state");
  }
  std::string log() const { return slurp(log_); }
  Ran mbpoll(std::vector<std::string> args) {
    std::vector<std::string> argv = {
        "/usr/bin/mbpoll",         "-m", "tcp", "-a", "1", "-0", "-1", "-o", "2", "-p",
        std::to_string(read_only_)};
    argv.insert(argv.end(), args.begin(), args.end());
    return run(argv, dir_ / "mbpoll.err");
  }

  TempDir dir_;
  fs::path log_ = dir_ / "drivegated.log";
  Sim sim_{"test-drive", dir_ / "drive"};
  int open_ = 0;
  int read_only_ = 0;
  int not_allowed_ = 0;
  int little_ = 0;
  std::unique_ptr<Gateway> gateway_;
  std::unique_ptr<Plc> plc_;
};

TEST_F(SecurityPlain, MbpollReadsFromAReadOnlyListenerAndItsWriteIsIllegalFunction) {
  ASSERT_EQ(plc_->write(reg::setpoint, {900}), 0);
  // Holding 0..2 (command, setpoint_rpm, heartbeat), PDU addressing (-0).
  const Ran read = mbpoll({"-t", "4", "-r", "0", "-c", "3", "127.0.0.1"});
  EXPECT_EQ(read.status, 0) << read.out << read.err;
  EXPECT_THAT(read.out, HasSubstr("[0]: \t0\n[1]: \t900\n[2]: \t0\n")) << read.out;
  // Input 0: status, online.
  const Ran status = mbpoll({"-t", "3:hex", "-r", "0", "-c", "1", "127.0.0.1"});
  EXPECT_EQ(status.status, 0) << status.out << status.err;
  const auto at = status.out.find("[0]: \t0x");
  ASSERT_NE(at, std::string::npos) << status.out;
  EXPECT_TRUE(std::stoul(status.out.substr(at + 6, 6), nullptr, 16) & reg::online) << status.out;

  // mbpoll reports the exception on stderr and exits 1.
  const Ran write = mbpoll({"-t", "4", "-r", "1", "127.0.0.1", "1500"});
  EXPECT_EQ(write.status, 1);
  EXPECT_THAT(write.err, HasSubstr("Write output (holding) register failed: Illegal function"))
      << write.out << write.err;
  EXPECT_EQ(plc_->holding(reg::setpoint, 1).regs.at(0), 900);
  EXPECT_TRUE(eventually([&] {
    return log().find("beyond its access level \"read\"") != std::string::npos;
  })) << log();
}

TEST_F(SecurityPlain, AnAddressNotAllowedIsClosedAtAcceptBeforeItSendsAByte) {
  RawSocket refused(not_allowed_);
  ASSERT_TRUE(refused.connected());  // the kernel completes the TCP handshake
  const auto r = refused.until_closed(5s);
  EXPECT_TRUE(r.closed) << "the daemon kept a client the allow list leaves out";
  EXPECT_TRUE(r.bytes.empty());
  // A request sent after that gets no Modbus reply either.
  EXPECT_TRUE(raw_request(not_allowed_, 1, {0x04, 0x00, 0x00, 0x00, 0x01}).empty());
  EXPECT_TRUE(eventually([&] {
    return log().find("127.0.0.1:" + std::to_string(not_allowed_) +
                      ": 1 client(s) closed at accept, not in the allow list (last: 127.0.0.1)") !=
           std::string::npos;
  })) << log();
  // The other listeners of the same daemon serve.
  EXPECT_TRUE(online(*plc_));
  EXPECT_EQ(plc_->write(reg::setpoint, {700}), 0);
  Plc reader(read_only_);
  ASSERT_TRUE(reader.connect());
  EXPECT_EQ(reader.holding(reg::setpoint, 1).regs.at(0), 700);
}

TEST_F(SecurityPlain, LittleWordOrderListenerSwapsThe32BitWords) {
  // A standing fault keeps fault_mask (input 2..3) and native_fault (input 4..5) still.
  sim_.control("fault over_current");
  ASSERT_TRUE(eventually([&] { return plc_->input(reg::fault_code, 1).regs.at(0) == 4; }));
  Plc little(little_);
  ASSERT_TRUE(little.connect());
  const auto b = plc_->input(reg::fault_mask, 4);
  const auto l = little.input(reg::fault_mask, 4);
  ASSERT_TRUE(b.ok());
  ASSERT_TRUE(l.ok());
  // fault_mask: over_current (bit 4); native_fault: test-drive's over_current, 1.
  EXPECT_EQ(b.regs, (std::vector<std::uint16_t>{0x0000, 0x0010, 0x0000, 0x0001}));
  EXPECT_EQ(l.regs, (std::vector<std::uint16_t>{0x0010, 0x0000, 0x0001, 0x0000}));
  // 16-bit registers are never reordered.
  EXPECT_EQ(little.input(reg::status, 2).regs, plc_->input(reg::status, 2).regs);
}

}  // namespace
}  // namespace drivegate::test::security_e2e_test
