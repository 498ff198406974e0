// What an acceptor does when accept() fails, for every listener of the daemon (Modbus, HTTP).
// Out of descriptors or memory, the connection stays in the backlog and the next accept fails
// at once the same way: accepting again straight away would turn the event loop into a busy loop
// that starves every other client. Those errors back off; any other (the peer gone before it was
// accepted) is retried at once. The warning is throttled: a full descriptor table fails every
// accept.
#pragma once

#include <spdlog/logger.h>

#include <boost/asio/error.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/system/error_code.hpp>
#include <cerrno>
#include <chrono>
#include <string_view>
#include <utility>

#include "net/log_throttle.h"

namespace drivegate::net {

inline constexpr std::chrono::milliseconds kAcceptRetry{100};

// EMFILE, ENFILE, ENOBUFS, ENOMEM.
inline bool accept_needs_back_off(const boost::system::error_code& ec) {
  return ec == boost::asio::error::no_descriptors || ec == boost::asio::error::no_buffer_space ||
         ec == boost::asio::error::no_memory ||
         (ec.category() == boost::system::system_category() && ec.value() == ENFILE);
}

// After accept() failed with `ec`: "`who`: accept failed: ..." (throttled by `throttle`), then
// `accept_again()`, at once or, out of resources, after kAcceptRetry on `retry_timer` (which the
// acceptor cancels when it closes; `accept_again` checks whether it is still open).
template <class AcceptAgain>
void after_accept_error(const boost::system::error_code& ec, std::string_view who,
                        spdlog::logger& log, LogThrottle& throttle,
                        boost::asio::steady_timer& retry_timer, AcceptAgain accept_again) {
  if (const auto held = throttle.admit(std::chrono::steady_clock::now())) {
    log.warn("{}: accept failed: {}{}", who, ec.message(), held_note(*held));
  }
  if (!accept_needs_back_off(ec)) {
    accept_again();
    return;
  }
  retry_timer.expires_after(kAcceptRetry);
  retry_timer.async_wait([again = std::move(accept_again)](const boost::system::error_code& e) {
    if (!e) again();
  });
}

}  // namespace drivegate::net
