#include "transport/serial_transport.h"

#include <boost/asio/post.hpp>
#include <boost/asio/write.hpp>

#include "transport/serial_line.h"

namespace drivegate {

namespace asio = boost::asio;

SerialTransport::SerialTransport(asio::io_context& io, BusConfig bus)
    : io_(io), bus_(std::move(bus)), port_(io) {}

void SerialTransport::open(Done done) {
  const std::error_code ec = open_serial(port_, bus_, lock_, &refused_);
  asio::post(io_, [done = std::move(done), ec] { done(ec); });
}

void SerialTransport::read(Received received) {
  port_.async_read_some(
      asio::buffer(chunk_),
      [this, received = std::move(received)](const boost::system::error_code& ec, std::size_t n) {
        received(from_asio(ec), ByteView(chunk_.data(), ec ? 0 : n));
      });
}

void SerialTransport::write(ByteView data, Done done) {
  tx_.assign(data.begin(), data.end());
  asio::async_write(port_, asio::buffer(tx_),
                    [done = std::move(done)](const boost::system::error_code& ec, std::size_t) {
                      done(from_asio(ec));
                    });
}

void SerialTransport::close() {
  boost::system::error_code ignored;
  port_.close(ignored);
  lock_.release();
}

std::string SerialTransport::explain(std::error_code ec) const {
  if (ec == PortError::in_use) {
    return "in use by " + (lock_.owner().empty() ? std::string("another program") : lock_.owner());
  }
  return ec.message();
}

std::string SerialTransport::caveat() const {
  std::string out = lock_.note();
  if (!refused_.empty()) {
    out += (out.empty() ? "" : "; ") + bus_.port +
           " did not take every setting asked: " + refused_ +
           ". It runs as the port has it: a pseudo-terminal has no parity "
           "(a loopback test may ignore this); on a real line, a device set as asked will not "
           "understand it (some USB adapters drop such settings: check with stty -F " +
           bus_.port + ")";
  }
  return out;
}

std::string SerialTransport::describe() const {
  return bus_.port + " (" + std::to_string(bus_.baud) + " baud, " + std::to_string(bus_.data_bits) +
         " data, parity " + std::string(to_string(bus_.parity)) + ", " +
         std::to_string(bus_.stop_bits) + " stop" + (bus_.echo ? ", echo" : "") +
         (bus_.rs485 ? ", RS-485" : "") + ")";
}

}  // namespace drivegate
