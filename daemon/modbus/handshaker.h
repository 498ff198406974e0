// The Modbus server's TLS handshake thread: the one thread of drivegated besides its event loop.
// A full handshake costs about 1.2 ms of OpenSSL CPU (the ECDHE and the signature, verifying the
// client's certificate chain); on the event loop, every other client of the daemon waited that
// long for each one. Here the loop hands over a connected socket's descriptor and the listener's
// TLS context; the thread runs SSL_do_handshake on it, non-blocking, over poll(2), with every
// handshake in flight at once (a client that stalls holds nothing but its own entry), and posts
// the result (the SSL*, or the error) back to the event loop, where the connection goes on with
// it (tls_stream.h). Nothing else runs here: no Modbus, no register image, no clock, no log, no
// counter; the result's handler runs on the loop.
//
// The descriptor stays the connection's: it is not closed until the result has come back (the
// thread reads and writes it until then). The loop ends a handshake early (its time limit, the
// listener's policy, the server closing) by shutting the socket down: the thread sees the end of
// the stream at once and reports the failure. The time limit itself is the connection's timer
// on the server's clock (connection.cpp), the one place it is kept.
//
// One thread, not a pool: drivegated's hosts have two cores or more, and one handshake thread at
// most takes one of them, whatever a flood does, leaving the other to the event loop; the
// per-address limit (net/address_rate.h) bounds how many handshakes a flood can start at all.
// It runs at a lower priority than the loop (nice +10), so that on a busy machine the loop's
// replies go first and handshakes wait.
#pragma once

#include <boost/asio/io_context.hpp>
#include <boost/asio/ssl/context.hpp>
#include <boost/system/error_code.hpp>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

#include "tls_stream.h"

namespace drivegate::modbus {

// The thread's name, as `top -H` and /proc/<pid>/task/*/comm show it (15 characters at most).
inline constexpr const char* kHandshakeThreadName = "modbus-tls-hs";

struct HandshakeResult {
  // The session: handshaken, or on failure what OpenSSL knows of why (the verification result,
  // the certificate the client sent). nullptr only when OpenSSL could not allocate one.
  SslPtr ssl;
  // None: the handshake completed. operation_aborted: the server stopped first.
  boost::system::error_code error;
};

class Handshaker {
 public:
  // Called on the event loop (posted to `io`), exactly once for every start().
  using Done = std::function<void(HandshakeResult)>;

  // Starts the thread. Results are posted to `io`.
  explicit Handshaker(boost::asio::io_context& io);
  ~Handshaker();  // stop()
  Handshaker(const Handshaker&) = delete;
  Handshaker& operator=(const Handshaker&) = delete;

  // On the event loop: handshakes (as the server) on `fd`, a connected non-blocking TCP socket
  // that the caller keeps open until `done` has run, with `context` (kept alive until then).
  void start(int fd, std::shared_ptr<boost::asio::ssl::context> context, Done done);
  // On the event loop: every handshake still in flight reports operation_aborted, later ones at
  // once; the thread is joined. Idempotent.
  void stop();

 private:
  struct Job {
    int fd = -1;
    std::shared_ptr<boost::asio::ssl::context> context;
    Done done;
    SslPtr ssl;
    short events = 0;  // what the handshake waits for (POLLIN or POLLOUT); 0 before its first step
  };

  void run();
  // Moves the handshake on; true when it is over (the result posted).
  bool step(Job& job);
  void finish(Job& job, const boost::system::error_code& error);

  boost::asio::io_context& io_;
  int wake_ = -1;  // an eventfd: start() and stop() interrupt the thread's poll
  std::mutex mutex_;
  std::vector<Job> incoming_;  // guarded by mutex_: handed over by start(), taken by run()
  bool stopping_ = false;      // guarded by mutex_
  std::thread thread_;
};

}  // namespace drivegate::modbus
