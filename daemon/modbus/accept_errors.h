// What an acceptor does when accept() fails, for every listener of the daemon (Modbus, HTTP).
// Out of descriptors or memory, the connection stays in the backlog and the next accept fails
// at once the same way: accepting again straight away would turn the event loop into a busy loop
// that starves every other client. Those errors back off; any other (the peer gone before it was
// accepted) is retried at once.
#pragma once

#include <boost/asio/error.hpp>
#include <boost/system/error_code.hpp>
#include <cerrno>
#include <chrono>

namespace drivegate::modbus {

inline constexpr std::chrono::milliseconds kAcceptRetry{100};

// EMFILE, ENFILE, ENOBUFS, ENOMEM.
inline bool accept_needs_back_off(const boost::system::error_code& ec) {
  return ec == boost::asio::error::no_descriptors || ec == boost::asio::error::no_buffer_space ||
         ec == boost::asio::error::no_memory ||
         (ec.category() == boost::system::system_category() && ec.value() == ENFILE);
}

}  // namespace drivegate::modbus
