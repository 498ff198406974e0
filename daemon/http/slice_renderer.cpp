#include "slice_renderer.h"

#include <algorithm>
#include <boost/asio/post.hpp>

namespace drivegate::http {

void SliceRenderer::render(std::shared_ptr<SlicedDocument> document, Done done) {
  if (document->whole()) {
    done(document->document());
    return;
  }
  const auto same = [&](const Job& j) { return j.document == document; };
  if (const auto it = std::find_if(queue_.begin(), queue_.end(), same); it != queue_.end()) {
    it->waiting.push_back(std::move(done));
    return;
  }
  queue_.push_back({std::move(document), {}});
  queue_.back().waiting.push_back(std::move(done));
  if (!posted_) {
    posted_ = true;
    boost::asio::post(executor_, [self = shared_from_this()] { self->slice(); });
  }
}

void SliceRenderer::slice() {
  posted_ = false;
  if (queue_.empty()) return;
  Job job = std::move(queue_.front());
  queue_.pop_front();
  if (job.document->render_slice(kSliceBytes)) {
    const auto whole = job.document->document();
    for (const Done& done : job.waiting) done(whole);
  } else {
    queue_.push_back(std::move(job));
  }
  if (!queue_.empty() && !posted_) {
    posted_ = true;
    boost::asio::post(executor_, [self = shared_from_this()] { self->slice(); });
  }
}

}  // namespace drivegate::http
