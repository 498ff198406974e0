// The documents the HTTP side makes a slice at a time (content.h, SlicedDocument): one slice of
// one of them per turn of the event loop, the documents in turn, so that however many requests
// wait on large documents, what the loop does between two Modbus requests is one slice. A
// document asked for by several requests while it is being made is made once for all of them.
#pragma once

#include <boost/asio/any_io_executor.hpp>
#include <deque>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "content.h"

namespace drivegate::http {

// The most one turn of the event loop does for one response: a slice of a document rendered, or
// of a response sent. A 17 KB document sent at once is one long system call on the event loop
// (loopback delivers it to the reader inside it), a 330 KB page rendered at once milliseconds;
// in slices, a Modbus request that arrives meanwhile is answered between two of them
// (docs/performance.md).
inline constexpr std::size_t kSliceBytes = 4 * 1024;

class SliceRenderer : public std::enable_shared_from_this<SliceRenderer> {
 public:
  using Done = std::function<void(std::shared_ptr<const std::string>)>;

  explicit SliceRenderer(boost::asio::any_io_executor executor) : executor_(std::move(executor)) {}

  // Calls `done` with `document` once it is whole: at once if it is, else from a later turn of
  // the event loop.
  void render(std::shared_ptr<SlicedDocument> document, Done done);
  // Documents not yet whole (the test's view).
  [[nodiscard]] std::size_t pending() const { return queue_.size(); }

 private:
  void slice();

  struct Job {
    std::shared_ptr<SlicedDocument> document;
    std::vector<Done> waiting;
  };
  boost::asio::any_io_executor executor_;
  std::deque<Job> queue_;  // the front's slice is next
  bool posted_ = false;    // slice() is posted
};

}  // namespace drivegate::http
