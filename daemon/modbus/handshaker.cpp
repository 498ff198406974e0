#include "handshaker.h"

#include <openssl/err.h>
#include <openssl/ssl.h>
#include <poll.h>
#include <pthread.h>
#include <sys/eventfd.h>
#include <sys/resource.h>
#include <unistd.h>

#include <boost/asio/error.hpp>
#include <boost/asio/post.hpp>
#include <cerrno>
#include <cstdint>
#include <utility>

namespace drivegate::modbus {
namespace {

namespace asio = boost::asio;

// How much nicer than the event loop the handshake thread runs (setpriority(2) is per thread on
// Linux).
constexpr int kNicer = 10;

void wake(int fd) {
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto n = ::write(fd, &one, sizeof one);
}

}  // namespace

Handshaker::Handshaker(asio::io_context& io)
    : io_(io), wake_(::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK)) {
  thread_ = std::thread([this] { run(); });
  ::pthread_setname_np(thread_.native_handle(), kHandshakeThreadName);
}

Handshaker::~Handshaker() {
  stop();
  if (wake_ >= 0) ::close(wake_);
}

void Handshaker::start(int fd, std::shared_ptr<asio::ssl::context> context, Done done) {
  Job job;
  job.fd = fd;
  job.context = std::move(context);
  job.done = std::move(done);
  {
    const std::lock_guard lock(mutex_);
    if (!stopping_) {
      incoming_.push_back(std::move(job));
      wake(wake_);
      return;
    }
  }
  finish(job, asio::error::operation_aborted);
}

void Handshaker::stop() {
  {
    const std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake(wake_);
  if (thread_.joinable()) thread_.join();
}

void Handshaker::finish(Job& job, const boost::system::error_code& error) {
  asio::post(io_, [done = std::move(job.done),
                   result = std::make_shared<HandshakeResult>(HandshakeResult{
                       std::move(job.ssl), error})]() mutable { done(std::move(*result)); });
  job.done = nullptr;
  job.context.reset();
}

bool Handshaker::step(Job& job) {
  if (!job.ssl) {
    job.ssl = new_socket_ssl(job.context->native_handle(), job.fd);
    if (!job.ssl) {
      finish(job, asio::error::no_memory);
      return true;
    }
  }
  ERR_clear_error();
  errno = 0;
  const int r = SSL_do_handshake(job.ssl.get());
  if (r == 1) {
    finish(job, {});
    return true;
  }
  boost::system::error_code error;
  const auto wait = ssl_wait(job.ssl.get(), r, error);
  if (!wait) {
    finish(job, error);
    return true;
  }
  job.events = *wait == asio::socket_base::wait_read ? POLLIN : POLLOUT;
  return false;
}

void Handshaker::run() {
  ::setpriority(PRIO_PROCESS, static_cast<id_t>(::gettid()),
                ::getpriority(PRIO_PROCESS, static_cast<id_t>(::gettid())) + kNicer);
  std::vector<Job> jobs;
  std::vector<pollfd> polled;
  for (;;) {
    {
      const std::lock_guard lock(mutex_);
      for (auto& job : incoming_) jobs.push_back(std::move(job));
      incoming_.clear();
      if (stopping_) break;
    }
    // Each handshake steps once on arrival (the ClientHello is usually there already), then
    // whenever its socket is ready for what it waits for (or has been shut down).
    std::vector<Job> waiting;
    for (auto& job : jobs) {
      if (job.events != 0 || !step(job)) waiting.push_back(std::move(job));
    }
    jobs = std::move(waiting);
    polled.assign(1, pollfd{.fd = wake_, .events = POLLIN, .revents = 0});
    for (const auto& job : jobs) {
      polled.push_back(pollfd{.fd = job.fd, .events = job.events, .revents = 0});
    }
    if (::poll(polled.data(), polled.size(), -1) < 0) continue;  // EINTR
    if (polled[0].revents != 0) {
      std::uint64_t count = 0;
      [[maybe_unused]] const auto n = ::read(wake_, &count, sizeof count);
    }
    waiting.clear();
    for (std::size_t i = 0; i < jobs.size(); ++i) {
      if (polled[i + 1].revents == 0 || !step(jobs[i])) waiting.push_back(std::move(jobs[i]));
    }
    jobs = std::move(waiting);
  }
  for (auto& job : jobs) finish(job, asio::error::operation_aborted);
}

}  // namespace drivegate::modbus
