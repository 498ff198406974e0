#include "sim_host.h"

#include <boost/asio/write.hpp>
#include <fcntl.h>
#include <unistd.h>

#include <sstream>

#include "core/serial_line.h"

namespace drivegate {

namespace asio = boost::asio;

namespace {
constexpr Millis kTickPeriod{10};
}

SimHost::SimHost(asio::io_context& io, const AdapterDescriptor& adapter, SimHostOptions options)
    : io_(io), adapter_(adapter), options_(std::move(options)), line_(io), tick_(io) {}

SimHost::~SimHost() { stop(); }

std::string SimHost::open() {
  if (options_.addresses.empty()) options_.addresses.push_back(adapter_.default_address);
  for (const auto address : options_.addresses) {
    SimEnv env;
    env.address = address;
    env.options = options_.options;
    std::string why;
    auto sim = adapter_.create_simulator(env, why);
    if (!sim) return std::string(adapter_.id) + " simulator refused: " + why;
    sims_.emplace_back(address, std::move(sim));
  }
  if (options_.port) {
    asio::serial_port port(io_);
    if (const auto ec = open_serial(port, *options_.port)) {
      return options_.port->port + ": " + ec.message();
    }
    line_.assign(::dup(port.native_handle()));
    path_ = options_.port->port;
    return {};
  }
  if (const auto ec = pty_.open()) return "cannot create a pseudo-terminal: " + ec.message();
  line_.assign(pty_.release_master());
  path_ = pty_.slave_path();
  if (options_.link) {
    std::error_code ec;
    std::filesystem::remove(*options_.link, ec);
    std::filesystem::create_symlink(path_, *options_.link, ec);
    if (ec) return options_.link->string() + ": cannot link to " + path_ + ": " + ec.message();
    path_ = options_.link->string();
  }
  return {};
}

std::string SimHost::path() const { return path_; }

void SimHost::start() {
  running_ = true;
  read_more();
  tick();
}

void SimHost::stop() {
  if (!running_) return;
  running_ = false;
  tick_.cancel();
  boost::system::error_code ignored;
  line_.close(ignored);
  if (options_.link) {
    std::error_code ec;
    std::filesystem::remove(*options_.link, ec);
  }
}

void SimHost::read_more() {
  line_.async_read_some(asio::buffer(chunk_), [this](const boost::system::error_code& ec,
                                                     std::size_t n) {
    if (ec || !running_) return;  // EIO: nothing holds the slave side; the host holds it, so rare
    const auto now = Clock::now();
    const ByteView rx(chunk_.data(), n);
    if (options_.echo) send(Bytes(rx.begin(), rx.end()), Millis(0));
    Bytes reply;
    for (auto& [address, sim] : sims_) {
      Bytes r = sim->on_receive(rx, now);
      reply.insert(reply.end(), r.begin(), r.end());
    }
    if (!reply.empty()) send(std::move(reply), options_.turnaround);
    read_more();
  });
}

void SimHost::send(Bytes bytes, Millis delay) {
  auto data = std::make_shared<Bytes>(std::move(bytes));
  const auto write = [this, data] {
    if (!running_) return;
    asio::async_write(line_, asio::buffer(*data),
                      [data](const boost::system::error_code&, std::size_t) {});
  };
  if (delay.count() == 0) {
    write();
    return;
  }
  auto timer = std::make_shared<asio::steady_timer>(io_, delay);
  timer->async_wait([timer, write](const boost::system::error_code& ec) {
    if (!ec) write();
  });
}

void SimHost::tick() {
  const auto now = Clock::now();
  for (auto& [address, sim] : sims_) {
    Bytes out = sim->on_tick(now);
    if (!out.empty()) send(std::move(out), Millis(0));
  }
  tick_.expires_after(kTickPeriod);
  tick_.async_wait([this](const boost::system::error_code& ec) {
    if (!ec && running_) tick();
  });
}

std::string SimHost::control(const std::string& line) {
  std::string command = line;
  std::optional<std::uint32_t> target;
  if (line.starts_with("@")) {
    const auto space = line.find(' ');
    try {
      target = static_cast<std::uint32_t>(std::stoul(line.substr(1, space - 1), nullptr, 0));
    } catch (const std::exception&) {
      return "error: '@' needs an address, e.g. '@31 state'";
    }
    command = space == std::string::npos ? "" : line.substr(space + 1);
  }
  std::ostringstream out;
  bool any = false;
  const auto now = Clock::now();
  for (auto& [address, sim] : sims_) {
    if (target && *target != address) continue;
    if (any) out << "\n";
    if (sims_.size() > 1) out << "@" << address << " ";
    out << sim->control(command, now);
    any = true;
  }
  if (!any) return "error: no simulated device at address " + std::to_string(*target);
  return out.str();
}

}  // namespace drivegate
