#include "sim_host.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <boost/asio/write.hpp>
#include <sstream>

#include "transport/serial_line.h"

namespace drivegate {

namespace asio = boost::asio;

namespace {
constexpr Millis kSimTickPeriod{10};

std::int64_t ns(TimePoint t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}
}  // namespace

SimHost::SimHost(asio::io_context& io, const AdapterDescriptor& adapter, SimHostOptions options)
    : io_(io), adapter_(adapter), options_(std::move(options)), line_(io), tick_(io), pace_(io) {}

SimHost::~SimHost() {
  // Asio reports a timer's failed cancel() by throwing; a destructor has no one to tell.
  try {
    stop();
  } catch (...) {  // nothing to do but to go on
  }
}

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
    if (const auto ec = open_serial(port, *options_.port, port_lock_)) {
      if (ec == PortError::in_use) return options_.port->port + ": in use by " + port_lock_.owner();
      return options_.port->port + ": " + ec.message();
    }
    line_.assign(::dup(port.native_handle()));
    path_ = options_.port->port;
    return {};
  }
  if (options_.wire_log) {
    log_.reset(std::fopen(options_.wire_log->c_str(), "w"));
    if (!log_) return options_.wire_log->string() + ": cannot write";
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

std::string SimHost::path() const {
  return path_;
}

void SimHost::start() {
  running_ = true;
  read_more();
  tick();
}

void SimHost::stop() {
  if (!running_) return;
  running_ = false;
  tick_.cancel();
  pace_.cancel();
  if (log_) std::fflush(log_.get());
  boost::system::error_code ignored;
  line_.close(ignored);
  if (options_.link) {
    std::error_code ec;
    std::filesystem::remove(*options_.link, ec);
  }
}

void SimHost::read_more() {
  line_.async_read_some(
      asio::buffer(chunk_), [this](const boost::system::error_code& ec, std::size_t n) {
        if (ec || !running_)
          return;  // EIO: nothing holds the slave side; the host holds it, so rare
        const auto now = Clock::now();
        const ByteView rx(chunk_.data(), n);
        const bool wire = options_.char_time.count() > 0;
        TimePoint rx_end = now;
        if (wire) {
          // The master's bytes occupy the line one character time each, after anything on it.
          rx_end = std::max(now, line_free_) + options_.char_time * static_cast<std::int64_t>(n);
          line_free_ = rx_end;
          if (log_) {
            std::fprintf(log_.get(), "rx %lld %lld %zu ", static_cast<long long>(ns(now)),
                         static_cast<long long>(ns(rx_end)), n);
            for (const auto b : rx) std::fprintf(log_.get(), "%02x", b);
            std::fputc('\n', log_.get());
          }
        }
        if (options_.echo) {
          if (wire) {
            // The master hears its own bytes as they finish on the line.
            send(Bytes(rx.begin(), rx.end()),
                 std::chrono::duration_cast<std::chrono::microseconds>(rx_end - now));
          } else {
            send(Bytes(rx.begin(), rx.end()), std::chrono::microseconds(0));
          }
        }
        Bytes reply;
        for (auto& [address, sim] : sims_) {
          Bytes r = sim->on_receive(rx, now);
          reply.insert(reply.end(), r.begin(), r.end());
        }
        if (!reply.empty()) {
          if (wire) {
            transmit(std::move(reply), rx_end + options_.turnaround);
          } else {
            send(std::move(reply), options_.turnaround);
          }
        }
        read_more();
      });
}

void SimHost::transmit(Bytes bytes, TimePoint earliest) {
  const bool idle = tx_queue_.empty();
  const TimePoint start = std::max(earliest, line_free_);
  line_free_ = start + options_.char_time * static_cast<std::int64_t>(bytes.size());
  tx_queue_.push_back({std::move(bytes), start});
  if (idle) pace();
}

// Writes every byte of the front frame whose character has ended by now (a late wake-up writes
// the ones it missed at once, so lateness does not accumulate), then sleeps until the next.
void SimHost::pace() {
  const auto now = Clock::now();
  while (!tx_queue_.empty()) {
    Frame& f = tx_queue_.front();
    std::size_t due = f.written;
    while (due < f.bytes.size() &&
           f.start + options_.char_time * static_cast<std::int64_t>(due + 1) <= now) {
      ++due;
    }
    if (due > f.written) {
      boost::system::error_code ec;
      asio::write(line_, asio::buffer(f.bytes.data() + f.written, due - f.written), ec);
      if (f.written == 0) f.first_written = Clock::now();
      f.written = due;
    }
    if (f.written < f.bytes.size()) {
      pace_.expires_at(f.start + options_.char_time * static_cast<std::int64_t>(f.written + 1));
      pace_.async_wait([this](const boost::system::error_code& ec) {
        if (!ec && running_) pace();
      });
      return;
    }
    if (log_) {
      std::fprintf(log_.get(), "tx %lld %lld %zu\n", static_cast<long long>(ns(f.first_written)),
                   static_cast<long long>(ns(Clock::now())), f.bytes.size());
    }
    tx_queue_.pop_front();
  }
}

void SimHost::send(Bytes bytes, std::chrono::microseconds delay) {
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
    if (out.empty()) continue;
    if (options_.char_time.count() > 0) {
      transmit(std::move(out), now);
    } else {
      send(std::move(out), std::chrono::microseconds(0));
    }
  }
  tick_.expires_after(kSimTickPeriod);
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
